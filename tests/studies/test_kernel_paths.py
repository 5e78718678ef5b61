"""Where two trainings part: the weight comparison of socialzoo.studies.kernel_paths on hand-made
checkpoints, and an unknown kernel path named."""

import numpy as np
import pytest

from socialzoo.studies.kernel_paths import KERNEL_PATHS, compare_weights, kernel_path_rows

safetensors = pytest.importorskip("safetensors.numpy")


def run_folder(path, weights_by_step, final):
    (path / "checkpoints").mkdir(parents=True)
    for step, w in weights_by_step.items():
        safetensors.save_file({"w": w}, str(path / "checkpoints" / f"step_{step:09d}.safetensors"))
    safetensors.save_file({"w": final}, str(path / "bc.safetensors"))
    return path


def test_compare_weights_finds_the_first_checkpoint_that_differs(tmp_path):
    w = np.arange(6, dtype=np.float32).reshape(2, 3)
    later = w + np.float32(0.5)
    base = run_folder(tmp_path / "a", {10: w, 20: w, 30: w}, w)
    same = run_folder(tmp_path / "b", {10: w, 20: w, 30: w}, w)
    parted = run_folder(tmp_path / "c", {10: w, 20: later, 30: later}, later)
    assert compare_weights(base, same) == ("none", 0.0)
    assert compare_weights(base, parted) == ("20", pytest.approx(0.5))
    # One ulp is a difference: the comparison is bitwise.
    ulp = np.nextafter(w, np.float32(100))
    assert compare_weights(base, run_folder(tmp_path / "d", {10: ulp, 20: w, 30: w}, w))[0] == "10"


def test_unknown_kernel_path_is_named(tmp_path):
    assert {"as-is", "again", "aten-default", "mkl-compatible", "threads-2"} <= set(KERNEL_PATHS)
    with pytest.raises(ValueError, match=r"'avx9'.*known"):
        kernel_path_rows(tmp_path / "demos.npz", tmp_path, ["as-is", "avx9"])
