"""Shared test fixtures."""

import importlib.util
import json
from pathlib import Path

import pytest

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


def _load_tool(name: str):
    """The module of tools/<name>.py (the tools folder is not a package)."""
    path = Path(__file__).resolve().parents[1] / "tools" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def load_tool():
    """A function name -> the module of tools/<name>.py."""
    return _load_tool
