"""PPO training throughput on gdc1 (env steps per second of `model.learn`: collection + update),
through socialzoo's SB3VecEnv (B rows of the batched core in one process) and through the obvious
path, `make_vec_env` of the gym id with 4 DummyVecEnv copies, in the same run.

Every configuration trains behind VecNormalize (as `socialzoo train ppo` does) with SB3's PPO
defaults except the rollout and minibatch sizes named in its label; the first rollout (env
creation, compilation, the first reset) is not timed. Besides wall-clock env-steps/s, each figure
has env-steps per CPU-second of this process (torch on --threads, the env on one core): the rate
an idle core would give, when other work shares the machine.

Run: python benchmarks/train_throughput.py [--json] [--seconds 20] [--threads 1]
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings
from dataclasses import asdict, dataclass

from _common import parser, positive_int

import socialzoo  # noqa: F401  (registers the ids)
from socialzoo.env.registration import ENV_VERSION

GDC1_ID = f"socialzoo/ActionSelection-v{ENV_VERSION}"


@dataclass
class TrainFigure:
    """One measured training configuration."""

    name: str
    envs: int
    n_steps: int
    batch_size: int
    env_steps: int
    seconds: float
    env_steps_per_s: float
    env_steps_per_cpu_s: float


def ours(rows: int):
    from socialzoo.env.sb3_vec import SB3VecEnv

    return SB3VecEnv(rows, map="gdc1")


def dummy(copies: int):
    import gymnasium as gym
    from stable_baselines3.common.env_util import make_vec_env

    return make_vec_env(lambda: gym.make(GDC1_ID), n_envs=copies, seed=0)


def measure(name: str, venv, n_steps: int, batch_size: int, seconds: float) -> TrainFigure:
    """Time whole rollouts (collection + update) of PPO on `venv` for at least `seconds`."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from socialzoo.train.sb3_common import quiet_logger

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*mini-batch size.*")
        model = PPO(
            "MlpPolicy", VecNormalize(venv), n_steps=n_steps, batch_size=batch_size, seed=0, device="cpu"
        )
    model.set_logger(quiet_logger())  # SB3's own logger leaves an empty /tmp/SB3-<date> folder
    rollout = n_steps * venv.num_envs
    model.learn(rollout)  # warm-up: env creation, compiled kernels, the first reset
    start, cpu_start = time.perf_counter(), time.process_time()
    done = 0
    while True:
        model.learn(rollout, reset_num_timesteps=False)
        done += rollout
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            break
    cpu = time.process_time() - cpu_start
    venv.close()
    return TrainFigure(
        name, venv.num_envs, n_steps, batch_size, done, round(elapsed, 2), done / elapsed, done / cpu
    )


def report(fig: TrainFigure, as_json: bool) -> None:
    if as_json:
        print(json.dumps(asdict(fig)))
    else:
        print(
            f"{fig.name:<44} envs={fig.envs:<3d} n_steps={fig.n_steps:<5d} batch={fig.batch_size:<4d} "
            f"{fig.env_steps_per_s:>8,.0f} env-steps/s  {fig.env_steps_per_cpu_s:>8,.0f} per CPU-s  "
            f"({fig.env_steps:,} steps in {fig.seconds:.1f} s)"
        )
    sys.stdout.flush()


def main() -> None:
    p = parser(__doc__)
    p.set_defaults(seconds=20.0)
    p.add_argument("--rows", type=positive_int, default=64, help="rows of the SB3VecEnv (default 64)")
    p.add_argument("--threads", type=positive_int, default=1, help="torch threads (default 1)")
    args = p.parse_args()
    import torch

    torch.set_num_threads(args.threads)
    b = args.rows
    n = max(1, 2048 // b)
    figures = [
        measure(f"SB3VecEnv B={b}, minibatch 256", ours(b), n, 256, args.seconds),
        measure(f"SB3VecEnv B={b}, SB3 minibatch 64", ours(b), n, 64, args.seconds),
        measure("socialzoo train ppo defaults (B=50)", ours(50), 40, 64, args.seconds),
        measure("make_vec_env 4 x DummyVecEnv, SB3 defaults", dummy(4), 2048, 64, args.seconds),
        measure("make_vec_env 4 x DummyVecEnv, minibatch 256", dummy(4), 512, 256, args.seconds),
    ]
    for fig in figures:
        report(fig, args.json)
    if not args.json:
        base = figures[3].env_steps_per_s
        print(f"speed-up over the SB3-default DummyVecEnv path: {figures[0].env_steps_per_s / base:.1f}x")
        print(f"torch threads {args.threads}; load average {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main()
