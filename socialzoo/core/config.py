"""Configuration of the world: robot, humans, laser and time step (SPEC sections 2 to 4)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, get_args

from socialzoo.core.validation import check_choice, check_fields, check_number

Kinematics = Literal["differential", "holonomic", "unicycle"]
KINEMATICS: tuple[str, ...] = get_args(Kinematics)


@dataclass(frozen=True, kw_only=True)
class RobotConfig:
    """The robot's motion model and footprint: the benchmark's differential drive (SPEC section 3)
    by default, or the holonomic and unicycle robots of the CrowdNav line of work.

    Kinematics (socialzoo.core.robot.step_robot) and what a command and the velocity state mean:
    - "differential": command (v, omega), m/s and rad/s, reached under the acceleration limits;
      the position advances by the mean of the old and new speed along the heading (SPEC 3).
    - "holonomic": command (vx, vy), world frame, m/s, taken at once (CrowdNav's ActionXY), its
      norm capped at max_speed; the heading stays as it is.
    - "unicycle": command (v, omega): the heading turns by omega * dt (at most max_rotation per
      step) and the robot then moves v * dt along the new heading, both at once (CrowdNav's
      ActionRot); 0 <= v <= max_speed.

    Attributes:
        length: footprint length along the heading, m (collision footprint).
        width: footprint width, m.
        max_linear_accel: motion-model limit on |dv/dt|, m/s^2 (differential drive).
        max_angular_accel: motion-model limit on |domega/dt|, rad/s^2 (differential drive).
        max_angular_speed: motion-model clamp on |omega|, rad/s (differential drive).
        max_speed: hard cap on the speed in the motion model, m/s (the sub-policies ask for less).
        kinematics: "differential", "holonomic" or "unicycle".
        radius: a disc footprint of this radius, m, instead of the length x width box (the
            CrowdNav robots: 0.3); None: the box.
        max_rotation: a unicycle's largest turn in one step, rad (CrowdNav: pi / 4).
    """

    length: float = 0.5
    width: float = 0.43
    max_linear_accel: float = 6.0
    max_angular_accel: float = 5.0
    max_angular_speed: float = 3.0
    max_speed: float = 2.25
    kinematics: Kinematics = "differential"
    radius: float | None = None
    max_rotation: float = math.pi / 4

    def __post_init__(self) -> None:
        check_fields(self)
        check_choice("RobotConfig", "kinematics", self.kinematics, KINEMATICS)
        check_number("RobotConfig", "max_rotation", self.max_rotation, low=0, low_open=True, high=math.pi)

    @property
    def half_length(self) -> float:
        """Half the footprint's length, m."""
        return self.length / 2.0

    @property
    def half_width(self) -> float:
        """Half the footprint's width, m."""
        return self.width / 2.0


@dataclass(frozen=True, kw_only=True)
class HumanConfig:
    """Social-force pedestrians (SPEC section 4, PedSim's Helbing-Molnar-Moussaid model).

    How many humans there are, where they spawn and how fast they prefer to walk is the scenario's
    business (socialzoo.scenarios.generator.ScenarioConfig); walls beyond the map's WallIndex reach
    (1 m) exert no force.

    Attributes:
        force_radius: agent radius subtracted from the wall distance in the obstacle force, m.
            PedSim's agentRadius, 0.2; the SPEC also lists a "social-force radius" of 0.4, which
            keeps humans 0.4-0.5 m off walls and squeezes them into robots standing in corridors
            (GoAlone on gdc1-quick: 89% collision-free at 0.4, 97% at 0.2; paper 97.5%).
        radius: collision and sensing radius, m.
        relaxation_time: tau of the desired force, s.
        desired_factor: weight of the desired force.
        obstacle_strength: weight of the wall force.
        obstacle_sigma: range of the wall force, m.
        social_strength: weight of the agent-agent force. SPEC gives "about 5 to 7.5"; 7.5 is
            the value that reproduces the paper's GoAlone success best (GoAlone on gdc1-quick,
            with force_radius 0.2: 95% collision-free at 5.0, 97% at 7.5; see docs/benchmark.md).
        social_lambda, social_gamma, social_n, social_n_prime: Moussaid parameters.
        robot_scale: robot-human position differences are divided by this before the social force.
        waypoint_radius: a waypoint within this distance counts as reached, m.
        learned_forces: whether the social and wall forces also act on people who walk by a
            learner's desired velocity (False: the desired velocity alone, through the relaxation;
            walls stay solid). A learned people policy file says which it was trained with
            (socialzoo.env.human_policy.LearnedHumanPolicy.learned_forces), and the world that
            walks it takes that.
        learned_relaxation_time: tau of the relaxation of people who walk by a learner's desired
            velocity towards it, s (None: relaxation_time). A learned people policy file may say
            which it was trained with (LearnedHumanPolicy.relaxation_time), and the world that
            walks it takes that.
    """

    force_radius: float = 0.2
    radius: float = 0.2
    relaxation_time: float = 0.5
    desired_factor: float = 1.0
    obstacle_strength: float = 5.0
    obstacle_sigma: float = 0.1
    social_strength: float = 7.5
    social_lambda: float = 2.0
    social_gamma: float = 0.35
    social_n: float = 2.0
    social_n_prime: float = 3.0
    robot_scale: float = 1.5
    waypoint_radius: float = 1.0
    learned_forces: bool = True
    learned_relaxation_time: float | None = None

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("obstacle_strength", "social_strength"))

    @property
    def learned_tau(self) -> float:
        """The learned people's relaxation time, s."""
        return self.relaxation_time if self.learned_relaxation_time is None else self.learned_relaxation_time


