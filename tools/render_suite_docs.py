"""Render the suite's scenario cards (socialzoo/scenarios/cards/*.toml) into docs/suite_scenarios.md,
with a picture of one seeded episode of each scenario in docs/images/suite/FAMILY.png.

    python tools/render_suite_docs.py                      # the page, and every registered family's picture
    python tools/render_suite_docs.py --only blind_corner  # the page, and that scenario's picture (name or letter)
    python tools/render_suite_docs.py --no-pictures        # the page only

A picture is the episode of the scenario's first validation seed, played by the GoAlone policy on
the action-selection task (EnvConfig(family=..., map=...)): the map's walls and doors, the robot's
and the people's paths coloured by time, starts and goals marked. A scenario whose family is not
registered yet (or whose map is not shipped yet) is skipped with a message, and its section says
that its picture is still to come; the page links every picture found in the images folder.
Needs matplotlib (the "plot" extra).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import unicodedata
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from socialzoo.core.metrics import metric
from socialzoo.scenarios.cards import CardError, ScenarioCard, card_path, suite_cards
from socialzoo.scenarios.suite import SUITE_SPLITS

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "suite_scenarios.md"
IMAGES = ROOT / "docs" / "images" / "suite"
POLICY = "goalone"
# People's start and end markers are numbered up to this many people; a crowd's are not.
MAX_LABELLED = 8
# Markers along each path, one every this many seconds, coloured by time like the paths.
MARKER_EVERY_S = 1.0


# ----------------------------------------------------------------------------------------- pictures


def family_status(family: str, map_name: str | None = None) -> str:
    """ "" when the family can be played on its map (or map_name), else why not, in a few words."""
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.catalogue import get_family
    from socialzoo.scenarios.families import FAMILIES

    if family not in FAMILIES:
        return f"the family {family!r} is not registered yet"
    try:
        get_family(family)
    except (ImportError, AttributeError) as err:
        # The registry may name a family's "module:Class" before the class is written.
        return f"the family {family!r} is registered but not written yet ({err})"
    if map_name is not None:
        try:
            load_map(map_name)
        except (OSError, ValueError, KeyError) as err:
            return f"its map {map_name!r} cannot be loaded ({err})"
    return ""


def play_episode(family: str, map_name: str | None = None, seed: int = 0) -> tuple[Any, Any, Any]:
    """(the map, the scenario, the EpisodeTrace) of `seed` of a family, played by GoAlone on the
    action-selection task (map_name: the family's own map when None)."""
    from socialzoo.agents import make_policy
    from socialzoo.bench.replay import benchmark_scenario, record_episode
    from socialzoo.env.config import EnvConfig
    from socialzoo.maps.map_file import load_map
    from socialzoo.scenarios.catalogue import get_family

    map_name = map_name or get_family(family).map_name
    world_map = load_map(map_name)
    config = EnvConfig(family=family, map=map_name)
    scenario = benchmark_scenario(config, seed, world_map)
    trace = record_episode(config, scenario, make_policy(POLICY), laser_rays=0, world_map=world_map)
    return world_map, scenario, trace


def _segments(points: Any) -> Any:
    """(K, 2, 2) segments between consecutive finite points of a (T, 2) path, and (K,) their
    start indices."""
    import numpy as np

    ok = np.isfinite(points).all(axis=1)
    keep = ok[:-1] & ok[1:]
    starts = np.flatnonzero(keep)
    return np.stack((points[starts], points[starts + 1]), axis=1), starts


def _doors(world_map: Any, scenario: Any) -> list[tuple[Any, str]]:
    """(segment (4,), label) of the map's doors and the scenario's scheduled doors."""
    import numpy as np

    # Map files gain `doors` (D, 4) and scenario scripts `doors` (D, 6) in the same release: either
    # may be missing on an older tree.
    found: list[tuple[Any, str]] = []
    map_doors = getattr(world_map, "doors", None)
    if map_doors is not None:
        found += [(row[:4], "") for row in np.asarray(map_doors, dtype=np.float64).reshape(-1, 4)]
    timed = getattr(getattr(scenario, "script", None), "doors", None)
    if timed is not None:
        for row in np.asarray(timed, dtype=np.float64).reshape(-1, 6):
            t_open, t_close = float(row[4]), float(row[5])
            until = f"-{t_close:.1f}" if math.isfinite(t_close) and t_close < 1e6 else ""
            found.append((row[:4], f"open {t_open:.1f}{until} s"))
    return found


def draw_episode(
    family: str,
    out_dir: str | Path,
    *,
    map_name: str | None = None,
    seed: int = 0,
    title: str | None = None,
    stem: str | None = None,
    dpi: int = 110,
) -> Path:
    """Play `seed` of a family with GoAlone and draw the episode: walls, doors, the robot's and the
    people's paths coloured by time, starts and goals; write out_dir/STEM.png (STEM: the family).

    Returns:
        The PNG written.
    """
    import numpy as np
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    from socialzoo.bench.figures import pyplot, save_figure

    world_map, scenario, trace = play_episode(family, map_name, seed)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 6.0))
    walls = np.asarray(world_map.walls, dtype=np.float64).reshape(-1, 2, 2)
    ax.add_collection(LineCollection(walls, colors="0.15", linewidths=1.4, label="walls"))
    door_labelled = False
    for segment, text in _doors(world_map, scenario):
        x1, y1, x2, y2 = (float(v) for v in segment)
        ax.plot([x1, x2], [y1, y2], "--", color="tab:orange", lw=2.2, label=None if door_labelled else "door")
        door_labelled = True
        if text:
            ax.annotate(text, ((x1 + x2) / 2, (y1 + y2) / 2), fontsize=7, color="tab:orange", ha="center")

    times = np.arange(trace.num_steps + 1) * trace.dt
    norm = Normalize(0.0, max(float(times[-1]), trace.dt))
    cmap = plt.get_cmap("viridis")
    every = max(round(MARKER_EVERY_S / trace.dt), 1)
    robot = np.asarray(trace.robot_pose[:, :2])
    people = np.asarray(trace.human_pos)

    for h in range(trace.num_humans):
        path = people[:, h]
        segs, starts = _segments(path)
        if len(segs):
            ax.add_collection(LineCollection(segs, cmap=cmap, norm=norm, array=times[starts], linewidths=1.4))
        marks = np.arange(0, len(path), every)
        marks = marks[np.isfinite(path[marks]).all(axis=1)]
        ax.scatter(path[marks, 0], path[marks, 1], c=times[marks], cmap=cmap, norm=norm, s=9, zorder=3)
        seen = np.flatnonzero(np.isfinite(path).all(axis=1))
        if len(seen):
            first, last = path[seen[0]], path[seen[-1]]
            ax.plot(*first, "o", ms=7, mfc="none", mec="0.2", zorder=4, label=None if h else "person start")
            ax.plot(*last, "x", ms=6, color="0.2", zorder=4, label=None if h else "person end")
            if trace.num_humans <= MAX_LABELLED:
                ax.annotate(
                    f"P{h}", first, xytext=(4, 4), textcoords="offset points", fontsize=7, color="0.2"
                )

    segs, starts = _segments(robot)
    ax.add_collection(
        LineCollection(segs, colors="black", linewidths=4.2, zorder=4, capstyle="round")
    )  # an outline that tells the robot's path from the people's
    line = LineCollection(segs, cmap=cmap, norm=norm, array=times[starts], linewidths=2.8, zorder=5)
    ax.add_collection(line)
    marks = np.arange(0, len(robot), every)
    ax.scatter(
        robot[marks, 0],
        robot[marks, 1],
        c=times[marks],
        cmap=cmap,
        norm=norm,
        marker="s",
        s=16,
        edgecolors="black",
        linewidths=0.5,
        zorder=6,
    )
    ax.plot(*robot[0], "^", ms=11, mfc="white", mec="black", zorder=7, label="robot start")
    goal = np.asarray(trace.goal[:2])
    ax.plot(*goal, "*", ms=15, mfc="tab:red", mec="black", zorder=7, label="robot goal")
    ax.add_patch(plt.Circle(goal, 0.5, fill=False, ls=":", color="tab:red", zorder=7))
    # Legend entries for the paths (their colours are the time's, so the entries are grey).
    ax.plot([], [], "-s", color="0.45", mec="black", lw=2.8, ms=4, label="robot path")
    if trace.num_humans:
        ax.plot([], [], "-o", color="0.45", lw=1.4, ms=3, label="person path")

    drawn = [walls.reshape(-1, 2), robot, goal[None]]
    drawn += [people[np.isfinite(people).all(axis=2)]] if people.size else []
    points = np.concatenate([p for p in drawn if len(p)])
    lo, hi = points.min(axis=0) - 0.5, points.max(axis=0) + 0.5
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    seconds = trace.num_steps * trace.dt
    ax.set_title(
        f"{title or family}\n{family} on {world_map.name}, seed {seed}, GoAlone: "
        f"{trace.outcome or 'ended'} after {seconds:.1f} s",
        fontsize=10,
    )
    fig.colorbar(line, ax=ax, shrink=0.8, label="time (s)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=5, fontsize=8, frameon=False)
    (path,) = save_figure(fig, out_dir, stem or family, formats=("png",), dpi=dpi)
    return path


# ------------------------------------------------------------------------------------------ the page


def slug(text: str) -> str:
    """The heading's anchor as the docs site makes it (Python-Markdown's toc slugify)."""
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def _number(value: float) -> str:
    return f"{value:g}"


def _span(low: float, high: float, unit: str = "") -> str:
    text = _number(low) if low == high else f"{_number(low)}-{_number(high)}"
    return f"{text} {unit}".strip() if unit and unit != "-" else text


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _count(card: ScenarioCard) -> str:
    low, high = card.num_people
    return _span(low, high)


def _split(first: int, size: int | None) -> str:
    return f"{first}-{first + size - 1}" if size is not None else f"from {first}"


def _seeds(card: ScenarioCard) -> str:
    return ", ".join(f"{name} {_split(*split)}" for name, split in card.seeds.items())


def _metric(name: str) -> str:
    unit = metric(name).unit
    return f"`{name}`" + (f" ({unit})" if unit and unit != "-" else "")


def _heading(card: ScenarioCard) -> str:
    return f"({card.letter}) {card.title}"


def _picture_seed(card: ScenarioCard) -> int:
    return card.seeds["val"].first


def card_section(card: ScenarioCard, picture: str | None) -> list[str]:
    """The page's lines of one card; `picture` is the image's path relative to the page, or None."""
    lines = [f"## {_heading(card)}", "", card.description, ""]
    if picture is not None:
        lines += [
            f"![{card.title}: seed {_picture_seed(card)} played by GoAlone]({picture})",
            "",
            f"*One seeded episode: seed {_picture_seed(card)} (the first validation case) played by "
            "GoAlone; paths coloured by time, squares the robot, dots the people, one mark a second.*",
            "",
        ]
    else:
        lines += [
            f"*No picture yet: `python tools/render_suite_docs.py --only {card.family}` draws it once "
            "the family and its map are in.*",
            "",
        ]
    robot = card.robot
    lines += [
        "| definition | |",
        "|---|---|",
        f"| Family | `{card.family}` (Fig. 7({card.letter}); card version {card.version}) |",
        f"| Map | `{card.map_name}` |",
        f"| Robot's start | {_cell(robot.start)} |",
        f"| Robot's goal | {_cell(robot.goal)} |",
        f"| Goal kind | {robot.goal_kind} |",
        f"| Defining event | {_cell(card.defining_event)} |",
        f"| Success | {_cell(' '.join(card.success))} |",
        f"| Seeds | {_seeds(card)} |",
        "",
        "**People**",
        "",
    ]
    for role in card.people:
        speed = "standing" if role.speed == (0.0, 0.0) else _span(*role.speed, "m/s")
        lines.append(f"- *{role.role}*: {_span(*role.count)}, {speed}. {role.behaviour}")
    lines += ["", "**Seeded variation**", ""]
    for item in card.variation:
        value = _span(*item.range, item.unit) if item.range is not None else ", ".join(item.values)
        lines.append(f"- {item.what}: {value}")
    lines += ["", "**Metrics of interest:** " + ", ".join(_metric(m) for m in card.metrics), ""]
    if card.notes:
        lines += ["**Notes**", ""] + [f"- {note}" for note in card.notes] + [""]
    lines += ["**Limitations, and where it differs from the guidelines**", ""]
    lines += [f"- {item}" for item in card.limitations] + ["", f"**Source:** {card.source}", ""]
    return lines


def page_text(cards: Sequence[ScenarioCard], doc: Path, image_dir: Path) -> str:
    """The page of `cards`, linking the pictures found in image_dir (relative to doc's folder)."""
    splits = ", ".join(f"{name} {_split(*split)}" for name, split in SUITE_SPLITS.items())
    lines = [
        "# The scenario suite: scenario cards",
        "",
        "<!-- Written by tools/render_suite_docs.py from socialzoo/scenarios/cards/*.toml: edit the cards, "
        "then run it. -->",
        "",
        'The 25 scenarios of Fig. 7 of Francis et al., "Principles and Guidelines for Evaluating Social '
        'Robot Navigation Algorithms" (ACM THRI 2025, arXiv 2306.16740), each a scenario family of '
        "socialzoo (`socialzoo.scenarios.suite`). Every scenario has a scenario card after the "
        "guidelines' (metadata, definition, usage), kept as data beside the family in "
        "`socialzoo/scenarios/cards/FAMILY.toml` and checked against its JSON Schema "
        "(`socialzoo/scenarios/card.schema.json`) and the suite when it is loaded "
        "(`socialzoo.scenarios.cards.load_card`, `suite_cards`): a card with a missing or mistyped field "
        "is a `CardError` naming the file and the field.",
        "",
        "The guidelines describe each scenario in words and a picture; the maps, distances, speeds, "
        "timings and head counts below are socialzoo's own choices, and each card says so in its "
        "source and limitations. Where a card gives the people's speeds as 0.5-1.3 m/s without more, "
        "they are socialzoo's default walking speeds (normal, mean 1.0 m/s, sd 0.1, clipped).",
        "",
        f"Seed splits of every scenario: {splits} (`socialzoo.scenarios.suite.SUITE_SPLITS`): no test case "
        "is ever a training case.",
        "",
        "| | scenario | family | map | goal | people |",
        "|---|---|---|---|---|---|",
    ]
    for card in cards:
        lines.append(
            f"| {card.letter} | [{card.title}](#{slug(_heading(card))}) | `{card.family}` | "
            f"`{card.map_name}` | {card.robot.goal_kind} | {_count(card)} |"
        )
    lines.append("")
    for card in cards:
        image = image_dir / f"{card.family}.png"
        picture = Path(os.path.relpath(image, doc.parent)).as_posix() if image.is_file() else None
        lines += card_section(card, picture)
    return "\n".join(lines).rstrip("\n") + "\n"


# ------------------------------------------------------------------------------------------ the tool


def _select(cards: Sequence[ScenarioCard], only: str | None) -> list[ScenarioCard]:
    if only is None:
        return list(cards)
    family = card_path(only).stem  # a family name or a letter; CardError when neither
    return [c for c in cards if c.family == family]


def render(
    *,
    only: str | None = None,
    doc: Path = DOC,
    image_dir: Path = IMAGES,
    pictures: bool = True,
    out: Any = sys.stdout,
) -> tuple[list[Path], list[str]]:
    """Draw the pictures (every card's, or only one's) of the registered families, then write
    the page. Returns (the pictures written, the families skipped)."""
    cards = suite_cards()
    written: list[Path] = []
    skipped: list[str] = []
    for card in _select(cards, only) if pictures else []:
        why = family_status(card.family, card.map_name)
        if why:
            print(f"skipped ({card.letter}) {card.family}: {why}", file=out)
            skipped.append(card.family)
            continue
        path = draw_episode(
            card.family,
            image_dir,
            map_name=card.map_name,
            seed=_picture_seed(card),
            title=_heading(card),
        )
        print(f"wrote {path}", file=out)
        written.append(path)
    doc.parent.mkdir(parents=True, exist_ok=True)
    doc.write_text(page_text(cards, doc, image_dir), encoding="utf-8")
    print(f"wrote {doc}", file=out)
    return written, skipped


def main(argv: Iterable[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", metavar="NAME", help="draw only this scenario's picture (family or letter)")
    parser.add_argument("--doc", type=Path, default=DOC, help="the page to write")
    parser.add_argument("--images", type=Path, default=IMAGES, help="the pictures' folder")
    parser.add_argument("--no-pictures", action="store_true", help="write the page only")
    args = parser.parse_args(None if argv is None else list(argv))
    if args.only is not None:
        try:
            card_path(args.only)
        except CardError as err:
            parser.error(str(err))
    render(only=args.only, doc=args.doc, image_dir=args.images, pictures=not args.no_pictures)
    return 0


if __name__ == "__main__":
    sys.exit(main())
