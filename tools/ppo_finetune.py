"""PPO fine-tuning from a learned policy file: does RL on the benchmark reward move an imitation
policy past Ref's success-against-blame front?

    python tools/ppo_finetune.py --init socialzoo/agents/shipped/dagger.safetensors \\
        --w-blame -2 --w-collision 0 --steps 400000 --out runs/finetune/w2.safetensors
    python tools/ref_tradeoff.py --halt-offsets 0 --learned dagger:runs/finetune/w2.safetensors

Starts Stable-Baselines3 PPO from an MlpPolicy file (`--init`; a ReLU or tanh MLP with its
observation normaliser, such as the shipped DAgger or BC): the actor's layers are copied from the
file and the file's normaliser is kept fixed (VecNormalize's observation statistics never update),
so the untrained model acts exactly as the file does (checked before training). The critic, new,
first learns for `--warmup` steps with the actor frozen; then PPO trains both with a small learning
rate for `--steps` steps on the benchmark env's own training scenarios (never a validation or
test scenario) with the reward's blame and collision weights set by `--w-blame` and
`--w-collision`. The result is written as a policy file of the same name as the source ("dagger"
by default), so `tools/ref_tradeoff.py --learned` evaluates it beside Ref's settings.
docs/reproduce.md ("A learned policy against Ref") gives the measurements.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.agents.mlp import MlpPolicy
from socialzoo.env.config import EnvConfig

# torch activation class of an MlpPolicy activation.
_TORCH_ACTIVATIONS = {"relu": "ReLU", "tanh": "Tanh"}


def ppo_from_policy(
    source: MlpPolicy, config: EnvConfig, *, num_envs: int = 50, seed: int = 0, **ppo: Any
) -> Any:
    """An SB3 PPO model on `config` whose actor is `source`'s network and whose observations are
    normalised by `source`'s fixed normaliser; `ppo`: PPO keyword arguments.

    Raises:
        ValueError: a source without a normaliser, or with an activation PPO's MLP cannot have.
    """
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    from socialzoo.env.sb3_vec import SB3VecEnv

    fixed = source.normalizer
    if fixed is None or source.activation not in _TORCH_ACTIVATIONS:
        raise ValueError(
            f"{source.path}: fine-tuning needs an MLP with an observation normaliser and a ReLU or tanh "
            f"activation (this one: normaliser {fixed is not None}, activation {source.activation!r})"
        )
    venv = VecNormalize(
        VecMonitor(SB3VecEnv(num_envs, config)),
        gamma=ppo.get("gamma", 0.99),
        clip_obs=fixed.clip,
        epsilon=fixed.epsilon,
    )
    venv.obs_rms.mean = fixed.mean.astype(np.float64)
    venv.obs_rms.var = fixed.var.astype(np.float64)
    venv.obs_rms.update = lambda batch: None  # the source's statistics stay as they are
    hidden = [int(w.shape[0]) for w, _ in source.layers[:-1]]
    model = PPO(
        "MlpPolicy",
        venv,
        seed=seed,
        device="cpu",
        verbose=0,
        policy_kwargs={
            "net_arch": {"pi": hidden, "vf": hidden},
            "activation_fn": getattr(torch.nn, _TORCH_ACTIVATIONS[source.activation]),
        },
        **ppo,
    )
    policy = model.policy
    linears = [m for m in policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)] + [
        policy.action_net
    ]
    with torch.no_grad():
        for layer, (w, b) in zip(linears, source.layers, strict=True):
            layer.weight.copy_(torch.as_tensor(w))
            layer.bias.copy_(torch.as_tensor(b))
    return model


def actor_parameters(model: Any) -> list[Any]:
    """The parameters of a PPO model's actor (its policy MLP and action head)."""
    policy = model.policy
    return [*policy.mlp_extractor.policy_net.parameters(), *policy.action_net.parameters()]


def finetune(model: Any, warmup: int, steps: int) -> None:
    """Train the critic alone for `warmup` env steps (the actor frozen), then both for `steps`."""
    actor = actor_parameters(model)
    for p in actor:
        p.requires_grad_(False)
    if warmup:
        model.learn(warmup)
    for p in actor:
        p.requires_grad_(True)
    if steps:
        model.learn(steps, reset_num_timesteps=not warmup)


def exported(model: Any, source: MlpPolicy) -> MlpPolicy:
    """The model's actor as an MlpPolicy of `source`'s name and observation."""
    from socialzoo.train.sb3_export import export_policy

    policy, _ = export_policy(model, source.name, source.observation, model.get_env())
    return policy


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--init", type=Path, required=True, help="the MlpPolicy file to start from")
    parser.add_argument("--out", type=Path, required=True, help="the fine-tuned policy file to write")
    parser.add_argument(
        "--w-blame", type=float, default=-0.1, help="reward weight of blame (benchmark: -0.1)"
    )
    parser.add_argument(
        "--w-collision", type=float, default=0.0, help="reward weight of collisions (benchmark: 0)"
    )
    parser.add_argument("--warmup", type=int, default=40_000, help="critic-only env steps first")
    parser.add_argument("--steps", type=int, default=400_000, help="PPO env steps after the warm-up")
    parser.add_argument("--lr", type=float, default=1e-5, help="Adam learning rate")
    parser.add_argument("--clip", type=float, default=0.1, help="PPO clip range")
    parser.add_argument(
        "--gamma", type=float, default=0.99, help="discount factor (SB3's and the paper's: 0.99)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seeds PPO and the training scenarios")
    args = parser.parse_args()
    import torch

    torch.set_num_threads(1)
    source = MlpPolicy.load(args.init)
    config = EnvConfig().replace(reward={"w_blame": args.w_blame, "w_collision": args.w_collision})
    model = ppo_from_policy(
        source, config, seed=args.seed, n_steps=40, batch_size=500, n_epochs=4, learning_rate=args.lr,
        clip_range=args.clip, ent_coef=0.0, gamma=args.gamma,
    )  # fmt: skip
    probe = np.random.default_rng(0).normal(
        source.normalizer.mean, np.sqrt(source.normalizer.var), (512, source.input_size)
    )
    if not np.array_equal(exported(model, source).act(probe), source.act(probe)):
        raise RuntimeError(f"{args.init}: the PPO actor does not act as the file does before training")
    start = time.perf_counter()
    finetune(model, args.warmup, args.steps)
    seconds = time.perf_counter() - start
    header = dict(source.header)
    run = {**vars(args), "init": str(args.init), "out": str(args.out), "seconds": round(seconds, 1)}
    header["training"] = {**header.get("training", {}), "finetune": run}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    exported(model, source).save(args.out, header)
    print(f"{args.out}: {args.warmup:,} + {args.steps:,} env steps in {seconds:.0f} s")


if __name__ == "__main__":
    main()
