"""The episode metrics, in one registry: each metric's name, label, unit, direction, kind and
description, read by the tasks' summaries, the results store, the tables, the figures and the viewer."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from functools import partial
from typing import Any, Literal, get_args

Kind = Literal["bool", "int", "float"]
Direction = Literal["higher", "lower", "neither"]
# Where a metric is computed: the two tasks' accumulators (socialzoo.env.metrics.EpisodeMetrics,
# socialzoo.env.crowd_outcome.CrowdNavMetrics), the people's metrics a config adds to the
# action-selection task's summaries (socialzoo.env.people) and the humans' metrics the benchmark
# runner adds to a trial (socialzoo.bench.human_metrics), and the evaluation guidelines' Table I
# (socialzoo.bench.guideline_metrics, from any trajectory: an env episode or an episode log), and
# on recorded scenes, the robot against the person it replaced and the reacting people against
# their tracks (socialzoo.env.replay).
Source = Literal["action_selection", "crowdnav", "people", "humans", "guidelines", "recorded"]
SOURCES: tuple[str, ...] = get_args(Source)
# Sources that register_metric added: the names of tasks written outside the package.
_TASK_SOURCES: set[str] = set()


class UnknownMetricError(KeyError):
    """A metric name that is not in the registry (socialzoo.core.metrics.METRICS)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else "unknown metric"


@dataclass(frozen=True, kw_only=True)
class Metric:
    """One episode metric.

    Attributes:
        name: the key of a summary, a trial row and a store column (an identifier).
        label: a short lowercase phrase for tables, axes and the viewer, without the unit; by
            default the name with spaces for underscores ("time_to_goal": "time to goal").
        unit: the SI unit of a value ("s", "m", "m/s", "m/s^3", "rad", "1/min"); "" for a number
            without one (flags, shares, ratios, counts, the reward's units).
        better: "higher" or "lower" is better, or "neither" (a size, not a quality: steps,
            distance travelled).
        kind: the value's type: "bool" (a flag; the CrowdNav task reports 0.0 / 1.0), "int" (a
            count) or "float" (NaN where it is undefined).
        description: what it is and how it is computed, in one or two sentences.
        sources: where it is computed (SOURCES), e.g. ("action_selection", "crowdnav").
        success_only: defined for successful episodes only (NaN otherwise); means are taken over
            the successful episodes.
        count: a count of events per episode (skewed, mostly zero, never negative): means get a
            bootstrap interval (socialzoo.bench.stats.count_interval).
        digits: decimals to print a mean with (a flag's mean is a share between 0 and 1).
    """

    name: str
    label: str = ""
    unit: str
    better: Direction
    kind: Kind
    description: str
    sources: tuple[str, ...]
    success_only: bool = False
    count: bool = False
    digits: int = 4

    def __post_init__(self) -> None:
        if self.label == "" and isinstance(self.name, str):
            object.__setattr__(self, "label", self.name.replace("_", " "))
        problems = []
        if not self.name.isidentifier():
            problems.append(f"name must be an identifier, got {self.name!r}")
        if not self.label or self.label != self.label.strip():
            problems.append(f"label must be a non-empty phrase, got {self.label!r}")
        if self.better not in get_args(Direction):
            problems.append(f"better must be one of {get_args(Direction)}, got {self.better!r}")
        if self.kind not in get_args(Kind):
            problems.append(f"kind must be one of {get_args(Kind)}, got {self.kind!r}")
        if not self.description.strip():
            problems.append("description must not be empty")
        if not self.sources or any(s not in SOURCES and s not in _TASK_SOURCES for s in self.sources):
            problems.append(
                f"sources must be some of {SOURCES} (or a task's own name, through register_metric), "
                f"got {self.sources!r}"
            )
        if self.count and self.kind != "int":
            problems.append(f"a count must be of kind 'int', got {self.kind!r}")
        if self.kind == "bool" and self.unit:
            problems.append(f"a flag has no unit, got {self.unit!r}")
        if isinstance(self.digits, bool) or not isinstance(self.digits, int) or not 0 <= self.digits <= 6:
            problems.append(f"digits must be an int in 0..6, got {self.digits!r}")
        if problems:
            raise ValueError(f"Metric {self.name!r}: " + "; ".join(problems))

    @property
    def higher_is_better(self) -> bool | None:
        """True when a higher value is better, False when a lower one is, None for neither."""
        return None if self.better == "neither" else self.better == "higher"

    @property
    def heading(self) -> str:
        """The label with its unit: "time to goal, s", "force (mean per step)"."""
        return f"{self.label}, {self.unit}" if self.unit else self.label


