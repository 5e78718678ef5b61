"""Static pictures of maps: walls, navigation graph and legal poses (matplotlib, imported lazily)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.maps.map_file import Map


def _axes(figsize: tuple[float, float]) -> Any:
    """The Axes of a new off-screen (Agg) matplotlib figure."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=figsize)[1]


def _save(ax: Any, title: str, path: str | Path, **title_options: Any) -> Path:
    """Finish a map picture (equal axes in metres, the title), write it to a PNG and close it."""
    import matplotlib.pyplot as plt

    ax.set_aspect("equal")
    ax.set_title(title, **title_options)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    path = Path(path)
    ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
    return path


def save_map_png(m: Map, path: str | Path, *, show_graph: bool = True, show_poses: bool = True) -> Path:
    """Write a picture of the map (walls, navigation graph, legal poses) to a PNG file; returns the path."""
    from matplotlib.collections import LineCollection

    ax = _axes((10, 8))
    walls = np.asarray(m.walls).reshape(-1, 2, 2)
    ax.add_collection(LineCollection(list(walls), colors="0.15", linewidths=0.8, label="walls"))
    if show_graph and len(m.edges):
        ax.add_collection(
            LineCollection(m.nodes[m.edges], colors="tab:blue", linewidths=0.6, alpha=0.6, label="graph")
        )
        ax.plot(m.nodes[:, 0], m.nodes[:, 1], "o", color="tab:blue", markersize=2.5)
    if show_poses and len(m.legal_poses):
        p = m.legal_poses
        ax.quiver(
            p[:, 0],
            p[:, 1],
            np.cos(p[:, 2]),
            np.sin(p[:, 2]),
            color="tab:orange",
            scale=40,
            width=0.003,
            label="legal poses",
        )
        ax.plot(p[:, 0], p[:, 1], "o", color="tab:orange", markersize=3)
    if m.region is not None:
        x0, y0, x1, y1 = m.region
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
    else:
        ax.autoscale()
    title = f"{m.name}: {m.num_walls} walls, {m.num_nodes} nodes, {len(m.edges)} edges, "
    return _save(ax, title + f"{len(m.legal_poses)} legal poses", path)


# Marker colour of each drive-check failure cause (socialzoo.bench.drive_check.DRIVE_CAUSES).
DRIVE_COLOURS = {
    "wall_collision": "black",
    "goal_unreachable": "tab:red",
    "start_unleavable": "tab:pink",
    "blocked_doorway": "tab:purple",
    "oscillation": "tab:olive",
    "stuck": "tab:brown",
    "timeout": "tab:gray",
}


def save_map_check_png(m: Map, check: Any, path: str | Path, drive: Any = None) -> Path:
    """Draw a map with what `socialzoo.scenarios.map_check.check_map` found, to a PNG; returns the path.

    Graph edges closer to a wall than the robot's wall distance are red, the others blue; legal
    poses with no feasible route to any other pose are red, the others orange; the title sums up
    the clearance and route statistics. With `drive` (a socialzoo.bench.drive_check.DriveReport),
    every route the robot could not complete is marked where it stopped (x, coloured by cause)
    and at the place its cause names (a ring: the narrow gap, the goal's join), with a legend of
    the causes, and the poses of failed routes are ringed in red.
    """
    from matplotlib.collections import LineCollection

    ax = _axes((11, 9))
    ax.add_collection(
        LineCollection(list(np.asarray(m.walls).reshape(-1, 2, 2)), colors="0.15", linewidths=0.8)
    )
    edges = np.asarray(m.edges, dtype=np.int64).reshape(-1, 2)
    if len(edges) and ((edges >= 0) & (edges < len(m.nodes))).all():
        tight = np.zeros(len(edges), dtype=bool)
        tight[list(check.tight_edges)] = True
        colours = np.where(tight[:, None], [[0.85, 0.1, 0.1, 0.9]], [[0.12, 0.47, 0.71, 0.6]])
        ax.add_collection(
            LineCollection(list(m.nodes[edges]), colors=colours, linewidths=np.where(tight, 1.6, 0.7))
        )
    if len(m.nodes):
        ax.plot(m.nodes[:, 0], m.nodes[:, 1], "o", color="tab:blue", markersize=2.5)
    p = np.asarray(m.legal_poses, dtype=np.float64).reshape(-1, 3)
    if len(p):
        stranded = np.zeros(len(p), dtype=bool)
        if check.routes is not None:
            stranded[list(check.routes.stranded)] = True
        colour = np.where(stranded, "tab:red", "tab:orange")
        ax.quiver(p[:, 0], p[:, 1], np.cos(p[:, 2]), np.sin(p[:, 2]), color=colour, scale=40, width=0.003)
        ax.scatter(p[:, 0], p[:, 1], c=colour, s=12, zorder=3)
    if drive is not None and len(drive.failures) and len(p):
        for cause in DRIVE_COLOURS:
            fails = [r for r in drive.failures if r.cause == cause]
            if not fails:
                continue
            stop = np.array([r.stop for r in fails])
            where = np.array([r.where for r in fails])
            ax.plot(stop[:, 0], stop[:, 1], "x", color=DRIVE_COLOURS[cause], ms=8, mew=2,
                    label=f"{cause.replace('_', ' ')} ({len(fails)})", zorder=4)  # fmt: skip
            ax.plot(where[:, 0], where[:, 1], "o", mfc="none", color=DRIVE_COLOURS[cause], ms=12, zorder=4)
        involved = sorted({k for r in drive.failures for k in (r.start, r.goal) if k < len(p)})
        ax.scatter(p[involved, 0], p[involved, 1], s=80, facecolors="none", edgecolors="tab:red", zorder=4)
        ax.legend(loc="best", fontsize=8, title="routes not completed: where they stopped")
    ax.autoscale()
    title = f"{m.name}: {'valid' if check.valid else 'INVALID'}, {check.num_components} component(s), "
    title += f"{len(check.tight_edges)} tight edges (red)"
    if check.routes is not None:
        r = check.routes
        title += (
            f"\n{r.num_feasible}/{r.num_pairs} feasible pose pairs (<= {r.max_route_length:g} m), "
            f"routes {r.shortest:.0f}-{r.longest:.0f} m, {len(r.stranded)} stranded poses (red)"
        )
    if drive is not None:
        done = len(drive.routes) - len(drive.failures)
        title += f"\ndriven alone: {done}/{len(drive.routes)} routes completed"
    return _save(ax, title, path, fontsize=10)
