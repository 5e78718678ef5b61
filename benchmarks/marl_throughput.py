"""Multi-agent env throughput on gdc1: the native TorchRL env (B = 256) against TorchRL's
PettingZooWrapper over the ParallelEnv (B = 1), in the same run.

Both step 1 robot (random sub-policies) + 8 learned humans (random velocities) + the other
humans of a 25-human crowd on their social force, with TorchRL's random actions
(`env.rand_action`) and `step_and_maybe_reset`, so finished episodes restart as in a collector.
An env-step is one world step; agent-steps count the 9 acting agents. Issue 13's target: the
native env at least 10x the wrapper in env-steps/s.

Run: python benchmarks/marl_throughput.py [--json] [--seconds 3] [--batch 256]
(--json: one JSON object per line with name, batch, env_steps_per_s, agent_steps_per_s)
"""

from __future__ import annotations

import json
import sys

import torch
from _common import measure, parser, positive_int

import socialzoo  # noqa: F401
from socialzoo.env.parallel import parallel_env
from socialzoo.env.torchrl_env import SocialNavTorchEnv

CROWD = {"scenario": {"min_humans": 25, "max_humans": 25}}
ROBOTS, LEARNED = 1, 8


def native(map_name: str, batch: int):
    env = SocialNavTorchEnv(
        batch_size=batch, seed=0, map=map_name, num_robots=ROBOTS, num_learned_humans=LEARNED, **CROWD
    )
    state = {"td": env.reset()}

    def step() -> None:
        _, state["td"] = env.step_and_maybe_reset(env.rand_action(state["td"]))

    return step


def wrapper(map_name: str):
    from torchrl.envs.libs.pettingzoo import PettingZooWrapper

    env = PettingZooWrapper(
        env=parallel_env(
            map=map_name, num_robots=ROBOTS, num_learned_humans=LEARNED, episode_info=False, **CROWD
        ),
        use_mask=True,
        return_state=True,
        done_on_any=False,
        seed=0,
    )
    state = {"td": env.reset()}

    def step() -> None:
        _, state["td"] = env.step_and_maybe_reset(env.rand_action(state["td"]))

    return step


def report(name: str, batch: int, calls_per_s: float, as_json: bool) -> None:
    env_steps = calls_per_s * batch
    fig = {
        "name": name,
        "batch": batch,
        "env_steps_per_s": env_steps,
        "agent_steps_per_s": env_steps * (ROBOTS + LEARNED),
    }
    if as_json:
        print(json.dumps(fig))
    else:
        print(
            f"{name:<44} B={batch:<5d} {env_steps:>10,.0f} env-steps/s {fig['agent_steps_per_s']:>12,.0f} agent-steps/s"
        )
    sys.stdout.flush()


def main() -> None:
    p = parser(__doc__.split("\n\n")[0])
    p.add_argument("--map", default="gdc1")
    p.add_argument("--batch", type=positive_int, default=256, help="worlds of the native env")
    args = p.parse_args()
    torch.set_num_threads(1)
    torch.manual_seed(0)
    label = f"R={ROBOTS} learned H={LEARNED} crowd 25"
    rates = {}
    rate, _ = measure(native(args.map, args.batch), args.seconds)
    rates["native"] = rate * args.batch
    report(f"native SocialNavTorchEnv {args.map} {label}", args.batch, rate, args.json)
    rate, _ = measure(wrapper(args.map), args.seconds)
    rates["wrapper"] = rate
    report(f"PettingZooWrapper(ParallelEnv) {args.map} {label}", 1, rate, args.json)
    if not args.json:
        print(f"native / wrapper: {rates['native'] / rates['wrapper']:.1f}x env-steps/s (target: 10x)")


if __name__ == "__main__":
    main()
