"""REPRODUCTION.md: for every table and figure of the paper, ours beside the paper's, the command, the wall time of
each part on this machine, and an explanation wherever we differ."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from socialzoo.bench.tables import policy_label
from socialzoo.reproduce.figures import draw_figures, figures_allowed
from socialzoo.reproduce.paper import PAPER_PROTOCOL, SPEC_REFERENCE
from socialzoo.reproduce.plan import PARTS, REFERENCE_PART
from socialzoo.reproduce.quirk_report import quirk_note, reference_section
from socialzoo.reproduce.results import RESULTS_DIR, load
from socialzoo.reproduce.seed_report import paper_outside_seeds, seed_note, seeds_section, selection_section
from socialzoo.reproduce.tables import build_tables, write_tables

REPORT_NAME = "REPRODUCTION.md"
FIGURES_DIR = "figures"
TABLES_DIR = "tables"

# Why a policy's numbers may differ from the paper's (prose; the numbers come from the results).
EXPLANATIONS: dict[str, str] = {
    "goalone": "An engineered policy: differences come from the simulators (socialzoo's batched "
    "social-force humans, planner and imported maps against the paper's ROS simulator).",
    "ref": "An engineered policy (SPEC section 10's rule): differences come from the simulators, "
    "as for GoAlone.",
    "bc": "Trained on our Ref's demonstrations in our simulator, one seed; the paper's own LfD "
    "numbers do not grow with the data, a sign of a large variance between runs.",
    "gail": "TorchRL's GAILLoss with a PPO generator on our simulator, one seed and our own "
    "defaults (the paper gives no hyper-parameters).",
    "pips": "Our own synthesiser (unit-checked features, z3 thresholds), not the paper's code.",
    "dqn": "Trained on the documented reward (SPEC section 11: the reference code's reward had a "
    "type slip) for the paper's short budget, one seed: the outcome varies a lot with the seed.",
    "ppo": "Trained on the documented reward and evaluated with its saved observation "
    "normalisation (SPEC section 11: the reference evaluated without it); the paper's short "
    "budget, one seed.",
}
# The machine facts of a training run the report lists (socialzoo.reproduce.results.machine_summary).
MACHINE_COLUMNS = (
    "cpu",
    "kernel_flags",
    "torch",
    "cpu_capability",
    "blas",
    "threads",
    "deterministic",
    "env",
)
QUICK_NOTE = (
    "- Everything: these are the `--quick` settings (tiny trainings, a few scenarios, a shorter "
    "time limit), so no difference here says anything about the paper."
)
PART_TITLES: dict[str, str] = {
    "demos": "Ref demonstrations",
    "rl-curves": "RL data efficiency (PPO and DQN training, every checkpoint evaluated)",
    "lfd": "LfD data efficiency (BC and GAIL at every size, PIPS, the table)",
    "performance": "performance on gdc1-test (trains what is missing)",
    "transfer": "transfer on ghc3-test (trains what is missing)",
    REFERENCE_PART: "PPO and DQN with the reference code's quirks (`--reference`)",
}


def _duration(seconds: float) -> str:
    whole = round(seconds)
    if whole >= 3600:
        return f"{whole // 3600} h {whole % 3600 // 60:02d} min"
    return f"{whole // 60} min {whole % 60:02d} s"


def _settings_section(run: Mapping[str, Any]) -> list[str]:
    s = run["settings"]
    lines = ["| setting | ours | paper |", "|---|---:|---:|"]
    for key, paper in PAPER_PROTOCOL.items():
        value = run.get("demo_steps") if key == "demo_steps" else s[key]  # the demos part records its steps
        text = f"{value:,}" if value is not None else "not recorded yet"
        if key == "demo_steps":
            text += f" ({s['demo_episodes']:,} episodes)"
        lines.append(f"| {key.replace('_', ' ')} | {text} | {paper:,} |")
    sizes = ", ".join(f"{n:,}" for n in s["lfd_sizes"])
    lines.append(f"| LfD sizes (BC, GAIL) | {sizes} | 155,400, 116,600, 77,700, 38,800, 3,500 |")
    return lines + _seed_settings(s)


def _seed_settings(s: Mapping[str, Any]) -> list[str]:
    """Rows of the settings table for training seeds and checkpoint choice (results that have them)."""
    if "seeds" not in s:
        return []
    seeds = ", ".join(str(s["seed"] + k) for k in range(s["seeds"]))
    choice = (
        f"best of the checkpoints every {s['select_every']:,} steps on {s['select_trials']:,} validation "
        "scenarios"
        if s.get("select_trials")
        else "the final policy"
    )
    trials = "all" if s.get("seed_trials") is None else f"the first {s['seed_trials']:,}"
    lines = [
        f"| training seeds | {s['seeds']} ({seeds}) | 1 |",
        f"| kept PPO/DQN policy | {choice} | final |",
    ]
    if s["seeds"] > 1:
        lines.append(f"| test scenarios of seeds after the first | {trials} | |")
    return lines


def _timings_section(timings: Mapping[str, Any]) -> list[str]:
    lines = [
        "| part | what it does | wall time | sessions | finished |",
        "|---|---|---:|---:|---|",
    ]
    total = 0.0
    for part in (*PARTS, REFERENCE_PART):
        entry = timings.get(part)
        if entry is None:
            if part != REFERENCE_PART:  # the reference part is listed only where it ran
                lines.append(f"| {part} | {PART_TITLES[part]} | no session recorded | 0 | no |")
            continue
        # Sessions that only read stored items back (a rerun) do not count as the part's time.
        seconds = entry.get("work_seconds", entry["seconds"])
        total += seconds
        lines.append(
            f"| {part} | {PART_TITLES[part]} | {_duration(seconds)} | {len(entry['sessions'])} "
            f"| {'yes' if entry['finished'] else 'no'} |"
        )
    lines.append(f"| all | | {_duration(total)} | | |")
    return lines


def _figure(name: str, prefix: str, caption: str, figures: set[str]) -> list[str]:
    if name not in figures:
        return [f"*{caption}: not drawn yet (its part has not run).*"]
    link = f"{prefix}{FIGURES_DIR}/{name}"
    return [f"![{caption}]({link}.png)", "", f"*{caption}* ([PDF]({link}.pdf))"]


def _reruns_section(run: Mapping[str, Any]) -> list[str]:
    """The policies whose rows were re-run after the full run (socialzoo.reproduce.rerun_rows)."""
    reruns = run.get("reruns") or []
    if not reruns:
        return []
    lines = [
        "## Rows re-run after the full run",
        "",
        "These policies' rows (every table, the seed aggregates and the training records) come from "
        "a later run of their seeds alone, put in place by `socialzoo.reproduce.rerun_rows`; every "
        "other row is the full run's.",
        "",
    ]
    for r in reruns:
        commands = "; ".join(f"`{c}`" for c in r.get("commands", []))
        label = policy_label(str(r["policy"]))
        ref = "; ".join(
            f"{m}: {c['rerun']:,} of {c['trials']:,} (published {c['published']:,})"
            for m, c in (r.get("ref_successes") or {}).items()
        )
        ref = f" Ref's successes in the re-run's evaluation, {ref}." if ref else ""
        lines.append(f"- {label}: {r.get('why', '')} At commit `{r.get('commit', '')}`: {commands}.{ref}")
    return [*lines, ""]


def _differences(
    tables: Mapping[str, tuple[list[dict[str, Any]], str]],
    seeds: list[dict[str, Any]] | None = None,
    reference: list[dict[str, Any]] | None = None,
) -> list[str]:
    lines = []
    for name, what in (
        ("performance", "performance (gdc1)"),
        ("transfer", "transfer (ghc3)"),
        ("lfd", "LfD"),
    ):
        rows = tables.get(name, ([], ""))[0]
        for r in rows:
            # Listed when the paper's number is outside our interval, or outside our seeds' range.
            beyond_seeds = name != "lfd" and paper_outside_seeds(seeds or [], name, str(r["policy"]))
            if not (r["differs"] or beyond_seeds):
                continue
            size = f" ({r['demonstration_steps']:,} steps)" if "demonstration_steps" in r else ""
            why = EXPLANATIONS.get(str(r["policy"]), "")
            note = seed_note(seeds or [], name, str(r["policy"])) if name != "lfd" else None
            if note:  # the seed spread measured, instead of "one seed"
                why = why.replace(", one seed: the outcome varies a lot with the seed", "").replace(
                    ", one seed", ""
                )
                why = f"{why} {note}"
            quirks = (
                quirk_note(reference or [], seeds or [], name, str(r["policy"])) if name != "lfd" else None
            )
            if quirks:
                why = f"{why} {quirks}"
            lines.append(
                f"- {what}, {policy_label(str(r['policy']))}{size}: ours {r['success_pct']:.1f}% "
                f"[{r['success_ci_low_pct']:.1f}, {r['success_ci_high_pct']:.1f}], paper "
                f"{r['paper_success_pct']:.1f}%. {why}"
            )
    if not lines:
        lines.append(
            "- No paper number lies outside our 90% interval (or our seeds' range) in the tables that have run."
        )
    return lines


def _rerun_section(results: Mapping[str, Any]) -> list[str]:
    """What a re-run elsewhere may differ by, with the machine facts of the stored training runs."""
    lines = [
        "## What a re-run may differ by",
        "",
        "What runs on the simulator alone (GoAlone, Ref, PIPS's synthesis, every evaluation of a "
        "policy file) is numpy and numba in float64; re-run on another 2-core machine of the same kind, "
        "GoAlone, Ref and PIPS came out bit for bit (issue 38). The torch-trained policies (BC, GAIL, "
        "DQN, PPO) are deterministic on one machine and one kernel path (one seed, one torch thread per "
        "training, torch's deterministic algorithms: two trainings give the same weights, "
        "tests/train/test_determinism.py). They part wherever torch or MKL takes another CPU code path "
        "(ATen's scalar kernels instead of its AVX2 ones, another MKL code path, two threads instead of "
        "one): `tools/kernel_paths.py` (socialzoo.studies.kernel_paths) trains one BC under several "
        "paths on one machine and finds where the weights part and what that does to success (its "
        "table, where published, closes this section). Another CPU (one with AVX-512, or of another "
        "vendor, on which MKL picks "
        "another path) or another torch or MKL build takes another path unasked: that is how the "
        "re-run's BC, GAIL and DQN moved while PPO moved by one episode in 2,000. Every run record "
        "(run.json's `machine`, socialzoo.train.machine) names what decides the path: CPU model and "
        "flags, torch's version, CPU capability and BLAS, thread counts, numpy's BLAS, Python, and "
        "`ATEN_CPU_CAPABILITY`, `MKL_CBWR` and `ONEDNN_MAX_CPU_ISA` when set; the first table below "
        "lists those of the stored runs. Setting the same paths on two machines (for example "
        "`ATEN_CPU_CAPABILITY=default MKL_CBWR=COMPATIBLE`, one thread, the same torch build) is what "
        "can make them train alike; a path that needs an instruction set the CPU lacks is not there "
        "to pin. Evaluations made before issue 38's fix of the batch compaction (commit ca3fa96: a "
        "compacted tail forgot the navigator's recovery state) depended slightly on how the trials "
        "were batched; a re-run of results stored before it may differ by a few episodes per test set "
        "from that alone (docs/reproduce.md).",
        "",
    ]
    seen: dict[tuple[Any, ...], list[str]] = {}
    for t in results.get("training", []):
        m = t.get("machine")
        if not isinstance(m, dict):
            continue
        key = tuple(m.get(k) for k in MACHINE_COLUMNS)
        seen.setdefault(key, []).append(str(t.get("run")))
    if not seen:
        return [
            *lines,
            "The stored training runs were made before run records named their machine; a re-run "
            "records it in every run.json.",
            "",
        ]
    lines += [
        "| runs | CPU | kernel flags | torch | CPU capability | BLAS | threads | deterministic | variables |",
        "|---:|---|---|---|---|---|---:|---|---|",
    ]
    for key, runs in seen.items():
        cells = " | ".join("" if v is None else str(v) for v in key)
        lines.append(f"| {len(runs)} | {cells} |")
    return [*lines, "", *_kernel_paths_table(results.get("kernel_paths", []))]


def _kernel_paths_table(rows: list[dict[str, Any]]) -> list[str]:
    """tools/kernel_paths.py's measurement: BC (seed 0) trained once per CPU kernel path."""
    if not rows:
        return []
    lines = [
        "Where the runs part, measured on this machine (`python tools/kernel_paths.py`): BC on the "
        "first demonstration steps of the recording, seed 0, one thread unless named, trained once per "
        "CPU kernel path, each in its own process; weights compared with the first path's at every "
        "checkpoint, and the final policies' success on the first gdc1-test scenarios.",
        "",
        "| kernel path | settings | demonstration steps | updates (checkpoint every) | first checkpoint "
        "that differs | largest weight difference at the end | success % (scenarios) |",
        "|---|---|---:|---:|---|---:|---|",
    ]
    for r in rows:
        trials = int(r["trials"])
        success = f"{r['success_pct']:.1f} ({trials:,})" if trials else ""
        lines.append(
            f"| {r['kernel_path']} | {r['settings'] or 'as installed'} | {int(r['demonstration_steps']):,} | "
            f"{int(r['updates']):,} ({int(r['checkpoint_every'])}) | {r['first_differing_update']} | "
            f"{r['largest_weight_difference']:.3g} | {success} |"
        )
    return [*lines, ""]


