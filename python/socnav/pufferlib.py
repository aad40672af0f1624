"""A native PufferLib environment over a socnav batch (the ``pufferlib`` extra).

``socnav.pufferlib.make(config, num_envs, seed=0)`` returns a ``pufferlib.PufferEnv``: one agent
per environment, flat observations, ``Discrete(7)`` or ``Box(3)`` actions, episodes restarting in
the step that ends them (SocNavGym's ``SAME_STEP``; PufferLib's native environments do the same).
It is its own vectorisation (``pufferlib.vector.make(socnav.pufferlib.SocNavPufferEnv,
env_kwargs=..., backend=pufferlib.vector.PufferEnv)``), as PufferLib's C environments are::

    import pufferlib.pufferl, pufferlib.models
    env = socnav.pufferlib.make("exp1", num_envs=256, seed=0)
    policy = pufferlib.models.Default(env, hidden_size=128)
    trainer = pufferlib.pufferl.PuffeRL(config, env, policy)  # a full config: PufferLib ships none

What is shared, what is copied at each step:

- ``observations`` and ``rewards`` *are* the batch's output buffers (``np.shares_memory``): the
  step writes them in place, and nothing is copied.
- ``terminals`` and ``truncations`` are bool arrays filled from the batch's uint32 flags (PufferLib
  wants bool; 2 bytes an environment).
- Discrete actions arrive as int32 and are converted to the batch's uint32 (4 bytes an
  environment); continuous ones are float32 already.
- Under PufferLib's ``Serial`` or ``Multiprocessing`` vectorisation the buffers are PufferLib's
  (``buf``, shared memory across workers), and each step copies the observations and rewards
  into them: the batch cannot write into memory it does not own.

``import pufferlib`` installs a SIGINT handler only with ``pufferlib.pufferl`` (which exits the
process on Ctrl+C); this module imports ``pufferlib`` alone.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

try:
    import pufferlib
except ImportError as e:  # the pufferlib extra is not installed
    raise ImportError("socnav.pufferlib needs PufferLib: pip install './python[pufferlib]'") from e

from socnav import _batch
from socnav._socnav import UsageError

__all__ = ["SocNavPufferEnv", "make", "EPISODE_INFO_KEYS"]

#: The episode statistics reported (as means over the episodes that ended in a step) in the
#: step's info list, which PufferLib's trainer averages into its ``environment/`` log.
EPISODE_INFO_KEYS = ("return", "length", "success", "collision", "collision_human", "timeout", "DISCOMFORT_DSRNN", "DISCOMFORT_SNGNN")


class SocNavPufferEnv(pufferlib.PufferEnv):
    """``num_envs`` socnav environments as one native PufferLib environment of ``num_envs``
    agents (see the module's documentation for what is shared)."""

    def __init__(
        self,
        config: str | Mapping[str, Any] = "exp1",
        num_envs: int = 1,
        *,
        seed: int = 0,
        action_type: str = "discrete",
        threads: int | None = None,
        backend: str = "cpu",
        buf: Mapping[str, np.ndarray] | None = None,
    ) -> None:
        self.action_type = _batch.check_choice("action_type", action_type, _batch.ACTION_TYPES)
        self._batch = _batch.build_batch(config, num_envs, seed, "same_step", threads, backend)
        self._batch.set_step_outputs(info=False, interactions=False, events=False)
        self.num_agents = self._batch.num_envs
        self.single_observation_space = _batch.observation_space(self._batch, "flat")
        self.single_action_space = _batch.action_space(self._batch, self.action_type)
        self._keys = _batch.Batch.keys()["episode"]
        self._out = self._batch.buffers()
        super().__init__(buf)
        # PufferLib's own buffers when it vectorises (``buf``); else the batch's, shared.
        self._copy = buf is not None
        if not self._copy:
            self.observations = self._out["obs"]
            self.rewards = self._out["reward"]
        self.tick = 0

    @property
    def shared(self) -> bool:
        """Whether ``observations`` and ``rewards`` are the batch's buffers (no copy per step)."""
        return not self._copy

    def reset(self, seed: int | None = None) -> tuple[np.ndarray, list[dict[str, Any]]]:
        """Every environment afresh; ``seed=s`` gives environment ``i`` the episode of seed
        ``s + i`` (PufferLib passes the trainer's seed)."""
        self._check_open()
        seeds = _batch.episode_seeds(seed, self.num_agents)
        if seeds is not None:
            self._batch.set_next_seeds(seeds)
        self._batch.reset(None)
        self._publish()
        self.terminals[:] = False
        self.truncations[:] = False
        self.tick = 0
        return self.observations, []

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """Step every environment; an ended episode restarts in the same step (its last
        observation is not kept: PufferLib's trainer bootstraps nothing from it)."""
        self._check_open()
        a = np.asarray(actions)
        if self.action_type == "discrete" and np.issubdtype(a.dtype, np.integer):
            a = a.astype(np.uint32, copy=False)
        _batch.step_batch(self._batch, self.action_type, a, self.num_agents)
        self._publish()
        np.not_equal(self._out["terminated"], 0, out=self.terminals)
        np.not_equal(self._out["truncated"], 0, out=self.truncations)
        self.tick += 1
        return self.observations, self.rewards, self.terminals, self.truncations, self._episode_info()

    def close(self) -> None:
        self._batch.close()

    def _publish(self) -> None:
        if self._copy:
            np.copyto(self.observations, self._out["obs"])
            np.copyto(self.rewards, self._out["reward"])

    def _episode_info(self) -> list[dict[str, Any]]:
        done = self._out["episode_done"].astype(bool)
        if not done.any():
            return []
        stats = self._out["episode"][done]
        info = {key: float(stats[:, self._keys.index(key)].mean()) for key in EPISODE_INFO_KEYS}
        info["episodes"] = int(done.sum())
        return [info]

    def _check_open(self) -> None:
        if self._batch.closed:
            raise UsageError("the environment is closed")


#: ``make(config, num_envs, *, seed=0, action_type="discrete", threads=None, backend="cpu")``:
#: ``num_envs`` environments of ``config`` as one :class:`SocNavPufferEnv`.
make = SocNavPufferEnv
