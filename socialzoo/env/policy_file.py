"""Policy files of the learned baselines and learned humans: weights as safetensors, plus a JSON
header; and the numpy forward pass of the networks they hold (mlp_forward, the only one)."""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

POLICY_FORMAT = "socialzoo-policy/1"
# safetensors metadata key under which the JSON header is stored.
HEADER_KEY = "socialzoo"
REQUIRED_KEYS = ("format", "policy", "network", "observation", "env_id", "training")
# Hidden-layer activations of the networks a policy file holds.
ACTIVATIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "tanh": np.tanh,
    "relu": lambda x: np.maximum(x, 0.0),
}


class PolicyFileError(ValueError):
    """A policy file that cannot be used: unreadable, not a socialzoo policy, or made for another env.

    A ValueError, as every loader's error is, so callers that refuse bad arguments with
    `except ValueError` refuse a bad policy file the same way; the message starts with the file.
    """


def env_version(env_id: str) -> int:
    """The version number of a Gymnasium id such as "socialzoo/ActionSelection-v2"."""
    match = re.fullmatch(r".+-v(\d+)", env_id)
    if match is None:
        raise ValueError(f"env id {env_id!r} has no version suffix (-vN)")
    return int(match.group(1))


def current_env_version() -> int:
    """The version of the benchmark env ids this package registers."""
    from socialzoo.env.registration import BENCHMARK_IDS

    versions = {env_version(env_id) for env_id in BENCHMARK_IDS}
    if len(versions) != 1:
        raise RuntimeError(f"the benchmark ids disagree on their version: {sorted(BENCHMARK_IDS)}")
    return versions.pop()


def _other_task(env_id: str, version: int) -> str | None:
    """The task of `env_id` when it is one of this package's ids but not of the benchmark's
    version `version` (a task numbering its versions apart, such as CrowdNav), else None."""
    from socialzoo.env.registration import task_ids

    kwargs = task_ids().get(env_id)
    if kwargs is None or env_version(env_id) == version:
        return None
    return str(kwargs["task"])


