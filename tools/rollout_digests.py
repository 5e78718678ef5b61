"""Digests of seeded rollouts of every registered env id and every adapter, to show that a refactor
keeps each id's rollouts bit for bit.

    python tools/rollout_digests.py --out before.json          # record
    python tools/rollout_digests.py --compare before.json      # record again and list what differs

With --recorded eth,univ (the ETH/UCY cache of `socialzoo data fetch eth-ucy`), it adds the CrowdNav
task's recorded scenes, replayed and hybrid (ORCA and social force), 16 rows for 300 steps each:
enough for episodes to end and hybrid people to react. The tool runs against another checkout's
package with PYTHONPATH=that/checkout. It runs under the reference numerics
(tools/reference_numerics.py: numpy's kernels no wider than AVX2), so that its digests compare
across machines.

A rollout is reset with a fixed seed and stepped with actions drawn from a fixed generator of its
own (never the spaces' samplers); an ended episode is reset without a seed (the stream goes on).
Each case keeps separate digests of the observations, the rewards, the end flags and the infos,
so a change of info conventions shows apart from a change of dynamics. tests/env/test_golden_rollouts.py
keeps a few of these digests (tests/env/golden_rollouts.json) and checks them on every run.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

# Steps per case: enough for CrowdNav's episodes to end and restart; the benchmark's cases with a
# short time limit restart too.
STEPS = 160


class Digest:
    """Running SHA-256 digests of a rollout's parts."""

    PARTS = ("obs", "reward", "flags", "info")

    def __init__(self) -> None:
        self._hash = {part: hashlib.sha256() for part in self.PARTS}

    def add(self, part: str, value: Any) -> None:
        """Feed `value` (arrays, numbers, dicts, lists, tensors) into the digest of `part`."""
        for chunk in _chunks(value):
            self._hash[part].update(chunk)

    def hexdigests(self) -> dict[str, str]:
        """Part -> the first 16 hex digits of its digest."""
        return {part: h.hexdigest()[:16] for part, h in self._hash.items()}


def _chunks(value: Any) -> Iterator[bytes]:
    """A canonical byte form of a value: dict keys sorted, arrays with dtype and shape."""
    if hasattr(value, "detach") and hasattr(value, "cpu"):  # a torch tensor
        value = value.detach().cpu().numpy()
    if isinstance(value, dict) or (hasattr(value, "keys") and hasattr(value, "items")):
        for key in sorted(value.keys(), key=str):
            yield str(key).encode()
            yield from _chunks(value[key])
    elif isinstance(value, (list, tuple)):
        yield b"["
        for item in value:
            yield from _chunks(item)
        yield b"]"
    elif isinstance(value, np.ndarray):
        array = np.ascontiguousarray(value)
        yield f"{array.dtype.str}{array.shape}".encode()
        if array.dtype == object:
            for item in array.reshape(-1):
                yield from _chunks(item)
        else:
            yield array.tobytes()
    elif isinstance(value, (bool, np.bool_)):
        yield b"T" if value else b"F"
    elif isinstance(value, (int, np.integer)):
        yield f"i{int(value)}".encode()
    elif isinstance(value, (float, np.floating)):
        number = float(value)
        yield b"nan" if math.isnan(number) else float(number).hex().encode()
    elif value is None:
        yield b"None"
    else:
        yield repr(value).encode()


def _action(space: Any, rng: np.random.Generator) -> Any:
    """One action of a gymnasium space from `rng`."""
    from gymnasium import spaces

    if isinstance(space, spaces.Discrete):
        return int(space.start + rng.integers(space.n))
    if isinstance(space, spaces.MultiDiscrete):
        return (rng.integers(space.nvec) + space.start).astype(np.int64)
    if isinstance(space, spaces.Box):
        return rng.uniform(space.low, space.high).astype(space.dtype)
    raise TypeError(f"no action drawer for {space}")


# ---------------------------------------------------------------- cases
def gym_single(env_id: str, seed: int = 3, steps: int = STEPS, **kwargs: Any) -> dict[str, str]:
    """gymnasium.make(env_id) reset with `seed`, stepped with drawn actions."""
    import gymnasium as gym

    import socialzoo  # noqa: F401  (registers the ids)

    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(seed + 1000)
    digest = Digest()
    obs, info = env.reset(seed=seed)
    digest.add("obs", obs)
    digest.add("info", info)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(_action(env.action_space, rng))
        digest.add("obs", obs)
        digest.add("reward", reward)
        digest.add("flags", (terminated, truncated))
        digest.add("info", info)
        if terminated or truncated:
            obs, info = env.reset()
            digest.add("obs", obs)
            digest.add("info", info)
    env.close()
    return digest.hexdigests()


