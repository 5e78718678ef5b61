"""Shared test fixtures, and the reference numerics (tools/reference_numerics.py) that the tests'
recorded digests hold under, set before anything imports numpy."""

import importlib.util
import json
from collections.abc import Callable
from pathlib import Path


def _load_tool(name: str):
    """The module of tools/<name>.py (the tools folder is not a package)."""
    path = Path(__file__).resolve().parents[1] / "tools" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# Before numpy's first import (here or in a process a test starts, which inherits the settings).
NUMERICS_PINNED = _load_tool("reference_numerics").use_reference_numerics()

import numpy as np  # noqa: E402
import pytest  # noqa: E402

# The social_gym 1.0 reference data (MIT, see its LICENSE), kept in the repository.
REFERENCE_DIR = Path(__file__).resolve().parents[1] / "maps" / "reference" / "socialgym"

# A small two-room map with a door, for fast episodes in the harness and policy tests.
ROOMS = {
    "format": "socialzoo-map/1",
    "name": "rooms",
    "walls": [[0, 0, 14, 0], [14, 0, 14, 6], [14, 6, 0, 6], [0, 6, 0, 0], [5, 0, 5, 2.2], [5, 3.8, 5, 6]],
    "graph": {
        "nodes": [[1, 1], [1, 5], [3, 3], [5, 3], [7, 3], [9, 3], [11, 3], [13, 1], [13, 5]],
        "edges": [[0, 2], [1, 2], [2, 3], [3, 4], [4, 5], [5, 6], [6, 7], [6, 8]],
    },
    "legal_poses": [[1, 1, 0], [1, 5, 0], [3, 3, 0], [13, 1, 3.14], [13, 5, 3.14], [11, 3, 3.14], [7, 4, 0]],
}


@pytest.fixture(scope="session")
def rooms_map_path(tmp_path_factory):
    """Path of the two-room map written as a socialzoo-map/1 file."""
    path = tmp_path_factory.mktemp("maps") / "rooms.json"
    path.write_text(json.dumps(ROOMS))
    return path


@pytest.fixture(scope="session")
def reference_dir():
    """The folder of the social_gym reference data (walls, gdc1 nodes and legal poses)."""
    return REFERENCE_DIR


def write_walker_policy(path, *, speed: float = 3.0, hidden: int = 8):
    """A learned human policy file that walks straight at its waypoint (human action frame):
    zero weights, so every human's action is tanh(speed) forward whatever it observes."""
    import numpy as np

    from socialzoo.env.config import EnvConfig
    from socialzoo.env.human_agents import human_observation_size
    from socialzoo.env.human_policy import LearnedHumanPolicy
    from socialzoo.env.policy_file import current_env_version

    k = EnvConfig().num_human_neighbours
    size = human_observation_size(k)
    layers = [
        (np.zeros((hidden, size)), np.zeros(hidden)),
        (np.zeros((2, hidden)), np.array([speed, 0.0])),
    ]
    policy = LearnedHumanPolicy(layers, "tanh", np.zeros(size), np.ones(size), k, "human")
    return policy.save(
        path, f"socialzoo/MultiAgent-v{current_env_version()}", {"algo": "handmade", "seed": 0}
    )


@pytest.fixture(scope="session")
def write_walker():
    """write_walker_policy, for tests that need walkers of other speeds."""
    return write_walker_policy


@pytest.fixture(scope="session")
def walker_policy_path(tmp_path_factory):
    """A learned human policy file whose humans walk straight at their waypoints."""
    return write_walker_policy(tmp_path_factory.mktemp("humans") / "walker.safetensors")


# A small Ref demonstration recording shared by the imitation and study tests: its episodes and
# their time limit (steps), about 3,000 transitions in all.
DEMO_EPISODES = 12
DEMO_MAX_STEPS = 250


@pytest.fixture(scope="session")
def small_demos(tmp_path_factory):
    """A demonstration file of DEMO_EPISODES Ref episodes on gdc1, cut at DEMO_MAX_STEPS steps
    (the tests that use it train with torch and TorchRL: skipped without them)."""
    pytest.importorskip("torch")
    pytest.importorskip("torchrl")
    from socialzoo.bench.demonstrations import DemoConfig, record_demonstrations

    path = tmp_path_factory.mktemp("demos") / "ref.npz"
    config = DemoConfig(
        episodes=DEMO_EPISODES,
        chunk_episodes=DEMO_EPISODES,
        batch_size=DEMO_EPISODES,
        env_overrides={"max_steps": DEMO_MAX_STEPS},
    )
    return record_demonstrations(path, config)


