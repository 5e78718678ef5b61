"""Check the TorchRL adapters on an accelerator: TorchRL's spec check with the tensors on DEVICE,
every tensor of a seeded rollout on DEVICE, and the rollout the same, value for value, as the
one on the CPU (the simulation runs in numpy either way; only the tensors move).

    python tools/gpu_torchrl_check.py --device cuda [--steps 60] [--batch 8]

Prints one line per env and a speed line (env steps/s on the CPU and on DEVICE, the transfers
included); exits 1 when a check fails. Run on a machine with a GPU (it is no test: CI has none).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable

import torch
from tensordict import TensorDictBase
from torchrl.envs import EnvBase
from torchrl.envs.utils import check_env_specs

from socialzoo.env.torchrl_env import SocialNavTorchEnv
from socialzoo.env.torchrl_single import ActionSelectionTorchEnv, CrowdNavTorchEnv


def _action_selection(batch: int, device: str) -> EnvBase:
    env = ActionSelectionTorchEnv(batch, max_steps=40, device=device)
    env.set_seed(0)
    return env


def _social_nav(batch: int, device: str) -> EnvBase:
    return SocialNavTorchEnv(
        batch_size=batch, seed=0, device=device, num_robots=2, num_learned_humans=3, max_steps=40
    )


def _crowdnav(batch: int, device: str) -> EnvBase:
    env = CrowdNavTorchEnv(batch, device=device)
    env.set_seed(0)
    return env


ENVS: dict[str, Callable[[int, str], EnvBase]] = {
    "ActionSelectionTorchEnv": _action_selection,
    "SocialNavTorchEnv (2 robots, 3 learned people)": _social_nav,
    "CrowdNavTorchEnv": _crowdnav,
}


def seeded_rollout(env: EnvBase, steps: int) -> TensorDictBase:
    """A rollout whose actions are drawn on the CPU from a fixed torch seed, then moved to the
    env's device, so that the CPU and DEVICE runs act alike."""
    cpu_actions = env.full_action_spec.clone().to("cpu")
    generator_state = torch.random.get_rng_state()
    torch.manual_seed(1234)

    def act(td: TensorDictBase) -> TensorDictBase:
        return td.update(cpu_actions.rand().to(env.device))

    try:
        return env.rollout(steps, policy=act, break_when_any_done=False)
    finally:
        torch.random.set_rng_state(generator_state)


def leaves_off_device(td: TensorDictBase, device: torch.device) -> list[str]:
    return [
        "/".join(key) if isinstance(key, tuple) else key
        for key, value in td.items(include_nested=True, leaves_only=True)
        if value.device != device
    ]


def leaves_that_differ(mine: TensorDictBase, reference: TensorDictBase) -> list[str]:
    keys = set(reference.keys(include_nested=True, leaves_only=True))
    if set(mine.keys(include_nested=True, leaves_only=True)) != keys:
        return ["(the key sets differ)"]
    return [str(key) for key in sorted(keys, key=str) if not torch.equal(mine[key].cpu(), reference[key])]


def steps_per_second(env: EnvBase, steps: int) -> float:
    start = time.perf_counter()
    seeded_rollout(env, steps)
    if env.device.type == "cuda":
        torch.cuda.synchronize()
    return steps * env.batch_size.numel() / (time.perf_counter() - start)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--device", default="cuda")
    parser.add_argument("--steps", type=int, default=60)
    parser.add_argument("--batch", type=int, default=8)
    args = parser.parse_args(argv)
    device = torch.empty(0, device=args.device).device  # "cuda" -> cuda:0, as the tensors say
    if device.type == "cuda":
        print(f"torch {torch.__version__}, {torch.cuda.get_device_name(device)}")
    failures = 0
    for name, make in ENVS.items():
        on_device = make(args.batch, args.device)
        check_env_specs(on_device, seed=0)
        on_device = make(args.batch, args.device)
        on_cpu = make(args.batch, "cpu")
        moved = seeded_rollout(on_device, args.steps)
        reference = seeded_rollout(on_cpu, args.steps)
        off = leaves_off_device(moved, device)
        differ = leaves_that_differ(moved, reference)
        ok = not off and not differ
        failures += not ok
        speed = (
            f"env steps/s: cpu {steps_per_second(make(args.batch, 'cpu'), args.steps):,.0f}, "
            f"{device} {steps_per_second(make(args.batch, args.device), args.steps):,.0f}"
        )
        print(
            f"{'ok  ' if ok else 'FAIL'} {name}: spec check passed; {len(reference.keys(True, True))} "
            f"tensors x {args.steps} steps x {args.batch} rows; off {device}: {off or 'none'}; "
            f"differ from the CPU run: {differ or 'none'}; {speed}"
        )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