class _Entries:
    """Registry entries of the metrics one source computes (`sources`, filled in), one helper a
    kind with the fields its kind fixes: a flag (its mean is a share, printed to 3 digits), a count
    of events per episode (fewer is better, 2 digits) and a float (NaN where undefined; no unit and
    `digits` decimals unless the entry says otherwise). Other entries are Metric(...)."""

    def __init__(self, *sources: str, digits: int = 4) -> None:
        self.flag = partial(Metric, sources=sources, unit="", kind="bool", digits=3)
        self.count = partial(
            Metric, sources=sources, unit="", better="lower", kind="int", count=True, digits=2
        )
        self.float = partial(Metric, sources=sources, unit="", kind="float", digits=digits)


_as = _Entries("action_selection")
_cn = _Entries("crowdnav")
_both = _Entries("action_selection", "crowdnav")
_people = _Entries("people")
_rec = _Entries("recorded")
_humans = _Entries("humans", digits=3)
_gl = _Entries("guidelines", digits=3)

_ENTRIES: tuple[Metric, ...] = (
    # ---------------------------------------------------------------- the robot's episode
    _both.flag(
        name="success",
        better="higher",
        description="The episode reached its goal without a collision. Action selection: the goal "
        "was reached (within EnvConfig.goal_radius, 0.5 m) with no human collision step and no wall "
        "collision; CrowdNav: the robot reached its goal before a collision or the time limit.",
    ),
    _as.flag(
        name="reached",
        label="goal reached",
        better="higher",
        description="The robot centre came within the goal radius of its goal (0.5 m), collisions or not.",
    ),
    _as.float(
        name="time_to_goal",
        unit="s",
        better="lower",
        success_only=True,
        digits=2,
        description="Episode time when the goal was reached, NaN when it was not; means are over "
        "the successful episodes (the paper's figure).",
    ),
    _as.float(
        name="distance_from_goal",
        unit="m",
        better="lower",
        digits=2,
        description="Distance between the robot centre and the goal at the end of the episode.",
    ),
    _as.float(
        name="distance_travelled",
        unit="m",
        better="neither",
        digits=2,
        description="Sum of the robot's step displacements (short where it stopped early, so no "
        "direction on its own).",
    ),
    _cn.flag(
        name="collision",
        better="lower",
        description="The episode ended in a collision: the robot's and a person's boundaries "
        "overlapped during a step (their closest approach along the step below 0).",
    ),
    _cn.flag(
        name="timeout",
        better="lower",
        description="The time limit ended the episode (a step starting 1 s or less before it).",
    ),
    _cn.float(
        name="navigation_time",
        unit="s",
        better="lower",
        success_only=True,
        digits=2,
        description="Episode time at the end of a successful episode (CrowdNav's success_times), "
        "NaN otherwise.",
    ),
    _cn.float(
        name="path_length",
        unit="m",
        better="neither",
        digits=2,
        description="Distance the robot moved during the episode.",
    ),
    _cn.count(
        name="discomfort_steps",
        description="Steps in discomfort: a person's boundary within discomfort_dist (0.2 m) of "
        "the robot's during the step, without a collision or the episode's end.",
    ),
    Metric(
        name="steps",
        unit="",
        better="neither",
        kind="int",
        digits=1,
        sources=("action_selection", "crowdnav"),
        description="Steps of the episode.",
    ),
    _as.float(
        name="duration",
        unit="s",
        better="neither",
        digits=2,
        description="Episode time: steps x the step duration.",
    ),
    _cn.float(
        name="discomfort_frequency",
        better="lower",
        description="Share of the episode's steps in discomfort (CrowdNav's frequency of being in danger).",
    ),
    _cn.float(
        name="min_separation",
        label="minimum separation",
        unit="m",
        better="higher",
        description="Smallest boundary distance between the robot and a person during the episode "
        "(negative: they overlapped); NaN with nobody.",
    ),
    _cn.float(
        name="intrusion_ratio",
        better="lower",
        description="Share of the episode's steps with a person's boundary within discomfort_dist "
        "(0.2 m) of the robot's during the step, a collision step included: CrowdNav's danger zone on the "
        "people's present positions. CrowdNav++'s intrusion ratio differs: there a step intrudes when the "
        "robot's centre is within the radii's sum of a person's true positions over the next 5 steps, "
        "and the episode's last step never counts.",
    ),
    _cn.float(
        name="return",
        better="higher",
        description="Sum of the episode's CrowdNav rewards.",
    ),
    _cn.float(
        name="discounted_return",
        better="higher",
        description="Sum over steps t of gamma ** (t dt v_pref) r_t, CrowdNav's total reward "
        "(gamma 0.9 per second at the preferred speed).",
    ),
    _both.float(
        name="mean_force",
        label="force (mean per step)",
        better="lower",
        description="Mean over the episode's steps of the social force term f = exp(-d^4), d the "
        "distance to the nearest visible human (SPEC section 9, socialzoo.env.reward).",
    ),
    _as.float(
        name="max_force",
        label="force (max per episode)",
        better="lower",
        description="Largest social force term f = exp(-d^4) of the episode's steps.",
    ),
    _both.float(
        name="mean_blame",
        label="blame (mean per step)",
        better="lower",
        description="Mean over the episode's steps of the blame b = 1 - erf(dist(h, S)), S the "
        "robot's next 0.5 s of motion and h the nearest visible human (SPEC section 9).",
    ),
    _as.float(
        name="max_blame",
        label="blame (max per episode)",
        better="lower",
        description="Largest blame b = 1 - erf(dist(h, S)) of the episode's steps.",
    ),
    _as.count(
        name="human_collisions",
        label="human collision steps",
        description="Steps with at least one human centre closer than the collision distance "
        "(0.4 m) to the robot's (SPEC: counted each step); the episode goes on.",
    ),
    _as.count(
        name="human_contacts",
        description="Sum over the episode's steps of the humans in collision with the robot.",
    ),
    _as.count(
        name="wall_collisions",
        label="wall collision steps",
        description="Steps with the robot's footprint touching a wall (the first ends the episode).",
    ),
    _as.float(
        name="average_step_reward",
        better="higher",
        description="The episode's total reward divided by its steps.",
    ),
    _as.float(
        name="total_reward",
        better="higher",
        digits=2,
        description="Sum of the episode's rewards (socialzoo.env.reward).",
    ),
    _as.float(
        name="min_human_distance",
        label="minimum distance to a human",
        unit="m",
        better="higher",
        description="Smallest centre distance between the robot and any present human (visible or "
        "not) over the episode; NaN with nobody.",
    ),
    _as.float(
        name="personal_space_intrusion_time",
        label="personal-space intrusion time",
        unit="s",
        better="lower",
        description="Time with the robot centre inside a human's intimate zone: a centre distance "
        "below personal_space + human_radius (0.45 + 0.2 m, MetricsConfig).",
    ),
    _as.float(
        name="path_irregularity",
        unit="rad",
        better="lower",
        description="Total rotation of the robot minus the rotation needed to face the goal from "
        "the start, floored at 0: Guzzi et al. 2013's unnecessary turning, not divided by the path length "
        "as their path irregularity (rad/m) is; divide by distance_travelled for theirs.",
    ),
    _as.float(
        name="path_length_ratio",
        better="higher",
        description="Straight start-goal distance over the distance travelled: 1 for a straight "
        "drive (a little above 1 at most, the goal counting as reached 0.5 m short); NaN when the "
        "robot did not move.",
    ),
    _as.float(
        name="jerk",
        unit="m/s^3",
        better="lower",
        description="Mean over the episode's steps of |a_t - a_(t-1)| / dt, a the linear "
        "acceleration from the speed, the robot at rest before the first step.",
    ),
    _as.flag(
        name="stuck",
        label="episodes stuck (share; no progress for 10 s while not halting)",
        better="lower",
        digits=4,
        description="The robot went MetricsConfig.stuck_time (10 s) of steps without its route "
        "left falling by stuck_progress (0.25 m) below its least value while it was not halting.",
    ),
    _as.float(
        name="max_time_without_progress",
        label="longest time without progress",
        unit="s",
        better="lower",
        digits=2,
        description="The longest stretch without progress towards the goal while not halting (see stuck).",
    ),
    # ---------------------------------------------------------------- the people (socialzoo.env.people)
    _people.count(
        name="group_intrusions",
        description="Times the robot's centre crossed the line between two members of a walking "
        "group (within 3 m of each other) between their positions.",
    ),
    _people.float(
        name="people_time_lost",
        label="people's time lost (mean per person)",
        unit="s",
        better="lower",
        digits=2,
        description="Mean over the people of the time they reach their route's goal end with the "
        "robot minus without it (the counterfactual rows; by the robot's episode end plus the "
        "route left at the preferred speed); NaN with nobody.",
    ),
    _people.float(
        name="people_time_lost_max",
        label="people's time lost (max per person)",
        unit="s",
        better="lower",
        digits=2,
        description="The largest time lost by a person of the episode (see people_time_lost).",
    ),
    _people.float(
        name="people_extra_distance",
        label="people's extra distance (mean per person)",
        unit="m",
        better="lower",
        digits=3,
        description="Mean over the people of the distance walked with the robot minus without it, "
        "each plus its route left (the counterfactual rows); NaN with nobody.",
    ),
    # ---------------------------------------------------------------- recorded scenes (socialzoo.env.replay)
    _rec.float(
        name="person_time",
        label="replaced person's time",
        unit="s",
        better="neither",
        digits=2,
        description="The recorded time of the person the robot took the place of, from its entry to its exit.",
    ),
    _rec.float(
        name="person_time_ratio",
        label="time against the replaced person",
        better="lower",
        digits=3,
        success_only=True,
        description="The robot's time to its goal over the replaced person's recorded time (success only).",
    ),
    _rec.float(
        name="person_path_deviation",
        label="deviation from the replaced person's path",
        unit="m",
        better="lower",
        digits=3,
        description="Mean over the robot's steps of its distance to the replaced person's recorded path (a "
        "polyline through its positions).",
    ),
    _rec.count(
        name="people_reacting",
        label="people who left their tracks",
        digits=4,
        description="Recorded people of a hybrid crowd who left their tracks because the robot came near.",
    ),
    _rec.float(
        name="reacting_time_lost",
        label="reacting people's time lost (mean)",
        unit="s",
        better="lower",
        digits=2,
        description="Mean over the people who left their tracks of the time they reached their route's end "
        "minus their recorded exit: the time they left the scene (or the robot's episode end) plus the "
        "straight distance left from there at their speed (they leave within the waypoint radius of it); "
        "NaN with nobody.",
    ),
    _rec.float(
        name="reacting_extra_distance",
        label="reacting people's extra distance (mean)",
        unit="m",
        better="lower",
        digits=3,
        description="Mean over the people who left their tracks of the distance they walked from there, plus "
        "the straight distance left to their route's end from where they left (or were at the robot's "
        "episode end), minus their recorded path from there; NaN with nobody.",
    ),
    _rec.count(
        name="people_walked_into_robot",
        label="collisions people walked into",
        digits=4,
        description="Contacts with a person that began with the person closing in on the robot faster than "
        "the robot on the person (their velocities along the line between them); in the CrowdNav task the "
        "contacts its collision judges during a step.",
    ),
    # ---------------------------------------------------------------- the humans (socialzoo.bench.human_metrics)
    _humans.float(
        name="humans_goal_rate",
        label="route goal reach rate",
        better="higher",
        description="Share of the humans with a route of two or more waypoints that reached its "
        "goal end (turned back there) during the episode.",
    ),
    _humans.float(
        name="humans_waypoints_per_min",
        label="waypoints reached per human",
        unit="1/min",
        better="higher",
        digits=2,
        description="Route waypoints reached per human and minute.",
    ),
    _humans.count(
        name="humans_hh_collisions",
        label="human-human collisions per episode",
        description="Times two humans came within 0.4 m of each other (each pair once per contact, at its start).",
    ),
    _humans.count(
        name="humans_hw_collisions",
        label="human-wall collisions per episode",
        description="Times a human's centre came within its radius (0.2 m) of a wall, or a wall stopped its move.",
    ),
    _humans.count(
        name="humans_hr_collisions",
        label="human-robot collisions per episode",
        digits=3,
        description="Times a human came within the robot collision distance (0.4 m) of a robot.",
    ),
    _humans.float(
        name="humans_min_human_distance",
        label="min human-human distance",
        unit="m",
        better="higher",
        description="Smallest centre distance between two humans over the episode; NaN with a single human.",
    ),
    _humans.float(
        name="humans_min_wall_distance",
        label="min human-wall distance",
        unit="m",
        better="higher",
        description="Smallest distance between a human centre and a wall over the episode; NaN when "
        "it never fell within the wall index's reach (1 m).",
    ),
    _humans.float(
        name="humans_min_robot_distance",
        label="min human-robot distance",
        unit="m",
        better="higher",
        description="Smallest centre distance between a human and a robot over the episode.",
    ),
    _humans.float(
        name="humans_mean_speed",
        label="mean speed",
        unit="m/s",
        better="neither",
        description="Mean speed over the humans and steps.",
    ),
    _humans.float(
        name="humans_path_ratio",
        label="path length / route length",
        better="lower",
        description="Distance walked until the route's goal end was first reached over the route's "
        "length from the spawn (to the waypoint radius), mean over the humans that reached it: 1 "
        "walks the route, more is a detour; NaN for none.",
    ),
    # ---------------------------------------------------------------- Table I of the evaluation guidelines
    # (Francis et al., ACM THRI 2025; socialzoo.bench.guideline_metrics, from any trajectory)
    _gl.flag(
        name="gl_success",
        label="success (guidelines)",
        better="higher",
        description="Table I's S: the robot centre came within the goal radius of its goal with no contact "
        "(wall, person or other robot) up to that sample.",
    ),
    _gl.count(
        name="gl_collisions",
        label="collisions (guidelines)",
        description="Table I's C: the episode's collisions of every kind, wall, human and other robot "
        "(gl_wall_collisions + gl_human_collisions + gl_robot_collisions).",
    ),
    _gl.count(
        name="gl_wall_collisions",
        label="wall collisions (guidelines)",
        description="Table I's WC: starts of a wall contact (the robot's disc overlapping a wall, or the "
        "simulator's wall flag), a contact lasting several steps counted once.",
    ),
    _gl.count(
        name="gl_human_collisions",
        label="human collisions (guidelines)",
        description="Table I's HC: starts of a contact with a person (discs overlapping, or the simulator's "
        "flag), per person, a contact lasting several steps counted once.",
    ),
    _gl.count(
        name="gl_robot_collisions",
        label="robot collisions (guidelines)",
        description="Table I's AC: starts of a contact with another robot (discs overlapping, or the "
        "simulator's flag), per robot.",
    ),
    _gl.flag(
        name="gl_timeout",
        label="timeout (guidelines)",
        better="lower",
        description="Table I's TO: the episode reached its time limit with neither the goal nor a collision "
        "(without a time limit: it ended with neither).",
    ),
    _gl.count(
        name="gl_failure_to_progress",
        label="failures to progress (guidelines)",
        description="Table I's FP: stretches in which some window of 10 s (GuidelineParams.progress_time) "
        "never brought the robot 0.25 m (progress_distance) closer to its goal than at the "
        "window's start.",
    ),
    _gl.float(
        name="gl_stalled_time",
        label="stalled time (guidelines)",
        unit="s",
        better="lower",
        digits=2,
        description="Table I's ST: time of the steps whose robot speed was below 0.05 m/s "
        "(GuidelineParams.stall_speed).",
    ),
    _gl.float(
        name="gl_time_to_goal",
        label="time to goal (guidelines)",
        unit="s",
        better="lower",
        success_only=True,
        digits=2,
        description="Table I's T: time of the first sample within the goal radius, NaN unless the episode "
        "succeeded.",
    ),
    _gl.float(
        name="gl_path_length",
        label="path length (guidelines)",
        unit="m",
        better="neither",
        digits=2,
        description="Table I's PL: sum of the robot's displacements between samples, up to the goal.",
    ),
    _gl.float(
        name="gl_spl",
        label="success weighted by path length",
        better="higher",
        description="Table I's SPL (Anderson et al. 2018): S l / max(p, l), p the path length and l the shortest "
        "path's length: an episode log's shortest_path_length, on socialzoo's own episodes the navigator's route "
        "length at the start (at least the straight line), else the straight line.",
    ),
    # gl_velocity_min/avg/max, gl_acceleration_min/avg/max, gl_jerk_min/avg/max: Table I's V, A and J
    *(
        _gl.float(
            name=f"gl_{quantity}_{stat}",
            label=f"{quantity} ({stat}, guidelines)",
            unit=unit,
            better="neither",
            description=f"Table I's {symbol}_{stat}: the {word} {what}.",
        )
        for quantity, symbol, unit, what in (
            ("velocity", "V", "m/s", "robot speed over the episode's steps"),
            (
                "acceleration",
                "A",
                "m/s^2",
                "linear acceleration, the change of speed per step over dt (negative: braking)",
            ),
            ("jerk", "J", "m/s^3", "linear jerk, the change of linear acceleration per step over dt"),
        )
        for stat, word in (("min", "smallest"), ("avg", "mean"), ("max", "largest"))
    ),
    _gl.float(
        name="gl_clearing_distance_min",
        label="clearing distance (min, guidelines)",
        unit="m",
        better="higher",
        description="Table I's CD_min: the smallest gap between the robot's disc and a wall over the episode "
        "(negative: overlap); NaN without walls.",
    ),
    _gl.float(
        name="gl_clearing_distance_avg",
        label="clearing distance (mean, guidelines)",
        unit="m",
        better="higher",
        description="Table I's CD_avg: the mean over the episode's samples of the gap between the robot's "
        "disc and the nearest wall; NaN without walls.",
    ),
    _gl.float(
        name="gl_personal_space_compliance",
        label="personal space compliance (guidelines)",
        better="higher",
        description="Table I's SC (PSC, Pérez-D'Arpino et al. 2021): share of the episode's samples with "
        "every person's disc at least 0.5 m (GuidelineParams.personal_space) from the robot's.",
    ),
    _gl.float(
        name="gl_min_distance_to_human",
        label="minimum distance to a human (guidelines)",
        unit="m",
        better="higher",
        description="Table I's DH_min: the smallest gap between the robot's disc and a person's over the "
        "episode (negative: overlap); NaN with nobody.",
    ),
    _gl.float(
        name="gl_min_time_to_collision",
        label="minimum time to collision (guidelines)",
        unit="s",
        better="higher",
        digits=2,
        description="Table I's TTC: the least time, over samples and people, until the robot's and a person's "
        "discs would touch if both kept their velocities; inf when never on a collision course, "
        "NaN with nobody.",
    ),
    _gl.float(
        name="gl_aggregated_time",
        label="aggregated time (guidelines)",
        unit="s",
        better="lower",
        digits=2,
        description="Table I's AT: time when the last of the cooperative set (the robot and the other robots "
        "with goals) first reached its goal; NaN when one never did.",
    ),
)

