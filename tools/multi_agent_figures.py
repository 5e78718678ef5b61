"""The figures of docs/multi_agent.md: training curves of a `socialzoo train humans` run.

Run: python tools/multi_agent_figures.py HISTORY.csv OUT.png
(HISTORY.csv: the run folder's history.csv; docs/multi_agent_history.csv is the shipped policy's)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from socialzoo.train.marl_run import read_history

PANELS = (
    ("human/reward", "humans: reward per step"),
    ("human/speed_error", "humans: |speed - preferred| / preferred"),
    ("human/waypoint_reached", "humans: waypoints reached per step"),
    ("human/contact", "humans: share of steps in contact"),
    ("human/wall_contact", "humans: share of steps touching a wall"),
    ("robot/reward", "robot (Ref): reward per step"),
)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("history", type=Path)
    p.add_argument("out", type=Path)
    args = p.parse_args()
    history = read_history(args.history)
    frames = [row["frames"] / 1000 for row in history]
    fig, axes = plt.subplots(2, 3, figsize=(11, 5.5))
    for ax, (key, title) in zip(axes.flat, PANELS, strict=True):
        ax.plot(frames, [row[key] for row in history])
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("thousand frames (world steps)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    fig.suptitle(
        "MAPPO learned humans on gdc1 (training scenarios), 25 learned humans, Ref robot", fontsize=10
    )
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
