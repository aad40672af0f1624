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
from socnav.render import HumanView, Trails, check_render_mode


class SocNavEnv(gym.Env):
    """One environment of ``config`` (see ``make``)."""

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 1}

    def __init__(
        self,
        config: str | Mapping[str, Any] = "exp1",
        *,
        obs_mode: str = "dict",
        action_type: str = "continuous",
        threads: int | None = 1,
        render_mode: str | None = None,
        render_size: int = 400,
    ) -> None:
        self.config = config
        self.render_mode = check_render_mode(render_mode)
        self.render_size = int(render_size)
        self.obs_mode = _batch.check_choice("obs_mode", obs_mode, _batch.OBS_MODES)
        self.action_type = _batch.check_choice("action_type", action_type, _batch.ACTION_TYPES)
        self._batch: Batch = _batch.build_batch(config, 1, None, "disabled", threads)
        self._layout = self._batch.layout()
        self._keys = Batch.keys()
        self.observation_space = _batch.observation_space(self._batch, obs_mode)
        self.action_space = _batch.action_space(self._batch, action_type)
        self._buf = self._batch.buffers()
        self._ended = True  # until the first reset
        # One frame per simulated step plays an episode in real time.
        self.metadata = {**self.metadata, "render_fps": 1.0 / self._batch.time_step}
        self._trails = Trails(1)
        self._human: HumanView | None = None
        self._steps = 0
        self._return = 0.0
        self._reward = 0.0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        _batch.reset_single(self._batch, seed)
        self._ended = False
        if self.render_mode is not None:
            self._trails.restart()
            self._trails.add(self._batch.robot_poses())
        self._steps, self._return, self._reward = 0, 0.0, 0.0
        if self.render_mode == "human":
            self.render()
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
        reward = float(b["reward"][0])
        self._steps += 1
        self._reward = reward
        self._return += reward
        if self.render_mode is not None:
            self._trails.add(self._batch.robot_poses())
        if self.render_mode == "human":
            self.render()
        return self._obs(), reward, terminated, truncated, self._info()

    # gymnasium 1.1 types the result as an unbound TypeVar (RenderFrame), which no concrete
    # type matches; later releases accept this one.
    def render(self) -> np.ndarray | None:  # type: ignore[override]
        """The environment from above, uint8 ``(H, W, 3)`` (``render_mode="rgb_array"``), with
        the robot's path since the reset; with ``"human"`` the same frame shown in a window
        (``socnav.render``), and None; None without a render mode."""
        if self.render_mode is None:
            return None
        frame = self._batch.render(0, self.render_size, self._trails.of(0))
        if self.render_mode == "rgb_array":
            return frame
        if self._human is None:
            self._human = HumanView("socnav", self.metadata["render_fps"])
        lines = [
            f"socnav {self.config if isinstance(self.config, str) else 'custom config'}",
            f"step {self._steps}",
            f"reward {self._reward:+.4f}",
            f"return {self._return:+.3f}",
        ]
        if self._ended:
            lines.append("!episode over")
        self._human.show(frame, lines)
        return None

    def close(self) -> None:
        if self._human is not None:
            self._human.close()
            self._human = None
        self._batch.close()
        super().close()

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
    render_mode: str | None = None,
    render_size: int = 400,
) -> SocNavEnv:
    """One environment of ``config`` (a shipped name, a TOML or SocNavGym YAML path or a dict of overrides);
    ``render_mode="rgb_array"`` makes ``render()`` return frames (``socnav.render``)."""
    return SocNavEnv(
        config,
        obs_mode=obs_mode,
        action_type=action_type,
        threads=threads,
        render_mode=render_mode,
        render_size=render_size,
    )