METRICS: dict[str, Metric] = {m.name: m for m in _ENTRIES}
if len(METRICS) != len(_ENTRIES):
    raise ValueError("socialzoo.core.metrics: two registry entries share a name")

_PACKAGE_NAMES = frozenset(METRICS)


def added_names() -> tuple[str, ...]:
    """The names register_metric added (tasks written outside the package), in the order added."""
    return tuple(name for name in METRICS if name not in _PACKAGE_NAMES)


def register_metric(**fields: Any) -> Metric:
    """Add a metric of a task written outside the package (Metric's fields; its `sources` may name
    that task) to the registry, where the results store, the benchmark's summaries and tables and the
    viewer's metric table (`added_names`) read it, as they read the package's entries; a figure draws
    it where its selection names it. Call it where the task is registered, once.

    Raises:
        ValueError: a malformed entry (Metric's checks), a source that is not an identifier, or a
            name that is registered already.
    """
    sources = fields.get("sources", ())
    new = {s for s in sources if s not in SOURCES and s not in _TASK_SOURCES}
    if any(not (isinstance(s, str) and s.isidentifier()) for s in new):
        raise ValueError(f"register_metric: sources must be task names (identifiers), got {sources!r}")
    if fields.get("name") in METRICS:
        raise ValueError(f"register_metric: a metric {fields['name']!r} is registered already")
    _TASK_SOURCES.update(new)
    try:
        entry = Metric(**fields)
    except (TypeError, ValueError):
        _TASK_SOURCES.difference_update(new)
        raise
    METRICS[entry.name] = entry
    return entry


