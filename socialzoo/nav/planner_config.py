"""Parameters of the trajectory-rollout local planner (SPEC section 6); see socialzoo.nav.local_planner."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from socialzoo.core.validation import check_fields, check_number


@dataclass(frozen=True, kw_only=True)
class LocalPlannerConfig:
    """Trajectory-rollout parameters (SPEC section 6).

    Attributes:
        curvature_min, curvature_max, curvature_step: the sampled arcs, 1/m (41 by default).
        turn_in_place_angle_deg: a target farther off the heading than this makes the robot
            stop and turn in place, degrees.
        turn_in_place_max_speed: the robot starts turning only once slower than this, m/s
            (it brakes first, as the reference does).
        obstacle_margin: required gap between the planning disc and any obstacle, m.
        max_arc_length: longest arc considered, m.
        target_clip: local targets farther than this are pulled in along their bearing, m (the
            reference clips its local target to the carrot distance, 1.5 m).
        clearance_cap: clearance counts up to this, m.
        planner_accel: linear acceleration and deceleration limit of the speed control, m/s^2.
        progress_weight: score per metre of progress towards the target.
        free_path_weight: score per metre of free path length.
        robot_radius: planning disc radius, m: smaller than the collision footprint (a
            0.5 x 0.43 m box, half-diagonal 0.332 m), as the SPEC allows; with the margin the
            disc still covers it, and GDC1's 0.87 m doors stay passable.
        human_radius: radius of a human disc, m.
        human_lookahead: a walking human is also an obstacle where it will be this many seconds
            later at its present velocity (0: present positions only, as the SPEC's rollout).
            The rollout itself sees a frozen scene; without this, people who walk into a
            slowing or waiting robot make up most collisions (GoAlone among 5-25 humans on GDC1:
            68% of episodes collision-free with 0, 82% with 0.5 s).
        min_wall_distance: hard floor of the escape rule on the centre's wall distance, m: with
            the distance field's lookup error (under 0.02 m) it keeps the footprint's corners
            off the walls even while the robot turns in place.
        min_human_distance: hard floor of the escape rule on robot-human centre distance, m.
        escape_slack: how much closer than now an escaping arc may pass, m.
        slide_band: a robot closer than wall_distance + slide_band to a wall turns towards its
            target slid along that wall (see ArcEvaluation.bearing), m.
        stuck_length: a robot whose every arc is blocked by walls within this is stuck, m.
        recovery_length: how far a stuck robot looks along candidate headings, m.
        recovery_angle_deg: a stuck robot turns in place until its heading is within this of
            the recovery direction, degrees.
        sample_spacing: spacing of wall-check samples along an arc, m.
        near_sample_spacing: finer spacing used up to `near_range`, m.
        near_range: extent of the finely sampled start of each arc, m.
        field_resolution: cell size of the wall distance field, m.
    """

    curvature_min: float = -2.0
    curvature_max: float = 2.0
    curvature_step: float = 0.1
    turn_in_place_angle_deg: float = 30.0
    turn_in_place_max_speed: float = 0.1
    obstacle_margin: float = 0.1
    max_arc_length: float = 5.0
    target_clip: float = 1.5
    clearance_cap: float = 1.0
    planner_accel: float = 5.0
    progress_weight: float = 1.0
    free_path_weight: float = 0.1
    robot_radius: float = 0.27
    human_radius: float = 0.2
    human_lookahead: float = 0.5
    min_wall_distance: float = 0.355
    min_human_distance: float = 0.45
    escape_slack: float = 0.04
    slide_band: float = 0.1
    stuck_length: float = 0.05
    recovery_length: float = 0.6
    recovery_angle_deg: float = 2.0
    sample_spacing: float = 0.1
    near_sample_spacing: float = 0.05
    near_range: float = 0.3
    field_resolution: float = 0.025

    def __post_init__(self) -> None:
        nonnegative = {"obstacle_margin", "progress_weight", "free_path_weight", "escape_slack", "near_range"}
        nonnegative |= {"human_lookahead", "turn_in_place_max_speed", "turn_in_place_angle_deg"}
        check_fields(self, nonnegative=nonnegative, signed=("curvature_min", "curvature_max"))
        if self.curvature_min >= self.curvature_max:
            raise ValueError(
                f"LocalPlannerConfig.curvature_min ({self.curvature_min!r}) must be below "
                f"curvature_max ({self.curvature_max!r})"
            )
        steps = (self.curvature_max - self.curvature_min) / self.curvature_step
        if abs(steps - round(steps)) > 1e-6:
            raise ValueError(
                f"LocalPlannerConfig.curvature_step ({self.curvature_step!r}) must divide "
                f"curvature_max - curvature_min ({self.curvature_max - self.curvature_min!r})"
            )
        check_number("LocalPlannerConfig", "turn_in_place_angle_deg", self.turn_in_place_angle_deg, high=180)
        for name, most, what in (
            ("min_wall_distance", self.wall_distance, "robot_radius + obstacle_margin"),
            ("min_human_distance", self.human_distance, "robot_radius + obstacle_margin + human_radius"),
            ("near_sample_spacing", self.sample_spacing, "sample_spacing"),
        ):
            if getattr(self, name) > most:
                raise ValueError(
                    f"LocalPlannerConfig.{name} ({getattr(self, name)!r}) exceeds {what} ({most!r})"
                )

    @property
    def curvatures(self) -> np.ndarray:
        """(A,) sampled curvatures, 1/m, increasing (A = 41 by default)."""
        count = round((self.curvature_max - self.curvature_min) / self.curvature_step) + 1
        return np.round(np.linspace(self.curvature_min, self.curvature_max, count), 12)

    @property
    def wall_distance(self) -> float:
        """Required distance from the robot centre to walls, m."""
        return self.robot_radius + self.obstacle_margin

    @property
    def human_distance(self) -> float:
        """Required robot-human centre distance, m."""
        return self.robot_radius + self.obstacle_margin + self.human_radius

    @property
    def field_pad(self) -> float:
        """The distance field extends this far past the walls, m: arcs (at most about 1.1 times
        the clipped target distance) of robots inside the walls' bounding box stay on the grid
        (a sample off the grid would read its border cell)."""
        return min(self.max_arc_length, 2.0 * self.target_clip)

    @property
    def field_range(self) -> float:
        """Distances are resolved up to this in the wall distance field, m."""
        return max(self.wall_distance, self.robot_radius + self.clearance_cap) + 0.1