def gym_vector(
    env_id: str, num_envs: int = 3, seed: int = 5, steps: int = STEPS, **kwargs: Any
) -> dict[str, str]:
    """gymnasium.make_vec(env_id, vector_entry_point) reset with `seed`, stepped with drawn actions."""
    import gymnasium as gym

    import socialzoo  # noqa: F401

    env = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point", **kwargs)
    rng = np.random.default_rng(seed + 2000)
    digest = Digest()
    obs, info = env.reset(seed=seed)
    digest.add("obs", obs)
    digest.add("info", info)
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(_action(env.action_space, rng))
        digest.add("obs", obs)
        digest.add("reward", reward)
        digest.add("flags", (terminated, truncated))
        digest.add("info", info)
    env.close()
    return digest.hexdigests()


def parallel(make: Callable[[], Any], seed: int = 7, steps: int = STEPS) -> dict[str, str]:
    """A PettingZoo ParallelEnv reset with `seed`, every live agent acting; a new episode on the end."""
    env = make()
    rng = np.random.default_rng(seed + 3000)
    digest = Digest()
    obs, info = env.reset(seed=seed)
    digest.add("obs", obs)
    digest.add("info", info)
    for _ in range(steps):
        actions = {agent: _action(env.action_space(agent), rng) for agent in env.agents}
        obs, reward, terminated, truncated, info = env.step(actions)
        digest.add("obs", obs)
        digest.add("reward", reward)
        digest.add("flags", (terminated, truncated))
        digest.add("info", info)
        if not env.agents:
            obs, info = env.reset()
            digest.add("obs", obs)
            digest.add("info", info)
    return digest.hexdigests()


def sb3_vec(num_envs: int = 3, seed: int = 9, steps: int = STEPS, **overrides: Any) -> dict[str, str]:
    """socialzoo's SB3 VecEnv seeded with `seed`."""
    from socialzoo.env.sb3_vec import SB3VecEnv

    env = SB3VecEnv(num_envs, **overrides)
    env.seed(seed)
    rng = np.random.default_rng(seed + 4000)
    digest = Digest()
    digest.add("obs", env.reset())
    for _ in range(steps):
        actions = np.array([_action(env.action_space, rng) for _ in range(num_envs)])
        obs, reward, done, infos = env.step(actions)
        digest.add("obs", obs)
        digest.add("reward", reward)
        digest.add("flags", done)
        digest.add("info", infos)
    env.close()
    return digest.hexdigests()


def torchrl_rollout(make: Callable[[], Any], seed: int = 11, steps: int = 60) -> dict[str, str]:
    """A TorchRL env's rollout with a random policy of its own seeded generator."""
    import torch

    env = make()
    env.set_seed(seed)
    torch.manual_seed(seed)
    rollout = env.rollout(steps, break_when_any_done=False)
    digest = Digest()
    for key in sorted(rollout.keys(include_nested=True, leaves_only=True), key=str):
        part = "info"
        name = key if isinstance(key, str) else "/".join(key)
        if "observation" in name:
            part = "obs"
        elif "reward" in name:
            part = "reward"
        elif name.endswith(("done", "terminated", "truncated")):
            part = "flags"
        digest.add(part, (name, rollout.get(key)))
    return digest.hexdigests()


def cases(recorded: tuple[str, ...] = ()) -> dict[str, Callable[[], dict[str, str]]]:
    """Case name -> a function computing its digests: every registered id, every adapter (and the
    `recorded` scenes, replayed and hybrid)."""
    import gymnasium as gym

    import socialzoo
    from socialzoo.env.parallel import parallel_crowd_env, parallel_env

    out: dict[str, Callable[[], dict[str, str]]] = {}
    ids = sorted(i for i in gym.registry if i.startswith("socialzoo/"))
    for env_id in ids:
        out[f"single {env_id}"] = lambda env_id=env_id: gym_single(env_id)
        out[f"vector {env_id}"] = lambda env_id=env_id: gym_vector(env_id)
    # Episodes that end (a short time limit) and other options of the benchmark's ids.
    out["single ActionSelection short"] = lambda: gym_single("socialzoo/ActionSelection-v2", max_steps=60)
    out["vector ActionSelection short"] = lambda: gym_vector("socialzoo/ActionSelection-v2", max_steps=50)
    out["single ActionSelection velocity"] = lambda: gym_single(
        "socialzoo/ActionSelection-v2", robot_action="velocity", max_steps=80
    )
    out["single ActionSelection socialgym1"] = lambda: gym_single(
        "socialzoo/ActionSelection-v2", observation={"layout": "socialgym1"}, steps=40
    )
    for people in (
        "orca",
        "groups",
        "sf@0.5+orca@0.5",
        "learned:socialzoo/agents/shipped/humans.safetensors",
    ):
        # The file of the package on the path (another checkout's with PYTHONPATH), from any folder;
        # the case keeps its name.
        models = people.replace("socialzoo/", f"{Path(socialzoo.__file__).parent}/", 1)
        out[f"vector ActionSelection people={people}"] = lambda models=models: gym_vector(
            "socialzoo/ActionSelection-v2", people={"models": models}, max_steps=70, steps=90
        )
    out["vector ActionSelection counterfactual"] = lambda: gym_vector(
        "socialzoo/ActionSelection-v2", people={"counterfactual": True}, max_steps=60, steps=70
    )
    out["vector CrowdNav discrete"] = lambda: gym_vector("socialzoo/CrowdNav-v1", action="discrete")
    out["vector CrowdNav dict"] = lambda: gym_vector("socialzoo/CrowdNav-v1", observation="dict", steps=60)
    out["vector CrowdNav world frame"] = lambda: gym_vector("socialzoo/CrowdNav-v1", action_frame="world")
    out["parallel benchmark 2 robots 3 learned"] = lambda: parallel(
        lambda: parallel_env(map="open_room", num_robots=2, num_learned_humans=3, max_steps=70)
    )
    out["parallel benchmark gdc1 velocity"] = lambda: parallel(
        lambda: parallel_env(num_robots=3, robot_action="velocity", max_steps=60)
    )
    out["parallel crowdnav 3 robots"] = lambda: parallel(lambda: parallel_crowd_env(num_robots=3))
    out["parallel crowdnav walls 2 robots"] = lambda: parallel(
        lambda: parallel_crowd_env(variant="Walls", num_robots=2), steps=60
    )
    out["sb3 benchmark"] = lambda: sb3_vec()
    out["sb3 benchmark short"] = lambda: sb3_vec(max_steps=50)
    out.update(_torchrl_cases())
    for scene in recorded:
        for humans in ("replay", "hybrid:orca", "hybrid:sf"):
            out[f"recorded {scene} {humans}"] = lambda scene=scene, humans=humans: gym_vector(
                "socialzoo/CrowdNavRecorded-v3", 16, steps=300, family=f"recorded_{scene}", humans=humans
            )
    return out