def metric(name: str) -> Metric:
    """The registered metric `name`.

    Raises:
        UnknownMetricError: `name` is not registered (the message lists the registered names).
    """
    try:
        return METRICS[name]
    except (KeyError, TypeError):
        raise UnknownMetricError(
            f"unknown metric {name!r}: add it to socialzoo.core.metrics.METRICS (registered: {', '.join(METRICS)})"
        ) from None


def registered(*names: str) -> tuple[str, ...]:
    """`names` as a tuple, each checked to be registered: a selection of metrics (a table's
    columns, a figure's panels) that fails at import when a name is misspelt.

    Raises:
        UnknownMetricError: a name is not registered.
    """
    for name in names:
        metric(name)
    return names


def names(source: str | None = None, *, kind: str | None = None) -> tuple[str, ...]:
    """The registered names in registry order: those computed by `source` (SOURCES) and of
    `kind`, where given. `names("action_selection")` is that task's summary keys, in order.

    The entries are in the order the tasks report them, so the CrowdNav task's own metrics sit
    between the ones it shares with the action-selection task (success, steps, mean_force,
    mean_blame).

    Raises:
        ValueError: an unknown source or kind.
    """
    if source is not None and source not in SOURCES and source not in _TASK_SOURCES:
        raise ValueError(f"source must be one of {SOURCES + tuple(sorted(_TASK_SOURCES))}, got {source!r}")
    if kind is not None and kind not in get_args(Kind):
        raise ValueError(f"kind must be one of {get_args(Kind)}, got {kind!r}")
    return tuple(
        m.name
        for m in METRICS.values()
        if (source is None or source in m.sources) and (kind is None or m.kind == kind)
    )


