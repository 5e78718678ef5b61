"""`socialzoo train people-bc`: learned people cloned from recorded people (ETH/UCY tracks)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from socialzoo.train.checks import check_int, check_number, check_seed
from socialzoo.train.people_closed_loop import HORIZON, closed_loop_ade, subject_cases
from socialzoo.train.people_demos import Demonstrations, demonstrations
from socialzoo.train.people_replay import WORLD_DT, replay_world
from socialzoo.train.skeleton import Trainer, TrainingRun, run_training

if TYPE_CHECKING:
    from socialzoo.env.human_policy import LearnedHumanPolicy

logger = logging.getLogger(__name__)

TRAINER = Trainer("people-bc", policy_file="people_bc.safetensors", inputs=("scenes",))


class PeopleDataError(ValueError):
    """Training scenes that give nothing to learn from (the message names them and says why)."""


@dataclass(frozen=True, kw_only=True)
class Args:
    """Behaviour cloning of learned people on recorded ETH/UCY tracks.

    Attributes:
        scenes: the training scenes, comma-separated: scenes of socialzoo.data.fetch.SCENES or track
            files (PATH or NAME=PATH: socialzoo.data.fetch.load_recording).
        out: run folder: people_bc.safetensors, run.json.
        seed: seed of the network's initialisation and the batches' order.
        cache: the scenes' cache folder (None: socialzoo.data.fetch.data_dir()).
        window: recorded frames per batch row of the replay.
        val_fraction: the last share of each scene's windows held out for early stopping.
        num_neighbours: neighbours in the observation (EnvConfig.num_human_neighbours).
        action_frame: the action's frame (EnvConfig.human_action_frame).
        action_scale: the action times this times the preferred speed is the desired velocity.
        velocity_noise: the velocity perturbation of the noisy copies, m/s per axis (`demonstrations`).
        noisy_copies: noisy copies of each demonstration (0: the recorded states only).
        label_frames: frames ahead that each label reaches: the desired velocity, held, that carries the
            person from its state to its recorded position that many frames later (1: the next frame;
            with a long relaxation time a label on the next frame amplifies the tracks' jitter).
        relaxation_time: tau of the learned people's relaxation towards the network's desired
            velocity, s (HumanConfig.learned_relaxation_time, written into the policy file): the
            longer it is, the longer they keep their velocity, and each label is the desired
            velocity that, held, reaches the recorded position `label_frames` frames on.
        learned_forces: whether the social force's people and wall forces act on the learned
            people too (HumanConfig.learned_forces, written into the policy file): then each label
            compensates the forces at its frame. Off (the default): the network's desired velocity
            alone moves them, and the labels are the recorded motion's.
        hidden: hidden units per layer.
        depth: hidden layers.
        lr: Adam learning rate.
        batch_size: demonstrations per gradient step.
        max_epochs: passes over the training demonstrations at most.
        patience: stop after this many passes without a better validation loss.
        threads: torch CPU threads.
        progress: show progress.
    """

    scenes: str = "eth,hotel,univ,zara1"
    out: Path = Path("runs/people_bc")
    seed: int = 0
    cache: Path | None = None
    window: int = 40
    val_fraction: float = 0.15
    num_neighbours: int = 6
    action_frame: Literal["world", "human"] = "human"
    action_scale: float = 4.0
    velocity_noise: float = 0.4
    noisy_copies: int = 2
    label_frames: int = 5
    relaxation_time: float = 16.0
    learned_forces: bool = False
    hidden: int = 128
    depth: int = 2
    lr: float = 1e-3
    batch_size: int = 512
    max_epochs: int = 200
    patience: int = 15
    threads: int = 1
    progress: bool = True

    def __post_init__(self) -> None:
        from socialzoo.data.fetch import check_recordings

        names = tuple(s.strip() for s in str(self.scenes).split(",") if s.strip())
        if not names:
            raise ValueError(f"Args.scenes must name at least one scene, got {self.scenes!r}")
        object.__setattr__(self, "scenes", ",".join(check_recordings(names)))
        object.__setattr__(self, "out", Path(self.out))
        if self.cache is not None:
            object.__setattr__(self, "cache", Path(self.cache))
        check_int(self, "window", low=2)
        check_int(self, "hidden", "depth", "batch_size", "max_epochs", "patience", "threads", low=1)
        check_int(self, "label_frames", low=1)
        check_int(self, "num_neighbours", "noisy_copies", low=0)
        check_seed(self)
        check_number(self, "velocity_noise", low=0.0)
        check_number(self, "relaxation_time", "action_scale", "lr", low=0.0, low_open=True)
        check_number(self, "val_fraction", low=0.0, low_open=True, high=0.5)

    @property
    def scene_names(self) -> tuple[str, ...]:
        """The training scenes."""
        return tuple(self.scenes.split(","))


# ---------------------------------------------------------------------------- training
def train(args: Args) -> Path:
    """Clone recorded people on the trainer skeleton; returns people_bc.safetensors.

    Each training scene is replayed in the batched core (socialzoo.env.core.BatchedCore, everyone a follower
    of its track, socialzoo.env.replay; one row per time window of `window` frames; a robot parked far away
    that nobody sees). At every recorded frame each person present on the frame before, the frame and the
    frame `label_frames` after gives one demonstration:

    - the observation a learned person has there (socialzoo.env.human_agents.human_observations): its
      route is its entry and its recorded exit (the last point of its whole track), its preferred speed
      its mean recorded speed, its own velocity the one it walked into the frame with (frame - 1 ->
      frame; the replay's is the next segment's, which would give the answer away), the others' as the
      replay has them; neighbour rows of the parked robot are zeroed (absent), as it is not there;
    - the action that walks it to its recorded position `label_frames` frames on (5, 2 s): the desired
      velocity v_d that, held, through the relaxation every learned person walks by
      (dv/dt = (v_d - v) / tau + F, tau = `relaxation_time`, 16 s, written into the policy file), covers
      the recorded displacement over those frames (the speed cap aside), expressed as an action of
      the policy's frame and scale (the inverse of socialzoo.env.human_agents.action_velocities),
      clipped to [-ACTION_LIMIT, ACTION_LIMIT]. By default no force acts on the learned people (F = 0,
      HumanConfig.learned_forces off, written into the policy file): the network's desired velocity
      alone moves them, and it sees its neighbours to keep clear of them. With `--learned-forces`, F is
      the other people's and walls' social forces at the frame, held over the frame, and each label
      compensates them. On the training scenes' held-out time, walked closed-loop, the people without
      forces came closer to the recorded ones on every scene, and a long relaxation time with a label
      2 s ahead closer than the people's own 0.5 s with a label on the next frame (docs/humans.md):
      over a few seconds real people keep their velocity, and the network steers it slowly.

    An MLP (tanh hidden layers, tanh output) is fitted to them with MSE and Adam; the last `val_fraction` of
    each scene's windows (in time) are held out for early stopping; on that held-out time the run also walks
    the policy closed-loop (closed_loop_ade) and records the error. The run folder holds run.json and
    people_bc.safetensors, a learned human policy file (socialzoo.env.human_policy) that `learned:PATH` walks
    anywhere; `socialzoo humans realism --models learned:PATH` measures it on a scene it never saw
    (socialzoo.studies.realism).
    """
    return run_training(TRAINER, args, fit)


def fit(run: TrainingRun) -> dict[str, Any]:
    """Collect the demonstrations, fit the network with early stopping, save the policy."""
    import torch

    from socialzoo.data.fetch import load_recording
    from socialzoo.train.marl_args import env_id
    from socialzoo.train.policy_net import mlp

    args: Args = run.args
    world = replay_world(learned_forces=args.learned_forces, relaxation_time=args.relaxation_time)
    train_parts, val_parts, per_scene, held_out = [], [], {}, {}
    for spec in args.scene_names:
        recording = load_recording(spec, cache=args.cache)
        name = recording.name  # a track file's NAME (or file stem), not its path
        demos = demonstrations(
            recording, window=args.window, num_neighbours=args.num_neighbours,
            action_frame=args.action_frame, action_scale=args.action_scale,
            world=world,
            velocity_noise=args.velocity_noise, noisy_copies=args.noisy_copies,
            label_frames=args.label_frames, seed=args.seed,
        )  # fmt: skip
        count = int(demos.window.max()) + 1 if len(demos) else 0
        cut = count - max(1, round(args.val_fraction * count))
        train_parts.append(demos.take(np.flatnonzero(demos.window < cut)))
        val_parts.append(demos.take(np.flatnonzero(demos.window >= cut)))
        held_out[name] = (recording, subject_cases(recording, cut * args.window, recording.num_frames - 1))
        per_scene[name] = {
            "demonstrations": len(demos),
            "clipped": round(float(demos.clipped.mean()), 4) if len(demos) else 0.0,
        }
        logger.info("people-bc: %s: %d demonstrations", name, len(demos))
    empty = [name for name, scene in per_scene.items() if not scene["demonstrations"]]
    if empty:
        raise PeopleDataError(
            f"people-bc: no demonstration in {', '.join(empty)}: one needs a person seen on "
            f"{args.label_frames + 2} frames in a row (--label-frames + 2), more than the waypoint radius "
            "from its exit"
        )
    train_set, val_set = Demonstrations.concatenate(train_parts), Demonstrations.concatenate(val_parts)
    if len(train_set) == 0:
        raise PeopleDataError(
            f"people-bc: nothing left to train on in {', '.join(per_scene)}: the last of each scene's windows "
            f"of {args.window} frames is held out for validation (--val-fraction), and no scene has a second; "
            "pass a smaller --window"
        )
    loc = train_set.obs.mean(0)
    scale = train_set.obs.std(0)
    scale = np.where(scale > 1e-6, scale, 1.0).astype(np.float32)
    # `depth` tanh layers of `hidden` units, then the 2 pre-tanh action means.
    net = mlp(train_set.obs.shape[1], [args.hidden] * args.depth, 2, "tanh", None)
    optimiser = torch.optim.Adam(net.parameters(), lr=args.lr)
    x = torch.as_tensor((train_set.obs - loc) / scale)
    y = torch.as_tensor(train_set.action)
    xv = torch.as_tensor((val_set.obs - loc) / scale)
    yv = torch.as_tensor(val_set.action)
    best, best_state, best_epoch, epoch = math.inf, None, 0, 0
    bar = run.progress(args.max_epochs, unit="epoch")
    history = []
    for epoch in range(1, args.max_epochs + 1):
        order = torch.randperm(len(x))
        total = 0.0
        for lo in range(0, len(x), args.batch_size):
            idx = order[lo : lo + args.batch_size]
            loss = ((torch.tanh(net(x[idx])) - y[idx]) ** 2).mean()
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item() * len(idx)
        with torch.no_grad():
            val = float(((torch.tanh(net(xv)) - yv) ** 2).mean())
        history.append((total / len(x), val))
        run.writer.add_scalar("loss/train", total / len(x), epoch)
        run.writer.add_scalar("loss/val", val, epoch)
        bar.update(1)
        if val < best:
            best, best_epoch = val, epoch
            best_state = {k: v.detach().clone() for k, v in net.state_dict().items()}
        elif epoch - best_epoch >= args.patience:
            break
    assert best_state is not None
    net.load_state_dict(best_state)
    see_robots_as_people(net, args.num_neighbours)
    policy = to_policy(net, loc, scale, args)
    policy.save(
        run.policy,
        env_id(),
        run.recorded(
            training_record(
                args, per_scene, len(train_set), len(val_set), best, best_epoch, command=run.record["command"]
            )
        ),
    )
    with torch.no_grad():
        baseline = float((yv**2).mean())
    # How close the policy walks to the recorded people of the held-out time, closed-loop: the
    # measure the trainer's defaults were chosen on (docs/humans.md).
    walked = {
        name: closed_loop_ade(recording, cases, run.policy, world=world)
        for name, (recording, cases) in held_out.items()
    }
    closed_loop = {name: round(float(a.mean()), 4) for name, a in walked.items() if len(a)}
    logger.info("people-bc: held-out time walked closed-loop, ADE over %d frames: %s", HORIZON, closed_loop)
    return {
        "held_out_closed_loop_ade": closed_loop,
        "held_out_closed_loop_ade_mean": round(float(np.mean(list(closed_loop.values()))), 4)
        if closed_loop
        else None,
        "train_demonstrations": len(train_set),
        "val_demonstrations": len(val_set),
        "scenes": per_scene,
        "epochs": epoch,
        "best_epoch": best_epoch,
        "val_mse": round(best, 6),
        "val_mse_zero_action": round(baseline, 6),
        "train_mse_last": round(history[-1][0], 6),
    }


def see_robots_as_people(net: Any, num_neighbours: int) -> None:
    """Zero the first layer's weights of the neighbours' robot flags. The recordings hold no robot,
    so the flags were 0 in every demonstration and their weights kept their random initial values:
    left so, a robot among the neighbours would add a random term. Zeroed, a robot is seen as the
    person its row otherwise describes (position and velocity), and nothing else changes."""
    import torch

    from socialzoo.env.human_agents import NEIGHBOUR_SIZE, OWN_SIZE

    flags = [OWN_SIZE + NEIGHBOUR_SIZE * k + NEIGHBOUR_SIZE - 1 for k in range(num_neighbours)]
    with torch.no_grad():
        net[0].weight[:, flags] = 0.0


def to_policy(net: Any, loc: np.ndarray, scale: np.ndarray, args: Args) -> LearnedHumanPolicy:
    """The trained network as a learned human policy."""
    from socialzoo.env.human_policy import LearnedHumanPolicy
    from socialzoo.train.policy_net import linear_layers

    return LearnedHumanPolicy(
        linear_layers(net), "tanh", loc, scale, args.num_neighbours, args.action_frame, args.action_scale,
        learned_forces=args.learned_forces, relaxation_time=args.relaxation_time,
    )  # fmt: skip


def training_record(
    args: Args,
    scenes: dict[str, Any],
    num_train: int,
    num_val: int,
    val_mse: float,
    best_epoch: int,
    *,
    command: str,
) -> dict[str, Any]:
    """The policy file's training record (plain JSON); `command` is the run's, as run.json holds it."""
    return {
        "algorithm": "people-bc",
        "scenes": list(args.scene_names),
        "seed": args.seed,
        "world_dt": WORLD_DT,
        "window": args.window,
        "velocity_noise": args.velocity_noise,
        "noisy_copies": args.noisy_copies,
        "label_frames": args.label_frames,
        "relaxation_time": args.relaxation_time,
        "learned_forces": args.learned_forces,
        "per_scene": scenes,
        "train_demonstrations": num_train,
        "val_demonstrations": num_val,
        "val_mse": round(val_mse, 6),
        "best_epoch": best_epoch,
        "command": command,
    }
