"""Built-in batched policies: baselines, and what evaluation and recording drive a batch with.

A policy is any callable ``policy(obs, env) -> actions`` that maps the observations of a
``socnav.make_vec`` environment (as its ``reset``/``step`` returned them) to the actions of every
environment: float32 ``(num_envs, 3)`` for ``action_type="continuous"``, integers ``(num_envs,)``
for ``"discrete"``. The built-ins:

- :class:`GoalPolicy`: turn toward the goal within one step, drive at full speed once within
  about 17° of it; blind to humans and obstacles (the controller of ``socnav run --policy goal``).
- :class:`OrcaPolicy`: the velocity ORCA gives the robot toward its goal among every human,
  moving group and obstacle (the simulator of the shadow robot behind STL/SPL), mapped to the
  robot's drive. It reads the batch state: on the GPU backend that is a download per step.
- :class:`RandomPolicy`: uniform random actions from its own seeded generator.
- :class:`StopPolicy`: the robot never moves (continuous zeros, or the discrete stop): what
  people alone do to a robot, the floor of the analysis of avoidable failures.

``get("goal")`` (or ``"orca"``, ``"random"``, ``"stop"``) builds one by name.
"""

from __future__ import annotations

from typing import Any, Callable, Protocol

import numpy as np

__all__ = ["BUILTIN", "GoalPolicy", "OrcaPolicy", "Policy", "RandomPolicy", "StopPolicy", "batch_of", "get"]


class Policy(Protocol):
    """Actions for every environment of ``env`` from its observations ``obs``."""

    def __call__(self, obs: Any, env: Any) -> np.ndarray: ...


def batch_of(env: Any) -> Any:
    """The Rust batch under a ``make_vec`` environment (through gymnasium wrappers)."""
    inner = getattr(env, "unwrapped", env)
    batch = getattr(inner, "_batch", None)
    if batch is None:
        raise TypeError(
            f"the built-in policies drive a socnav.make_vec environment, got {type(env).__name__}"
        )
    return batch


def _continuous_only(env: Any, name: str) -> None:
    action_type = getattr(getattr(env, "unwrapped", env), "action_type", "continuous")
    if action_type != "continuous":
        raise ValueError(
            f"the {name} policy gives continuous actions; make the environment with "
            f"action_type='continuous' (got {action_type!r})"
        )


class GoalPolicy:
    """The go-to-goal controller (module docs)."""

    name = "goal"

    def __call__(self, obs: Any, env: Any) -> np.ndarray:
        _continuous_only(env, self.name)
        return batch_of(env).policy_actions("goal")


class OrcaPolicy:
    """The ORCA-driven robot (module docs)."""

    name = "orca"

    def __call__(self, obs: Any, env: Any) -> np.ndarray:
        _continuous_only(env, self.name)
        return batch_of(env).policy_actions("orca")


class RandomPolicy:
    """Uniform random actions: continuous in [-1, 1] (lateral 0 for a diff-drive robot), or
    discrete actions uniform over the 7; from ``numpy.random.default_rng(seed)``."""

    name = "random"

    def __init__(self, seed: int | None = 0) -> None:
        self._rng = np.random.default_rng(seed)

    def __call__(self, obs: Any, env: Any) -> np.ndarray:
        inner = getattr(env, "unwrapped", env)
        n = batch_of(env).num_envs  # as the other built-ins, any socnav environment (one or a batch)
        if getattr(inner, "action_type", "continuous") == "discrete":
            return self._rng.integers(0, 7, size=n, dtype=np.uint32)
        a = self._rng.uniform(-1.0, 1.0, size=(n, 3)).astype(np.float32)
        if not batch_of(env).holonomic:
            a[:, 1] = 0.0
        return a


class StopPolicy:
    """The robot never moves: zeros (continuous), or action 6, stop (discrete)."""

    name = "stop"

    def __call__(self, obs: Any, env: Any) -> np.ndarray:
        inner = getattr(env, "unwrapped", env)
        n = batch_of(env).num_envs
        if getattr(inner, "action_type", "continuous") == "discrete":
            return np.full(n, 6, dtype=np.uint32)
        return np.zeros((n, 3), dtype=np.float32)


BUILTIN: dict[str, Callable[..., Policy]] = {
    "goal": GoalPolicy,
    "orca": OrcaPolicy,
    "random": RandomPolicy,
    "stop": StopPolicy,
}


def get(name: str, seed: int | None = 0) -> Policy:
    """The built-in policy ``name`` (``"goal"``, ``"orca"``, ``"random"`` or ``"stop"``; ``seed``
    seeds the random one)."""
    if name not in BUILTIN:
        raise ValueError(f"unknown policy {name!r}: the built-ins are {', '.join(map(repr, BUILTIN))}")
    return RandomPolicy(seed) if name == "random" else BUILTIN[name]()
