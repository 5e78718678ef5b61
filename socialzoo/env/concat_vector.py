"""Several batched VectorEnvs of one task side by side as one VectorEnv: rows 0..B_0-1 are the first
env's, the next B_1 the second's, and so on."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, cast

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from socialzoo.env.tasks.base import batch_actions, check_box_batch
from socialzoo.env.vector import checked_reset_mask


class ConcatVectorEnv(VectorEnv):
    """The parts' rows end to end (below).

    Each part keeps its own world, so the parts may play different maps: the suite's families,
    one part each, train one policy (`socialzoo train crowdnav --families`). Every part must have
    the same single observation and action spaces and reset in the same step
    (AutoresetMode.SAME_STEP, as socialzoo's TaskVectorEnv does); their infos are joined key by
    key, row arrays end to end (a key a part lacks is zeros, or False for a mask, in its rows).
    `render()` gives the parts' frames in row order, when they were made with a render_mode.

    Args:
        parts: the VectorEnvs, at least one.

    Raises:
        ValueError: no part, or parts whose single spaces or render modes differ (naming the first
            that does).
    """

    metadata: dict[str, Any] = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, parts: Sequence[VectorEnv]) -> None:
        if not parts:
            raise ValueError("ConcatVectorEnv needs at least one part")
        first = parts[0]
        for i, part in enumerate(parts[1:], start=1):
            if part.single_observation_space != first.single_observation_space:
                raise ValueError(f"ConcatVectorEnv: part {i}'s observation space differs from part 0's")
            if part.single_action_space != first.single_action_space:
                raise ValueError(f"ConcatVectorEnv: part {i}'s action space differs from part 0's")
            if part.render_mode != first.render_mode:
                raise ValueError(
                    f"ConcatVectorEnv: part {i}'s render_mode {part.render_mode!r} differs from part 0's "
                    f"{first.render_mode!r}"
                )
        self.parts = list(parts)
        self.sizes = [part.num_envs for part in parts]
        self.bounds = np.cumsum([0, *self.sizes])
        self.num_envs = int(self.bounds[-1])
        self.single_observation_space = first.single_observation_space
        self.single_action_space = first.single_action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.config = getattr(first, "config", None)
        self.render_mode = first.render_mode
        self.metadata = {**first.metadata, "autoreset_mode": AutoresetMode.SAME_STEP}
        # Each part's observations after its last reset or step (None before the first reset), for
        # a reset whose mask leaves a part out.
        self._last_obs: list[Any] | None = None

    @property
    def metric_types(self) -> dict[str, type]:
        """Every part's episode metric types (socialzoo.env.vector.TaskVectorEnv.metric_types)."""
        types: dict[str, type] = {}
        for part in self.parts:
            types.update(getattr(part, "metric_types", {}))
        return types

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict]:
        """Reset every part; part i is seeded from (seed, i), so the parts draw different episodes.

        options["reset_mask"] ((num_envs,) bools, after the first reset) resets only the masked
        rows: each part gets its slice of the mask (and, with a seed, reseeds only those rows), and
        a part with no masked row is left as it is (its rows' reset infos are zeros).
        options["cases"] (one case per reset row, with its "split") go to the parts in row order,
        each part's from its own split. Other options go to every part.

        Raises:
            ValueError: a bad reset_mask, or cases that are not one per row to reset.
        """
        options = dict(options or {})
        name = type(self).__name__
        slices: list[np.ndarray | None] = [None] * len(self.parts)
        if "reset_mask" in options:
            mask = checked_reset_mask(
                options.pop("reset_mask"), self.num_envs, self._last_obs is not None, name
            )
            slices = [mask[lo:hi] for lo, hi in zip(self.bounds, self.bounds[1:], strict=False)]
        counts = [size if m is None else int(m.sum()) for m, size in zip(slices, self.sizes, strict=True)]
        cases = options.pop("cases", None)
        if cases is not None and len(cases) != sum(counts):
            raise ValueError(f"{name}: {sum(counts)} rows to reset but {len(cases)} cases")
        first_case = np.cumsum([0, *counts])
        results: list[tuple[Any, dict[str, Any]]] = []
        for i, (part, part_mask) in enumerate(zip(self.parts, slices, strict=True)):
            if counts[i] == 0:
                assert self._last_obs is not None  # checked_reset_mask refuses a mask before the first reset
                results.append((self._last_obs[i], {}))
                continue
            part_seed = None if seed is None else int(np.random.SeedSequence([seed, i]).generate_state(1)[0])
            part_options = dict(options)
            if part_mask is not None:
                part_options["reset_mask"] = part_mask
            if cases is not None:
                part_options["cases"] = list(cases[first_case[i] : first_case[i + 1]])
            results.append(part.reset(seed=part_seed, options=part_options))
        self._last_obs = [o for o, _ in results]
        return self._join(self._last_obs), self._join_info([info for _, info in results])

    def step(self, actions: Any) -> tuple[Any, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step every part with its rows' actions.

        Raises:
            ValueError: actions of another row count, or a bad action in any row (naming its
                row), before any part steps.
        """
        # Checked as a whole first: a part refusing its rows after an earlier part stepped would
        # leave the parts' episodes out of step, and extra rows would go unnoticed.
        name = type(self).__name__
        actions = batch_actions(self.single_action_space, actions, (self.num_envs,), name)
        if isinstance(self.single_action_space, spaces.Box):
            check_box_batch(self.single_action_space, actions, name)
        out = [
            part.step(actions[lo:hi])
            for part, lo, hi in zip(self.parts, self.bounds, self.bounds[1:], strict=False)
        ]
        obs, reward, terminated, truncated, infos = zip(*out, strict=True)
        self._last_obs = list(obs)
        return (
            self._join(self._last_obs),
            np.concatenate(reward),
            np.concatenate(terminated),
            np.concatenate(truncated),
            self._join_info(list(infos)),
        )

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Every row's frame, the parts' in row order (a tuple of num_envs frames, as Gymnasium's
        vector envs render); None when the parts have no render_mode."""
        if self.render_mode is None:
            return None
        frames: list[np.ndarray] = []
        for part in self.parts:  # each gives a tuple of frames: the parts share the render_mode
            frames.extend(cast(tuple[np.ndarray, ...], part.render()))
        return tuple(frames)

    def close_extras(self, **kwargs: Any) -> None:
        """Close every part."""
        for part in self.parts:
            part.close()

    # ------------------------------------------------------------------ joining
    def _join(self, values: list[Any]) -> Any:
        if isinstance(values[0], dict):
            return {k: np.concatenate([v[k] for v in values]) for k in values[0]}
        return np.concatenate(values)

    def _join_info(self, infos: list[dict[str, Any]]) -> dict[str, Any]:
        keys: list[str] = []
        for info in infos:
            keys.extend(k for k in info if k not in keys)
        out: dict[str, Any] = {}
        for key in keys:
            present = [info[key] for info in infos if key in info]
            if isinstance(present[0], dict):
                out[key] = self._join_info([info.get(key, {}) for info in infos])
                continue
            example = np.asarray(present[0])
            pieces = []
            for info, size in zip(infos, self.sizes, strict=True):
                if key in info:
                    pieces.append(np.asarray(info[key]))
                else:
                    pieces.append(np.zeros((size, *example.shape[1:]), dtype=example.dtype))
            out[key] = np.concatenate(pieces)
        return out
