"""Put a re-run of one learned policy's seeds into the published reproduction.

    python tools/rerun_policy_rows.py --policy pips --seed 0=S0.json --seed 1=S1.json ... \\
        --performance BENCH_GDC1 --transfer BENCH_GHC3 --ref BENCH_REF \\
        --command "socialzoo train pips --demos DEMOS --seed K --out SK.json" \\
        --command "socialzoo benchmark --policies pips:S0.json,... --maps gdc1 --trials 2000" \\
        --why "The synthesiser changed (issue 38)."

Each --seed names a training seed of the published run and its policy file, evaluated in the
benchmark folders as `<policy>:<file>`; BENCH_REF holds Ref on both maps. The rows go in by
socialzoo.reproduce.rerun_rows.replace_policy_rows (which checks Ref's trials against the published
ones), each seed's training record keeps the published run's name, and the tables, figures and
REPRODUCTION.md are drawn again from results/reproduction/. --root is the repository (default: the
current folder).
"""

from __future__ import annotations

import argparse
import json
import subprocess
from pathlib import Path
from typing import Any

from socialzoo.reproduce.publish import PUBLISHED_DIR, redraw_published
from socialzoo.reproduce.rerun_rows import PolicyRerun, replace_policy_rows
from socialzoo.reproduce.results import RESULTS_DIR, TRAINING_FILE


def training_record(policy: str, seed: int, file: Path, run_name: str) -> dict[str, Any]:
    """training.json's record of one re-run training: a PIPS program's sidecar, or the trainer's
    run.json beside the policy file."""
    if policy == "pips":
        from socialzoo.train.pips import read_program_record

        data = read_program_record(file)
    else:
        path = file.parent / "run.json"
        data = json.loads(path.read_text()) if path.is_file() else {}
    if not data:
        raise SystemExit(f"{file}: no training record beside it (NAME.train.json or run.json)")
    args, results = data.get("args", {}), data.get("results", {})
    return {
        "run": run_name,
        "trainer": policy,
        "demonstration_steps": args.get("steps") if policy in ("bc", "gail", "pips") else None,
        "env_steps": results.get("env_steps"),
        "wall_seconds": round(float(data.get("wall_seconds", results.get("wall_seconds", 0.0))), 1),
        "seed": seed,
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--policy", required=True)
    parser.add_argument("--seed", action="append", required=True, help="SEED=POLICY_FILE, once per seed")
    parser.add_argument("--performance", type=Path, required=True)
    parser.add_argument("--transfer", type=Path, required=True)
    parser.add_argument("--ref", type=Path, required=True)
    parser.add_argument("--command", action="append", default=[])
    parser.add_argument("--why", default="")
    parser.add_argument(
        "--ref-tolerance",
        type=int,
        default=0,
        help="scenarios Ref's successes may differ by per map (default 0)",
    )
    parser.add_argument("--root", type=Path, default=Path("."))
    args = parser.parse_args()
    files = {int(k): Path(v).resolve() for k, v in (s.split("=", 1) for s in args.seed)}
    base = args.root / PUBLISHED_DIR
    published = json.loads((base / RESULTS_DIR / TRAINING_FILE).read_text())
    names = {int(t["seed"]): t["run"] for t in published if t.get("trainer") == args.policy}
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=args.root, capture_output=True, text=True, check=True
    ).stdout.strip()
    rerun = PolicyRerun(
        policy=args.policy,
        seed_specs={seed: f"{args.policy}:{file}" for seed, file in files.items()},
        performance=args.performance,
        transfer=args.transfer,
        ref=args.ref,
        commands=tuple(args.command),
        commit=commit,
        training=tuple(
            training_record(args.policy, seed, file, names.get(seed, f"{args.policy}-s{seed}"))
            for seed, file in sorted(files.items())
        ),
        why=args.why,
        ref_tolerance=args.ref_tolerance,
    )
    for path in replace_policy_rows(base, rerun):
        print("rewrote", path)
    print("wrote", redraw_published(args.root))


if __name__ == "__main__":
    main()