def _torchrl_cases() -> dict[str, Callable[[], dict[str, str]]]:
    """The TorchRL adapters, when torchrl is installed."""
    try:
        import torchrl  # noqa: F401
    except ImportError:
        return {}
    from socialzoo.env.torchrl_env import SocialNavTorchEnv
    from socialzoo.env.torchrl_single import ActionSelectionTorchEnv, CrowdNavTorchEnv

    return {
        "torchrl multi-agent": lambda: torchrl_rollout(
            lambda: SocialNavTorchEnv(
                batch_size=2, map="open_room", num_robots=2, num_learned_humans=2, max_steps=40
            )
        ),
        "torchrl single": lambda: torchrl_rollout(lambda: ActionSelectionTorchEnv(num_envs=2, max_steps=40)),
        "torchrl crowdnav": lambda: torchrl_rollout(lambda: CrowdNavTorchEnv(num_envs=2)),
    }


def record(names: list[str] | None = None) -> dict[str, dict[str, str]]:
    """Digests of the named cases (all by default)."""
    table = cases()
    chosen = names if names is not None else list(table)
    return {name: table[name]() for name in chosen}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", help="write the digests to this JSON file")
    parser.add_argument("--compare", help="compare with the digests of this JSON file")
    parser.add_argument(
        "--only", nargs="*", help="case names or their first words, e.g. recorded (default: all)"
    )
    parser.add_argument("--recorded", default="", help="recorded scenes to add, e.g. eth,univ")
    args = parser.parse_args(argv)
    before = json.loads(open(args.compare).read()) if args.compare else None
    table = cases(tuple(s for s in args.recorded.split(",") if s))
    names = list(before) if before else None
    if args.only:
        names = [n for n in table if any(n == o or n.startswith(o + " ") for o in args.only)]
        names += [o for o in args.only if not any(n == o or n.startswith(o + " ") for n in table)]
    digests: dict[str, dict[str, str]] = {}
    differ = 0
    for name in names or list(table):
        if name not in table:
            print(f"MISSING  {name}")
            differ += 1
            continue
        digests[name] = table[name]()
        if before is not None:
            changed = [p for p in Digest.PARTS if before.get(name, {}).get(p) != digests[name][p]]
            differ += bool(changed)
            print(
                f"{'DIFFERS' if changed else 'same   '}  {name}"
                + (f"  ({', '.join(changed)})" if changed else "")
            )
        else:
            print(f"{name}: {digests[name]}")
        sys.stdout.flush()
    if args.out:
        with open(args.out, "w") as f:
            json.dump(digests, f, indent=1, sort_keys=True)
    if before is not None:
        print(f"{differ} of {len(digests)} cases differ")
    return 1 if differ else 0


if __name__ == "__main__":
    # The digests are compared across machines: numpy's kernels no wider than AVX2 (see
    # tools/reference_numerics.py), set before numpy loads, in a fresh process where needed.
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from reference_numerics import reference_settings

    missing = {k: v for k, v in reference_settings().items() if k not in os.environ}
    if missing:
        os.execve(sys.executable, [sys.executable, *sys.argv], {**os.environ, **missing})
    sys.exit(main())
