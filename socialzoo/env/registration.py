"""Gymnasium ids of socialzoo's tasks, and the one Version History of every env (the only copy: the adapters'
docstrings point here).

Version History (action-selection ids, their ParallelEnv and TorchRL envs):
    socialzoo/Recorded-v4 and socialzoo/CrowdNavRecorded-v3 (the recorded ids, each two versions ahead
        of its task's other ids; no other id changes), on 2026-11-29: an episode lasts its whole time
        budget (twice the replaced person's time, docs/recorded.md), however long. Each row's budget
        was cut at its task's default limit (the smaller of the two), 80 s in Recorded-v3 (max_steps
        3200) and 200 s in CrowdNavRecorded-v2, which the longest budgets pass (up to 466 s; 13 of univ's
        and 5 of zara2's 100 and 78 test cases in Recorded-v3). The ids' limits are now a day
        (RECORDED_TIME_CEILING); a limit given in their config still cuts a longer budget. Only the
        episodes with longer budgets change, past the old limits. In Recorded-v4 the people of the
        "groups" model walk with their recorded companions (entering together), each along its own
        route (socialzoo.scenarios.recorded_people.RecordedPeople.companion_groups); they were grouped
        in slot order, strangers, and given their group's first route. In both, a person a model walks
        whose entry frame has no next frame recorded when the world reaches it (one seen on one frame)
        enters where it was last recorded, not at NaN (the five scenes have none: unchanged there).
    socialzoo/Suite-v3 and socialzoo/CrowdNavSuite-v2 (the suite ids, each one version ahead of its
        task's other ids; no other id changes), on 2026-11-29: an escort (families following_person,
        leading_person, accompanying_peer) holds all the way, not only at the goal. The escorted
        person must stay in its place (within the band, and ahead of the robot that follows it,
        behind the robot that leads it, beside the robot that accompanies it), never out of it for
        more than 2 s at a stretch nor for more than a fifth of the time; else the robot cannot
        count its goal (socialzoo.scenarios.script.Script). The band was checked at the goal only,
        where the person stops, so GoAlone and a robot that halted 20 s first succeeded in every
        case. The followed and accompanied persons walk at 0.6-0.9 m/s, a pace the CrowdNav robot
        (1 m/s) can keep (they walked at the default 0.5-1.3 m/s). Other families' rollouts under
        these ids are unchanged.
    Within socialzoo/Recorded-v3 and socialzoo/CrowdNavRecorded-v2, rollouts unchanged (observations,
        rewards, end flags): only the episode metrics reacting_time_lost and reacting_extra_distance of
        hybrid people change, on 2026-11-29: every reacting person is counted to its route's end, as one
        still walking at the episode's end was (the straight way left, and that way at its speed). One
        who left, within the waypoint radius of that end, was counted to where it left (both read about
        that way low), and one whose slot's next person entered before it left lacked it in its time.
    Within socialzoo/CrowdNavRecorded-v2, rollouts unchanged (observations, rewards, end flags): only
        the episode metric people_walked_into_robot changes, on 2026-11-29: it counts the contacts the
        CrowdNav task judges during a step (the closest approach, blamed where it first came within
        touching), not the world's at the steps' ends, which missed collisions judged mid-step.
    Within socialzoo/Recorded-v3 and socialzoo/CrowdNavRecorded-v2, rollouts unchanged (observations,
        rewards, end flags): only the episode metric reacting_extra_distance of hybrid people changes,
        on 2026-11-29: a reacting person's distance walked counts from the step after its reaction to
        the step in which it left (it counted the reaction's step, walked on its track, and not the
        leaving one).
    Within v2 (and CrowdNav's v1), default rollouts unchanged: the presets sf-eth-ucy and
        orca-eth-ucy were fitted again on 2026-11-29 (the realism cases' exit fix: a modelled person
        leaves at its exit), so people specs that name them walk otherwise.
    socialzoo/Recorded-v3 and socialzoo/CrowdNavRecorded-v2 (the recorded ids, each one version
        ahead of its task's other ids; no other id changes): a recorded row plays the same whatever
        else its batch holds. Past the last frame of its own recording everyone on a track leaves
        (the row whose recording was the batch's longest kept them standing on its last frame, and
        a single env is such a row), and a reacting person's recorded distance left starts where
        the person is, partway along its segment, and adds the row's own frames in order (the
        metric reacting_extra_distance read up to one segment low, and its last bits depended on
        the batch).
    Within v2 (and CrowdNav's v1), default rollouts unchanged: the presets sf-eth-ucy and
        orca-eth-ucy were fitted again (the realism cases' protocol fix), so people specs that name
        them walk otherwise; hybrid people react only to a robot they can see (robot_visible).
    Within CrowdNav's v1, default rollouts unchanged: a robot radius or discomfort distance given
        to the task (robot=, reward=) also spaces its drawn cases, as CrowdNav's generator does
        (the cases were drawn for a 0.3 m robot and 0.2 m, whatever the task's robot and reward).
    Within CrowdNav's v1, CrowdNavConfig.observed_people (the K nearest people in the observation)
        is new and opt-in (None, every slot in slot order, the default), so no id's rollouts change.
    Within v2, the ids socialzoo/ActionSelectionReference-v2 and
        socialzoo/ActionSelectionTransferReference-v2 (the reference code's quirks on, EnvConfig.quirks)
        are new; with the quirks off (the default) no other id's rollouts change.
    Within v2, the ids socialzoo/Recorded-v2 and socialzoo/CrowdNavRecorded-v1 (recorded scenes) are
        new, and no other id's rollouts change. Later within v2 (and CrowdNav's v1), only the
        episode metric reacting_extra_distance of hybrid people changes: a person who entered
        its slot and reacted in the same step was credited the jump from the slot's previous
        occupant's last position. The ids' default (people replaying) rollouts are unchanged,
        and so are hybrid rollouts' observations, rewards and end flags.
    Within v2, the ids socialzoo/Suite-v2 and socialzoo/CrowdNavSuite-v1 (CrowdNav's v1) are new;
        the observation's signal block is opt-in (signals=True), so no other id's rollouts change.
    socialzoo_parallel_v2, socialzoo_crowdnav_v2 (the ParallelEnvs' metadata names; every id
        keeps its version: the ids have one robot): robots after the first start at least 1 m
        from every person and every other robot (scenario_source.with_robots; they could start
        inside a person), and CrowdNav++'s random robots keep CrowdNav's spacing among
        themselves. Only multi-robot rollouts change (ParallelEnv, TorchRL multi-agent).
    v2: the robot recovers when it makes no progress (backs off, replans over another edge),
        its carrot is in sight only along a line keeping its full wall distance, its plans
        join the graph by lines it can drive; people in contact with the robot do not press
        into it; episode metrics gain `stuck` (and failure causes).
        Within v2, default rollouts unchanged: learned people that the env drives
        (people="learned:PATH") keep off a robot they touch as social-force people do (they
        pressed into it); the adapters became one per ecosystem over the task interface, and
        only infos changed (socialzoo.env.tasks; tests/env/test_golden_rollouts.py).
    v1: force and blame no longer skip the passed human (only the followed one, SPEC 9);
        the robot's carrot stays in sight of its wall distance and its plans keep clear
        of walls; scenarios draw only feasible start/goal pairs (unchanged on GDC1/GHC3).
    v0: initial release.
"""

