"""socnav configs as Ray RLlib environments: one socnav batch per env runner.

RLlib's env runners can host a gymnasium vector environment each (``gym_env_vectorize_mode=
VECTOR_ENTRY_POINT``), so a runner steps one socnav batch of ``num_envs_per_env_runner``
environments, and more runners (on more nodes of a Ray cluster) step more batches::

    import socnav.rllib
    config = socnav.rllib.ppo_config("exp2", num_env_runners=8, num_envs_per_env_runner=256)
    algo = config.build_algo()
    for _ in range(100):
        print(algo.train()["env_runners"]["episode_return_mean"])

Or with a config of your own: ``socnav.rllib.register()`` registers the environment creator as
``"socnav"`` (``config.environment("socnav", env_config={"config": "exp2", ...})``), and
``config.env_runners(gym_env_vectorize_mode=gym.VectorizeMode.VECTOR_ENTRY_POINT, ...)`` makes
RLlib hand it ``num_envs``.

Keeping RLlib's own per-step cost small: RLlib turns the vector environment's info dict into one
dict per environment at every step (its ``DictInfoToList``), a Python loop over environments and
keys; socnav's info holds 32 metrics and their masks, so by default the adapter returns an empty
info (``info_keys=[]``) and RLlib's loop has nothing to copy. Ask for the metrics you log
(``info_keys=["SUCCESS", "COLLISION", "episode"]``) or all of them (``info_keys=None``). RLlib's
other per-step work (episode bookkeeping, the module's forward pass) is per runner and per step,
not per environment, so large batches per runner amortise it.

Seeds: RLlib seeds runner ``k`` with ``seed + k``; the adapter gives environment ``i`` of that
runner the episode seed ``(seed + k) * num_envs + i``, so runners never play the same episodes.

Needs the ``rllib`` extra (``pip install 'socnav[rllib]'``: Ray with its pinned gymnasium) and
torch.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import gymnasium as gym
import numpy as np

from socnav import _batch
from socnav.vector import SocNavVectorEnv

# The name `register` gives the environment creator in Ray's registry.
ENV_NAME = "socnav"


class _RLlibVectorEnv(gym.vector.VectorWrapper):
    """A socnav vector environment as an RLlib env runner steps it: only the info keys asked
    for, and each runner's episodes apart from the others'."""

    def __init__(self, env: SocNavVectorEnv, info_keys: Sequence[str] | None) -> None:
        super().__init__(env)
        self._keep = None if info_keys is None else set(info_keys)

    def reset(self, *, seed: Any = None, options: dict[str, Any] | None = None):
        if isinstance(seed, (int, np.integer)):
            seed = int(seed) * self.num_envs
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, self._info(info)

    def step(self, actions: Any):
        obs, reward, terminated, truncated, info = self.env.step(actions)
        return obs, reward, terminated, truncated, self._info(info)

    def _info(self, info: dict[str, Any]) -> dict[str, Any]:
        if self._keep is None:
            return info
        return {k: v for k, v in info.items() if k.removeprefix("_") in self._keep}


def env_creator(env_config: Mapping[str, Any]) -> gym.vector.VectorEnv:
    """The vector environment of one env runner, from RLlib's ``env_config`` (an ``EnvContext``,
    to which RLlib adds ``num_envs``). Keys: ``config`` (a shipped config name, a TOML or SocNavGym YAML path or a
    dict of overrides; default ``"exp1"``), ``num_envs``, ``obs_mode`` (default ``"flat"``: RLlib's
    default modules take one vector), ``action_type`` (default ``"discrete"``), ``threads`` (CPU
    threads of the runner's batch; default 1, as a runner has one CPU by default), ``backend``,
    ``seed`` (of the batch before RLlib's first reset; default 0) and ``info_keys`` (see the
    module docs; default ``[]``)."""
    cfg = dict(env_config)
    env = SocNavVectorEnv(
        cfg.get("config", "exp1"),
        _batch.check_count("num_envs", cfg.get("num_envs", 1)),
        seed=_batch.check_seed(cfg.get("seed", 0)),
        obs_mode=cfg.get("obs_mode", "flat"),
        action_type=cfg.get("action_type", "discrete"),
        backend=cfg.get("backend", "cpu"),
        threads=cfg.get("threads", 1),
    )
    return _RLlibVectorEnv(env, cfg.get("info_keys", []))


def register(name: str = ENV_NAME) -> str:
    """Register ``env_creator`` in Ray's registry under ``name`` (on the driver: Ray ships the
    registry to the runners); returns ``name``."""
    from ray.tune.registry import register_env

    register_env(name, env_creator)
    return name


def ppo_config(
    config: str | Mapping[str, Any] = "exp1",
    *,
    num_env_runners: int = 2,
    num_envs_per_env_runner: int = 64,
    seed: int | None = 0,
    **env_config: Any,
):
    """An RLlib ``PPOConfig`` over socnav: ``num_env_runners`` runners of one batch of
    ``num_envs_per_env_runner`` environments each, of the socnav config ``config``;
    ``env_config`` as ``env_creator`` reads it. Change anything else on the returned config
    (``.training(...)``, ``.learners(...)``) before ``build_algo()``."""
    from ray.rllib.algorithms.ppo import PPOConfig

    name = register()
    return (
        PPOConfig()
        .environment(name, env_config={"config": config, **env_config})
        .env_runners(
            num_env_runners=num_env_runners,
            num_envs_per_env_runner=num_envs_per_env_runner,
            gym_env_vectorize_mode=gym.VectorizeMode.VECTOR_ENTRY_POINT,
        )
        .debugging(seed=seed)
    )
