"""The studies (and the trainers' evaluation) read their metrics' labels, digits, kinds and
directions from the metric registry (socialzoo.core.metrics)."""

import pytest

from socialzoo.core.metrics import axis_label, metric, registered
from socialzoo.studies import crowd_matrix, human_compare, rl_curves
from socialzoo.train import sb3_common, validation


def test_crowd_matrix_cells_come_from_the_registry():
    for key, label, digits, scale in crowd_matrix.METRICS:
        m = metric(key)
        if m.kind == "bool":
            assert (label, digits, scale) == (axis_label(key), m.digits - 2, 100.0)
        else:
            assert (label, digits, scale) == (m.heading, m.digits, 1.0)
    labels = {key: label for key, label, _, _ in crowd_matrix.METRICS}
    assert labels["success"] == "success, %"
    assert labels["people_time_lost"] == "people's time lost (mean per person), s"


def test_crowd_matrix_heatmaps_brighten_towards_better(tmp_path, monkeypatch):
    plt = pytest.importorskip("matplotlib.pyplot")
    config = crowd_matrix.MatrixConfig(policies=("goalone",), humans=("sf",), maps=("gdc1",))
    row = {"policy": "goalone", "humans": "sf", "map": "gdc1", "trials": 1}
    row |= {f"{key}_mean": 1.0 for key, *_ in crowd_matrix.METRICS}
    maps = []
    monkeypatch.setattr(
        plt.Figure,
        "savefig",
        lambda fig, *a, **k: maps.extend(ax.images[0].cmap.name for ax in fig.axes if ax.images),
    )
    crowd_matrix.plot_matrix([row], config, tmp_path / "m.png")
    want = ["viridis" if metric(key).higher_is_better else "viridis_r" for key, *_ in crowd_matrix.METRICS]
    assert maps == want and want[0] == "viridis" and want[1] == "viridis_r"


def test_human_comparison_robot_rows_come_from_the_registry():
    assert human_compare.ROBOT_METRICS == (
        ("success_rate", "robot success rate", metric("success").digits),
        ("mean_force_mean", "robot force (mean per step)", metric("mean_force").digits),
        ("mean_blame_mean", "robot blame (mean per step)", metric("mean_blame").digits),
    )
    assert human_compare.COLLISION_KEYS == (
        "humans_hh_collisions",
        "humans_hw_collisions",
        "humans_hr_collisions",
    )


def test_curves_and_evaluations_name_registered_metrics():
    assert [(k, label) for k, label, _ in rl_curves.CURVE_PANELS] == [
        (k, axis_label(k)) for k, _, _ in rl_curves.CURVE_PANELS
    ]
    assert rl_curves.CURVE_PANELS[0] == ("success", "success, %", 100.0)
    assert registered(*validation.EVALUATION_METRICS) and registered(*sb3_common.EPISODE_METRICS)
