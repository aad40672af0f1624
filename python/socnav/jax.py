"""socnav's outputs as JAX arrays on the CPU (the ``jax`` extra).

JAX assumes that an array never changes; a socnav batch overwrites its output buffers at every
``step`` and ``reset``. So the default is a copy, and a view is an explicit choice with a rule:

- ``view=False`` (default): every array is JAX's own copy, valid for ever.
- ``view=True``: the flat observation (and the reward from 1,024 environments on: every buffer
  of 4 KiB or more) *is* the batch's buffer, through DLPack, without a copy; the extension's
  allocator aligns those buffers to the 64 bytes XLA requires, and JAX copies smaller ones. The
  dict observation's blocks (strided slices of the row) and the flags (bool arrays made from the
  batch's uint32) are copies either way. **The rule**: such an array holds the latest step's values only until the next
  ``step`` or ``reset`` of the environment, which overwrites them under JAX's feet; and JAX
  dispatches work asynchronously, so anything computed from it must be finished
  (``jax.block_until_ready``) before the environment steps again. Keep a value past the step
  with ``jnp.array(x, copy=True)``.

::

    env = socnav.jax.wrap(socnav.make_vec("exp2", num_envs=4096, obs_mode="flat"), view=True)
    obs, _ = env.reset(seed=0)
    for _ in range(1000):
        actions = jax.block_until_ready(policy(params, obs))
        obs, reward, terminated, truncated, info = env.step(np.asarray(actions))
"""

from __future__ import annotations

from typing import Any

import numpy as np

try:
    import jax
    import jax.numpy as jnp
except ImportError as e:  # the jax extra is not installed
    raise ImportError("socnav.jax needs JAX: pip install './python[jax]'") from e

import gymnasium as gym

__all__ = ["JaxVectorEnv", "asarray", "wrap"]


def asarray(x: np.ndarray, *, view: bool = False) -> jax.Array:
    """``x`` as a JAX array on the CPU: a copy, or with ``view=True`` the same memory through
    DLPack (JAX copies instead when ``x`` is not 64-byte aligned; see the module's rule)."""
    if not view:
        return jnp.array(x, copy=True)
    if not x.flags.c_contiguous:
        raise ValueError("a view needs a C-contiguous array")
    return jax.dlpack.from_dlpack(x)


def shares_memory(a: jax.Array, x: np.ndarray) -> bool:
    """Whether the JAX array ``a`` is a view of ``x``'s buffer (no copy was made)."""
    return int(a.unsafe_buffer_pointer()) == int(x.__array_interface__["data"][0])


class JaxVectorEnv(gym.vector.VectorWrapper):
    """A socnav vector environment whose ``reset`` and ``step`` give JAX arrays: the observation
    (flat, or the dict's blocks), the reward, ``terminated`` and ``truncated``; ``info`` stays numpy.
    Actions may be JAX or numpy arrays."""

    def __init__(self, env: gym.vector.VectorEnv, *, view: bool = False) -> None:
        super().__init__(env)
        if view and getattr(env.unwrapped, "copy", False):
            raise ValueError("view=True over an environment made with copy=True would view the copies")
        self.view = bool(view)

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        return self._jax(obs), info

    def step(self, actions: Any) -> tuple[Any, jax.Array, jax.Array, jax.Array, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(np.asarray(actions))
        return self._jax(obs), self._one(reward), self._one(terminated), self._one(truncated), info

    def _jax(self, obs: Any) -> Any:
        if isinstance(obs, dict):
            return {k: self._one(v) for k, v in obs.items()}
        return self._one(obs)

    def _one(self, x: np.ndarray) -> jax.Array:
        # Strided arrays (the dict's blocks) are copied; JAX copies small (unaligned) ones itself.
        return asarray(x, view=self.view and x.flags.c_contiguous)


def wrap(env: gym.vector.VectorEnv, *, view: bool = False) -> JaxVectorEnv:
    """``env`` (``socnav.make_vec``) giving JAX arrays: copies, or views with ``view=True`` (see
    the module's rule)."""
    return JaxVectorEnv(env, view=view)
