"""A policy file: an MLP's weights in a ``.npz``, run with numpy alone (no learning library at run time).

Keys: ``format`` (``"shc-policy-1"``), ``action`` (the action space: ``gait``, ``residual``, ``joints``),
``activation`` (of the hidden layers: ``tanh``, ``relu`` or ``identity``), ``layers`` (their count ``K``), ``w0``,
``b0`` … ``w{K-1}``, ``b{K-1}`` (layer ``k``: ``x ← act(w_k · x + b_k)``, the last one without the activation),
``obs_mean``, ``obs_std`` and ``obs_clip`` (the observation normalised first: ``clip((o − mean) / std, ±clip)``;
``obs_clip`` 0: not clipped), ``names`` (the observation entries it was trained on,
:func:`~shc_cli.loop.policy.observe.observation_names`) and ``residual_limit`` [m]. The action is the network's
output clipped to −1…1 (what stable-baselines3's ``predict(deterministic=True)`` does for a Box of −1…1). The
older form ``weights``, ``bias``, ``action`` (one linear layer) is read too.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, cast

import numpy as np

from shc_cli.loop.policy.actions import ACTIONS, RESIDUAL_LIMIT, ActionName

FORMAT = "shc-policy-1"
Activation = Literal["tanh", "relu", "identity"]
ACTIVATIONS: tuple[Activation, ...] = ("tanh", "relu", "identity")


class PolicyFileError(ValueError):
    """A policy file that cannot be read or does not fit (one line: the file, what, how to fix)."""


@dataclass(frozen=True)
class Policy:
    """``action = clip(MLP(normalised observation), −1, 1)`` for one action space (see the module)."""

    action: ActionName
    layers: tuple[tuple[np.ndarray, np.ndarray], ...]
    activation: Activation = "tanh"
    obs_mean: np.ndarray | None = None
    obs_std: np.ndarray | None = None
    obs_clip: float = 0.0
    names: tuple[str, ...] = ()
    residual_limit: float = RESIDUAL_LIMIT
    info: dict[str, str] = field(default_factory=dict)
    """Free text kept with the weights (where it came from: the learning library, the env's keywords)."""

    @classmethod
    def constant(cls, action: ActionName, values: np.ndarray, observations: int) -> Policy:
        """The policy that always gives ``values`` (zero weights)."""
        bias = np.asarray(values, dtype=np.float64)
        return cls(action, ((np.zeros((len(bias), observations)), bias),), activation="identity")

    @property
    def observations(self) -> int:
        return int(self.layers[0][0].shape[1])

    @property
    def actions(self) -> int:
        return int(self.layers[-1][0].shape[0])

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        x = np.asarray(observation, dtype=np.float64)
        if self.obs_mean is not None and self.obs_std is not None:
            x = (x - self.obs_mean) / self.obs_std
            if self.obs_clip > 0:
                x = np.clip(x, -self.obs_clip, self.obs_clip)
        last = len(self.layers) - 1
        for k, (w, b) in enumerate(self.layers):
            x = w @ x + b
            if k < last:
                x = np.tanh(x) if self.activation == "tanh" else np.maximum(x, 0.0) if self.activation == "relu" else x
        return np.asarray(np.clip(x, -1.0, 1.0), dtype=np.float32)

    def save(self, path: Path) -> None:
        arrays: dict[str, np.ndarray] = {
            "format": np.array(FORMAT), "action": np.array(self.action), "activation": np.array(self.activation),
            "layers": np.array(len(self.layers)), "obs_clip": np.array(self.obs_clip),
            "names": np.array(self.names, dtype=str), "residual_limit": np.array(self.residual_limit),
            "info": np.array(json.dumps(self.info, sort_keys=True))}
        for k, (w, b) in enumerate(self.layers):
            arrays[f"w{k}"], arrays[f"b{k}"] = w, b
        if self.obs_mean is not None and self.obs_std is not None:
            arrays["obs_mean"], arrays["obs_std"] = self.obs_mean, self.obs_std
        with path.open("wb") as handle:
            np.savez(handle, **arrays)  # type: ignore[arg-type]  # (numpy's stub: savez's keywords)

    @classmethod
    def load(cls, path: Path) -> Policy:
        """Read a policy file.

        Raises:
            PolicyFileError: not a readable ``.npz`` policy, or its arrays do not fit together (one line)."""
        if not path.is_file():
            raise PolicyFileError(f"{path}: no such file")
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {key: data[key] for key in data.files}
        except (OSError, ValueError, EOFError) as error:
            raise PolicyFileError(f"{path}: not a policy file ({error}); write one with "
                                  "shc_cli.loop.policy.file.Policy.save") from None
        return _from_arrays(path, arrays)


def _text(arrays: dict[str, np.ndarray], key: str, default: str) -> str:
    return str(arrays[key]) if key in arrays else default


def _from_arrays(path: Path, arrays: dict[str, np.ndarray]) -> Policy:
    def bad(what: str) -> PolicyFileError:
        return PolicyFileError(f"{path}: {what}; write it again with shc_cli.loop.policy.file.Policy.save")

    name = _text(arrays, "action", "")
    action = next((known for known in ACTIONS if known == name), None)
    if action is None:
        raise bad(f"action '{name}' is not one of {', '.join(ACTIONS)}")
    if "weights" in arrays and "format" not in arrays:  # the first form: one linear layer
        layers: list[tuple[np.ndarray, np.ndarray]] = [(arrays["weights"], arrays.get("bias", np.zeros(0)))]
        activation: str = "identity"
    else:
        if _text(arrays, "format", "") != FORMAT:
            raise bad(f"format '{_text(arrays, 'format', '')}' is not {FORMAT}")
        activation = _text(arrays, "activation", "tanh")
        if activation not in ACTIVATIONS:
            raise bad(f"activation '{activation}' is not one of {', '.join(ACTIVATIONS)}")
        count = int(arrays["layers"]) if "layers" in arrays else 0
        missing = [key for k in range(count) for key in (f"w{k}", f"b{k}") if key not in arrays]
        if count < 1 or missing:
            raise bad(f"no layer {missing[0] if missing else 'w0'}")
        layers = [(arrays[f"w{k}"], arrays[f"b{k}"]) for k in range(count)]
    layers = [(np.asarray(w, dtype=np.float64), np.asarray(b, dtype=np.float64)) for w, b in layers]
    width = layers[0][0].shape[1] if layers[0][0].ndim == 2 else -1
    for k, (w, b) in enumerate(layers):
        if w.ndim != 2 or b.shape != (w.shape[0],) or w.shape[1] != width or not (
                np.isfinite(w).all() and np.isfinite(b).all()):
            raise bad(f"layer {k}: weights {w.shape} and bias {b.shape} do not chain (out × in, out) or are not finite")
        width = w.shape[0]
    mean, std = arrays.get("obs_mean"), arrays.get("obs_std")
    observations = layers[0][0].shape[1]
    if (mean is None) != (std is None) or (mean is not None and std is not None and (
            mean.shape != (observations,) or std.shape != (observations,) or not (std > 0).all())):
        raise bad(f"obs_mean and obs_std must both be ({observations},), std positive")
    names = tuple(str(n) for n in arrays["names"]) if "names" in arrays else ()
    if names and len(names) != observations:
        raise bad(f"{len(names)} observation names for {observations} inputs")
    info = json.loads(_text(arrays, "info", "{}"))
    return Policy(action, tuple(layers), cast(Activation, activation),
                  None if mean is None else np.asarray(mean, dtype=np.float64),
                  None if std is None else np.asarray(std, dtype=np.float64),
                  float(arrays["obs_clip"]) if "obs_clip" in arrays else 0.0, names,
                  float(arrays["residual_limit"]) if "residual_limit" in arrays else RESIDUAL_LIMIT,
                  {str(k): str(v) for k, v in info.items()} if isinstance(info, dict) else {})
