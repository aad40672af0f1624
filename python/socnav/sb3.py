"""Stable-Baselines3 adapter: a socnav batch as an SB3 ``VecEnv``.

    from stable_baselines3 import PPO
    from socnav.sb3 import make_sb3

    env = make_sb3("exp1", num_envs=16, seed=0)
    model = PPO("MultiInputPolicy", env).learn(100_000)

The batch steps in Rust in its SAME_STEP autoreset mode, which is SB3's convention: an
environment whose episode ends is reset within the same ``step``, its returned observation is
the new episode's first, and ``infos[i]["terminal_observation"]`` holds the last one of the
episode that ended. Every returned array is a fresh copy (SB3 keeps ``_last_obs`` across steps,
while the batch overwrites its buffers in place).

Finished environments also report, as SB3's ``Monitor`` wrapper does, ``infos[i]["episode"] =
{"r": return, "l": length, "t": seconds since the adapter was made}`` plus every per-episode
statistic of docs/spec.md 8.3 by name (``socnav.metrics.EPISODE_KEYS``), and
``infos[i]["is_success"]``;
SB3's logger therefore shows ``rollout/ep_rew_mean``, ``ep_len_mean`` and ``success_rate``, and
``socnav.metrics.EpisodeLog.add(infos)`` collects the statistics.

Performance: the batch steps on all cores by default and torch's OpenMP threads busy-wait
between operations, so the two slow each other down badly when they share the cores (SB3's PPO
ran ~5x slower on a 2-core machine with torch's default threads than with
``torch.set_num_threads(1)``). With small policies, give torch one thread (or set
``OMP_WAIT_POLICY=PASSIVE``), or split the cores with ``threads=``.

This module is the only place socnav imports ``stable_baselines3`` (and with it torch): ``import
socnav`` works without them.
"""

from __future__ import annotations

import time
from typing import Any, Mapping, Sequence

import numpy as np
from gymnasium import spaces

try:
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env.base_vec_env import (
        VecEnv,
        VecEnvIndices,
        VecEnvObs,
        VecEnvStepReturn,
    )
except ImportError as e:  # pragma: no cover - exercised only without SB3
    raise ImportError(
        "socnav.sb3 needs Stable-Baselines3 (and torch): pip install stable-baselines3"
    ) from e

from socnav import _batch
from socnav.metrics import EPISODE_KEYS, EpisodeLog
from socnav.vector import SocNavVectorEnv, make_vec

_RETURN = EPISODE_KEYS.index("return")
_LENGTH = EPISODE_KEYS.index("length")
_SUCCESS = EPISODE_KEYS.index("success")


