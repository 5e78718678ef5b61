"""`socialzoo steps-to-ref`: its answer in words and its argument checks."""

from socialzoo.cli import main
from socialzoo.cli.steps_cmd import describe


def _record(steps, steps_ci, rates):
    return {
        "reference": {"label": "ref", "success_rate": 0.9},
        "checkpoints": [{"step": 50_000 * (i + 1), "success_rate": r} for i, r in enumerate(rates)],
        "steps": steps,
        "steps_ci": steps_ci,
        "trials": 200,
        "validation_set": "gdc1-val",
        "total_steps": 50_000 * len(rates),
    }


def test_describe_names_the_step_or_the_best_checkpoint():
    found = describe(_record(100_000, 50_000, [0.85, 0.92]))
    assert "ref succeeds in 90.0% of 200 gdc1-val" in found
    assert "after 100,000 steps" in found and "covers it after 50,000" in found
    missed = describe(_record(None, None, [0.5, 0.7, 0.6]))
    assert "No PPO checkpoint up to 150,000 steps reaches it" in missed and "70.0% at 100,000" in missed


def test_total_steps_must_be_a_multiple_of_the_checkpoint_interval(tmp_path, capsys):
    code = main(
        ["steps-to-ref", "--out", str(tmp_path), "--total-steps", "1000", "--checkpoint-every", "300"]
    )
    assert code == 2
    assert "--total-steps (1000) must be a multiple of --checkpoint-every (300)" in capsys.readouterr().err


def test_a_run_folder_of_other_arguments_is_a_usage_error(tmp_path, capsys):
    # Found rerunning `socialzoo steps-to-ref --out DIR` with another --total-steps: a RunDirError
    # traceback (exit status 1) instead of the one line `socialzoo train` gives for the same folder.
    from socialzoo.train.ppo import PPOArgs
    from socialzoo.train.run_dir import RunDir

    run = tmp_path / "ppo_long"
    RunDir(run, "ppo", PPOArgs(out=run, total_steps=4000, checkpoint_every=2000))
    before = (run / "run.json").read_text()
    argv = ["--total-steps", "2000", "--checkpoint-every", "2000", "--no-progress", "--no-figures"]
    assert main(["steps-to-ref", "--out", str(tmp_path), *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("socialzoo steps-to-ref: error: ") and "total_steps differ" in err
    assert (run / "run.json").read_text() == before
