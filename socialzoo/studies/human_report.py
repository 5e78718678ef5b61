"""How each crowd model walks: the people of a model on a map's validation scenarios, without a
robot, measured as pedestrian studies measure crowds."""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.bench.human_metrics import HumanEpisodeMetrics
from socialzoo.bench.tables import write_csv
from socialzoo.core.files import json_text, write_text_atomic
from socialzoo.core.validation import check_int, check_number
from socialzoo.env.config import EnvConfig
from socialzoo.env.people import People, without_robots
from socialzoo.env.world import step_world
from socialzoo.humans.models import PeopleConfig
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.generator import ScenarioConfig
from socialzoo.scenarios.scenario_sets import validation_set
from socialzoo.scenarios.start_state import scenarios_to_state
from socialzoo.studies.human_compare import REACH_TOLERANCE

# Weidmann (1993): free speed, the fit's gamma and the jam density.
WEIDMANN_V0, WEIDMANN_GAMMA, WEIDMANN_RHO_MAX = 1.34, 1.913, 5.4
# Speed samples are taken every this many steps (0.25 s at dt = 0.025 s).
SAMPLE_EVERY = 10
COLUMNS = (
    "model",
    "people",
    "mean_speed",
    "speed_p10",
    "speed_p90",
    "mean_density",
    "reach_rate",
    "time_to_goal_median",
    "path_length_ratio",
    "pp_contacts_per_min",
    "pw_contacts_per_min",
)


@dataclass(frozen=True, kw_only=True)
class HumanReportConfig:
    """What the report measures.

    Attributes:
        humans: people specs, one report row each ("learned:PATH" for a learned model).
        map: the map (its validation scenarios, never a test set, are walked).
        scenarios: scenarios per model.
        seconds: how long the people walk, s.
        scenario: the head counts and speeds of the scenarios.
        density_radius: radius of the local density's disc, m.
        env_overrides: EnvConfig fields for every model, e.g. {"world": {"orca": {...}}} (its
            "people" is the report's own).
    """

    humans: tuple[str, ...] = ("sf", "orca", "groups")
    map: str = "gdc1"
    scenarios: int = 16
    seconds: float = 60.0
    scenario: ScenarioConfig = field(default_factory=ScenarioConfig)
    density_radius: float = 1.5
    env_overrides: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "humans", tuple(self.humans))
        if not self.humans:
            raise ValueError("HumanReportConfig.humans is empty")
        for spec in self.humans:
            PeopleConfig(models=spec)  # a bad spec fails here, naming it
        if len(set(self.humans)) != len(self.humans):
            raise ValueError(f"HumanReportConfig.humans has duplicates: {list(self.humans)!r}")
        check_int("HumanReportConfig", "scenarios", self.scenarios, low=1)
        check_number("HumanReportConfig", "seconds", self.seconds, low=0, low_open=True)
        check_number("HumanReportConfig", "density_radius", self.density_radius, low=0, low_open=True)
        if "people" in self.env_overrides:
            raise ValueError("HumanReportConfig.env_overrides must not set people: the report sets them")
        EnvConfig().replace(**dict(self.env_overrides))  # a bad override fails here, naming it


@dataclass(frozen=True)
class WalkResult:
    """What one model's people did.

    Attributes:
        spec: the people spec.
        row: the report row (COLUMNS).
        speed: (S,) sampled speeds, m/s.
        density: (S,) the local density at each sample, 1/m^2.
        time_to_goal: (A,) first arrival times at the goal end, s.
        pref_speed: mean preferred speed of the people, m/s.
    """

    spec: str
    row: dict[str, Any]
    speed: np.ndarray
    density: np.ndarray
    time_to_goal: np.ndarray
    pref_speed: float


def weidmann_speed(density: np.ndarray, free_speed: float = WEIDMANN_V0) -> np.ndarray:
    """Weidmann's (1993) walking speed at a density (1/m^2), m/s; 0 at and beyond the jam density."""
    rho = np.asarray(density, dtype=np.float64)
    with np.errstate(divide="ignore"):
        v = free_speed * (1.0 - np.exp(-WEIDMANN_GAMMA * (1.0 / rho - 1.0 / WEIDMANN_RHO_MAX)))
    return np.where(rho < WEIDMANN_RHO_MAX, v, 0.0)


def spec_label(spec: str) -> str:
    """A people spec as the report shows it: the shipped learned humans' file (which `--humans learned`
    names by its absolute path, this machine's) as "learned" alone."""
    from socialzoo.agents import SHIPPED_DIR

    return spec.replace(f"learned:{SHIPPED_DIR / 'humans.safetensors'}", "learned")


def model_slug(spec: str) -> str:
    """A file-name part for a people spec ("learned:runs/h.safetensors" -> "learned")."""
    parts = [p.strip() for p in spec.split("+")]
    names = []
    for part in parts:
        name, _, share = part.partition("@")
        names.append(name.split(":")[0] + share)
    return re.sub(r"[^A-Za-z0-9.]+", "-", "-".join(names)).strip("-")