@dataclass(frozen=True, kw_only=True)
class LaserConfig:
    """2D laser scan against walls and human discs.

    Attributes:
        num_rays: rays evenly spread over the field of view.
        fov_deg: field of view, degrees, centred on the heading.
        max_range: m.
        noise_std: Gaussian range noise, m (0 for none).
    """

    num_rays: int = 180
    fov_deg: float = 270.0
    max_range: float = 10.0
    noise_std: float = 0.0

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("noise_std",))
        check_number("LaserConfig", "fov_deg", self.fov_deg, high=360)


@dataclass(frozen=True, kw_only=True)
class OrcaConfig:
    """ORCA people (socialzoo.humans.orca; van den Berg et al. 2011), the reference library's
    parameters by name. Two documented sets: the defaults, fitted to the benchmark's
    social-force people (tools/fit_orca.py: the closest mean and 10th-percentile speed, reach
    rate and time to goal on gdc1's validation scenarios; docs/humans.md), and CrowdNav's
    (`OrcaConfig.preset("crowdnav")`).

    Attributes:
        neighbor_dist: agents farther than this are not avoided, m.
        max_neighbors: at most this many nearest agents are avoided.
        time_horizon: agents avoid each other for this long ahead, s.
        time_horizon_obst: agents avoid walls for this long ahead, s (the walls within
            time_horizon_obst * speed + radius count).
        radius: a person's radius in ORCA's constraints, m.
        max_speed: the speed limit, m/s; None: each person's preferred speed (the scenario's).
        robot_visible: the people see and avoid the robots (False: CrowdNav's invisible robot).
        robot_radius: the radius the people give a robot, m; None: the robot's disc radius, or
            the half-diagonal of its box footprint (0.33 m for the benchmark's robot).
    """

    neighbor_dist: float = 4.0
    max_neighbors: int = 10
    time_horizon: float = 2.0
    time_horizon_obst: float = 0.45
    radius: float = 0.35
    max_speed: float | None = None
    robot_visible: bool = True
    robot_radius: float | None = None

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("max_neighbors",))
        if not isinstance(self.robot_visible, bool):
            raise ValueError(f"OrcaConfig.robot_visible must be a bool, got {self.robot_visible!r}")

    @classmethod
    def preset(cls, name: str) -> OrcaConfig:
        """A documented parameter set: "socialzoo" (the defaults) or "crowdnav" (CrowdNav's
        people: neighbor_dist 10, max_neighbors 10, time_horizon 5, time_horizon_obst 5,
        radius 0.3, max_speed 1; its robot is invisible only in CrowdNav's own task, so set
        robot_visible=False with `dataclasses.replace` to have that too).

        Raises:
            ValueError: an unknown name, listing the known ones.
        """
        presets = {
            "socialzoo": {},
            "crowdnav": {
                "neighbor_dist": 10.0,
                "max_neighbors": 10,
                "time_horizon": 5.0,
                "time_horizon_obst": 5.0,
                "radius": 0.3,
                "max_speed": 1.0,
            },
        }
        if name not in presets:
            raise ValueError(f"unknown ORCA parameter set {name!r}; known: {sorted(presets)}")
        return cls(**presets[name])  # type: ignore[arg-type]

    def robot_disc(self, robot: RobotConfig) -> float:
        """The radius the people give a robot of config `robot`, m."""
        if self.robot_radius is not None:
            return self.robot_radius
        disc = getattr(robot, "radius", None)
        return float(disc) if disc is not None else math.hypot(robot.half_length, robot.half_width)


@dataclass(frozen=True, kw_only=True)
class GroupConfig:
    """The forces that keep a walking group together (Moussaid et al. 2010, "The walking
    behaviour of pedestrian social groups and its impact on crowd dynamics"), added to the social
    force of people who walk in a group (socialzoo.humans.groups). The defaults are PySocialForce's.

    Attributes:
        coherence: weight of the attraction to the group's centre of mass, beyond
            (group size - 1) / 2 m from it (Moussaid's beta_2; PySocialForce 3.0).
        repulsion: weight of the push away from a member closer than repulsion_threshold
            (beta_3; PySocialForce 1.0).
        repulsion_threshold: m (PySocialForce 0.55).
        gaze: weight of the slowing down that keeps the others' centre in the field of view
            (beta_1; PySocialForce 4.0).
        vision_deg: half-width of the field of view, degrees (Moussaid: 90).
    """

    coherence: float = 3.0
    repulsion: float = 1.0
    repulsion_threshold: float = 0.55
    gaze: float = 4.0
    vision_deg: float = 90.0

    def __post_init__(self) -> None:
        check_fields(self, nonnegative=("coherence", "repulsion", "gaze"))
        check_number("GroupConfig", "vision_deg", self.vision_deg, low=0, high=180, low_open=True)


@dataclass(frozen=True, kw_only=True)
class WorldConfig:
    """Everything the world step needs besides the map and the state.

    Attributes:
        dt: physics and decision step, s (SPEC: 0.025).
        robot: robot parameters.
        human: human parameters.
        laser: laser parameters, or None for no scan.
        human_collision_distance: robot-human centre distance counted as a collision, m.
        orca: parameters of the people that ORCA drives (WorldState.human_model).
        groups: the group forces of people who walk in a group (WorldState.human_group).
    """

    dt: float = 0.025
    robot: RobotConfig = field(default_factory=RobotConfig)
    human: HumanConfig = field(default_factory=HumanConfig)
    laser: LaserConfig | None = None
    human_collision_distance: float = 0.4
    orca: OrcaConfig = field(default_factory=OrcaConfig)
    groups: GroupConfig = field(default_factory=GroupConfig)

    def __post_init__(self) -> None:
        check_fields(self)