from __future__ import annotations

import dataclasses

import gymnasium as gym

from socialzoo.core.config import WorldConfig
from socialzoo.env.crowd_variants import CROWD_ENV_VERSION, VARIANTS, crowd_env_id
from socialzoo.env.quirks import REFERENCE_QUIRKS
from socialzoo.scenarios.catalogue import get_family

# Every id is a task's Gymnasium env and VectorEnv (the kwargs name the task and its config).
ENTRY = "socialzoo.env.gym_env:TaskEnv"
VECTOR_ENTRY = "socialzoo.env.vector:TaskVectorEnv"
# The version of every id (see the module docstring's Version History).
ENV_VERSION = 2

# id -> kwargs for the single-agent benchmark envs.
BENCHMARK_IDS: dict[str, dict] = {
    f"socialzoo/ActionSelection-v{ENV_VERSION}": {"task": "action_selection", "map": "gdc1"},
    f"socialzoo/ActionSelectionTransfer-v{ENV_VERSION}": {"task": "action_selection", "map": "ghc3"},
}


# The benchmark ids with the reference code's quirks (SPEC section 11) on, one per map.
REFERENCE_IDS: dict[str, dict] = {
    f"socialzoo/ActionSelectionReference-v{ENV_VERSION}": {
        "task": "action_selection",
        "map": "gdc1",
        "quirks": dataclasses.asdict(REFERENCE_QUIRKS),
    },
    f"socialzoo/ActionSelectionTransferReference-v{ENV_VERSION}": {
        "task": "action_selection",
        "map": "ghc3",
        "quirks": dataclasses.asdict(REFERENCE_QUIRKS),
    },
}


def _family_id(name: str) -> str:
    return "socialzoo/" + "".join(part.capitalize() for part in name.split("_")) + f"-v{ENV_VERSION}"


# The scenario families with ids of their own (socialzoo.scenarios.catalogue), e.g.
# socialzoo/HallwayHeadOn-v2, each on the small map it is designed for; short episodes (60 s).
FAMILY_ID_NAMES = (
    "hallway_head_on",
    "overtaking",
    "crossing",
    "doorway",
    "circle_crossing",
    "parallel_traffic",
)
FAMILY_IDS: dict[str, dict] = {
    _family_id(name): {
        "task": "action_selection",
        "map": get_family(name).map_name,
        "family": name,
        "max_steps": 2400,
    }
    for name in FAMILY_ID_NAMES
}


# The CrowdNav task and its variants (socialzoo.env.crowd_variants), e.g. socialzoo/CrowdNav-v1; their
# version is the task's own (CROWD_ENV_VERSION), apart from the benchmark's.
CROWD_IDS: dict[str, dict] = {crowd_env_id(name): {"task": "crowdnav", "variant": name} for name in VARIANTS}


