"""REPRODUCTION.md's account of the reference code's quirks (SPEC section 11; `--reference`): PPO and DQN with every
quirk on and with each alone, and the quirks' measured effect on each learned row of "Where we differ"."""

from __future__ import annotations

import statistics
from collections.abc import Mapping, Sequence
from typing import Any

from socialzoo.bench.tables import interval_text, policy_label
from socialzoo.env.quirks import ALL_QUIRKS, QUIRK_LABELS, ReferenceQuirks
from socialzoo.reproduce.paper import EXPERIMENT_MAPS, PAPER_SUCCESS
from socialzoo.reproduce.runs import REFERENCE_TRAINERS, quirk_set


def _sets(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """The quirk sets among `rows`: every quirk together first, then the switches in declaration order."""
    present = {quirk_set(r) for r in rows}
    return [q for q in (ALL_QUIRKS, *ReferenceQuirks.names()) if q in present]


def _set_label(quirks: str) -> str:
    return "all" if quirks == ALL_QUIRKS else QUIRK_LABELS[quirks]


def _rates(
    rows: Sequence[Mapping[str, Any]], experiment: str, policy: str, quirks: str = ALL_QUIRKS
) -> dict[int, float]:
    """Seed -> success % of the runs of quirk set `quirks` of a policy in an experiment."""
    return {
        int(r["seed"]): 100 * float(r["success_rate"])
        for r in rows
        if r["experiment"] == experiment and r["policy"] == policy and quirk_set(r) == quirks
    }


def _where(paper: float, rates: Sequence[float]) -> str:
    if paper < min(rates):
        return f"below all {len(rates)}"
    if paper > max(rates):
        return f"above all {len(rates)}"
    return "inside that range"


def _inside(paper: float, rates: Sequence[float]) -> bool:
    return min(rates) <= paper <= max(rates)


def quirk_note(
    reference: Sequence[Mapping[str, Any]], seeds: Sequence[Mapping[str, Any]], experiment: str, policy: str
) -> str | None:
    """The measured effect of the reference code's quirks on one learned row, for "Where we
    differ"; None for an engineered policy or an experiment the quirks are not run on. Every quirk
    together first, then each quirk run alone (`--reference QUIRK`), each a range over its seeds
    against the paper's number.

    Which policies the quirks can reach is a fact of the code, not of a run: the quirks change the
    env's reward (socialzoo.env.quirks), the socialgym1 layout's theta entry and PPO's evaluation, so
    only the trainers that read the reward (socialzoo.reproduce.runs.REFERENCE_TRAINERS) are
    retrained; BC, GAIL and PIPS learn from Ref's actions in the paper layout, which no quirk changes
    (tests/reproduce/test_quirk_report.py records Ref's demonstrations both ways and compares them).

    Args:
        reference: the `--reference` rows (reference.csv: quirks, experiment, policy, seed, success_rate).
        seeds: the seeds rows of our default runs (seeds.csv), for our mean over the same seeds.
        experiment: "performance" or "transfer".
        policy: the row's policy name.
    """
    if experiment not in EXPERIMENT_MAPS or policy in ("goalone", "ref"):
        return None
    if policy not in REFERENCE_TRAINERS:
        return (
            "The reference quirks cannot explain it: they change the reward, the socialgym1 layout "
            f"and PPO's evaluation, and {policy_label(policy)} learns from Ref's actions in the paper "
            "layout, which are the same with every quirk on."
        )
    paper = PAPER_SUCCESS[policy][EXPERIMENT_MAPS[experiment][1]]
    by_seed = {q: _rates(reference, experiment, policy, q) for q in _sets(reference)}
    measured = {q: [rates[k] for k in sorted(rates)] for q, rates in by_seed.items() if rates}
    if not measured:
        return "Not yet measured with the reference quirks on (`socialzoo reproduce --out DIR --reference`)."
    sentences = []
    values = measured.pop(ALL_QUIRKS, None)
    if values is not None:
        mean = statistics.fmean(values)
        ours = next(
            (r for r in seeds if r["experiment"] == experiment and r["policy"] == policy),
            None,
        )
        shift = ""
        if ours is not None:
            base = float(ours["mean_pct"])
            shift = f" against our {base:.1f}% ({mean - base:+.1f} points)"
        verdict = (
            "so the quirks can explain it" if _inside(paper, values) else "so the quirks do not explain it"
        )
        sentences.append(
            f"With every reference quirk on (`--reference`, {len(values)} seeds): {min(values):.1f}% to "
            f"{max(values):.1f}%, mean {mean:.1f}%{shift}; the paper's {paper:.1f}% lies "
            f"{_where(paper, values)}, {verdict}."
        )
    if measured:
        parts = [
            f"{QUIRK_LABELS[q]} {min(v):.1f}% to {max(v):.1f}% (mean {statistics.fmean(v):.1f}%; the paper's "
            f"{paper:.1f}% {_where(paper, v)})"
            for q, v in measured.items()
        ]
        sentences.append(f"One quirk at a time (`--reference QUIRK`): {'; '.join(parts)}.")
        explaining = [QUIRK_LABELS[q] for q, v in measured.items() if _inside(paper, v)]
        if values is not None and _inside(paper, values):
            explaining.insert(0, "every quirk together")
        sentences.append(
            f"So {' and '.join(explaining)} can explain it."
            if explaining
            else f"So no quirk measured{', alone or together,' if values is not None else ' alone'} explains it."
        )
    return " ".join(sentences)


def reference_section(results: Mapping[str, Any], tables: Mapping[str, Any]) -> list[str]:
    """The learned rows trained and evaluated with the reference code's quirks (`--reference`),
    beside ours and the paper's."""
    rows = results.get("reference", [])
    lines = [
        "## The reference code's quirks (`--reference`)",
        "",
        "SPEC section 11 lists where the reference code (social_gym 1.0) departed from the paper; each "
        "departure is a switch of the env config (`socialzoo.env.quirks.ReferenceQuirks`), all on in the "
        "ids `socialzoo/ActionSelectionReference-v2` (gdc1) and `socialzoo/ActionSelectionTransferReference-v2` "
        "(ghc3). `socialzoo reproduce --reference` trains PPO and DQN on them (goal distance along x only, "
        'the reward "distance gained + bonus") and evaluates PPO without its observation normalisation. '
        "BC, GAIL and PIPS are not retrained: they learn from Ref's actions in the paper layout, never "
        "from the reward, and Ref's demonstrations are the same with every quirk on. "
        "`--reference QUIRK[,QUIRK]` runs one quirk alone, each its own set of seeds (a quirk of the "
        "evaluation alone, PPO's, evaluates our own PPO runs without their normalisation).",
        "",
    ]
    if not rows:
        return [*lines, "*Not run yet (`socialzoo reproduce --out DIR --reference`).*", ""]
    first = min(int(r["seed"]) for r in rows)
    head_trials = sorted({int(r["trials"]) for r in rows if int(r["seed"]) == first})
    other_trials = sorted({int(r["trials"]) for r in rows if int(r["seed"]) != first})
    if other_trials and other_trials != head_trials:
        lines[-2] += (
            f" Seed {first} played the first {' / '.join(f'{n:,}' for n in head_trials)} scenarios of each "
            f"test set, the other seeds the first {' / '.join(f'{n:,}' for n in other_trials)} "
            "(`--seed-trials`)."
        )
    lines += [
        "| experiment | policy | quirks | ours success % | reference quirks success % [90% CI] | "
        "reference, seeds | paper % |",
        "|---|---|---|---:|---|---|---:|",
    ]
    for experiment in ("performance", "transfer"):
        ours = {str(t["policy"]): t for t in tables.get(experiment, ([], ""))[0]}
        _, index = EXPERIMENT_MAPS[experiment]
        for policy in REFERENCE_TRAINERS:
            for quirks in _sets(rows):
                mine = [
                    r
                    for r in rows
                    if r["experiment"] == experiment and r["policy"] == policy and quirk_set(r) == quirks
                ]
                if not mine:
                    continue
                head = next((r for r in mine if int(r["seed"]) == first), mine[0])
                rates = sorted(100 * r["success_rate"] for r in mine)
                spread = f"{rates[0]:.1f} to {rates[-1]:.1f} ({len(rates)} seeds)" if len(rates) > 1 else ""
                our = f"{ours[policy]['success_pct']:.1f}" if policy in ours else "n/a"
                lines.append(
                    f"| {experiment} | {policy_label(policy)} | {_set_label(quirks)} | {our} | "
                    f"{interval_text(head, 'success', 1, 100.0)} | {spread} "
                    f"| {PAPER_SUCCESS[policy][index]:.1f} |"
                )
    return [*lines, ""]