def walk(spec: str, cfg: HumanReportConfig) -> WalkResult:
    """Walk one model's people on the map's validation scenarios and measure them."""
    config = EnvConfig(map=cfg.map, scenario=cfg.scenario).replace(
        **dict(cfg.env_overrides), people={"models": spec}
    )
    m = load_map(cfg.map)
    walls = m.wall_index
    test_set = dataclasses.replace(validation_set(cfg.map), cfg=cfg.scenario)
    n = cfg.scenarios
    people = People(config.people, config.world, n, config.num_robots, config.max_humans, walls, m)
    scenarios, kinds = people.prepare(test_set.scenarios(range(n), m))
    state = without_robots(scenarios_to_state(scenarios, num_robots=1, max_humans=config.max_humans))
    state.human_model[:] = people.models_of(kinds)
    # With a preset's parameters and a learned policy file's dynamics, as in the env.
    world = people.world
    tracker = HumanEpisodeMetrics(
        n, config.max_humans, 0, walls, world.human_collision_distance, world.human.waypoint_radius
    )
    rows = np.arange(n)
    tracker.reset(rows, state)
    mask = state.human_mask
    arrived = np.full(mask.shape, np.nan)
    speeds, densities = [], []
    steps = round(cfg.seconds / world.dt)
    no_command, no_halt = np.zeros((n, 0, 2)), np.zeros((n, 0), dtype=bool)
    radius2 = cfg.density_radius**2
    area = math.pi * radius2
    for k in range(steps):
        desired, learned = people.drive(state, None, None)
        after, events = step_world(state, walls, world, no_command, no_halt, desired, learned)
        tracker.update(state, after, events.human_blocked, world.dt, np.zeros(n, dtype=bool))
        turned = np.isnan(arrived) & (state.human_direction > 0) & (after.human_direction < 0) & mask
        arrived[turned] = (k + 1) * world.dt
        state = after
        if (k + 1) % SAMPLE_EVERY == 0:
            pos = state.human_pos
            near = ((pos[:, :, None] - pos[:, None]) ** 2).sum(-1) < radius2
            count = (near & mask[:, None, :]).sum(-1)
            speeds.append(np.linalg.norm(state.human_vel, axis=-1)[mask])
            densities.append(count[mask] / area)
    summaries = tracker.summaries(rows)
    speed = np.concatenate(speeds) if speeds else np.zeros(0)
    density = np.concatenate(densities) if densities else np.zeros(0)
    routes = mask & (state.human_route_len > 1)
    person_minutes = float(mask.sum()) * cfg.seconds / 60.0
    ratios = [s["humans_path_ratio"] for s in summaries if np.isfinite(s["humans_path_ratio"])]
    reach = arrived[routes]
    row = {
        "model": spec_label(spec),
        "people": int(mask.sum()),
        "mean_speed": float(speed.mean()) if len(speed) else math.nan,
        "speed_p10": float(np.percentile(speed, 10)) if len(speed) else math.nan,
        "speed_p90": float(np.percentile(speed, 90)) if len(speed) else math.nan,
        "mean_density": float(density.mean()) if len(density) else math.nan,
        "reach_rate": float(np.mean(~np.isnan(reach))) if len(reach) else math.nan,
        "time_to_goal_median": float(np.nanmedian(reach)) if np.any(~np.isnan(reach)) else math.nan,
        "path_length_ratio": float(np.mean(ratios)) if ratios else math.nan,
        "pp_contacts_per_min": sum(s["humans_hh_collisions"] for s in summaries) / person_minutes,
        "pw_contacts_per_min": sum(s["humans_hw_collisions"] for s in summaries) / person_minutes,
    }
    return WalkResult(
        spec,
        row,
        speed,
        density,
        reach[~np.isnan(reach)],
        float(state.human_pref_speed[mask].mean()),
    )


def targets(rows: list[dict[str, Any]]) -> dict[str, dict[str, bool]]:
    """For each learned model (a spec with "learned"), whether it meets the learned humans'
    targets against the social force ("sf" or "social_force" among the rows): reach rate at least
    0.9 times the social force's, and no more person-wall contacts per person-minute."""
    reference = next((r for r in rows if r["model"] in ("sf", "social_force")), None)
    if reference is None:
        return {}
    out = {}
    for r in rows:
        if "learned" in r["model"]:
            out[r["model"]] = {
                "reach": r["reach_rate"] >= (1.0 - REACH_TOLERANCE) * reference["reach_rate"],
                "wall_contacts": r["pw_contacts_per_min"] <= reference["pw_contacts_per_min"],
            }
    return out


