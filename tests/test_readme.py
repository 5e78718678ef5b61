"""The README's Python examples run as written (each ```python block, in a fresh namespace)."""

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
# The block's first import names the library it shows; torch-based ones need the train extra.
NEEDS = {"stable_baselines3": "stable_baselines3", "torchrl": "torchrl"}


def _title(block: str) -> str:
    return block.strip().splitlines()[0][:60]


def test_readme_has_the_four_examples():
    text = "\n".join(BLOCKS)
    for needle in ("gym.make(", "parallel_env(", "SB3VecEnv(", "ActionSelectionTorchEnv("):
        assert needle in text, f"the README lost its example with {needle}"


@pytest.fixture
def one_torch_thread():
    """torch on one thread while the block runs: the tests share few cores (as the trainers' --threads)."""
    torch = pytest.importorskip("torch")
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.mark.parametrize("block", BLOCKS, ids=[_title(b) for b in BLOCKS])
def test_readme_block_runs(block, request):
    for name, module in NEEDS.items():
        if name in block:
            pytest.importorskip(module)
            request.getfixturevalue("one_torch_thread")
    exec(compile(block, str(README), "exec"), {"__name__": "__readme__"})
