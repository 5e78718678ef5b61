"""Learned CrowdNav policies at inference: the attention-over-people network (socialzoo.train.crowd_attention) and
its policy head, run in numpy from a socialzoo policy file (safetensors with a JSON header)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from socialzoo.env.crowd_observation import human_features, robot_features
from socialzoo.env.crowd_variants import CROWD_ENV_VERSION
from socialzoo.env.policy_file import (
    PolicyFileError,
    env_version,
    mlp_forward,
    read_policy_file,
    save_policy_file,
)

POLICY_NAME = "crowdnav"
# The CrowdNav task's env ids carry their own version (socialzoo.env.crowd_variants).
_LAYER = re.compile(r"(?P<group>.+)\.(?P<index>\d+)\.(?P<kind>weight|bias)$")


def _layers(tensors: dict[str, np.ndarray], prefix: str, where: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """The float64 (W.T (in, out), b) pairs of a torch Sequential's Linear layers named
    prefix.<i>.weight, in order: the layers of socialzoo.env.policy_file.mlp_forward."""
    found: dict[int, dict[str, np.ndarray]] = {}
    for name, value in tensors.items():
        match = _LAYER.fullmatch(name)
        if match and match["group"] == prefix:
            found.setdefault(int(match["index"]), {})[match["kind"]] = value
    if not found or any(set(v) != {"weight", "bias"} for v in found.values()):
        raise PolicyFileError(f"{where}: no complete layers {prefix}.<i>.weight/bias")
    return [
        (found[i]["weight"].astype(np.float64).T, found[i]["bias"].astype(np.float64)) for i in sorted(found)
    ]


class CrowdAttentionPolicy:
    """A learned CrowdNav policy (PPO with attention over people), greedy.

    Greedy: the most likely of CrowdNav's discrete actions, or the mean velocity.

    The file's tensors: `attention.embed.*`, `attention.value.*`, `attention.score.*` (the pooling network),
    `policy.*` (the policy MLP on its features) and `action.weight`, `action.bias` (the action head: logits,
    or the mean action in [-1, 1]). Its header says the observation's person slots and layout
    (`header["observation"]["signals"]` true for the task's signals, 9 robot and 8 person features,
    socialzoo.env.crowd_observation; a file without the key has CrowdNav's joint state, 6 and 7), the
    activation of the policy MLP, the action kind and the task's env id.

    Args:
        tensors: the file's tensors (listed above).
        header: its header.
        where: the file, for messages.
    """

    name = POLICY_NAME
    reads_core = False

    def __init__(self, tensors: dict[str, np.ndarray], header: dict[str, Any], where: str = "policy") -> None:
        network = header.get("network", {})
        try:
            self.slots = int(header["observation"]["slots"])
            signals = header["observation"].get("signals", False)
            self.action_kind = str(network["action"])
            self.activation = str(network["activation"])
        except (AttributeError, KeyError, TypeError, ValueError) as err:
            raise PolicyFileError(f"{where}: the header lacks the crowd policy's shape ({err})") from None
        if not isinstance(signals, bool):
            raise PolicyFileError(
                f"{where}: header observation.signals must be true or false, got {signals!r}"
            )
        self.signals = signals
        self.robot_dim = len(robot_features(signals))
        self.human_dim = len(human_features(signals))
        if self.action_kind not in ("discrete", "continuous") or self.activation not in ("tanh", "relu"):
            raise PolicyFileError(
                f"{where}: unknown action {self.action_kind!r} or activation {self.activation!r}"
            )
        self.embed = _layers(tensors, "attention.embed", where)
        self.value = _layers(tensors, "attention.value", where)
        self.score = _layers(tensors, "attention.score", where)
        self.policy = (
            _layers(tensors, "policy", where) if any(k.startswith("policy.") for k in tensors) else []
        )
        if "action.weight" not in tensors or "action.bias" not in tensors:
            raise PolicyFileError(f"{where}: no action head (action.weight, action.bias)")
        self.action = (
            tensors["action.weight"].astype(np.float64).T,
            tensors["action.bias"].astype(np.float64),
        )
        pair = self.robot_dim + self.human_dim
        if self.embed[0][0].shape[0] != pair:
            layout = "with" if signals else "without"
            raise PolicyFileError(
                f"{where}: the embedding takes {self.embed[0][0].shape[0]} inputs, not {pair} (the layout "
                f"{layout} signals, header observation.signals)"
            )
        self.header = header

    @property
    def task_overrides(self) -> dict[str, Any]:
        """The task config it acts in: CrowdNav's discrete or continuous actions, as it was trained
        (and the signals, for a policy trained with them; the world action frame, for one trained
        with CrowdNav's world-frame velocities: its header's training.task.action_frame)."""
        task = self.header.get("training", {}).get("task", {})
        world = isinstance(task, dict) and task.get("action_frame") == "world"
        return {
            "action": self.action_kind,
            **({"signals": True} if self.signals else {}),
            **({"action_frame": "world"} if world else {}),
        }

    def check_config(self, config: Any) -> None:
        """Refuse a task config whose robot moves by other kinematics than the one it was trained on
        (its header's training.task.robot.kinematics): a unicycle's (speed, turn) played as holonomic
        velocities, or the reverse, has as many actions and runs without a word.

        Raises:
            PolicyTaskError: the two kinematics differ.
        """
        from socialzoo.agents import PolicyTaskError

        robot = self.header.get("training", {}).get("task", {}).get("robot", {})
        trained = robot.get("kinematics") if isinstance(robot, dict) else None
        acting = getattr(getattr(config, "robot", None), "kinematics", None)
        if trained and acting and trained != acting:
            raise PolicyTaskError(
                f"policy {self.name!r} was trained with a {trained} robot ({self.header.get('env_id')}), but this "
                f"task's robot is {acting}: evaluate it on a task of its kinematics (e.g. --variant "
                f"{'Unicycle' if trained == 'unicycle' else 'the default'})"
            )

    @property
    def observation_size(self) -> int:
        """Length of the flat observation the policy reads."""
        return self.robot_dim + (self.human_dim + 1) * self.slots

    def features(self, obs: np.ndarray) -> np.ndarray:
        """(N, R + value size) [robot state, attention-pooled crowd feature] of flat observations
        (R: the robot's features, 6, with signals 9)."""
        n, h, r, p = obs.shape[0], self.slots, self.robot_dim, self.human_dim
        robot = obs[:, :r].astype(np.float64)
        humans = obs[:, r : r + h * p].reshape(n, h, p).astype(np.float64)
        mask = obs[:, r + h * p :] > 0.5
        pairs = np.concatenate((np.broadcast_to(robot[:, None, :], (n, h, r)), humans), axis=-1)
        emb = mlp_forward(pairs, self.embed, "relu", activate_last=True)
        present = mask[..., None].astype(np.float64)
        crowd = (emb * present).sum(1, keepdims=True) / np.maximum(present.sum(1, keepdims=True), 1.0)
        both = np.concatenate((emb, np.broadcast_to(crowd, emb.shape)), axis=-1)
        scores = mlp_forward(both, self.score, "relu")[..., 0]
        scores = np.where(mask, scores, -np.inf)
        top = np.max(scores, axis=1, keepdims=True)
        exp = np.where(mask, np.exp(scores - np.where(np.isfinite(top), top, 0.0)), 0.0)
        weights = exp / np.maximum(exp.sum(1, keepdims=True), 1e-300)
        pooled = (weights[..., None] * mlp_forward(emb, self.value, "relu")).sum(1)
        return np.concatenate((robot, pooled), axis=-1)

    def action_output(self, obs: np.ndarray) -> np.ndarray:
        """(N, A) the action head's output: logits, or mean actions before clipping."""
        # The policy MLP's hidden layers, then the action head, which is not activated.
        return mlp_forward(self.features(np.asarray(obs)), [*self.policy, self.action], self.activation)

    def act(self, obs: np.ndarray, task: Any = None) -> np.ndarray:
        """Greedy actions of (N, D) flat observations: (N,) action indices, or (N, 2) in [-1, 1]."""
        obs = np.asarray(obs)
        if obs.ndim != 2 or obs.shape[1] != self.observation_size:
            raise ValueError(
                f"{self.name}: observations must be (N, {self.observation_size}), got {obs.shape}"
            )
        out = self.action_output(obs)
        if self.action_kind == "discrete":
            return np.argmax(out, axis=-1).astype(np.int64)
        return np.clip(out, -1.0, 1.0).astype(np.float32)

    def config(self) -> dict[str, Any]:
        """What the policy is (its header's network and training records)."""
        return {"network": self.header.get("network"), "training": self.header.get("training")}

    def save(self, path: str | Path, tensors: dict[str, Any]) -> Path:
        """Write `tensors` with this policy's header to `path`."""
        return save_policy_file(path, tensors, self.header)

    @classmethod
    def load(cls, path: str | Path) -> CrowdAttentionPolicy:
        """Load a policy file, refusing one of another kind or task version (PolicyFileError).

        The file's env id must be of the CrowdNav task's version (CROWD_ENV_VERSION: what a policy
        observes and how it acts), or a current id of the task with a version of its own
        (socialzoo/CrowdNavSuite-v2, whose versions mark changes of its scenarios and success rule).
        """
        from socialzoo.env.registration import task_ids

        tensors, header = read_policy_file(path, check_env_version=False)
        if header.get("policy") != POLICY_NAME:
            raise PolicyFileError(
                f"{path}: a {header.get('policy')!r} policy file, not a {POLICY_NAME!r} one"
            )
        try:
            theirs = env_version(str(header["env_id"]))
        except ValueError as err:
            raise PolicyFileError(f"{path}: {err}") from None
        current = task_ids().get(str(header["env_id"]), {}).get("task") == "crowdnav"
        if theirs != CROWD_ENV_VERSION and not current:
            raise PolicyFileError(
                f"{path}: trained on {header['env_id']} but this socialzoo's CrowdNav task is v{CROWD_ENV_VERSION}; "
                "retrain it (`socialzoo train crowdnav`)"
            )
        return cls(tensors, header, str(path))
