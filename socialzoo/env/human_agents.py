"""Observations, actions and rewards of learned humans (the optional human agents of the envs)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from socialzoo.core.geometry import rotate
from socialzoo.core.jit import kernel
from socialzoo.core.state import WorldState
from socialzoo.core.validation import check_fields
from socialzoo.core.walls import WallIndex

# Per-neighbour entries: x, y, vx, vy (relative, human frame), is_robot.
NEIGHBOUR_SIZE = 5
# Own entries: waypoint x, y; velocity x, y; preferred speed; nearest wall x, y; wall in reach.
OWN_SIZE = 8
# Centre distance counted as contact between two agents, m (SPEC: 0.4 for robot-human).
CONTACT_DISTANCE = 0.4


@dataclass(frozen=True, kw_only=True)
class HumanRewardConfig:
    """The learned humans' reward per step: a weighted sum of the terms of `HumanStep`.

    reward = progress * metres gained towards the waypoint
             + waypoint_bonus * (a waypoint was reached this step)
             - speed * |speed - preferred speed| / preferred speed
             - human_contact * (another human within contact_distance)
             - robot_contact * (a robot within contact_distance)
             - wall_contact * (a wall within wall_distance, or a wall stopped the move)
             - wall_clearance * (how far inside wall_margin of a wall: 0 at wall_margin,
                                 1 at wall_distance and closer)

    The defaults are the reward of env version v1 (progress minus 1 per step in contact with a
    human or robot); the trainers of socialzoo.train set their own weights.

    Attributes:
        progress: weight of the distance gained towards the current waypoint, per metre.
        waypoint_bonus: paid on the step a waypoint is reached.
        speed: weight of the relative deviation from the preferred walking speed, per step.
        human_contact: penalty per step within contact_distance of another present human.
        robot_contact: penalty per step within contact_distance of a robot.
        wall_contact: penalty per step with the centre within wall_distance of a wall.
        wall_clearance: penalty per step for walking close to a wall, growing linearly from 0 at
            wall_margin to its full weight at wall_distance: a warning before the contact, which
            the contact penalty alone gives only once it is too late.
        contact_distance: centre distance counted as contact with a human or robot, m.
        wall_distance: centre-to-wall distance counted as contact, m (the human radius).
        wall_margin: centre-to-wall distance where the clearance penalty starts, m (above
            wall_distance).
    """

    progress: float = 1.0
    waypoint_bonus: float = 0.0
    speed: float = 0.0
    human_contact: float = 1.0
    robot_contact: float = 1.0
    wall_contact: float = 0.0
    wall_clearance: float = 0.0
    contact_distance: float = CONTACT_DISTANCE
    wall_distance: float = 0.2
    wall_margin: float = 0.4

    def __post_init__(self) -> None:
        # Every weight may be 0; the distances must be > 0.
        distances = ("contact_distance", "wall_distance", "wall_margin")
        check_fields(self, nonnegative=[f.name for f in fields(self) if f.name not in distances])
        if not self.wall_margin > self.wall_distance:
            raise ValueError(
                f"HumanRewardConfig.wall_margin ({self.wall_margin}) must exceed wall_distance "
                f"({self.wall_distance})"
            )


@dataclass(frozen=True)
class HumanStep:
    """One step of the learned humans; every array is (B, L), zero or False for absent humans.

    Attributes:
        reward: the weighted reward (HumanRewardConfig).
        progress: distance gained towards the waypoint the human had before the step, m.
        waypoint_reached: the human reached its waypoint this step (it moved on to the next one).
        human_contact: another present human within the contact distance after the step.
        robot_contact: a robot within the contact distance after the step.
        wall_contact: a wall within the wall distance after the step, or a wall stopped the move.
        wall_clearance: how far inside the wall margin after the step, 0 (outside) to 1 (at the
            wall distance or closer).
        speed_error: |speed - preferred speed| / preferred speed after the step.
    """

    reward: np.ndarray
    progress: np.ndarray
    waypoint_reached: np.ndarray
    human_contact: np.ndarray
    robot_contact: np.ndarray
    wall_contact: np.ndarray
    wall_clearance: np.ndarray
    speed_error: np.ndarray

    @property
    def contact(self) -> np.ndarray:
        """(B, L) in contact with a human or a robot (the ParallelEnv's info["contact"])."""
        return self.human_contact | self.robot_contact


def action_velocities(
    state: WorldState, humans: np.ndarray, action: np.ndarray, frame: str, scale: float = 1.0
) -> np.ndarray:
    """(B, L, 2) world-frame desired velocities, m/s, of learned humans' actions.

    Args:
        state: the world before the step.
        humans: (L,) learned human slots.
        action: (B, L, 2) in [-1, 1], times scale times the preferred speed.
        frame: "world" (the action is a world-frame vector) or "human" (in the human's own frame,
            x towards its waypoint, the frame of its observation).
        scale: EnvConfig.human_action_scale.
    """
    scaled = action * (scale * state.human_pref_speed[:, humans, None])
    if frame == "human":
        return rotate(scaled, human_frames(state, humans))
    return scaled


def human_observation_size(num_neighbours: int) -> int:
    """Length of a learned human's observation."""
    return OWN_SIZE + NEIGHBOUR_SIZE * num_neighbours


def human_mirror_signs(num_neighbours: int) -> np.ndarray:
    """(D,) +1 / -1 per observation entry: the observation of the mirror image of a situation.

    Mirroring about the human's x axis (towards its waypoint) negates every y component: of the
    waypoint, the velocity, the nearest wall point and each neighbour's position and velocity.
    A policy with no handedness acts on the mirrored observation with the mirrored action
    (action y negated).
    """
    signs = np.ones(human_observation_size(num_neighbours), dtype=np.float32)
    signs[[1, 3, 6]] = -1.0  # waypoint y, velocity y, nearest wall y
    for k in range(num_neighbours):
        start = OWN_SIZE + NEIGHBOUR_SIZE * k
        signs[[start + 1, start + 3]] = -1.0  # relative position y, relative velocity y
    return signs


def human_frames(state: WorldState, humans: np.ndarray) -> np.ndarray:
    """(B, L) heading of each learned human's frame: towards its current waypoint, rad."""
    to_target = state.human_target[:, humans] - state.human_pos[:, humans]
    return np.arctan2(to_target[..., 1], to_target[..., 0])


def human_observations(
    state: WorldState, walls: WallIndex, humans: np.ndarray, num_neighbours: int
) -> np.ndarray:
    """Observations of the learned humans.

    A learned human sees, in its own frame (x axis towards its current route waypoint): that
    waypoint, its velocity and preferred speed, the nearest wall point, and its nearest neighbours
    (humans and robots) with their relative velocity.

    Args:
        state: the world.
        walls: the map's wall index.
        humans: (L,) indices of the learned human slots.
        num_neighbours: K nearest agents listed (absent ones are zero rows).

    Returns:
        (B, L, 8 + 5K) float32, human frame (x towards its waypoint), SI units. Slots of absent
        humans are all zero.
    """
    humans = np.asarray(humans, dtype=np.int64)
    pos = state.human_pos[:, humans]
    heading = human_frames(state, humans)
    # numpy's cos and sin (those `rotate` takes) of the frames and of the robots' headings; the
    # rest is one compiled pass (_fill_human_observations) with numpy's operations in its order.
    cos, sin = np.cos(-heading), np.sin(-heading)
    robot_theta = state.robot_pose[..., 2]
    robot_dir = np.stack((np.cos(robot_theta), np.sin(robot_theta)), axis=-1)
    closest, dist = walls.nearest(pos)
    obs = np.zeros((state.batch_size, len(humans), human_observation_size(num_neighbours)), dtype=np.float32)
    _fill_human_observations(
        state.human_pos, state.human_vel, state.human_target, state.human_pref_speed, state.human_mask,
        state.robot_pose, state.robot_vel, robot_dir, humans, cos, sin, closest, dist,
        min(num_neighbours, state.max_humans + state.robot_pose.shape[1]), obs,
    )  # fmt: skip
    return obs


@kernel
def _fill_human_observations(
    human_pos, human_vel, human_target, pref_speed, mask, robot_pose, robot_vel, robot_dir, humans,
    cos, sin, closest, dist, k, obs,
):  # fmt: skip
    """`human_observations` after the frames' cos and sin and the nearest walls: fills obs
    (B, L, D) of present learned humans (absent ones stay zero). The neighbours are the k nearest
    present agents (people, then robots, by slot; ties to the lower slot, as a stable argsort),
    each rotated into the human's frame as `rotate` does (c * x - s * y, s * x + c * y)."""
    batch, num = human_pos.shape[0], human_pos.shape[1]
    robots = robot_pose.shape[1]
    agents = num + robots
    dist2 = np.empty(agents)
    taken = np.empty(agents, dtype=np.bool_)
    for b in range(batch):
        for i in range(humans.shape[0]):
            h = humans[i]
            if not mask[b, h]:
                continue
            c, s = cos[b, i], sin[b, i]
            px, py = human_pos[b, h, 0], human_pos[b, h, 1]
            vx, vy = human_vel[b, h, 0], human_vel[b, h, 1]
            tx, ty = human_target[b, h, 0] - px, human_target[b, h, 1] - py
            obs[b, i, 0] = c * tx - s * ty
            obs[b, i, 1] = s * tx + c * ty
            obs[b, i, 2] = c * vx - s * vy
            obs[b, i, 3] = s * vx + c * vy
            obs[b, i, 4] = pref_speed[b, h]
            if math.isfinite(dist[b, i]):
                wx, wy = closest[b, i, 0] - px, closest[b, i, 1] - py
                obs[b, i, 5] = c * wx - s * wy
                obs[b, i, 6] = s * wx + c * wy
                obs[b, i, 7] = 1.0
            if k == 0:
                continue
            for j in range(agents):
                taken[j] = False
                if j < num:
                    present = mask[b, j] and j != h
                    rx, ry = human_pos[b, j, 0] - px, human_pos[b, j, 1] - py
                else:
                    present = True
                    rx, ry = robot_pose[b, j - num, 0] - px, robot_pose[b, j - num, 1] - py
                dist2[j] = rx * rx + ry * ry if present else math.inf
            for n in range(k):
                # The nearest agent not yet listed; NaN sorts last, as in numpy.
                best = -1
                for j in range(agents):
                    if taken[j]:
                        continue
                    d = dist2[j]
                    if best < 0 or d < dist2[best] or (math.isnan(dist2[best]) and not math.isnan(d)):
                        best = j
                taken[best] = True
                if not math.isfinite(dist2[best]):
                    continue
                if best < num:
                    rx, ry = human_pos[b, best, 0] - px, human_pos[b, best, 1] - py
                    ux, uy = human_vel[b, best, 0] - vx, human_vel[b, best, 1] - vy
                    robot = 0.0
                else:
                    r = best - num
                    rx, ry = robot_pose[b, r, 0] - px, robot_pose[b, r, 1] - py
                    ux = robot_vel[b, r, 0] * robot_dir[b, r, 0] - vx
                    uy = robot_vel[b, r, 0] * robot_dir[b, r, 1] - vy
                    robot = 1.0
                start = OWN_SIZE + NEIGHBOUR_SIZE * n
                obs[b, i, start] = c * rx - s * ry
                obs[b, i, start + 1] = s * rx + c * ry
                obs[b, i, start + 2] = c * ux - s * uy
                obs[b, i, start + 3] = s * ux + c * uy
                obs[b, i, start + 4] = robot


def human_step(
    before: WorldState,
    after: WorldState,
    humans: np.ndarray,
    walls: WallIndex,
    blocked: np.ndarray,
    config: HumanRewardConfig,
) -> HumanStep:
    """Reward and its terms for the learned humans' step before -> after.

    Progress is measured towards the waypoint each human had before the step, so switching to
    the next waypoint does not make the reward jump.

    Args:
        before: the world before the step.
        after: the world after the step.
        humans: (L,) learned human slots.
        walls: the map's wall index.
        blocked: (B, H) humans whose move a wall stopped this step (StepEvents.human_blocked).
        config: the reward weights and contact distances.
    """
    humans = np.asarray(humans, dtype=np.int64)
    _, wall_dist = walls.nearest(after.human_pos[:, humans])
    shape = (after.batch_size, len(humans))
    terms = np.empty((4,) + shape)  # reward, progress, wall clearance, speed error
    flags = np.empty((4,) + shape, dtype=bool)  # waypoint reached, human, robot and wall contact
    weights = np.array(
        [
            config.progress, config.waypoint_bonus, config.speed, config.human_contact,
            config.robot_contact, config.wall_contact, config.wall_clearance,
            config.contact_distance**2, config.wall_distance, config.wall_margin,
        ]
    )  # fmt: skip
    _human_step_terms(
        before.human_pos, before.human_target, before.human_waypoint, after.human_pos, after.human_vel,
        after.human_waypoint, after.human_pref_speed, after.human_mask, after.robot_pose, humans,
        wall_dist, blocked, weights, terms, flags,
    )  # fmt: skip
    return HumanStep(
        reward=terms[0],
        progress=terms[1],
        waypoint_reached=flags[0],
        human_contact=flags[1],
        robot_contact=flags[2],
        wall_contact=flags[3],
        wall_clearance=terms[2],
        speed_error=terms[3],
    )


@kernel
def _human_step_terms(
    pos0, target0, waypoint0, pos, vel, waypoint, pref_speed, mask, robot_pose, humans, wall_dist,
    blocked, weights, terms, flags,
):  # fmt: skip
    """`human_step`'s terms in one pass over (B, L): terms (reward, progress, wall clearance,
    speed error) and flags (waypoint reached, human, robot and wall contact), zero and
    False for absent humans. The operations are numpy's in its order (a norm is the square root
    of x * x + y * y; the reward's terms are added and subtracted left to right), so the results
    are the same bit for bit."""
    w_progress, w_bonus, w_speed, w_human = weights[0], weights[1], weights[2], weights[3]
    w_robot, w_wall, w_clearance = weights[4], weights[5], weights[6]
    limit, wall_distance, wall_margin = weights[7], weights[8], weights[9]
    for b in range(pos.shape[0]):
        for i in range(humans.shape[0]):
            h = humans[i]
            present = mask[b, h]
            tx, ty = target0[b, h, 0], target0[b, h, 1]
            ax, ay = tx - pos0[b, h, 0], ty - pos0[b, h, 1]
            px, py = pos[b, h, 0], pos[b, h, 1]
            cx, cy = tx - px, ty - py
            gained = math.sqrt(ax * ax + ay * ay) - math.sqrt(cx * cx + cy * cy)
            reached = waypoint[b, h] != waypoint0[b, h]
            near_human = False
            for j in range(pos.shape[1]):
                dx, dy = pos[b, j, 0] - px, pos[b, j, 1] - py
                if dx * dx + dy * dy < limit and mask[b, j] and j != h:
                    near_human = True
                    break
            near_robot = False
            for r in range(robot_pose.shape[1]):
                dx, dy = robot_pose[b, r, 0] - px, robot_pose[b, r, 1] - py
                if dx * dx + dy * dy < limit:
                    near_robot = True
                    break
            d = wall_dist[b, i]
            wall = d < wall_distance or blocked[b, h]
            clearance = (wall_margin - d) / (wall_margin - wall_distance)
            if not math.isnan(clearance):
                clearance = min(max(clearance, 0.0), 1.0)
            if wall:
                clearance = 1.0
            vx, vy = vel[b, h, 0], vel[b, h, 1]
            speed = math.sqrt(vx * vx + vy * vy)
            pref = pref_speed[b, h]
            speed_error = abs(speed - pref) / max(pref, 1e-9)
            human_contact = near_human and present
            robot_contact = near_robot and present
            wall_contact = wall and present
            reward = (
                w_progress * gained
                + w_bonus * (1.0 if reached else 0.0)
                - w_speed * speed_error
                - w_human * (1.0 if human_contact else 0.0)
                - w_robot * (1.0 if robot_contact else 0.0)
                - w_wall * (1.0 if wall_contact else 0.0)
                - w_clearance * (clearance if present else 0.0)
            )
            terms[0, b, i] = reward if present else 0.0
            terms[1, b, i] = gained if present else 0.0
            terms[2, b, i] = clearance if present else 0.0
            terms[3, b, i] = speed_error if present else 0.0
            flags[0, b, i] = reached and present
            flags[1, b, i] = human_contact
            flags[2, b, i] = robot_contact
            flags[3, b, i] = wall_contact