@pytest.fixture(scope="session")
def load_tool():
    """A function name -> the module of tools/<name>.py."""
    return _load_tool


# ------------------------------------------------------------------ random buildings (maps, navigation)


def _random_building(rng: np.random.Generator) -> np.ndarray:
    """A grid of rooms: walls every 4 m with 1 m door gaps, plus a few random segments; (W, 4)."""
    walls = []
    for x in range(0, 21, 4):
        for y0 in range(0, 20, 4):
            walls.append((x, y0, x, y0 + 1.5))
            walls.append((x, y0 + 2.5, x, y0 + 4))
            walls.append((y0, x, y0 + 1.5, x))
            walls.append((y0 + 2.5, x, y0 + 4, x))
    a = rng.uniform(0, 20, (15, 2))
    extra = np.hstack((a, a + rng.uniform(-1.5, 1.5, (15, 2))))
    return np.vstack((np.array(walls, float), extra))


@pytest.fixture
def random_building() -> Callable[[np.random.Generator], np.ndarray]:
    """Walls of a 20 m x 20 m building of 4 m rooms with doors, drawn from a generator."""
    return _random_building


def run_go_alone(m, starts: np.ndarray, goals: np.ndarray, max_steps: int = 3200) -> tuple[np.ndarray, ...]:
    """GoAlone without humans from each start (K, 3) to each goal (K, 2), as one batch, through the
    navigator (its carrot kept in sight, as the envs do), the sub-policy and the robot motion model.

    Returns:
        (reached (K,) bool, hit_wall (K,) bool, steps (K,) int, final pose (K, 3)).
    """
    from socialzoo.core.config import WorldConfig
    from socialzoo.core.robot import step_robot
    from socialzoo.nav.distance_field import distance_field
    from socialzoo.nav.graph import graph_of
    from socialzoo.nav.local_planner import LocalPlannerConfig
    from socialzoo.nav.navigator import Navigator, Sight
    from socialzoo.nav.subpolicies import GO_ALONE, HALT, SubPolicyConfig, subpolicy_commands

    walls = m.wall_index
    world = WorldConfig()
    robot = world.robot
    sub, planner = SubPolicyConfig(), LocalPlannerConfig()
    n = len(starts)
    pose = np.asarray(starts, dtype=np.float64).copy()
    vel = np.zeros((n, 2))
    target = np.asarray(goals, dtype=np.float64)[:, :2]
    field = distance_field(walls, planner.field_resolution, planner.field_range, planner.field_pad)
    nav = Navigator(graph_of(m), n, sight=Sight(field, planner.wall_distance))
    nav.reset(np.arange(n), pose[:, None, :2], target[:, None])
    no_humans = (np.zeros((n, 0, 2)), np.zeros((n, 0, 2)), np.zeros((n, 0), dtype=bool))
    done = np.zeros(n, dtype=bool)
    reached = np.zeros(n, dtype=bool)
    hit_wall = np.zeros(n, dtype=bool)
    steps = np.full(n, max_steps)
    for t in range(max_steps):
        carrot = nav.update(pose[:, None, :2])[:, 0]
        action = np.where(done, HALT, GO_ALONE)  # finished robots halt (and cost nothing)
        command, halt, _ = subpolicy_commands(
            action, pose, vel, carrot, *no_humans, walls, sub, planner, robot, world.dt
        )
        pose, vel = step_robot(pose, vel, command, halt, world.dt, robot)
        hit = walls.footprint_hits(pose, robot.half_length, robot.half_width) & ~done
        arrived = (np.hypot(*(pose[:, :2] - target).T) < 0.5) & ~done
        hit_wall |= hit
        reached |= arrived
        steps[hit | arrived] = t + 1
        done |= hit | arrived
        if done.all():
            break
    return reached, hit_wall, steps, pose


@pytest.fixture
def go_alone() -> Callable[..., tuple[np.ndarray, ...]]:
    """`run_go_alone`: GoAlone without humans on a batch of start/goal pairs."""
    return run_go_alone
