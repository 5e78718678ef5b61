"""How learned humans meet walls, against social-force humans: contacts, closeness, side drift.

    python tools/human_wall_diagnosis.py social_force runs/humans/checkpoints/step_000384000.humans.safetensors
    python tools/human_wall_diagnosis.py --scenarios 64 social_force socialzoo/agents/shipped/humans.safetensors

Every human of the first N gdc1 validation scenarios (socialzoo.scenarios.scenario_sets.validation_set, never
a test set) walks with the given policy ("social_force" or a learned human policy file) for a fixed
number of steps while the robot runs GoAlone. Printed per policy: wall-contact events per episode
(a human's centre coming within 0.2 m of a wall, or a wall stopping its move: the count of
socialzoo.bench.human_metrics), steps in wall contact per episode (summed over the humans), the
share of human-steps within 0.25 m and 0.3 m of a wall, and the mean lateral component of the
learned humans' action in their own frame (negative: to the right of the way to their waypoint).
It is how the side drift of unsymmetrised learned humans was found (docs/multi_agent.md).
"""

from __future__ import annotations

import argparse

import numpy as np

from socialzoo.env.config import EnvConfig
from socialzoo.env.human_policy import LearnedHumanPolicy
from socialzoo.env.tasks.action_selection import ActionSelectionTask
from socialzoo.nav.subpolicies import GO_ALONE
from socialzoo.scenarios.scenario_sets import validation_set

WALL_CONTACT = 0.2  # socialzoo.bench.human_metrics.HUMAN_RADIUS


def diagnose(spec: str, map_name: str, scenarios: int, steps: int) -> dict[str, float]:
    """The wall figures of one human policy over the first `scenarios` validation scenarios."""
    scenario_set = validation_set(map_name)
    chosen = scenario_set.scenarios(range(scenarios))
    policy = None if spec == "social_force" else LearnedHumanPolicy.load(spec)
    overrides = (
        {}
        if policy is None
        else {"num_learned_humans": scenario_set.cfg.max_humans, **policy.env_overrides()}
    )
    task = ActionSelectionTask(EnvConfig(map=map_name, **overrides), len(chosen))
    task.reset_rows(np.arange(len(chosen)), chosen)
    core = task.core
    robot_action = np.full((len(chosen), 1), GO_ALONE)
    touching = np.zeros(core.state.human_mask.shape, dtype=bool)
    events = contact_steps = human_steps = 0
    within = {0.25: 0, 0.3: 0}
    lateral: list[float] = []
    for _ in range(steps):
        action = None
        if policy is not None:
            action = policy.act(task.human_obs)
            lateral.append(float(action[..., 1][core.state.human_mask].mean()))
        result = task.step(robot_action, action).detail
        mask = core.state.human_mask
        _, dist = core.walls.nearest(core.state.human_pos)
        touch = ((dist < WALL_CONTACT) | result.events.human_blocked) & mask
        events += int((touch & ~touching).sum())
        contact_steps += int(touch.sum())
        touching = touch
        human_steps += int(mask.sum())
        for limit in within:
            within[limit] += int(((dist < limit) & mask).sum())
    n = len(chosen)
    return {
        "events": events / n,
        "contact_steps": contact_steps / n,
        "within_0.25": 100 * within[0.25] / max(human_steps, 1),
        "within_0.3": 100 * within[0.3] / max(human_steps, 1),
        "lateral": float(np.mean(lateral)) if lateral else float("nan"),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("policies", nargs="+", help="social_force or learned human policy files")
    parser.add_argument("--map", default="gdc1", help="map of the validation scenarios (default gdc1)")
    parser.add_argument("--scenarios", type=int, default=32, help="validation scenarios (default 32)")
    parser.add_argument("--steps", type=int, default=1600, help="steps per scenario (default 1600 = 40 s)")
    args = parser.parse_args()
    columns = ["policy", "wall events / episode", "wall-contact steps / episode", "within 0.25 m, %"]
    columns += ["within 0.3 m, %", "mean lateral action"]
    print("| " + " | ".join(columns) + " |")
    print("|---|---|---|---|---|---|")
    for spec in args.policies:
        r = diagnose(spec, args.map, args.scenarios, args.steps)
        print(
            f"| {spec} | {r['events']:.2f} | {r['contact_steps']:.1f} | {r['within_0.25']:.2f} | "
            f"{r['within_0.3']:.2f} | {r['lateral']:+.3f} |"
        )


if __name__ == "__main__":
    main()
