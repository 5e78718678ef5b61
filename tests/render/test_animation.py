"""write_animation writes looping GIFs that read back frame for frame, and refuses what it cannot."""

from __future__ import annotations

import importlib.util

import imageio.v3 as iio
import numpy as np
import pytest

from socialzoo.render.animation import write_animation


def make_frames(n: int, height: int = 48, width: int = 64) -> list[np.ndarray]:
    out = []
    for k in range(n):
        frame = np.full((height, width, 3), 255, np.uint8)
        frame[:, k * 4 : k * 4 + 4] = (245, 140, 30)
        out.append(frame)
    return out


def test_gif_round_trip(tmp_path):
    path = write_animation(iter(make_frames(10)), tmp_path / "anim.gif", fps=20)
    assert path.exists()
    read = iio.imread(path, index=None)
    assert read.shape[0] == 10
    assert read.shape[1:3] == (48, 64)
    # Frame 3 has its orange band at columns 12..15.
    assert np.abs(read[3, 10, 13, :3].astype(int) - (245, 140, 30)).max() <= 8
    meta = iio.immeta(path, index=0)
    assert meta.get("loop") == 0
    assert meta.get("duration") == 50


def test_gif_stride(tmp_path):
    path = write_animation(make_frames(10), tmp_path / "sub" / "strided.gif", fps=10, stride=3)
    assert iio.imread(path, index=None).shape[0] == 4  # frames 0, 3, 6, 9


def test_bad_input(tmp_path):
    with pytest.raises(ValueError, match="suffix"):
        write_animation(make_frames(2), tmp_path / "anim.png")
    with pytest.raises(ValueError, match="stride"):
        write_animation(make_frames(2), tmp_path / "anim.gif", stride=0)
    with pytest.raises(ValueError, match="fps"):
        write_animation(make_frames(2), tmp_path / "anim.gif", fps=0)
    with pytest.raises(ValueError, match="no frames"):
        write_animation([], tmp_path / "anim.gif")
    with pytest.raises(ValueError, match="shape"):
        write_animation([make_frames(1)[0], make_frames(1, 32, 32)[0]], tmp_path / "anim.gif")
    with pytest.raises(ValueError, match="uint8"):
        write_animation([np.zeros((8, 8, 3))], tmp_path / "anim.gif")


@pytest.mark.skipif(importlib.util.find_spec("imageio_ffmpeg") is not None, reason="imageio-ffmpeg installed")
def test_mp4_without_ffmpeg_says_what_to_install(tmp_path):
    with pytest.raises(ImportError, match="imageio-ffmpeg"):
        write_animation(make_frames(2), tmp_path / "anim.mp4")


@pytest.mark.skipif(importlib.util.find_spec("imageio_ffmpeg") is None, reason="needs imageio-ffmpeg")
def test_mp4_round_trip(tmp_path):
    path = write_animation(make_frames(8), tmp_path / "anim.mp4", fps=10)
    assert path.stat().st_size > 0