def table_heading(name: str) -> str:
    """A table's heading of a metric's means: "time to goal, s (successful episodes only)"."""
    m = metric(name)
    return m.heading + (" (successful episodes only)" if m.success_only else "")


def axis_label(name: str) -> str:
    """A figure axis's label of a metric's means: flags as percentages ("success, %"), and
    "(successes)" after a success-only metric ("time to goal, s (successes)")."""
    m = metric(name)
    if m.kind == "bool":
        return f"{m.label}, %"
    return m.heading + (" (successes)" if m.success_only else "")


def describe(metric_names: Iterable[str] | None = None) -> str:
    """A Markdown table of the metrics (default every registered one): name, unit, better, kind,
    flags (successful episodes only, a count) and description.

    Raises:
        UnknownMetricError: a name is not registered.
    """
    chosen = [metric(n) for n in (METRICS if metric_names is None else metric_names)]
    lines = ["| metric | unit | better | kind | flags | description |", "|---|---|---|---|---|---|"]
    for m in chosen:
        flags = [f for f, on in (("successful episodes only", m.success_only), ("a count", m.count)) if on]
        lines.append(
            f"| `{m.name}` | {m.unit or '-'} | {m.better} | {m.kind} | {', '.join(flags) or '-'} | {m.description} |"
        )
    return "\n".join(lines) + "\n"
