"""The scripts of benchmarks/ at their smallest sizes: their --json output is JSON (figures are never
asserted here; speed is read from the scripts' own output)."""

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def script(name: str):
    """The module of benchmarks/NAME.py (its folder on the path, for `_common`)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
        sys.modules[name] = module  # dataclasses look their module up there
        spec.loader.exec_module(module)  # type: ignore[union-attr]
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return module


def test_harness_figures_are_json_when_every_trial_is_in_the_tail():
    # With N <= B every trial has a row from the start: no body, whose rates were NaN, not JSON.
    figures = script("harness_throughput").measure("gdc1", ["goalone"], trials=1, batch=2)
    assert figures["body_trials"] == 0
    assert figures["body_trials_per_s"] is None and figures["body_trials_per_cpu_s"] is None
    assert json.loads(json.dumps(figures, allow_nan=False))["tail_trials"] == 1


def test_render_speed_prints_json_lines(monkeypatch, capsys, tmp_path):
    # DEVELOPERS.md and compare_commits.py count on --json in every script; render_speed had none.
    argv = ["render_speed.py", "--steps", "2", "--map", "hallway", "--json", "--gif", str(tmp_path / "a.gif")]
    monkeypatch.setattr(sys, "argv", argv)
    script("render_speed").main()
    figures = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [f["name"] for f in figures] == ["follow 640x480 antialias=2", "map 640x480 antialias=2"]
    assert all(f["frames"] == 2 and f["frames_per_s"] > 0 for f in figures)
    assert figures[0]["gif_frames"] == 1


def test_a_peak_not_measured_is_printed_as_none_not_zero(capsys):
    # world_throughput --counterfactual's episodes measure no peak and printed "peak 0.0 MiB".
    common = script("_common")
    figure = common.Figure("episodes sf", 2, 10.0, 250.0, None)
    common.report(figure, as_json=True)
    common.report(figure, as_json=False)
    as_json, text = capsys.readouterr().out.splitlines()
    assert json.loads(as_json)["peak_mem_mib"] is None
    assert "peak" not in text and "agent-steps/s" in text


def test_a_kernel_compiled_during_the_timed_calls_is_not_timed():
    # With a cold numba cache, env_throughput's single env compiled arc_wall_codes on its 6th call, the
    # first timed one: 1 env-step/s printed at --seconds 0.5 (1,355 once the cache was warm).
    import numba

    common = script("_common")
    kernel = numba.njit(lambda x: x + 1.5)
    calls = [0]

    def step() -> None:
        calls[0] += 1
        if calls[0] == 7:  # the second timed call compiles (a new kernel: seconds)
            kernel(1.0)

    _, timed = common.measure(step, seconds=0.05, warmup=5)
    assert timed > 10


def test_a_kernel_compiled_while_traced_is_not_in_the_peak():
    # nav_throughput --batches 1 4 with a cold numba cache printed a peak of 14.8 MiB at B=4 (0.6 MiB
    # warm): B > 1 passes arrays of another layout, whose kernels compiled inside the traced steps.
    import numba
    import numpy as np

    common = script("_common")
    kernel = numba.njit(lambda x: x * 2.5)

    def build():
        data = np.zeros(1000)  # 8 KiB

        def step() -> None:
            kernel(data)

        return step

    assert common.traced_peak_mib(build) < 0.1


@pytest.mark.skipif(not (ROOT / ".git").exists(), reason="compares git revisions of a checkout")
def test_compare_commits_runs_one_revision_against_itself(tmp_path):
    # `compare_commits.py HEAD HEAD ...` (an A/A run: the noise) said "'HEAD' is neither a folder nor a
    # revision": both sides were checked out into one folder, tree-HEAD.
    toy = tmp_path / "toy.py"
    toy.write_text('import json\nprint(json.dumps({"name": "toy", "env_steps_per_s": 5.0}))\n')
    command = [sys.executable, str(ROOT / "benchmarks" / "compare_commits.py"), "HEAD", "HEAD", "toy.py"]
    out = subprocess.run(
        [*command, "--scripts", str(tmp_path), "--rounds", "1", "--no-warmup"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr
    assert "round 1  toy" in out.stdout and "new/old 1.000" in out.stdout


@pytest.mark.parametrize(
    "argv",
    [
        ["world_throughput.py", "--batches", "1", "--humans", "sf", "orca", "--repeats", "0"],
        ["train_throughput.py", "--rows", "0"],
        ["recorded_throughput.py", "--rounds", "0"],
        ["render_speed.py", "--steps", "0"],
        ["reproduce_profile.py", "--body-batches", "64,0"],
    ],
    ids=lambda argv: argv[0],
)
def test_a_count_below_one_is_refused_by_argparse(argv):
    # They ended in a ZeroDivisionError or an IndexError traceback after minutes of measuring, or printed
    # a figure of nothing; now argparse names the option before anything runs.
    out = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / argv[0]), *argv[1:]], capture_output=True, text=True
    )
    assert out.returncode == 2, out.stderr
    assert f"argument {argv[-2]}: expected an integer >= 1" in out.stderr


def test_seconds_must_be_a_finite_positive_number():
    common = script("_common")
    for text in ("0", "-1", "nan", "inf", "x"):
        with pytest.raises(SystemExit):
            common.parser("").parse_args(["--seconds", text])
    assert common.parser("").parse_args(["--seconds", "0.5"]).seconds == 0.5


def test_render_speed_prints_a_small_gif_size_not_as_zero(monkeypatch, capsys, tmp_path):
    # --steps 5 printed "GIF of 3 frames: 0.1 s, 0.0 MiB" for a 22 KiB file.
    argv = ["render_speed.py", "--steps", "2", "--map", "hallway", "--gif", str(tmp_path / "a.gif")]
    monkeypatch.setattr(sys, "argv", argv)
    script("render_speed").main()
    line = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("GIF"))
    assert float(line.split(", ")[-1].removesuffix(" MiB")) == pytest.approx(
        (tmp_path / "a.gif").stat().st_size / 2**20, rel=1e-2
    )


def test_training_scaling_gives_a_speed_up_whatever_the_order_of_modes(monkeypatch, capsys):
    # --modes local,serial printed "speed-up -" for local: the baseline was set only once serial had run.
    import socialzoo.reproduce.backend

    monkeypatch.setattr(socialzoo.reproduce.backend, "run_tasks", lambda *args, **kwargs: None)
    monkeypatch.setattr(sys, "argv", ["training_scaling.py", "--modes", "local,serial", "--json"])
    script("training_scaling").main()
    figures = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [f["mode"] for f in figures] == ["serial", "local"]
    assert all(f["speedup_over_serial"] is not None for f in figures)
