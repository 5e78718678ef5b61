"""The action-selection task's outcome of one step for each robot: reward terms, reward, goal
reached, terminated and truncated."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from socialzoo.core.state import WorldState
from socialzoo.env.config import EnvConfig, RobotAction
from socialzoo.env.reward import compute_reward, force_and_blame, progress
from socialzoo.env.world import StepEvents, robot_velocity_vectors
from socialzoo.nav.subpolicies import FOLLOW

# Robots slower than this (m/s) count as still for the blame term.
STILL_SPEED = 1e-3


def followed_human(robot_action: np.ndarray, target: np.ndarray, mode: RobotAction) -> np.ndarray:
    """(B, R) the human that force and blame leave out: the target of Follow, -1 otherwise.

    SPEC section 9: "in Follow the followed human is skipped". Only Follow skips; a passed human
    (Pass) counts like anyone else, and velocity actions never skip.

    Args:
        robot_action: (B, R) sub-policy indices, or (B, R, 2) velocity actions.
        target: (B, R) the sub-policy's target human this step, -1 for none.
        mode: the config's robot_action ("subpolicy" or "velocity").
    """
    target = np.asarray(target, dtype=np.intp)
    if mode != "subpolicy":
        return np.full(target.shape, -1, dtype=np.intp)
    action = np.asarray(robot_action).reshape(target.shape)
    return np.where(action == FOLLOW, target, -1)


def goal_reached(pos: np.ndarray, goal: np.ndarray, radius: float) -> np.ndarray:
    """(...) bool: robot centre `pos` (..., 2) within `radius` (m) of `goal` (..., 2), world frame."""
    to_goal = pos - goal
    return (to_goal**2).sum(-1) < radius**2


def episode_end(
    reached: np.ndarray, wall_collision: np.ndarray, out_of_time: np.ndarray, was_done: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(terminated, truncated), bool arrays of one shape: how episodes end this step.

    Terminated: the goal is reached or a wall touched. Truncated: out of time without
    terminating. Neither for an episode that had already ended (`was_done`).
    """
    terminated = (reached | wall_collision) & ~was_done
    truncated = out_of_time & ~terminated & ~was_done
    return terminated, truncated


@dataclass(frozen=True)
class RobotOutcome:
    """What one step meant for each robot; every array is (B, R).

    Attributes:
        reward: the weighted reward (SPEC section 9); 0 for robots whose episode had ended.
        progress: distance gained towards the goal d_g, m.
        force: social force term f in [0, 1], before weighting.
        blame: blame term b in [0, 1], before weighting.
        reached: goal within goal_radius after the step.
        wall_collision: the footprint touches a wall after the step.
        human_collisions: int, humans within the collision distance after the step.
        terminated: the episode ended this step (goal reached or wall collision).
        truncated: the time limit ended the episode this step.
    """

    reward: np.ndarray
    progress: np.ndarray
    force: np.ndarray
    blame: np.ndarray
    reached: np.ndarray
    wall_collision: np.ndarray
    human_collisions: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray


def robot_outcome(
    before: WorldState,
    after: WorldState,
    events: StepEvents,
    visible: np.ndarray,
    skip: np.ndarray,
    halted: np.ndarray,
    was_done: np.ndarray,
    config: EnvConfig,
    may_arrive: np.ndarray | None = None,
    max_steps: np.ndarray | None = None,
) -> RobotOutcome:
    """Reward terms, reward and episode end of every robot for the step before -> after.

    The task's rules in one place: ActionSelectionTask.step calls `robot_outcome` once per step,
    so a reward variant is a change here (and in the pure terms of socialzoo.env.reward).

    Args:
        before: the world state before the step (B worlds, R robots, H humans).
        after: the world state after the step.
        events: the step's collision events.
        visible: (B*R, H) bool, the humans each robot sees after the step (robot-major rows).
        skip: (B, R) human left out of force and blame (`followed_human`), -1 for none.
        halted: (B, R) bool, robots that were told to halt this step (Halt, no target, or done).
        was_done: (B, R) bool, robots whose episode had ended before this step.
        config: the env's configuration (reward weights, goal radius, time limit, the reference
            code's quirks: socialzoo.env.quirks).
        may_arrive: (B, R) bool, robots whose goal may count as reached now (a robot escorting a
            person arrives only with that person: socialzoo.env.script); None: all.
        max_steps: (B,) each row's own step limit (a recorded scene's time budget), cut by the
            config's where that is lower (the recorded ids' is a day: socialzoo.env.registration);
            None: the config's for all.

    Returns:
        The RobotOutcome.
    """
    b, r = after.robot_pose.shape[:2]
    pos = after.robot_pose[..., :2].reshape(b * r, 2)
    goal = after.robot_goal[..., :2].reshape(b * r, 2)
    human_pos = np.repeat(after.human_pos, r, axis=0) if r > 1 else after.human_pos
    skip = np.asarray(skip).reshape(-1)
    quirks = config.quirks
    d_g = progress(before.robot_pose[..., :2].reshape(b * r, 2), pos, goal, quirks.goal_distance_x_only)
    speed = after.robot_vel[..., 0].reshape(-1)
    still = np.asarray(halted, dtype=bool).reshape(-1) | (np.abs(speed) < STILL_SPEED)
    vel_world = robot_velocity_vectors(after).reshape(b * r, 2)
    force, blame = force_and_blame(
        pos, vel_world, still, human_pos, visible, skip, config.reward.blame_horizon
    )
    reached = goal_reached(pos, goal, config.goal_radius)
    if may_arrive is not None:
        reached &= np.asarray(may_arrive, dtype=bool).reshape(-1)
    wall = events.robot_wall.reshape(-1)
    contacts = events.robot_human.sum(-1).reshape(-1)
    # The success bonus is paid on the step the goal is reached (collision-free or not); the
    # benchmark's success metric additionally requires zero collisions (EpisodeMetrics).
    reward, _ = compute_reward(d_g, blame, force, reached, contacts, config.reward, quirks)
    done = np.asarray(was_done, dtype=bool).reshape(-1)
    limit = config.max_steps if max_steps is None else np.minimum(config.max_steps, max_steps)
    out_of_time = np.repeat(after.step_count >= limit, r)
    terminated, truncated = episode_end(reached, wall, out_of_time, done)
    shape = (b, r)
    return RobotOutcome(
        reward=np.where(done, 0.0, reward).reshape(shape),
        progress=d_g.reshape(shape),
        force=force.reshape(shape),
        blame=blame.reshape(shape),
        reached=reached.reshape(shape),
        wall_collision=wall.reshape(shape),
        human_collisions=contacts.reshape(shape),
        terminated=terminated.reshape(shape),
        truncated=truncated.reshape(shape),
    )
