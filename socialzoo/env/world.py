"""The world step: robots and humans of B worlds advance one dt together."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from socialzoo.core.config import RobotConfig, WorldConfig
from socialzoo.core.jit import kernel
from socialzoo.core.robot import step_robot, world_velocity
from socialzoo.core.state import WorldState
from socialzoo.core.walls import WallIndex
from socialzoo.humans.models import ORCA, REPLAY
from socialzoo.humans.motion import keep_off_robots
from socialzoo.humans.people import step_people, step_people_packed
from socialzoo.humans.routes import advance_waypoints

_DIFFERENTIAL = RobotConfig()


@dataclass(frozen=True)
class StepEvents:
    """What happened during one step.

    Attributes:
        robot_wall: (B, R) the robot's footprint touches a wall after the step.
        robot_human: (B, R, H) robot-human centre distance below the collision distance.
        human_blocked: (B, H) a wall stopped the human's move this step.
    """

    robot_wall: np.ndarray
    robot_human: np.ndarray
    human_blocked: np.ndarray


def robot_velocity_vectors(state: WorldState, robot: RobotConfig | None = None) -> np.ndarray:
    """(B, R, 2) robot velocity in the world frame, m/s (robot: the kinematics that say what the
    velocity state means; default the differential drive)."""
    return world_velocity(state.robot_pose, state.robot_vel, robot or _DIFFERENTIAL)


def robot_collisions(state: WorldState, walls: WallIndex, cfg: WorldConfig) -> tuple[np.ndarray, np.ndarray]:
    """(robot_wall (B, R), robot_human (B, R, H)) collision flags for the current state."""
    return robot_wall_contacts(state, walls, cfg), robot_human_contacts(state, cfg)


def robot_wall_contacts(state: WorldState, walls: WallIndex, cfg: WorldConfig) -> np.ndarray:
    """(B, R) robots whose footprint touches a wall in the current state."""
    if cfg.robot.radius is not None:  # a disc footprint
        return walls.nearest(state.robot_pose[..., :2])[1] < cfg.robot.radius
    return walls.footprint_hits(state.robot_pose, cfg.robot.half_length, cfg.robot.half_width)


def robot_human_contacts(state: WorldState, cfg: WorldConfig) -> np.ndarray:
    """(B, R, H) robot-person centre distances below the collision distance, present people only."""
    b, r = state.robot_pose.shape[:2]
    out = np.empty((b, r, state.human_pos.shape[1]), dtype=bool)
    _contacts(state.robot_pose, state.human_pos, state.human_mask, cfg.human_collision_distance**2, out)
    return out


@kernel
def _contacts(robot_pose, human_pos, mask, distance2, out):  # type: ignore[no-untyped-def]
    """robot_human_contacts into out (B, R, H): the squared centre distance (the two squares added)
    below distance2, for present people."""
    for b in range(out.shape[0]):
        for q in range(out.shape[1]):
            for h in range(out.shape[2]):
                dx, dy = robot_pose[b, q, 0] - human_pos[b, h, 0], robot_pose[b, q, 1] - human_pos[b, h, 1]
                out[b, q, h] = mask[b, h] and dx * dx + dy * dy < distance2


def step_world(
    state: WorldState,
    walls: WallIndex,
    cfg: WorldConfig,
    robot_command: np.ndarray,
    robot_halt: np.ndarray | None = None,
    human_desired_vel: np.ndarray | None = None,
    human_learned: np.ndarray | None = None,
    robot_visible: bool = True,
    sparse_people: bool = False,
    human_contacts: bool = True,
) -> tuple[WorldState, StepEvents]:
    """Advance every world by one step of cfg.dt.

    This is the one copy of the dynamics. Every adapter (ParallelEnv, the single-agent benchmark,
    vector envs, the evaluation runner) calls `step_world`.

    Humans react to the robots' positions and velocities at the start of the step.

    Args:
        state: current state (not modified).
        walls: the map's wall index.
        cfg: world configuration.
        robot_command: (B, R, 2) requested (v, omega), m/s and rad/s.
        robot_halt: (B, R) bool; robots whose velocity is set to zero at once.
        human_desired_vel: (B, H, 2) desired velocities for learned humans, m/s, world frame.
        human_learned: (B, H) bool; humans driven by `human_desired_vel` instead of their route.
        robot_visible: False: the humans neither see nor avoid the robots (CrowdNav's invisible
            robot); collisions with them still count.
        sparse_people: step only the rows where a model moves someone, each with only its present
            people (socialzoo.humans.people.step_people_packed; the same steps, for recorded scenes
            whose slots are mostly empty and whose replayed people no model moves).
        human_contacts: False: events.robot_human is left all False, for a caller that places
            people after the step (the replay) and counts the contacts where it put them.

    Returns:
        (new_state, events).
    """
    if robot_halt is None:
        robot_halt = np.zeros(state.robot_pose.shape[:2], dtype=bool)
    hcfg = cfg.human
    # Each human's model (social force, ORCA, learned; walking groups) by WorldState.human_model
    # and human_group: socialzoo.humans.people.
    anyone_moved, moved, target = True, None, None
    if sparse_people:
        moved = state.human_mask & (state.human_model != REPLAY)
        anyone_moved = bool(moved.any())
    if anyone_moved:
        rest = (
            state.human_pref_speed,
            state.human_mask,
            state.human_model,
            state.human_group,
            state.robot_pose[..., :2] if robot_visible else state.robot_pose[:, :0, :2],
            robot_velocity_vectors(state, cfg.robot)[:, : state.num_robots if robot_visible else 0],
            walls,
            cfg,
            human_desired_vel,
            human_learned,
        )
        if sparse_people:
            # A recorded scene's packing gathers the targets of the people it steps (a pass over every
            # slot of the cold route array cost more than the rest of the gather), and
            # advance_waypoints reads the moved people's from the route (target None).
            human_pos, human_vel, blocked = step_people_packed(
                state.human_pos, state.human_vel, state.human_route, state.human_waypoint, *rest, moved=moved
            )
        else:
            target = state.human_target
            human_pos, human_vel, blocked = step_people(state.human_pos, state.human_vel, target, *rest)
    else:
        # Nobody moved (replayed people only: step_people_packed would leave each where it stood).
        human_pos, human_vel = state.human_pos.copy(), state.human_vel.copy()
        blocked = np.zeros(state.human_mask.shape, dtype=bool)
    # A step that moved nobody (replayed people only, each where it stood) presses nobody into a robot.
    if robot_visible and anyone_moved:
        # People the social force moves (its own and learned people, whose desired velocity it
        # follows) do not press deeper into a robot they touch (socialzoo.humans.motion.
        # keep_off_robots: the model has no body force); ORCA people keep off by construction, and
        # on a recorded scene the replay places its replayed people.
        human_pos, human_vel = keep_off_robots(
            state.human_pos, human_pos, human_vel,
            (state.human_mask if moved is None else moved) & (state.human_model != ORCA),
            state.robot_pose[..., :2], cfg.human_collision_distance, walls,
        )  # fmt: skip
    waypoint, direction = advance_waypoints(
        human_pos,
        state.human_route,
        state.human_route_len,
        state.human_waypoint,
        state.human_direction,
        hcfg.waypoint_radius,
        target,
        # Only the people a model moved: the replay places its replayed people, points one who
        # starts to react or enters a slot at its route itself, and absent slots stay absent.
        moved,
    )
    robot_pose, robot_vel = step_robot(
        state.robot_pose, state.robot_vel, robot_command, robot_halt, cfg.dt, cfg.robot
    )
    new_state = WorldState(
        robot_pose=robot_pose,
        robot_vel=robot_vel,
        robot_goal=state.robot_goal,
        human_pos=human_pos,
        human_vel=human_vel,
        human_pref_speed=state.human_pref_speed,
        human_mask=state.human_mask,
        human_route=state.human_route,
        human_route_len=state.human_route_len,
        human_waypoint=waypoint,
        human_direction=direction,
        step_count=state.step_count + 1,
        noise_key=state.noise_key,
        human_model=state.human_model,
        human_group=state.human_group,
    )
    robot_wall = robot_wall_contacts(new_state, walls, cfg)
    if human_contacts:
        robot_human = robot_human_contacts(new_state, cfg)
    else:
        robot_human = np.zeros(robot_pose.shape[:2] + human_pos.shape[1:2], dtype=bool)
    return new_state, StepEvents(robot_wall=robot_wall, robot_human=robot_human, human_blocked=blocked)