def save_policy_file(path: str | Path, tensors: Mapping[str, Any], header: Mapping[str, Any]) -> Path:
    """Write `tensors` (name -> array) and `header` (plain JSON) to a safetensors file.

    A policy file holds plain tensors (no pickled objects, so loading never executes code from the
    file) and, in the safetensors metadata, one JSON header that says what the tensors are and
    what they were trained for: the network, the observation layout, the env id and version, the
    normalisation statistics, and how the policy was made (algorithm, command, seed, steps).

    Args:
        path: the file to write (parent folders are created).
        tensors: numpy arrays or torch tensors; stored as contiguous numpy arrays.
        header: the JSON header; "format" is filled in. Must hold REQUIRED_KEYS.

    Returns:
        `path`.

    Raises:
        ValueError: a required header key is missing, or the header is not plain JSON.
    """
    from safetensors.numpy import save_file

    header = {"format": POLICY_FORMAT, **header}
    missing = [k for k in REQUIRED_KEYS if k not in header]
    if missing:
        raise ValueError(f"policy header lacks {missing}")
    try:
        text = json.dumps(header, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as err:
        raise ValueError(f"policy header is not plain JSON: {err}") from None
    arrays = {
        # A torch tensor goes through detach().cpu().numpy().
        name: np.ascontiguousarray(value.detach().cpu().numpy() if hasattr(value, "detach") else value)
        for name, value in tensors.items()
    }
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    save_file(arrays, str(tmp), metadata={HEADER_KEY: text})
    tmp.replace(path)
    return path


def read_policy_file(
    path: str | Path, *, check_env_version: bool = True
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Read and check a policy file.

    Loading checks all of the header and refuses a file made for another observation layout or
    env version, or one whose tensors hold NaN or inf.

    Args:
        path: a file written by `save_policy_file`.
        check_env_version: refuse a file trained on another version of the benchmark env.

    Returns:
        (tensors, header).

    Raises:
        PolicyFileError: naming the file and what is wrong with it.
    """
    from safetensors import SafetensorError, safe_open

    path = Path(path)
    if not path.is_file():
        raise PolicyFileError(f"{path}: no such policy file")
    try:
        with safe_open(str(path), framework="numpy") as f:
            metadata = f.metadata() or {}
            tensors = {name: f.get_tensor(name) for name in f.keys()}
    except (SafetensorError, OSError, ValueError) as err:
        raise PolicyFileError(f"{path}: not a safetensors policy file ({err})") from None
    broken = sorted(name for name, t in tensors.items() if t.dtype.kind in "fc" and not np.isfinite(t).all())
    if broken:
        # A diverged training run: such a network would still act (argmax of NaN is 0), silently.
        raise PolicyFileError(f"{path}: tensors {broken} hold non-finite values (NaN or inf)")
    if HEADER_KEY not in metadata:
        raise PolicyFileError(f"{path}: a safetensors file without a socialzoo policy header")
    try:
        header = json.loads(metadata[HEADER_KEY])
    except json.JSONDecodeError as err:
        raise PolicyFileError(f"{path}: the policy header is not JSON ({err})") from None
    if not isinstance(header, dict) or header.get("format") != POLICY_FORMAT:
        found = header.get("format") if isinstance(header, dict) else type(header).__name__
        raise PolicyFileError(f"{path}: format {found!r}, expected {POLICY_FORMAT!r}")
    missing = [k for k in REQUIRED_KEYS if k not in header]
    if missing:
        raise PolicyFileError(f"{path}: the policy header lacks {missing}")
    if check_env_version:
        try:
            theirs = env_version(str(header["env_id"]))
        except ValueError as err:
            raise PolicyFileError(f"{path}: {err}") from None
        ours = current_env_version()
        task = _other_task(str(header["env_id"]), ours)
        if task is not None:
            # A current id of a task with its own version numbers (CrowdNav): not an outdated file.
            raise PolicyFileError(
                f"{path}: a {header['policy']!r} policy for {header['env_id']}, a {task!r} task env, not for "
                f"this socialzoo's v{ours} benchmark envs; load it as a policy of the {task!r} task"
            )
        if theirs != ours:
            raise PolicyFileError(
                f"{path}: trained on {header['env_id']} (v{theirs}) but this socialzoo's benchmark env is "
                f"v{ours}; retrain it (`socialzoo train {header['policy']}`) or use the socialzoo release "
                f"it was made with"
            )
    return tensors, header


def checked_layers(owner: str, weights: Sequence[tuple[Any, Any]]) -> list[tuple[np.ndarray, np.ndarray]]:
    """The (weight (out, in), bias (out,)) pairs as float32 arrays, checked to chain.

    Raises:
        ValueError: naming `owner` and the layer, for no layers, a bad shape, or a layer that does
            not take the previous layer's output.
    """
    if not weights:
        raise ValueError(f"{owner}: the network has no layers")
    layers = [(np.asarray(w, dtype=np.float32), np.asarray(b, dtype=np.float32)) for w, b in weights]
    for i, (w, b) in enumerate(layers):
        if w.ndim != 2 or b.shape != (w.shape[0],):
            raise ValueError(f"{owner}: layer {i} has weight {w.shape} and bias {b.shape}")
        if i and w.shape[1] != layers[i - 1][0].shape[0]:
            raise ValueError(
                f"{owner}: layer {i} takes {w.shape[1]} inputs, the layer before gives {layers[i - 1][0].shape[0]}"
            )
    return layers


class FileNetwork:
    """What a policy that holds a policy file's network keeps (the robots' MlpPolicy and the learned
    humans' policy): its layers (weights (out, in) and biases, checked to chain), the hidden-layer
    activation (a key of ACTIVATIONS), the file's header, and the file it was loaded from (path and
    sha256, None until `loaded_from`). Errors start with `owner`, the subclass's name."""

    def __init__(
        self, owner: str, weights: Sequence[tuple[Any, Any]], activation: str, header: dict[str, Any] | None
    ) -> None:
        if activation not in ACTIVATIONS:
            raise ValueError(f"{owner}: activation must be one of {sorted(ACTIVATIONS)}, got {activation!r}")
        self.layers = checked_layers(owner, weights)
        self.activation = activation
        self.header = dict(header or {})
        self.path: Path | None = None
        self.digest: str | None = None

    @property
    def input_size(self) -> int:
        """D, the length of the observations the network takes."""
        return int(self.layers[0][0].shape[1])

    def forward(self, x: np.ndarray) -> np.ndarray:
        """The network's outputs for inputs x (N, D) (mlp_forward)."""
        return mlp_forward(x, [(w.T, b) for w, b in self.layers], self.activation)

    def config(self) -> dict[str, Any]:
        """What identifies this policy for the results store: the file's digest and training record."""
        return {"file_sha256": self.digest, "training": self.header.get("training", {})}

    def loaded_from(self, path: str | Path) -> None:
        """Record the file this policy was read from: its path and the sha256 of its bytes."""
        self.path = Path(path)
        self.digest = hashlib.sha256(self.path.read_bytes()).hexdigest()


def mlp_parts(layers: Sequence[tuple[Any, Any]], activation: str, output: str) -> tuple[dict, dict]:
    """A network's layers as a policy file holds them: tensors net.<i>.weight (out, in), net.<i>.bias
    (out,), and the header's "network" entry (kind, sizes: the inputs, then each layer's outputs, activation,
    output)."""
    tensors = {f"net.{i}.{k}": t for i, (w, b) in enumerate(layers) for k, t in (("weight", w), ("bias", b))}
    sizes = [int(layers[0][0].shape[1])] + [int(w.shape[0]) for w, _ in layers]
    return tensors, {"kind": "mlp", "sizes": sizes, "activation": activation, "output": output}


def mlp_layers(tensors: Mapping[str, Any], network: Any, outputs: tuple[str, ...]) -> list[tuple[Any, Any]]:
    """The (weight, bias) layers of `mlp_parts`, checked against the header's "network" entry: an
    "mlp" whose output is one of `outputs`, each weight of the header's sizes (a ValueError; a
    KeyError for a missing tensor)."""
    if not isinstance(network, dict):
        raise ValueError(f"the header's network is a {type(network).__name__}, not an object")
    if network.get("kind") != "mlp":
        raise ValueError(f"network kind {network.get('kind')!r} is not 'mlp'")
    if network.get("output") not in outputs:
        raise ValueError(f"network output {network.get('output')!r} is not one of {outputs}")
    sizes = [int(s) for s in network["sizes"]]
    weights = [(tensors[f"net.{i}.weight"], tensors[f"net.{i}.bias"]) for i in range(len(sizes) - 1)]
    for i, (w, _) in enumerate(weights):
        if tuple(w.shape) != (sizes[i + 1], sizes[i]):
            raise ValueError(
                f"net.{i}.weight has shape {w.shape}, the header says {(sizes[i + 1], sizes[i])}"
            )
    return weights


def mlp_forward(
    x: np.ndarray,
    layers: Sequence[tuple[np.ndarray, np.ndarray]],
    activation: str,
    *,
    activate_last: bool = False,
) -> np.ndarray:
    """The numpy forward pass of a multilayer perceptron: x @ w + b per layer, `activation` between.

    Every network of a policy file runs through it (the learned robot policies, a stack of their
    checkpoints, the learned humans, the CrowdNav attention network), so their arithmetic is the
    same: the products and sums in the dtype of the arrays given, in this order.

    Args:
        x: (..., in) inputs.
        layers: (w, b) per layer, w of shape (in, out) (a torch Linear's weight transposed: pass
            `weight.T`), or (..., in, out) for a weight per row; b broadcastable to the output.
        activation: a key of ACTIVATIONS.
        activate_last: also apply the activation after the last layer (a hidden block whose output
            feeds another network).

    Returns:
        (..., out) outputs of the last layer.

    Raises:
        ValueError: an unknown activation.
    """
    if activation not in ACTIVATIONS:
        raise ValueError(f"mlp_forward: activation must be one of {sorted(ACTIVATIONS)}, got {activation!r}")
    act = ACTIVATIONS[activation]
    last = len(layers) - 1
    for i, (w, b) in enumerate(layers):
        x = x @ w + b
        if i < last or activate_last:
            x = act(x)
    return x
