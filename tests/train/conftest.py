"""A small Ref demonstration recording shared by the imitation tests (short gdc1 episodes)."""

import pytest

# Episodes of the small recording, and its time limit (steps): about 3,000 transitions.
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
