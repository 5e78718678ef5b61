"""tools/check_replay.py on recordings of one's own: any frame rate, any size of scene."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from socialzoo.data import Recording, Track
from socialzoo.scenarios.catalogue import FAMILIES, register_family
from socialzoo.scenarios.recorded import RecordedScene

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("check_replay", ROOT / "tools" / "check_replay.py")
check_replay = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
spec.loader.exec_module(check_replay)  # type: ignore[union-attr]


def _family(name: str, dt: float, count: int) -> str:
    """A recorded family of `count` people crossing a square, frames dt s apart (walking 1.2 m/s)."""
    if name not in FAMILIES:
        rng = np.random.default_rng(1)
        tracks = []
        for person in range(count):
            a, b = rng.uniform(-8, 8, 2), rng.uniform(-8, 8, 2)
            n = int(np.ceil(np.hypot(*(b - a)) / 1.2 / dt)) + 1
            tracks.append(Track(person, int(rng.integers(0, round(60 / dt))), np.linspace(a, b, n)))
        tracks.sort(key=lambda t: (t.first_frame, t.person))
        frames = max(t.last_frame for t in tracks) + 1
        recording = Recording(name=name, dt=dt, num_frames=frames, tracks=tuple(tracks), source="test")
        register_family(RecordedScene(recording, name=name))
    return name


@pytest.mark.parametrize(
    ("dt", "count"),
    [(0.4, 60), (0.04, 60), (0.4, 3)],  # 2.5 Hz; 25 Hz (a frame shorter than the 0.1 s step); no test split
)
def test_every_recorded_position_is_replayed_where_the_file_has_it(dt, count):
    name = _family(f"recorded_check_{round(1 / dt)}hz_{count}", dt, count)
    compared, worst, mismatched = check_replay.check_scene(name, cases=8)
    assert compared > 0
    assert worst < 0.01 and mismatched == 0


def test_no_cases_is_refused_by_argparse(monkeypatch, capsys):
    # --cases 0 ended in an IndexError traceback (scenarios[0] of no scenarios).
    monkeypatch.setattr("sys.argv", ["check_replay.py", "--scenes", "eth", "--cases", "0"])
    with pytest.raises(SystemExit) as exit_:
        check_replay.main()
    assert (
        exit_.value.code == 2 and "argument --cases: expected a positive integer" in capsys.readouterr().err
    )
