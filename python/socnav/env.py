"""``SocNavEnv``: one environment as a ``gymnasium.Env`` (a batch of one, autoreset off).

Unlike the vector environment it returns fresh arrays at every call, as single-environment
code expects (observations kept across steps stay valid).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
import gymnasium as gym

from socnav import _batch
from socnav._socnav import Batch


class SocNavEnv(gym.Env):
    """One environment of ``config`` (see ``make``)."""

    metadata = {"render_modes": []}

    def __init__(
        self,
        config: str | Mapping[str, Any] = "exp1",
        *,
        obs_mode: str = "dict",
        action_type: str = "continuous",
        threads: int | None = 1,
    ) -> None:
        self.obs_mode = _batch.check_choice("obs_mode", obs_mode, _batch.OBS_MODES)
        self.action_type = _batch.check_choice("action_type", action_type, _batch.ACTION_TYPES)
        self._batch: Batch = _batch.build_batch(config, 1, None, "disabled", threads)
        self._layout = self._batch.layout()
        self._keys = Batch.keys()
        self.observation_space = _batch.observation_space(self._batch, obs_mode)
        self.action_space = _batch.action_space(self._batch, action_type)
        self._buf = self._batch.buffers()
        self._ended = True  # until the first reset

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        _batch.reset_single(self._batch, seed)
        self._ended = False
        # SocNavGym's reset reports no metrics.
        return self._obs(), {}

    def step(self, action: Any):
        a = np.asarray(action)
        batch_action: np.ndarray
        if self.action_type == "continuous":
            if a.shape != (3,):
                raise ValueError(f"action must have shape (3,), got {a.shape}")
            batch_action = a.reshape(1, 3)
        else:
            if a.shape != ():
                raise ValueError(f"a discrete action is one integer, got shape {a.shape}")
            batch_action = a.reshape(1)
        _batch.check_running(self._ended)
        _batch.step_batch(self._batch, self.action_type, batch_action, 1)
        b = self._buf
        terminated, truncated = bool(b["terminated"][0]), bool(b["truncated"][0])
        self._ended = terminated or truncated
        return self._obs(), float(b["reward"][0]), terminated, truncated, self._info()

    def _obs(self) -> Any:
        flat = self._buf["obs"].copy()
        if self.obs_mode == "flat":
            return flat[0]
        return {k: v[0] for k, v in _batch.split_obs(flat, self._layout).items()}

    def _info(self) -> dict[str, float | None]:
        """SocNavGym's info dict: every metric as a float, ``None`` where 0.1.1 has ``None``
        (``TIME_TO_REACH_GOAL`` before success; the batch carries NaN there)."""
        row = self._buf["info"][0]
        return {
            key: None if np.isnan(row[k]) else float(row[k])
            for k, key in enumerate(self._keys["info"])
        }


def make(
    config: str | Mapping[str, Any] = "exp1",
    *,
    obs_mode: str = "dict",
    action_type: str = "continuous",
    threads: int | None = 1,
) -> SocNavEnv:
    """One environment of ``config`` (a shipped name, a TOML path or a dict of overrides)."""
    return SocNavEnv(config, obs_mode=obs_mode, action_type=action_type, threads=threads)
