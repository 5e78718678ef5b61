"""`socialzoo metrics LOG.json ...`: a table per log, the CSV of all of them, and a bad log a named
error (exit 2) with nothing written."""

import csv
import json

import numpy as np
import pytest

from socialzoo.bench.episode_log import make_episode_log, write_episode_log
from socialzoo.cli import main
from socialzoo.core.metrics import names


def _log(tmp_path, name, xs):
    pos = np.stack([np.asarray(xs, float), np.zeros(len(xs))], axis=1)
    log = make_episode_log(dt=0.5, robot_pos=pos, goal=[3, 0], robot_radius=0.3, goal_radius=0.5, label=name)
    return write_episode_log(tmp_path / f"{name}.json", log)


def test_tables_and_csv(tmp_path, capsys):
    # "fast" reaches x = 2.5 (within 0.5 m of the goal) after 3 steps of 0.5 s; "slow" never does.
    fast, slow = _log(tmp_path, "fast", [0, 1, 2, 2.5]), _log(tmp_path, "slow", [0, 0.1, 0.2])
    out = tmp_path / "table.csv"
    assert main(["metrics", str(fast), str(slow), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"{fast} (fast)" in printed and f"{slow} (slow)" in printed
    assert "gl_time_to_goal" in printed and "1.50  s" in printed
    rows = list(csv.DictReader(out.open()))
    assert [r["metric"] for r in rows] == list(names("guidelines")) * 2
    by = {(r["label"], r["metric"]): r for r in rows}
    assert by[("fast", "gl_success")]["value"] == "1" and by[("slow", "gl_success")]["value"] == "0"
    assert (
        float(by[("fast", "gl_path_length")]["value"]) == 2.5
        and by[("fast", "gl_path_length")]["unit"] == "m"
    )
    assert by[("slow", "gl_time_to_goal")]["value"] == "nan"


def test_a_bad_log_names_file_and_field_and_writes_nothing(tmp_path, capsys):
    good = _log(tmp_path, "good", [0, 1])
    bad = tmp_path / "bad.json"
    data = json.loads(good.read_text())
    data["robot"]["goal_radius"] = "half a metre"
    bad.write_text(json.dumps(data))
    out = tmp_path / "table.csv"
    assert main(["metrics", str(good), str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr()
    # One line in the CLI's form, "socialzoo COMMAND: error: ...", as every other command's input errors.
    assert err.err.startswith("socialzoo metrics: error: invalid episode log: ")
    assert f"{bad}: robot.goal_radius: 'half a metre' is not of type 'number'" in err.err
    assert err.out == "" and not out.exists()


def test_thresholds_are_options(tmp_path, capsys):
    log = _log(tmp_path, "slow", [0, 0.1, 0.2])
    assert main(["metrics", str(log), "--stall-speed", "0.5"]) == 0
    assert "gl_stalled_time                 1.00  s" in capsys.readouterr().out  # both steps at 0.2 m/s
    assert main(["metrics", str(log), "--progress-time", "0"]) == 2
    assert (err := capsys.readouterr().err).startswith("socialzoo metrics: error: ")
    assert "progress_time must be > 0" in err


def test_an_out_that_is_one_of_the_logs_is_refused_and_the_log_kept(tmp_path, capsys, monkeypatch):
    # `socialzoo metrics run.json --out run.json` (a --out typed where a log was meant) wrote the
    # CSV over the episode log it had just read: the log was lost.
    log = _log(tmp_path, "run", [0, 1, 2])
    before = log.read_bytes()
    monkeypatch.chdir(tmp_path)
    for out in (str(log), "run.json", "./sub/../run.json"):
        (tmp_path / "sub").mkdir(exist_ok=True)
        assert main(["metrics", str(log), "--out", out]) == 2
        err = capsys.readouterr().err
        assert err.startswith("socialzoo metrics: error: --out") and "run.json" in err
        assert log.read_bytes() == before


def test_out_help_names_the_columns_written(tmp_path, capsys):
    # --help said "(log, metric, value, unit)" while the CSV has a label column too (docs/guideline_metrics.md
    # names all five); found following that page.
    with pytest.raises(SystemExit):
        main(["metrics", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    out = tmp_path / "table.csv"
    assert main(["metrics", str(_log(tmp_path, "one", [0, 1])), "--out", str(out)]) == 0
    header = out.read_text().splitlines()[0].split(",")
    assert f"this CSV ({', '.join(header)})" in help_text
