"""Write rendered frames to an animated GIF or an MP4 video."""

from __future__ import annotations

import importlib.util
import itertools
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from socialzoo.core.validation import check_int, check_number

GIF_SUFFIXES = (".gif",)
VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov", ".mkv", ".avi", ".webm")


def write_animation(
    frames: Iterable[np.ndarray], path: str | Path, fps: float = 20.0, stride: int = 1
) -> Path:
    """Write frames as a looping GIF or an MP4 video, chosen by the file suffix.

    Frames are consumed one at a time: an MP4 is streamed to ffmpeg, a GIF keeps each frame as a
    palette image (one byte per pixel) until the file is written.

    GIFs need only Pillow (a dependency of matplotlib and imageio); MP4 needs the ffmpeg plugin of imageio
    (`pip install imageio-ffmpeg`).

    Args:
        frames: (H, W, 3) uint8 RGB frames, all of the same size.
        path: output file; ".gif" or a video suffix (".mp4", ".mov", ".mkv", ".avi", ".webm").
        fps: frames per second of the animation (after subsampling). GIF delays are stored in
            hundredths of a second and many viewers slow down delays under 0.02 s, so keep
            fps <= 50 for GIFs.
        stride: keep every `stride`-th frame, starting with the first.

    Returns:
        The path written.

    Raises:
        ValueError: unknown suffix, bad fps or stride, a malformed frame, frames of different
            sizes, or no frames at all.
        ImportError: a video was asked for but the imageio-ffmpeg plugin is not installed.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in GIF_SUFFIXES + VIDEO_SUFFIXES:
        raise ValueError(
            f"write_animation: unknown suffix {path.suffix!r} of {path}; use .gif or one of {VIDEO_SUFFIXES}"
        )
    check_number("write_animation", "fps", fps, low=0, low_open=True)
    check_int("write_animation", "stride", stride, low=1)
    if suffix in VIDEO_SUFFIXES and importlib.util.find_spec("imageio_ffmpeg") is None:
        raise ImportError(
            f"writing {path.name} needs the ffmpeg plugin of imageio: `pip install imageio-ffmpeg`, "
            "or write a .gif instead"
        )
    kept = itertools.islice(frames, 0, None, stride)
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix in GIF_SUFFIXES:
        _write_gif(kept, path, fps)
    else:
        _write_video(kept, path, fps)
    return path


def _checked(frames: Iterable[np.ndarray]) -> Iterable[np.ndarray]:
    """Frames, each checked to be (H, W, 3) uint8 RGB of the first frame's size."""
    shape = None
    for index, raw in enumerate(frames):
        frame = np.asarray(raw)
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError(
                f"frame {index} must be an (H, W, 3) uint8 array, got {frame.shape} {frame.dtype}"
            )
        if shape is None:
            shape = frame.shape
        elif frame.shape != shape:
            raise ValueError(f"frame {index} has shape {frame.shape}, the first frame {shape}")
        yield frame
    if shape is None:
        raise ValueError("write_animation: no frames to write")


def _write_gif(frames: Iterable[np.ndarray], path: Path, fps: float) -> None:
    """A GIF that loops forever, each frame with its own adaptive palette, written by Pillow."""
    from PIL import Image

    # Quantising as frames arrive keeps one byte per pixel in memory instead of Pillow's four.
    images = [
        Image.fromarray(frame).quantize(
            colors=256, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE
        )
        for frame in _checked(frames)
    ]
    images[0].save(
        path, format="GIF", save_all=True, append_images=images[1:], duration=1000.0 / fps, loop=0, disposal=1
    )


def _write_video(frames: Iterable[np.ndarray], path: Path, fps: float) -> None:
    """A video (the container's default codec, H.264 for MP4) streamed through imageio-ffmpeg."""
    import imageio.v2 as imageio

    # H.264 needs even sides: macro_block_size=2 pads an odd side by one pixel, no more.
    with imageio.get_writer(path, fps=fps, macro_block_size=2) as writer:
        for frame in _checked(frames):
            writer.append_data(frame)  # type: ignore[attr-defined]
