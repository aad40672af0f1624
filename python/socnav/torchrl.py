"""A TorchRL environment over a socnav batch (the ``torchrl`` extra).

``socnav.torchrl.make_env(config, num_envs, seed=0)`` returns a ``torchrl.envs.EnvBase`` with
``batch_size = [num_envs]``: ``observation`` (the flat row, float32), ``action`` (one of the 7
discrete actions, or forward, lateral and rotation in [-1, 1]), ``reward`` ``(num_envs, 1)``,
``done`` / ``terminated`` / ``truncated`` ``(num_envs, 1)``. Ended environments wait for a reset
(the batch's ``DISABLED`` autoreset) and restart through ``_reset`` masks, so TorchRL decides when
to reset::

    env = socnav.torchrl.make_env("exp2", num_envs=64, seed=0)
    data = env.rollout(200, policy, break_when_any_done=False)   # (64, 200)

What is shared and what is copied: TorchRL keeps every step's tensordict (a rollout stacks them,
a collector hands them to the learner), so a step's outputs must outlive the next step, which
overwrites the batch's buffers. Each step therefore copies the observation, reward and flags
once out of the batch's buffers (the ``copy=True`` outputs of ``socnav.make_vec``) and wraps
those arrays as tensors without a second copy (``torch.from_numpy``). Actions go to the batch
without a copy when they are contiguous uint32 (discrete) or float32 (continuous) CPU tensors.
"""

from __future__ import annotations

from typing import Any, Mapping

import gymnasium as gym
import numpy as np

try:
    import torch
    from tensordict import TensorDict, TensorDictBase
    from torchrl.data import Bounded, Categorical, Composite, Unbounded
    from torchrl.envs import EnvBase
except ImportError as e:  # the torchrl extra is not installed
    raise ImportError("socnav.torchrl needs TorchRL: pip install './python[torchrl]'") from e

import socnav
from socnav import _batch

__all__ = ["SocNavTorchRLEnv", "make_env"]


class SocNavTorchRLEnv(EnvBase):
    """``num_envs`` socnav environments as one batched TorchRL environment (see the module's
    documentation)."""

    def __init__(
        self,
        config: str | Mapping[str, Any] = "exp1",
        num_envs: int = 1,
        *,
        seed: int = 0,
        action_type: str = "discrete",
        threads: int | None = None,
        backend: str = "cpu",
    ) -> None:
        env = socnav.make_vec(
            config,
            num_envs=num_envs,
            seed=seed,
            obs_mode="flat",
            action_type=action_type,
            autoreset_mode="disabled",
            backend=backend,
            threads=threads,
            copy=True,
            step_info=False,
        )
        super().__init__(device="cpu", batch_size=torch.Size([env.num_envs]))
        self._env = env
        self.action_type = action_type
        self._next_seed: int | None = seed
        n = env.num_envs
        dim = env.unwrapped._batch.layout()["dim"]
        self.observation_spec = Composite(
            observation=Unbounded(shape=(n, dim), dtype=torch.float32), shape=(n,)
        )
        if action_type == "discrete":
            self.action_spec = Categorical(n=_batch.N_DISCRETE, shape=(n,), dtype=torch.int64)
        else:
            space = _batch.action_space(env.unwrapped._batch, action_type)
            assert isinstance(space, gym.spaces.Box)
            low = torch.as_tensor(np.broadcast_to(space.low, (n, 3)).copy())
            high = torch.as_tensor(np.broadcast_to(space.high, (n, 3)).copy())
            self.action_spec = Bounded(low=low, high=high, shape=(n, 3), dtype=torch.float32)
        self.reward_spec = Unbounded(shape=(n, 1), dtype=torch.float32)
        self.done_spec = Composite(
            done=Categorical(n=2, shape=(n, 1), dtype=torch.bool),
            terminated=Categorical(n=2, shape=(n, 1), dtype=torch.bool),
            truncated=Categorical(n=2, shape=(n, 1), dtype=torch.bool),
            shape=(n,),
        )
        # Which environments ended and have not been reset since (TorchRL resets them).
        self._terminated = np.zeros(n, dtype=bool)
        self._truncated = np.zeros(n, dtype=bool)

    @property
    def vector_env(self) -> socnav.SocNavVectorEnv:
        """The socnav vector environment underneath."""
        return self._env

    def _set_seed(self, seed: int | None) -> None:
        """The next full reset gives environment ``i`` the episode of seed ``seed + i``."""
        self._next_seed = None if seed is None else _batch.check_seed(seed)

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        mask = None if tensordict is None else tensordict.get("_reset", None)
        if mask is None:
            obs, _ = self._env.reset(seed=self._next_seed)
            self._next_seed = None
            self._terminated[:] = False
            self._truncated[:] = False
        else:
            m = mask.reshape(self.batch_size).cpu().numpy().astype(bool)
            obs, _ = self._env.reset(options={"reset_mask": m})
            self._terminated[m] = False
            self._truncated[m] = False
        return self._outputs(obs)

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        action = tensordict.get("action")
        a = action.detach().cpu().numpy()
        if self.action_type == "discrete":
            a = a.astype(np.uint32, copy=False)
        obs, reward, terminated, truncated, _ = self._env.step(a)
        self._terminated |= terminated
        self._truncated |= truncated & ~terminated
        out = self._outputs(obs)
        out.set("reward", torch.from_numpy(reward).unsqueeze(-1))
        return out

    def _outputs(self, obs: np.ndarray) -> TensorDictBase:
        terminated = torch.from_numpy(self._terminated.copy()).unsqueeze(-1)
        truncated = torch.from_numpy(self._truncated.copy()).unsqueeze(-1)
        return TensorDict(
            {"observation": torch.from_numpy(obs), "terminated": terminated, "truncated": truncated,
             "done": terminated | truncated},
            batch_size=self.batch_size,
        )

    def close(self, *, raise_if_closed: bool = True) -> None:
        self._env.close()
        super().close(raise_if_closed=raise_if_closed)


#: ``make_env(config, num_envs, *, seed=0, action_type="discrete", threads=None, backend="cpu")``:
#: ``num_envs`` environments of ``config`` as one :class:`SocNavTorchRLEnv`.
make_env = SocNavTorchRLEnv