def render_reproduction(results: Mapping[str, Any], prefix: str = "", figures: set[str] | None = None) -> str:
    """The text of REPRODUCTION.md from loaded results.

    Args:
        results: socialzoo.reproduce.results.load's output.
        prefix: path from the Markdown file to the folder holding results/, figures/, tables/.
        figures: names of the figures drawn (None: those the results allow); one the results do not
            allow is not linked (an earlier run's file in the folder).
    """
    run = results["run"]
    tables = build_tables(results)
    allowed = figures_allowed(results)
    figures = allowed if figures is None else set(figures) & allowed
    machine = run["machine"]
    quick = run["settings"]["name"] == "quick"
    lines = [
        "# Reproducing the Social Action Selection benchmark (SocialGym, Holtz & Biswas 2022)",
        "",
        f"Generated by `{run['command']}` (settings `{run['settings']['name']}`, hash "
        f"`{run['settings_hash']}`) from the stored results in [`{prefix}{RESULTS_DIR}/`]({prefix}{RESULTS_DIR}/). "
        "Every number here is read from those files; none is typed. The paper's numbers come from "
        f"{SPEC_REFERENCE} (`socialzoo.reproduce.paper`). Intervals are 90% (success: Wilson; "
        'means: Student-t). "differs" marks a paper number outside our interval.',
        "",
    ]
    if quick:
        lines += [
            "> These are the `--quick` settings: tiny trainings and a few test scenarios with a "
            "shorter time limit. They show that every part runs; their numbers are not comparable "
            "with the paper's.",
            "",
        ]
    lines += ["## Settings", "", *_settings_section(run), "", *_reruns_section(run)]
    lines += [
        "## Time on this machine",
        "",
        f"{machine['cpus']} CPUs, {machine['platform']}, Python {machine['python']}. Wall time of each part "
        "summed over the sessions that made items (a resumed part counts every session; a rerun "
        "that only read stored items back does not); a part also trains the policies it needs "
        "that an earlier part did not.",
        "",
        *_timings_section(results.get("timings", {})),
        "",
    ]
    for name, title in (
        ("performance", "Table: performance on the training map (gdc1-test)"),
        ("transfer", "Table: transfer to GHC3 (ghc3-test)"),
    ):
        lines += [f"## {title}", ""]
        lines += [tables[name][1] if name in tables else "*Not run yet.*", ""]
    lines += ["## Figure: success rates, and force, blame and time to goal", ""]
    lines += _figure("success", prefix, "Success rate per policy and map (black ticks: the paper)", figures)
    lines += [""] + _figure("metrics", prefix, "Force, blame and time to goal (successful episodes)", figures)
    lines += ["", "## Figure: RL data efficiency (PPO and DQN checkpoints)", ""]
    lines += _figure("rl_curves", prefix, "Success, time and reward per checkpoint, 90% bands", figures)
    lines += [""] + ([tables["rl_curves"][1]] if "rl_curves" in tables else [])
    lines += ["", "## Table: LfD data efficiency", ""]
    lines += [tables["lfd"][1] if "lfd" in tables else "*Not run yet.*", ""]
    lines += _figure("lfd", prefix, "LfD success against demonstration steps (crosses: the paper)", figures)
    lines += [""] + selection_section(results.get("selection", []))
    profiles = (
        _figure("profiles", prefix, "Performance profiles: share of seeds above each success rate", figures)
        if results.get("profiles")
        else []
    )
    lines += seeds_section(results, profiles)
    seeds = results.get("seeds", [])
    differences = [QUICK_NOTE] if quick else _differences(tables, seeds, results.get("reference", []))
    lines += ["## Where we differ", "", *differences, ""]
    runs = (
        "The paper's RL curves and LfD numbers come from one training run each, as ours do."
        if not seeds
        else "The paper's RL curves and LfD numbers come from one training run each; ours from "
        f"{max(int(r['seeds']) for r in seeds)} seeds (every seed's curve is drawn)."
    )
    lines += [
        "Beyond these, socialzoo follows the paper where the reference code did not (SPEC section 11): "
        "Euclidean goal distance, every policy trained on the same documented reward, learned "
        f"policies evaluated with their saved normalisation. {runs}",
        "",
    ]
    lines += reference_section(results, tables)
    lines += _rerun_section(results)
    training = results.get("training", [])
    if training:
        lines += [
            "## Trained policies",
            "",
            "| run | trainer | demonstration steps | env steps | wall time |",
            "|---|---|---:|---:|---:|",
        ]
        for t in training:
            demo = f"{t['demonstration_steps']:,}" if t.get("demonstration_steps") else ""
            env = f"{t['env_steps']:,}" if t.get("env_steps") else ""
            wall = _duration(t["wall_seconds"]) if isinstance(t.get("wall_seconds"), (int, float)) else ""
            lines.append(f"| {t['run']} | {t['trainer']} | {demo} | {env} | {wall} |")
        lines.append("")
    return "\n".join(lines)


def write_report(out_dir: str | Path, figures: bool = True) -> Path:
    """Tables (out_dir/tables/), figures (out_dir/figures/) and out_dir/REPRODUCTION.md from
    out_dir/results/; returns the report's path. Without `figures`, the figures already drawn
    are linked (a report between parts)."""
    out = Path(out_dir)
    results = load(out / RESULTS_DIR)
    write_tables(build_tables(results), out / TABLES_DIR)
    if figures:
        drawn = set(draw_figures(results, out / FIGURES_DIR))
    else:
        drawn = {p.stem for p in (out / FIGURES_DIR).glob("*.png")}
    path = out / REPORT_NAME
    path.write_text(render_reproduction(results, "", drawn))
    return path
