"""Episodes of the CrowdNav task for the episode viewer (socialzoo.render.replay_html): one case
played by each policy, recorded state by state into the viewer's EpisodeTrace.

The task has no global plan, laser or sub-policies: the trace's plan is the straight line from
start to goal, its carrot the goal, its scan empty and its actions -1 (velocity actions); the
robot's disc is drawn as a square of its diameter, and a holonomic robot's heading follows its
velocity so that the viewer shows where it goes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from socialzoo.bench.crowd_eval import CrowdActor
from socialzoo.core.robot import world_velocity
from socialzoo.env.crowd_config import CrowdNavConfig
from socialzoo.env.crowd_core import CrowdNavCore
from socialzoo.env.crowd_source import CrowdCaseSource
from socialzoo.nav.crowd_cases import Split
from socialzoo.render.replay_data import EpisodeTrace, ReplayScene


def record_crowd_episode(
    act: CrowdActor, label: str, config: CrowdNavConfig, split: Split, case: int
) -> EpisodeTrace:
    """Play case `case` of a split with `act` and record it."""
    core = CrowdNavCore(config, 1)
    scenario = CrowdCaseSource(config, 1).fixed(split, [case])
    core.reset_rows([0], scenario)
    poses, vels, humans, human_vels, rewards, collisions = [], [], [], [], [], []
    forces, blames, walls, carrots = [], [], [], []
    metrics: dict[str, float] = {}

    def snapshot() -> None:
        s = core.state
        assert s is not None
        velocity = world_velocity(s.robot_pose[0, 0], s.robot_vel[0, 0], config.robot)
        pose = s.robot_pose[0, 0].copy()
        speed = float(np.hypot(*velocity))
        if config.robot.kinematics == "holonomic" and speed > 1e-6:
            pose[2] = np.arctan2(velocity[1], velocity[0])
        poses.append(pose)
        vels.append([speed, 0.0])
        humans.append(s.human_pos[0][s.human_mask[0]].copy())
        human_vels.append(s.human_vel[0][s.human_mask[0]].copy())
        carrots.append(core.seen_goal()[0][0, 0].copy())

    snapshot()
    while not metrics:
        step = core.step(act(core.observation.flat(), core))  # type: ignore[union-attr]
        rewards.append(float(step.outcome.reward[0]))
        collisions.append(int(step.outcome.collision[0] and not step.wall_collision[0]))
        walls.append(bool(step.wall_collision[0]))
        forces.append(float(core.step_force[0]))
        blames.append(float(core.step_blame[0]))
        snapshot()
        metrics = step.metrics.get(0, {})
    outcome = "success" if metrics["success"] else "collision" if metrics["collision"] else "timeout"
    steps = len(rewards)
    s = core.state
    assert s is not None
    goal = s.robot_goal[0, 0].copy()
    start = poses[0][:2]
    return EpisodeTrace(
        label=label,
        dt=config.time_step,
        robot_pose=np.array(poses),
        robot_vel=np.array(vels),
        goal=goal,
        human_pos=np.array(humans),
        human_vel=np.array(human_vels),
        carrot=np.array(carrots),
        plans=(np.array([start, goal[:2]]),),
        plan_index=np.zeros(steps + 1, dtype=np.int64),
        laser_angles=np.zeros(1),
        laser_steps=np.zeros(1, dtype=np.int64),
        laser_ranges=np.full((1, 1), 1.0),
        laser_max_range=1.0,
        action=np.full(steps, -1),
        target_human=np.full(steps, -1),
        reward=np.array(rewards),
        force=np.array(forces),
        blame=np.array(blames),
        human_collisions=np.array(collisions),
        wall_collision=np.array(walls, dtype=bool),
        metrics=metrics,
        outcome=outcome,
    )


def crowd_scene(config: CrowdNavConfig, traces: Sequence[EpisodeTrace], title: str) -> ReplayScene:
    """The viewer's scene of the task: the arena (or the map's walls) around every trace."""
    points = np.concatenate(
        [np.concatenate((t.robot_pose[:, :2], t.human_pos.reshape(-1, 2), t.goal[None, :2])) for t in traces]
    )
    low, high = points.min(0) - 1.0, points.max(0) + 1.0
    walls = np.zeros((0, 4))
    if config.map is not None:
        from socialzoo.nav.maps import load_map

        walls = load_map(config.map).walls
    diameter = 2.0 * float(config.robot.radius)  # type: ignore[arg-type]
    return ReplayScene(
        title=title,
        map_name=config.map or "arena",
        walls=walls,
        bounds=(float(low[0]), float(low[1]), float(high[0]), float(high[1])),
        robot_length=diameter,
        robot_width=diameter,
        human_radius=config.cases.human_radius,
        goal_radius=float(config.robot.radius),  # type: ignore[arg-type]
    )
