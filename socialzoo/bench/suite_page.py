"""The scenario suite's outputs: per metric a policy x scenario table (CSV, Markdown) and heatmap (PNG), and the
static results page (results.html) with the heatmaps, each scenario's card and its replays."""

from __future__ import annotations

import base64
import dataclasses
import html
import json
import logging
import math
from collections.abc import Mapping, Sequence
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from socialzoo.bench.figures import pyplot, save_figure
from socialzoo.bench.tables import (
    interval_text,
    markdown_table,
    policy_labels,
    value_key,
    write_csv,
)
from socialzoo.bench.task_benchmark import STORE_FILE
from socialzoo.core.files import write_text_atomic
from socialzoo.core.metrics import axis_label, metric

if TYPE_CHECKING:
    from socialzoo.bench.suite import SuiteResult, SuiteScenario

logger = logging.getLogger(__name__)

CONFIG_FILE = "config.json"
TABLES_DIR = "tables"
HEATMAPS_DIR = "heatmaps"
PAGE_FILE = "results.html"
# Which interval each kind of value has (socialzoo.bench.task_benchmark.summarize), for the tables and the page.
INTERVAL_KINDS = "rates: Wilson score; counts per episode: BCa bootstrap; other means: Student-t"


def metric_scale(name: str) -> float:
    """What a metric's values are shown times: a flag's rate as a percentage, a number as it is."""
    return 100.0 if metric(name).kind == "bool" else 1.0


def metric_digits(name: str) -> int:
    """Decimals a metric's value is shown with: one for a flag's percentage, else the registry's."""
    return 1 if metric(name).kind == "bool" else metric(name).digits


def write_suite_tables(result: SuiteResult, out: Path) -> list[Path]:
    """Per metric, tables/METRIC.csv (policy rows; for each scenario its value and interval
    columns) and tables/METRIC.md (cells "value [low, high]"); suite.md (every metric's table)
    and suite.csv (one row per policy and scenario, every metric). The CSVs hold a flag's rate as
    a share (0-1), the Markdown as a percentage."""
    files: list[Path] = []
    labels = policy_labels(result.policies)
    sections = [
        "# Scenario suite results",
        "",
        f"{result.config.task} task; {result.config.seeds} seeds per policy and scenario; values in brackets: "
        f"two-sided {result.confidence:.0%} confidence intervals ({INTERVAL_KINDS}).",
    ]
    for name in result.metrics:
        scale, digits = metric_scale(name), metric_digits(name)
        rows = []
        for policy in result.policies:
            row: dict[str, Any] = {"policy": policy}
            for s in result.scenarios:
                e = result.entry(policy, s.name) or {}
                for key, column in (
                    (value_key(name), s.name),
                    (f"{name}_ci_low", f"{s.name}_ci_low"),
                    (f"{name}_ci_high", f"{s.name}_ci_high"),
                ):
                    value = e.get(key)
                    row[column] = math.nan if value is None else float(value)
            rows.append(row)
        files.append(write_csv(rows, out / TABLES_DIR / f"{name}.csv"))
        header = ["policy", *(s.label for s in result.scenarios)]
        cells = [
            [labels[p]]
            + [interval_text(result.entry(p, s.name), name, digits, scale) for s in result.scenarios]
            for p in result.policies
        ]
        text = [f"## {axis_label(name)}", "", *markdown_table(header, cells)]
        files.append(write_text_atomic(out / TABLES_DIR / f"{name}.md", "\n".join(text) + "\n"))
        sections += ["", *text]
    files.append(write_text_atomic(out / "suite.md", "\n".join(sections) + "\n"))
    columns = ["policy", "scenario", "letter", "test_set", "trials"]
    for name in result.metrics:
        columns += [value_key(name), f"{name}_ci_low", f"{name}_ci_high"]
    letters = {s.name: s.letter for s in result.scenarios}
    long_rows = [{**e, "scenario": e["map"], "letter": letters[e["map"]]} for e in result.entries]
    files.append(write_csv(long_rows, out / "suite.csv", columns))
    return files


