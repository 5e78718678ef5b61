"""Engineered robots of the CrowdNav task: ORCA (CrowdNav's own baseline) and social force."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from socialzoo.core.config import HumanConfig, OrcaConfig
from socialzoo.core.robot import world_velocity

# CrowdNav's radius padding of every agent in the robot's ORCA step, m.
_ORCA_PADDING = 0.01


def velocity_to_action(velocity: np.ndarray, task: Any) -> np.ndarray:
    """The task's actions that come closest to world-frame velocities (B, R, 2): (B, R, 2) or
    (B, R) (with one robot (B, 2) or (B,)).

    A velocity is turned into the task's action: (vx, vy) / v_pref in the action frame (the goal frame by
    default) for a holonomic robot; for a unicycle, the turn towards the velocity's direction (at most pi/4)
    and its speed; for the discrete action set, the nearest of CrowdNav's 81 actions.
    """
    config = task.config
    robot = config.robot
    v_pref = config.preferred_speed
    b, r = velocity.shape[:2]
    if robot.kinematics == "holonomic":
        command = task.to_action_frame(velocity)
        action = np.clip(command / v_pref, -1.0, 1.0)
    else:
        heading = task.core.state.robot_pose[..., 2]
        turn = np.angle(np.exp(1j * (np.arctan2(velocity[..., 1], velocity[..., 0]) - heading)))
        turn = np.clip(turn, -robot.max_rotation, robot.max_rotation)
        speed = np.minimum(np.hypot(velocity[..., 0], velocity[..., 1]), v_pref)
        command = np.stack((speed, turn), axis=-1)
        action = np.stack((2.0 * speed / v_pref - 1.0, turn / robot.max_rotation), axis=-1)
    if task.action_table is None:
        out = action.astype(np.float32)
        return out[:, 0] if r == 1 else out
    # The nearest of the discrete actions, in the same terms as the command.
    table = task.action_table
    distance = ((command.reshape(b * r, 1, 2) - table[None, :, :]) ** 2).sum(-1)
    index = np.argmin(distance, axis=1).astype(np.int64).reshape(b, r)
    return index[:, 0] if r == 1 else index


class CrowdOrcaRobot:
    """CrowdNav's ORCA robot.

    CrowdNav's crowd_sim/envs/policy/orca.py: the robot and the people in one ORCA step in which only the
    robot is driven; the robot prefers its goal direction at its preferred speed, the people are assumed to
    prefer standing still (the robot does not know their goals), every radius is padded by 0.01 m plus
    `safety_space`; CrowdNav's parameters (neighbour distance 10, 10 neighbours, time horizons 5 s).
    Reciprocity is ORCA's premise: against invisible people who do not avoid back it fails often, as CrowdNav
    reports (0.43 success).

    Args:
        safety_space: extra radius of every agent in the robot's ORCA step, the robot's and each
            person's, as CrowdNav pads them, m (CrowdNav: 0; 0.15 for its demonstrations).
        orca: ORCA's parameters (default CrowdNav's).
    """

    name = "orca"
    reads_core = True

    def __init__(self, safety_space: float = 0.0, orca: OrcaConfig | None = None) -> None:
        if not safety_space >= 0.0:
            raise ValueError(f"CrowdOrcaRobot: safety_space must be >= 0, got {safety_space!r}")
        self.safety_space = float(safety_space)
        self.orca = orca or OrcaConfig.preset("crowdnav")

    def act(self, obs: np.ndarray, task: Any) -> np.ndarray:
        """The ORCA velocity of every robot, as the task's actions (each robot driven, the other
        robots seen like the people)."""
        from socialzoo.humans.orca import orca_velocities

        core, config = task.core, task.config
        s = core.state
        robot = config.robot
        b, h = s.human_mask.shape
        r = s.robot_pose.shape[1]
        pos = np.concatenate((s.robot_pose[..., :2], s.human_pos), axis=1)
        robot_vel = world_velocity(s.robot_pose, s.robot_vel, robot)
        vel = np.concatenate((robot_vel, s.human_vel), axis=1)
        target, left = core.seen_goal()
        to_goal = target - s.robot_pose[..., :2]
        distance = np.hypot(to_goal[..., 0], to_goal[..., 1])[..., None]
        pref = np.zeros((b, r + h, 2))
        # CrowdNav: the goal direction at the preferred speed, slower only within a metre of the
        # goal (among walls: towards the carrot, slower within a metre of the route's end).
        if core.navigator is None:
            pref[:, :r] = to_goal / np.maximum(distance, 1.0) * config.preferred_speed
        else:
            scale = np.minimum(left[..., None], 1.0) / np.maximum(distance, 1e-9)
            pref[:, :r] = to_goal * scale * config.preferred_speed
        # CrowdNav pads the people's radii by the safety space too, not only the robot's.
        radius = np.full((b, r + h), config.cases.human_radius + _ORCA_PADDING + self.safety_space)
        radius[:, :r] = float(robot.radius) + _ORCA_PADDING + self.safety_space
        max_speed = np.full((b, r + h), config.preferred_speed)
        present = np.concatenate((np.ones((b, r), dtype=bool), s.human_mask), axis=1)
        drive = np.zeros((b, r + h), dtype=bool)
        drive[:, :r] = True
        new = orca_velocities(
            pos,
            vel,
            pref,
            radius,
            max_speed,
            present,
            drive,
            present,
            core.walls,
            self.orca,
            config.time_step,
        )
        return velocity_to_action(new[:, :r], task)

    def config(self) -> dict[str, Any]:
        """The policy's parameters."""
        return {"safety_space": self.safety_space, "orca": dataclasses.asdict(self.orca)}


class CrowdSocialForceRobot:
    """The robot as one more social-force pedestrian heading for its goal.

    The benchmark's PedSim model, heading for the goal at the preferred speed; the robot's velocity is its
    velocity after one step of the force.

    Args:
        human: the social-force parameters (default the benchmark's people's).
    """

    name = "social_force"
    reads_core = True

    def __init__(self, human: HumanConfig | None = None) -> None:
        self.human = human or HumanConfig()

    def act(self, obs: np.ndarray, task: Any) -> np.ndarray:
        """Each robot's velocity after one step of the social force, as the task's actions (the
        other robots push like people)."""
        from socialzoo.humans.social_force import human_acceleration

        core, config = task.core, task.config
        s = core.state
        b = s.human_mask.shape[0]
        r = s.robot_pose.shape[1]
        pos = np.concatenate((s.robot_pose[..., :2], s.human_pos), axis=1)
        robot_vel = world_velocity(s.robot_pose, s.robot_vel, config.robot)
        vel = np.concatenate((robot_vel, s.human_vel), axis=1)
        target = np.concatenate((core.seen_goal()[0], s.human_pos), axis=1)
        speed = np.concatenate((np.full((b, r), config.preferred_speed), s.human_pref_speed), axis=1)
        mask = np.concatenate((np.ones((b, r), dtype=bool), s.human_mask), axis=1)
        no_robot = np.zeros((b, 0, 2))
        accel, _ = human_acceleration(
            pos, vel, target, speed, mask, no_robot, no_robot, core.walls, self.human
        )
        new = robot_vel + accel[:, :r] * config.time_step
        norm = np.hypot(new[..., 0], new[..., 1])
        new *= np.minimum(1.0, config.preferred_speed / np.maximum(norm, 1e-12))[..., None]
        return velocity_to_action(new, task)

    def config(self) -> dict[str, Any]:
        """The policy's parameters."""
        return {"human": dataclasses.asdict(self.human)}