# The guidelines' scenario suite (socialzoo.scenarios.suite): any registered family by the `family`
# keyword (default its scenario a, frontal_approach) on that family's map (map=None), with the
# people's gestures and the nearest door in the observation. The action-selection task with the
# family ids' 60 s episodes; the CrowdNav task as its Walls variant runs among walls (social-force
# people of radius 0.2 m, a visible robot, 10 physics substeps, 16 wall rays), 60 s, 20 person slots.
SUITE_DEFAULT_FAMILY = "frontal_approach"
# The suite ids' own versions, one ahead of their task's other ids (the Version History's first line).
SUITE_VERSION = ENV_VERSION + 1
CROWD_SUITE_VERSION = CROWD_ENV_VERSION + 1
SUITE_ID = f"socialzoo/Suite-v{SUITE_VERSION}"
CROWD_SUITE_ID = f"socialzoo/CrowdNavSuite-v{CROWD_SUITE_VERSION}"
SUITE_IDS: dict[str, dict] = {
    SUITE_ID: {
        "task": "action_selection",
        "map": None,
        "family": SUITE_DEFAULT_FAMILY,
        "max_steps": 2400,
        "signals": True,
    },
    CROWD_SUITE_ID: {
        "task": "crowdnav",
        "variant": "Walls",
        "map": None,
        "family": SUITE_DEFAULT_FAMILY,
        "time_limit": 60.0,
        "max_humans": 20,
        "signals": True,
    },
}


# Recorded scenes (socialzoo.scenarios.recorded): the robot in a recorded person's place, by the
# `family` keyword (recorded_eth, recorded_hotel, recorded_univ, recorded_zara1, recorded_zara2;
# `socialzoo data fetch eth-ucy` first), the people replaying their tracks by default (people
# "hybrid:sf", "hybrid:orca" react). Each episode's time budget is its scene's (twice the replaced
# person's time): the task's own limit, which a budget never exceeds (min with it), is set to
# RECORDED_TIME_CEILING, and a config limit given below a budget cuts it. The CrowdNav task in the
# open with a visible robot and person slots for the scene's largest episode; the action-selection
# task on the scene's open area as a map.
RECORDED_DEFAULT_FAMILY = "recorded_eth"
# The recorded ids' own versions, two ahead of their task's other ids (the Version History's first line).
RECORDED_VERSION = ENV_VERSION + 2
CROWD_RECORDED_VERSION = CROWD_ENV_VERSION + 2
# The recorded ids' task limit, s: a day, above any recorded person's budget (the five scenes' reach 466 s).
RECORDED_TIME_CEILING = 86400.0
RECORDED_IDS: dict[str, dict] = {
    f"socialzoo/Recorded-v{RECORDED_VERSION}": {
        "task": "action_selection",
        "map": None,
        "family": RECORDED_DEFAULT_FAMILY,
        "people": {"models": "replay"},
        "max_steps": round(RECORDED_TIME_CEILING / WorldConfig().dt),  # the action-selection task's steps
    },
    f"socialzoo/CrowdNavRecorded-v{CROWD_RECORDED_VERSION}": {
        "task": "crowdnav",
        "map": None,
        "family": RECORDED_DEFAULT_FAMILY,
        "humans": "replay",
        "robot_visible": True,
        "time_limit": RECORDED_TIME_CEILING,
    },
}


def register_task(env_id: str, task: str, **kwargs: object) -> None:
    """Register `env_id` as the Gymnasium env and VectorEnv of `task` (idempotent: the same
    registration again does nothing).

    Args:
        env_id: "namespace/Name-vN".
        task: the task's registry name (socialzoo.env.tasks.TASKS) or its "module:Class" path.
        **kwargs: the task's config fields as plain JSON values.

    Raises:
        ValueError: `env_id` is registered already with other kwargs or entry points (an id names
            one set-up: register the other one under another id or version).
    """
    wanted = {"task": task, **kwargs}
    if env_id in gym.registry:
        spec = gym.spec(env_id)
        if (spec.entry_point, spec.vector_entry_point, spec.kwargs) != (ENTRY, VECTOR_ENTRY, wanted):
            raise ValueError(
                f"register_task: {env_id} is already registered with {spec.kwargs} "
                f"(entry point {spec.entry_point}); got {wanted} (register it under another id or version)"
            )
        return
    gym.register(
        id=env_id,
        entry_point=ENTRY,
        vector_entry_point=VECTOR_ENTRY,
        kwargs=wanted,
        disable_env_checker=False,
    )


def task_ids() -> dict[str, dict]:
    """Every id of socialzoo's tasks -> its registration kwargs (with "task", the task's name)."""
    return {**CROWD_IDS, **BENCHMARK_IDS, **REFERENCE_IDS, **FAMILY_IDS, **SUITE_IDS, **RECORDED_IDS}


def register_envs() -> None:
    """Register every id of socialzoo's tasks (idempotent)."""
    for env_id, kwargs in task_ids().items():
        register_task(env_id, **kwargs)