def plot_heatmap(result: SuiteResult, name: str, out_dir: Path) -> Path:
    """heatmaps/NAME.png: the metric's value of each policy (rows) on each scenario (columns),
    each cell written out; green is better where the metric has a better direction."""
    plt = pyplot()
    scale, digits = metric_scale(name), metric_digits(name)
    values = np.array(
        [
            [
                scale * float((result.entry(p, s.name) or {}).get(value_key(name), math.nan))
                for s in result.scenarios
            ]
            for p in result.policies
        ]
    )
    better = metric(name).better
    cmap = plt.get_cmap({"higher": "RdYlGn", "lower": "RdYlGn_r"}.get(better, "viridis")).with_extremes(
        bad="#dddddd"
    )
    rows, cols = values.shape
    fig, ax = plt.subplots(figsize=(2.2 + 0.75 * cols, 1.2 + 0.45 * rows))
    finite = values[np.isfinite(values)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if metric(name).kind == "bool":
        low, high = 0.0, 100.0
    elif high <= low:
        low, high = low - 0.5, high + 0.5
    # An infinite mean (a time to collision: never on a collision course) takes the colour of its end
    # of the scale; only a missing value (NaN) is grey.
    shown = np.where(np.isinf(values), np.where(values > 0, high, low), values)
    image = ax.imshow(np.ma.masked_invalid(shown), cmap=cmap, vmin=low, vmax=high, aspect="auto")
    for i in range(rows):
        for j in range(cols):
            value = values[i, j]
            text = "n/a" if math.isnan(value) else f"{value:.{min(digits, 2)}f}"
            ax.text(j, i, text, ha="center", va="center", fontsize=7)
    ax.set_xticks(range(cols))
    ax.set_xticklabels([s.label for s in result.scenarios], rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(rows))
    ax.set_yticklabels(list(policy_labels(result.policies).values()), fontsize=8)
    bar = fig.colorbar(image, ax=ax, fraction=0.04, pad=0.02)
    bar.ax.tick_params(labelsize=7)
    suffix = {"higher": " (higher is better)", "lower": " (lower is better)"}.get(better, "")
    ax.set_title(axis_label(name) + suffix, fontsize=9)
    return save_figure(fig, out_dir, name, formats=("png",))[0]


_STYLE = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 0 auto; max-width: 1200px; padding: 0 1.2em 3em;
       color: #222; }
h1 { margin-bottom: 0.2em; }
nav a { margin-right: 1em; }
.meta, .muted { color: #666; }
.notes { background: #fff7e0; border-left: 4px solid #e0b030; padding: 0.5em 0.5em 0.5em 2em; }
figure.heatmap { margin: 1.2em 0; }
figure.heatmap img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { color: #555; font-size: 90%; }
.cards { display: grid; grid-template-columns: repeat(auto-fill, minmax(340px, 1fr)); gap: 1em; }
article.card { border: 1px solid #ddd; border-radius: 6px; padding: 0.6em 1em; }
article.card h3 { margin: 0.2em 0; }
dl.card-fields dt { font-weight: 600; }
dl.card-fields dd { margin: 0 0 0.4em 1em; }
pre.card-text { white-space: pre-wrap; font-size: 90%; }
details summary { cursor: pointer; font-weight: 600; margin: 0.4em 0; }
table { border-collapse: collapse; margin: 0.6em 0 1.4em; font-size: 90%; }
th, td { border: 1px solid #ddd; padding: 0.25em 0.5em; text-align: left; vertical-align: top; }
th { background: #f4f4f4; }
caption { text-align: left; font-weight: 600; padding-bottom: 0.3em; }
"""


def scenario_card(scenario: SuiteScenario) -> Any:
    """The scenario card of a suite scenario (socialzoo.scenarios.cards.load_card); None outside
    the suite; the error's text where the card cannot be read."""
    from socialzoo.scenarios.cards import load_card

    if not scenario.letter:
        return None
    try:
        return load_card(scenario.name)
    except (ValueError, OSError) as err:  # the cards' CardError is a ValueError
        logger.warning("the scenario card of %s cannot be read: %s", scenario.name, err)
        return f"The card cannot be read: {err}"


def _span(pair: Sequence[Any], unit: str = "") -> str:
    """A (least, most) pair as "1-3 m", or as "1 m" where they are equal."""
    low, high = pair
    unit = f" {unit}" if unit and unit != "-" else ""
    return f"{low}{unit}" if low == high else f"{low}-{high}{unit}"


def card_html(card: Any) -> str:
    """A scenario card as HTML: a ScenarioCard's description, robot, people, defining event,
    success, variation, metrics of interest, notes, limitations and source as a definition list;
    text as it is; another mapping or dataclass field by field (nested values as JSON)."""
    if card is None:
        return ""
    if isinstance(card, str):
        return f'<pre class="card-text">{html.escape(card)}</pre>'
    if hasattr(card, "defining_event") and hasattr(card, "robot"):
        return _scenario_card_html(card)
    if dataclasses.is_dataclass(card) and not isinstance(card, type):
        fields = dataclasses.asdict(card)
    elif isinstance(card, Mapping):
        fields = dict(card)
    else:
        return f'<pre class="card-text">{html.escape(str(card))}</pre>'
    items = [
        (str(key), value if isinstance(value, str) else json.dumps(value, default=str))
        for key, value in fields.items()
    ]
    return _definitions(items)


def _definitions(items: Sequence[tuple[str, str | list[str]]]) -> str:
    """A definition list; a list value is one line per item."""
    parts = []
    for term, value in items:
        lines = [value] if isinstance(value, str) else value
        if not lines:
            continue
        body = "<br>".join(html.escape(line) for line in lines)
        parts.append(f"<dt>{html.escape(term)}</dt><dd>{body}</dd>")
    return f'<dl class="card-fields">{"".join(parts)}</dl>'


def _scenario_card_html(card: Any) -> str:
    robot = card.robot
    people = [
        f"{_span(p.count)} {p.role}, {_span(p.speed, 'm/s')}: {p.behaviour}"
        for p in getattr(card, "people", ())
    ]
    varies = [
        f"{v.what}: {_span(v.range, v.unit)}" if v.range is not None else f"{v.what}: {', '.join(v.values)}"
        for v in getattr(card, "variation", ())
    ]
    items: list[tuple[str, str | list[str]]] = [
        ("what happens", str(getattr(card, "description", ""))),
        ("robot", [f"start: {robot.start}", f"goal ({robot.goal_kind}): {robot.goal}"]),
        ("people", people),
        ("defining event", str(card.defining_event)),
        ("success", list(getattr(card, "success", ()))),
        ("the seed varies", varies),
        ("metrics of interest", ", ".join(getattr(card, "metrics", ()))),
        ("notes", list(getattr(card, "notes", ()))),
        ("limitations", list(getattr(card, "limitations", ()))),
        ("source", f"{getattr(card, 'source', '')} (card version {getattr(card, 'version', '?')})"),
    ]
    return _definitions(items)


def _image_uri(path: Path) -> str | None:
    if not path.is_file():
        return None
    return "data:image/png;base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def _heatmaps(result: SuiteResult, folder: Path) -> list[str]:
    parts = ['<section id="heatmaps">', "<h2>Heatmaps</h2>"]
    for name in result.metrics:
        uri = _image_uri(folder / HEATMAPS_DIR / f"{name}.png")
        title = html.escape(axis_label(name))
        picture = (
            f'<img src="{uri}" alt="heatmap of {title}">'
            if uri
            else '<p class="muted">no heatmap was drawn</p>'
        )
        parts.append(
            f'<figure class="heatmap" id="heatmap-{name}">{picture}<figcaption><b>{title}</b>: '
            f"{html.escape(metric(name).description)}</figcaption></figure>"
        )
    parts.append("</section>")
    return parts


def _scenario_card(result: SuiteResult, scenario: SuiteScenario) -> str:
    labels = policy_labels(result.policies)
    rows = []
    for policy in result.policies:
        entry = result.entry(policy, scenario.name)
        success = interval_text(entry, "success", 1, 100.0) if entry and "success_rate" in entry else "-"
        links = [
            f'<a href="{html.escape(r.path)}">case {r.case} ({"success" if r.success else "failure"})</a>'
            for r in result.replays
            if r.scenario == scenario.name and r.policy == policy
        ]
        rows.append(
            f"<tr><td>{html.escape(labels[policy])}</td><td>{success}</td>"
            f"<td>{entry['trials'] if entry else 0}</td><td>{', '.join(links) or '-'}</td></tr>"
        )
    missing = "No scenario card yet." if scenario.letter else "A family outside the suite: no scenario card."
    card = card_html(scenario_card(scenario))
    card = (
        f"<details><summary>Scenario card</summary>{card}</details>"
        if card
        else f'<p class="muted">{missing}</p>'
    )
    unit = next(u for u in result.units if u.scenario == scenario)
    return (
        f'<article class="card" id="scenario-{scenario.name}"><h3>{html.escape(scenario.label)}</h3>'
        f'<p class="muted">family <code>{scenario.name}</code> on the {html.escape(scenario.map_name)} map; '
        f"{html.escape(unit.split)} cases 0-{unit.cases - 1}</p>"
        f"<p>{html.escape(scenario.description)}</p>{card}"
        "<table><tr><th>policy</th><th>success, %</th><th>episodes</th><th>replays</th></tr>"
        f"{''.join(rows)}</table></article>"
    )


def _tables(result: SuiteResult) -> list[str]:
    labels = policy_labels(result.policies)
    parts = [
        '<section id="tables">',
        "<h2>Tables</h2>",
        f"<p>Mean over seeds with its two-sided {result.confidence:.0%} confidence interval ({INTERVAL_KINDS}; "
        "a success-only metric over the successful episodes).</p>",
    ]
    header = "".join(f"<th>{html.escape(s.label)}</th>" for s in result.scenarios)
    for name in result.metrics:
        scale, digits = metric_scale(name), metric_digits(name)
        rows = "".join(
            f"<tr><th>{html.escape(labels[p])}</th>"
            + "".join(
                f"<td>{interval_text(result.entry(p, s.name), name, digits, scale)}</td>"
                for s in result.scenarios
            )
            + "</tr>"
            for p in result.policies
        )
        files = f'<a href="{TABLES_DIR}/{name}.csv">{name}.csv</a>, <a href="{TABLES_DIR}/{name}.md">{name}.md</a>'
        parts.append(
            f'<table class="metric" id="table-{name}"><caption>{html.escape(axis_label(name))} '
            f'<span class="muted">({files})</span></caption>'
            f"<tr><th>policy</th>{header}</tr>{rows}</table>"
        )
    parts.append("</section>")
    return parts


def suite_document(result: SuiteResult, folder: Path) -> str:
    """The results page of a run whose files are in `folder`, as an HTML string.

    The page has no script and fetches nothing: heatmaps are inlined as data URIs, the rest are links
    to files of the run's folder (replay pages, tables, store). It reads the run's SuiteResult
    (socialzoo.bench.suite) and nothing else.
    """
    from socialzoo import __version__

    config = result.config
    title = f"Scenario suite: {len(result.policies)} policies x {len(result.scenarios)} scenarios"
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    meta = (
        f"the {config.task} task; policies {', '.join(result.policies)}; {config.seeds} seeds per policy and "
        f"scenario; {result.played} episodes played for this page, {result.reused} read from the store; "
        f"socialzoo {__version__}; written {stamp}"
    )
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in result.notes)
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        f'<header><h1>{html.escape(title)}</h1><p class="meta">{html.escape(meta)}</p>',
        '<nav><a href="#heatmaps">Heatmaps</a><a href="#scenarios">Scenarios</a><a href="#tables">Tables</a>'
        f'<a href="{STORE_FILE}">{STORE_FILE}</a><a href="suite.csv">suite.csv</a>'
        f'<a href="{CONFIG_FILE}">{CONFIG_FILE}</a></nav>',
        f'<ul class="notes">{notes}</ul>' if notes else "",
        "</header>",
        *_heatmaps(result, folder),
        '<section id="scenarios"><h2>Scenarios</h2><div class="cards">',
        *(_scenario_card(result, s) for s in result.scenarios),
        "</div></section>",
        *_tables(result),
        "</body></html>",
    ]
    return "\n".join(p for p in parts if p) + "\n"


def write_suite_page(result: SuiteResult, path: str | Path) -> Path:
    """Write the results page (`suite_document`) to `path`, whole or not at all; the heatmaps are
    read from the page's folder (heatmaps/METRIC.png). Returns the path."""
    path = Path(path)
    return write_text_atomic(path, suite_document(result, path.parent))