class SocNavSB3VecEnv(VecEnv):
    """``num_envs`` socnav environments of one config as a Stable-Baselines3 ``VecEnv``.

    Parameters
    ----------
    config : str or mapping, default ``"exp1"``
        A shipped config name, a TOML or SocNavGym YAML path, or a dict of overrides with an optional ``"base"``
        (as for ``socnav.make_vec``).
    num_envs : int, default 1
        Number of environments in the batch.
    seed : int, optional
        Seed of the batch (0 when ``None``); :meth:`seed` sets the one of the next reset.
    obs_mode : {"dict", "flat"}, default ``"dict"``
        ``"dict"``: SocNavGym's blocks (use SB3's ``MultiInputPolicy``); ``"flat"``: one float32
        row per environment (``MlpPolicy``).
    action_type : {"continuous", "discrete"}, default ``"continuous"``
        ``Box(-1, 1, (3,))`` (forward, lateral, rotation; lateral bounded to 0 for a
        differential-drive robot) or ``Discrete(7)`` (SocNavGym's ``DiscreteActions``).
    threads : int, optional
        CPU threads stepping the batch (all cores when ``None``).
    **vec_kwargs
        Further arguments of ``socnav.make_vec`` (e.g. ``backend``, or ``reward_fn`` where
        available); not ``autoreset_mode`` nor ``copy``, which the adapter sets itself.

    Notes
    -----
    With ``obs_mode="dict"`` the blocks of entity types whose capacity is 0 in the config (e.g.
    exp1's ``laptops`` and ``tables``) are left out of the observation space and the
    observations: they are always empty, and SB3's policies cannot reshape empty arrays.

    The environments are rows of one Rust batch, not Python objects: :meth:`get_attr` answers
    only the attributes every environment shares, :meth:`set_attr` and :meth:`env_method` raise.
    ``observation_space`` and ``action_space`` are one environment's, as SB3 expects.
    """

    #: Attributes :meth:`get_attr` reads, the same for every environment of the batch.
    PER_ENV_ATTRIBUTES = ("render_mode", "observation_space", "action_space", "obs_mode", "action_type", "spec")

    def __init__(
        self,
        config: str | Mapping[str, Any] = "exp1",
        num_envs: int = 1,
        *,
        seed: int | None = None,
        obs_mode: str = "dict",
        action_type: str = "continuous",
        threads: int | None = None,
        **vec_kwargs: Any,
    ) -> None:
        fixed = {"autoreset_mode", "copy"} & set(vec_kwargs)
        if fixed:
            raise TypeError(
                f"{', '.join(sorted(fixed))} cannot be chosen: SB3's VecEnv semantics need the "
                "same_step autoreset, and the adapter copies what it returns itself"
            )
        self.venv: SocNavVectorEnv = make_vec(
            config,
            num_envs,
            seed=seed,
            obs_mode=obs_mode,
            action_type=action_type,
            autoreset_mode="same_step",
            threads=threads,
            **vec_kwargs,
        )
        self.obs_mode = obs_mode
        self.action_type = action_type
        observation_space = self.venv.single_observation_space
        # Blocks of an entity type the config never has (capacity 0, e.g. exp1's laptops and
        # tables) are left out: they carry nothing, and SB3's policies cannot reshape the empty
        # arrays (``reshape((-1, 0, 14))``).
        self._keys: tuple[str, ...] | None = None
        if isinstance(observation_space, spaces.Dict):
            self._keys = tuple(
                k for k, block in observation_space.spaces.items() if int(np.prod(block.shape or ())) > 0
            )
            observation_space = spaces.Dict({k: observation_space[k] for k in self._keys})
        super().__init__(self.venv.num_envs, observation_space, self.venv.single_action_space)
        # The seeds the first reset uses: the constructor's, as make_vec's reset would.
        self._seeds: list[int | None] = (
            [None] * self.num_envs if seed is None else [(int(seed) + i) % (1 << 64) for i in range(self.num_envs)]
        )
        self._actions: np.ndarray | None = None
        self._t0 = time.perf_counter()

    # -- the VecEnv protocol ------------------------------------------------------------------

    def reset(self) -> VecEnvObs:
        """Reset every environment; environment i plays the episode of seed ``seed + i`` for the
        seed set by :meth:`seed` (or the constructor's, on the first reset), else the next
        episode of its seed sequence. Returns the observations (copies) only, as SB3 does."""
        seeds = None if self._seeds[0] is None else list(self._seeds)
        obs, _ = self.venv.reset(seed=seeds)
        self._reset_seeds()
        self._reset_options()
        self.reset_infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        self._actions = None
        return self._copy_obs(obs)

    def step_async(self, actions: np.ndarray) -> None:
        """Start stepping the batch with ``actions`` (``(num_envs, 3)`` floats for continuous
        actions, ``(num_envs,)`` integers, or ``(num_envs, 1)``, for discrete ones) on its own
        thread (``SocNavVectorEnv.send``): bad actions raise here, and the caller may work until
        :meth:`step_wait`."""
        if self._actions is not None:
            raise RuntimeError("step_async() twice: call step_wait() for the step in flight first")
        a = np.asarray(actions)
        if self.action_type == "discrete" and a.shape == (self.num_envs, 1):
            a = a.reshape(self.num_envs)
        self.venv.send(a)
        self._actions = a

    def step_wait(self) -> VecEnvStepReturn:
        """Wait for the step :meth:`step_async` started.

        Returns
        -------
        obs : numpy.ndarray or dict of numpy.ndarray
            Fresh copies; for environments that finished, the new episode's first observation.
        rewards : numpy.ndarray
            float32 ``(num_envs,)``.
        dones : numpy.ndarray
            bool ``(num_envs,)``: terminated or truncated.
        infos : list of dict
            Per environment: ``"TimeLimit.truncated"`` (True only for a time-limit end without
            termination); for finished environments also ``"terminal_observation"``,
            ``"episode"`` (SB3 Monitor's ``r``/``l``/``t`` plus the docs/spec.md 8.3 statistics) and
            ``"is_success"``.
        """
        if self._actions is None:
            raise RuntimeError("step_wait() without step_async(): call step_async(actions) first")
        self._actions = None
        obs, reward, terminated, truncated, info = self.venv.recv()
        dones = terminated | truncated
        infos: list[dict[str, Any]] = [{"TimeLimit.truncated": False} for _ in range(self.num_envs)]
        if dones.any():
            self._finish(infos, np.flatnonzero(dones), terminated, truncated, info)
        return self._copy_obs(obs), reward.copy(), dones, infos

    def _finish(
        self,
        infos: list[dict[str, Any]],
        done: np.ndarray,
        terminated: np.ndarray,
        truncated: np.ndarray,
        info: dict[str, Any],
    ) -> None:
        """Fill the infos of the environments that finished this step."""
        has_final = info.get("_final_obs")
        ended = info.get("_episode")
        if has_final is None or ended is None or not (has_final[done].all() and ended[done].all()):
            raise RuntimeError(
                "the batch reported finished environments without their final observation or "
                "episode statistics (is it in the same_step autoreset mode?)"
            )
        final_obs = info["final_obs"]  # a fresh copy made by the vector env
        stats = np.stack([np.asarray(info["episode"][k]) for k in EPISODE_KEYS], axis=1)
        t = round(time.perf_counter() - self._t0, 6)
        for i in done:
            row = stats[i]
            episode: dict[str, Any] = {"r": float(row[_RETURN]), "l": int(row[_LENGTH]), "t": t}
            episode.update((k, float(v)) for k, v in zip(EPISODE_KEYS, row))
            episode["seed"] = int(info["episode"]["seed"][i])
            if self._keys is not None:
                terminal = {k: final_obs[k][i].copy() for k in self._keys}
            else:
                terminal = final_obs[i].copy()
            infos[i].update(
                {
                    "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
                    "terminal_observation": terminal,
                    "episode": episode,
                    "is_success": bool(row[_SUCCESS] != 0.0),
                }
            )

    def _copy_obs(self, obs: Any) -> VecEnvObs:
        # The vector env returns views of the batch's buffers, overwritten by the next step.
        if self._keys is not None:
            return {k: np.array(obs[k], copy=True) for k in self._keys}
        return np.array(obs, copy=True)

    def close(self) -> None:
        self.venv.close()

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Set the seed of the next :meth:`reset`: environment i plays the episode of seed
        ``seed + i``, SB3's convention, and the list of those seeds is returned. ``None`` draws a
        seed from numpy's global generator, as SB3 does."""
        if seed is None:
            seed = int(np.random.randint(0, np.iinfo(np.uint32).max, dtype=np.uint32))
        seed = _batch.check_seed(seed)
        self._seeds = [(seed + i) % (1 << 64) for i in range(self.num_envs)]
        return list(self._seeds)

    def set_options(self, options: list[dict[str, Any]] | dict[str, Any] | None = None) -> None:
        """socnav's reset takes no options: only ``None`` or empty dicts are accepted."""
        entries = options if isinstance(options, list) else [options]
        if any(entries):
            raise ValueError(f"socnav environments take no reset options, got {options!r}")
        super().set_options(options)

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """One value per environment of an attribute all environments share (see
        ``PER_ENV_ATTRIBUTES``); ``AttributeError`` for any other name."""
        values = {
            "render_mode": None,
            "observation_space": self.observation_space,
            "action_space": self.action_space,
            "obs_mode": self.obs_mode,
            "action_type": self.action_type,
            "spec": None,
        }
        if attr_name not in values:
            raise AttributeError(
                f"socnav environments have no per-environment attribute {attr_name!r}: they are "
                f"rows of one Rust batch; readable: {', '.join(self.PER_ENV_ATTRIBUTES)}"
            )
        return [values[attr_name] for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Not supported: the environments are rows of one Rust batch, with no Python
        attributes to set."""
        raise AttributeError(
            f"cannot set {attr_name!r}: socnav environments are rows of one Rust batch, with no "
            "per-environment Python attributes (configure them through the config instead)"
        )

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> list[Any]:
        """Not supported: the environments are rows of one Rust batch, with no Python
        methods; use the adapter's own (``reset``, ``step``) or ``self.venv``."""
        raise AttributeError(
            f"cannot call {method_name!r} per environment: socnav environments are rows of one "
            "Rust batch, with no per-environment Python methods"
        )

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        """True for SB3's ``Monitor`` (and its base classes): the adapter reports episodes in
        ``infos[i]["episode"]`` exactly as ``Monitor`` does, so SB3's ``evaluate_policy`` reads
        the true returns and lengths there. False for every other wrapper."""
        wrapped = isinstance(wrapper_class, type) and issubclass(Monitor, wrapper_class)
        return [wrapped for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        raise NotImplementedError("socnav's SB3 adapter does not render; use the socnav CLI's render command")


def make_sb3(
    config: str | Mapping[str, Any] = "exp1",
    num_envs: int = 1,
    *,
    seed: int | None = None,
    obs_mode: str = "dict",
    action_type: str = "continuous",
    threads: int | None = None,
    **vec_kwargs: Any,
) -> SocNavSB3VecEnv:
    """A Stable-Baselines3 ``VecEnv`` of ``num_envs`` environments of ``config`` (see
    :class:`SocNavSB3VecEnv` for the arguments)."""
    return SocNavSB3VecEnv(
        config,
        num_envs,
        seed=seed,
        obs_mode=obs_mode,
        action_type=action_type,
        threads=threads,
        **vec_kwargs,
    )


def evaluate(
    model: Any,
    env: SocNavSB3VecEnv,
    episodes_per_env: int = 1,
    *,
    deterministic: bool = True,
    seed: int | None = None,
) -> EpisodeLog:
    """Roll out ``model`` until every environment has finished ``episodes_per_env`` episodes,
    and return their statistics (``env.num_envs * episodes_per_env`` episodes).

    Like ``sb3_eval.py`` of SocNavGym (docs/spec.md 8.3) the policy is deterministic by default.
    Only the first ``episodes_per_env`` episodes of each environment count, so that short episodes
    (collisions) are not over-represented, as they would be by stopping after the first N
    episodes of the whole batch.

    Parameters
    ----------
    model : object with ``predict(obs, state, episode_start, deterministic)``
        An SB3 algorithm or policy.
    env : SocNavSB3VecEnv
        The environments; reset first (with ``seed`` when given).
    episodes_per_env : int, default 1
    deterministic : bool, default True
    seed : int, optional
        Seed of the reset.

    Returns
    -------
    socnav.metrics.EpisodeLog
        ``log.summary()`` gives the paper's table.
    """
    episodes_per_env = _batch.check_count("episodes_per_env", episodes_per_env)
    if seed is not None:
        env.seed(seed)
    obs = env.reset()
    log = EpisodeLog()
    left = np.full(env.num_envs, episodes_per_env)
    state = None
    starts = np.ones(env.num_envs, dtype=bool)
    while left.any():
        actions, state = model.predict(obs, state=state, episode_start=starts, deterministic=deterministic)
        obs, _, dones, infos = env.step(actions)
        for i in np.flatnonzero(dones & (left > 0)):
            log.add_rows(infos[i]["episode"])
            left[i] -= 1
        starts = dones
    return log