def write_report(results: list[WalkResult], cfg: HumanReportConfig, out_dir: Path) -> list[Path]:
    """report.csv and report.md in out_dir."""
    rows = [r.row for r in results]
    files = [write_csv(rows, out_dir / "report.csv", COLUMNS, blank_nan=False, lineterminator="\n")]
    lines = [
        f"# How each crowd model walks ({cfg.map}, {cfg.scenarios} validation scenarios, {cfg.seconds:g} s, no robot)",
        "",
        "| model | people | speed (m/s) [p10, p90] | density (1/m²) | reach rate | time to goal (s, median) "
        "| path ratio | person-person contacts / min | person-wall contacts / min |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['people']} | {r['mean_speed']:.2f} [{r['speed_p10']:.2f}, {r['speed_p90']:.2f}] "
            f"| {r['mean_density']:.3f} | {r['reach_rate']:.3f} | {r['time_to_goal_median']:.1f} "
            f"| {r['path_length_ratio']:.3f} | {r['pp_contacts_per_min']:.3f} | {r['pw_contacts_per_min']:.3f} |"
        )
    checks = targets(rows)
    if checks:
        lines += [
            "",
            f"Learned humans against the social force (reach rate within {REACH_TOLERANCE:.0%}, "
            "no more wall contacts):",
            "",
        ]
        for model, ok in checks.items():
            lines.append(
                f"- {model}: reach {'met' if ok['reach'] else 'NOT met'}, "
                f"wall contacts {'met' if ok['wall_contacts'] else 'NOT met'}"
            )
    lines.append("")
    files.append(write_text_atomic(out_dir / "report.md", "\n".join(lines)))
    return files


def plot_walk(result: WalkResult, out_dir: Path) -> Path:
    """walk_<model>.png: speed histogram, speed against local density with Weidmann's curve, time
    to goal."""
    from socialzoo.bench.figures import pyplot, save_figure

    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    ax = axes[0]
    ax.hist(result.speed, bins=np.linspace(0.0, 1.6, 33), color="tab:blue")
    ax.set_xlabel("speed (m/s)")
    ax.set_ylabel("samples")
    ax.set_title("speed")
    ax = axes[1]
    rho = np.linspace(0.05, 5.4, 200)
    ax.plot(rho, weidmann_speed(rho), "k-", label="Weidmann 1993")
    ax.plot(
        rho, weidmann_speed(rho, result.pref_speed), "k--", label=f"scaled to v0 = {result.pref_speed:.2f}"
    )
    # Local densities are counts over one disc's area: one point per count seen often enough.
    values, counts = np.unique(np.round(result.density, 9), return_counts=True)
    for value in values[counts >= 20]:
        chosen = np.abs(result.density - value) < 1e-6
        ax.errorbar(
            value, result.speed[chosen].mean(), yerr=result.speed[chosen].std(), fmt="o", color="tab:red"
        )
    ax.set_xlabel("local density (1/m²)")
    ax.set_ylabel("speed (m/s)")
    ax.set_xlim(0, max(1.0, float(np.percentile(result.density, 99)) * 1.2 if len(result.density) else 1.0))
    ax.set_ylim(0, 1.6)
    ax.legend(fontsize=8)
    ax.set_title("fundamental diagram")
    ax = axes[2]
    ax.hist(result.time_to_goal, bins=20, color="tab:green")
    ax.set_xlabel("time to goal (s)")
    ax.set_title(f"reach rate {result.row['reach_rate']:.2f}")
    fig.suptitle(f"people: {spec_label(result.spec)}")
    fig.tight_layout()
    return save_figure(fig, out_dir, f"walk_{model_slug(result.spec)}", ("png",), dpi=110)[0]


def human_report(
    cfg: HumanReportConfig, out_dir: str | Path, *, figures: bool = True
) -> tuple[list[WalkResult], list[Path]]:
    """Walk every model of `cfg` and write the report into out_dir (created).

    For each people spec (socialzoo.humans.models: "sf", "orca", "groups", "learned:PATH", mixes) the
    scenarios' people walk their routes for a while (the world step, no robot), and the report gives, per
    model:

    - speed: mean and the 10-90% range over people and time (sampled every 0.25 s);
    - speed against local density, the fundamental diagram, beside Weidmann's (1993) curve
      v(rho) = 1.34 (1 - exp(-1.913 (1 / rho - 1 / 5.4))) m/s, and the same curve scaled to the
      people's mean preferred speed; local density = people within density_radius (the person
      included) / the disc's area;
    - contacts: person-person (centres closer than 0.4 m) and person-wall (closer than 0.2 m, or a
      wall stopped the move) contact onsets per person-minute (socialzoo.bench.human_metrics);
    - path length ratio (walked / route length, for those who reached their route's goal end) and
      time to goal (first arrival at the goal end; the share of people arriving is the reach rate).

    It writes report.md and report.csv (one row per model; learned models are checked against the targets of
    the learned humans: reach rate within 10% of the social force's, no more wall contacts per person-minute),
    walk_<model>.png (speed histogram, fundamental diagram, time to goal) and config.json.

    Returns:
        (results, files written).
    """
    results = [walk(spec, cfg) for spec in cfg.humans]
    # Made once the walks are done: an unknown map leaves no empty folder behind.
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = write_report(results, cfg, out)
    record = {
        **asdict(cfg),
        "humans": [spec_label(spec) for spec in cfg.humans],
        "env_overrides": dict(cfg.env_overrides),
    }
    files.append(write_text_atomic(out / "config.json", json_text(record, indent=2, default=str) + "\n"))
    if figures:
        files += [plot_walk(r, out) for r in results]
    return results, files
