"""The pieces both environments share: building the Rust batch from a config argument, the
spaces from its layout, and the validation of actions."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np
from gymnasium import spaces

from socnav._socnav import DISCRETE_ACTIONS, Batch, ConfigError

ACTION_TYPES = ("continuous", "discrete")
OBS_MODES = ("dict", "flat")
BACKENDS = ("auto", "cpu", "gpu")
N_DISCRETE = len(DISCRETE_ACTIONS)


def build_batch(
    config: str | Mapping[str, Any],
    num_envs: int,
    seed: int | None,
    autoreset_mode: str,
    threads: int | None,
    backend: str = "cpu",
) -> Batch:
    """``config``: a shipped name or a TOML or SocNavGym YAML path, or a dict of overrides with an optional
    ``"base"`` key naming the config they apply to (default ``"exp1"``)."""
    if isinstance(config, Mapping):
        overrides = dict(config)
        base = overrides.pop("base", "exp1")
        text = json_text(overrides, config_error)
    elif isinstance(config, str):
        base, text = config, None
    else:
        raise TypeError(f"config must be a name, a path or a dict, got {type(config).__name__}")
    num_envs = check_count("num_envs", num_envs)
    check_choice("backend", backend, BACKENDS)
    return Batch(
        base, int(num_envs), 0 if seed is None else check_seed(seed), autoreset_mode, threads, text, None, backend
    )


def with_overrides(config: str | Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """``config`` (a name, a path, or a dict of overrides with ``"base"``) with ``overrides`` (the
    TOML layout) applied on top, tables merged key by key:
    ``with_overrides("exp2", {"observation": {"robot_velocity": True}})``."""
    if isinstance(config, str):
        merged: dict[str, Any] = {"base": config}
    elif isinstance(config, Mapping):
        merged = dict(config)
    else:
        raise TypeError(f"config must be a name, a path or a dict, got {type(config).__name__}")
    return _merge(merged, overrides)


def _merge(into: dict[str, Any], top: Mapping[str, Any]) -> dict[str, Any]:
    for key, value in top.items():
        below = into.get(key)
        into[key] = _merge(dict(below), value) if isinstance(below, Mapping) and isinstance(value, Mapping) else value
    return into


def config_error(problems: list[tuple[str | None, str]], prefix: str = "") -> ConfigError:
    """A ``ConfigError`` raised in Python, with ``problems`` as the core's carry them: ``(key or
    None, message)`` pairs; ``prefix`` (a file, say) leads each message."""
    problems = [(key, f"{prefix}{message}") for key, message in problems]
    err = ConfigError("invalid configuration:\n  - " + "\n  - ".join(m for _, m in problems))
    err.problems = problems
    return err


def json_text(value: Mapping[str, Any], refuse: Callable[[list[tuple[str | None, str]]], Exception]) -> str:
    """``value`` (a table of overrides, a parsed YAML config, a state document) as JSON text,
    numpy scalars and arrays as numbers and lists. What JSON cannot hold (a NaN or infinity at
    any depth, an object of another type) is raised as ``refuse(problems)``, every such value
    named by its dotted key, so that the core's parser never sees it and says only where in the
    text it stopped."""
    problems: list[tuple[str | None, str]] = []
    plain = _plain_json(value, "", problems)
    if problems:
        raise refuse(problems)
    return json.dumps(plain, allow_nan=False)


def _plain_json(value: Any, name: str, problems: list[tuple[str | None, str]]) -> Any:
    """``value`` with numpy's types made Python's; see :func:`json_text`."""
    if isinstance(value, Mapping):
        return {str(k): _plain_json(v, f"{name}.{k}" if name else str(k), problems) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain_json(v, f"{name}[{i}]", problems) for i, v in enumerate(value)]
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        if not np.isfinite(value):
            problems.append((name, f"`{name}` must be finite, got {value}"))
        return value
    problems.append((name, f"`{name}` is a {type(value).__name__} ({value!r}), which JSON cannot hold"))
    return None


def observation_space(batch: Batch, obs_mode: str) -> spaces.Space:
    """The space of one environment's observation: a flat float32 row, or the SocNavGym dict
    (``robot`` and one ``(capacity, 14)`` block per entity type, padded with zeros)."""
    layout = batch.layout()
    if obs_mode == "flat":
        return spaces.Box(-np.inf, np.inf, (layout["dim"],), np.float32)
    blocks: dict[str, spaces.Space[Any]] = {"robot": spaces.Box(-np.inf, np.inf, (layout["robot"],), np.float32)}
    for key, (_, capacity) in layout["entities"].items():
        blocks[key] = spaces.Box(-np.inf, np.inf, (capacity, layout["record"]), np.float32)
    return spaces.Dict(blocks)


def action_space(batch: Batch, action_type: str) -> spaces.Space:
    """Forward, lateral and rotation in [-1, 1]; a differential-drive robot's lateral bound is
    [0, 0], as in SocNavGym. Or the 7 discrete actions."""
    if action_type == "discrete":
        return spaces.Discrete(N_DISCRETE)
    lateral = 1.0 if batch.holonomic else 0.0
    low = np.array([-1.0, -lateral, -1.0], dtype=np.float32)
    return spaces.Box(low, -low, (3,), np.float32)


def split_obs(flat: np.ndarray, layout: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Views of a ``(n, dim)`` observation as the dict blocks (no copy)."""
    n = flat.shape[0]
    out = {"robot": flat[:, : layout["robot"]]}
    record = layout["record"]
    for key, (offset, capacity) in layout["entities"].items():
        out[key] = flat[:, offset : offset + capacity * record].reshape(n, capacity, record)
    return out


def reset_single(batch: Batch, seed: int | None) -> None:
    """Reset a batch of one environment into the episode of seed ``seed``, else into the next
    episode of its sequence."""
    if seed is not None:
        batch.set_next_seeds([check_seed(seed)])
    batch.reset_envs(np.ones(1, dtype=bool))


_SEED_LIMIT = 1 << 64


def check_count(name: str, value: Any) -> int:
    """``value`` as an int of at least 1 (a count of environments, episodes, pixels), or an
    error naming ``name``: a float or a bool is refused, not rounded."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an int, got {value!r} ({type(value).__name__})")
    if value < 1:
        raise ValueError(f"{name} must be at least 1, got {value}")
    return int(value)


def check_seed(seed: Any) -> int:
    """``seed`` as an int in 0..2**64, or a ValueError naming it."""
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"a seed must be an int, got {seed!r} ({type(seed).__name__})")
    if not 0 <= int(seed) < _SEED_LIMIT:
        raise ValueError(f"a seed must be in 0..2**64, got {seed}")
    return int(seed)


def episode_seeds(seed: Any, num_envs: int) -> list[int | None] | None:
    """The next-episode seeds a vector ``reset(seed=...)`` names: ``None`` for none, ``s + i``
    (wrapping at 2**64) for an int ``s``, or a list's own (one per environment)."""
    if seed is None:
        return None
    if isinstance(seed, np.ndarray) and seed.ndim != 1:
        raise ValueError(f"seeds must be one per environment, shape ({num_envs},), got shape {seed.shape}")
    if isinstance(seed, (list, tuple, np.ndarray)):
        seeds = list(seed)
        if len(seeds) != num_envs:
            raise ValueError(f"{len(seeds)} seeds given for {num_envs} environments (one per environment)")
        return [None if s is None else check_seed(s) for s in seeds]
    first = check_seed(seed)
    return [(first + i) % _SEED_LIMIT for i in range(num_envs)]


def seeds_of(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """uint64 seeds from their low and high uint32 words."""
    return lo.astype(np.uint64) | (hi.astype(np.uint64) << np.uint64(32))


def check_running(ended: bool) -> None:
    """A single environment cannot step past the end of its episode (SocNavGym raises too)."""
    if ended:
        raise RuntimeError("step() after the episode ended: call reset() first")


def check_choice(name: str, value: str, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")
    return value


def step_batch(batch: Batch, action_type: str, actions: Any, num_envs: int, send: bool = False) -> None:
    """Validate ``actions`` (shape, dtype, finiteness, range for discrete) and step; with
    ``send``, only start the step (``Batch.recv`` waits for it)."""
    a = np.asarray(actions)
    if action_type == "continuous":
        if a.shape != (num_envs, 3):
            raise ValueError(f"actions must have shape ({num_envs}, 3), got {a.shape}")
        if not np.issubdtype(a.dtype, np.number) or np.issubdtype(a.dtype, np.complexfloating):
            raise ValueError(f"actions must be real numbers, got dtype {a.dtype}")
        a = np.ascontiguousarray(a, dtype=np.float32)
        if not np.isfinite(a).all():
            bad = np.argwhere(~np.isfinite(a))[0]
            raise ValueError(f"actions[{bad[0]}, {bad[1]}] is {a[tuple(bad)]}: actions must be finite")
        (batch.send_continuous if send else batch.step_continuous)(a)
    else:
        if a.shape != (num_envs,):
            raise ValueError(f"actions must have shape ({num_envs},), got {a.shape}")
        if not np.issubdtype(a.dtype, np.integer):
            raise ValueError(f"discrete actions must be integers, got dtype {a.dtype}")
        if a.size and (a.min() < 0 or a.max() >= N_DISCRETE):
            k = int(np.argmax((a < 0) | (a >= N_DISCRETE)))
            raise ValueError(f"actions[{k}] is {a[k]}: discrete actions are 0..{N_DISCRETE - 1}")
        a = np.ascontiguousarray(a, dtype=np.uint32)
        (batch.send_discrete if send else batch.step_discrete)(a)


@dataclass(frozen=True)
class RewardInputs:
    """What a custom reward function sees of one step of the batch; the first axis of every
    array is the environment. The arrays may be views of buffers the next step overwrites:
    copy what you keep.

    Attributes:
        actions: the actions given to ``step`` (continuous ``(n, 3)`` float32 in [-1, 1], or
            discrete ``(n,)`` integers).
        obs: the observation each environment reached at this step, before an autoreset
            replaced it (``"dict"`` blocks or the ``"flat"`` row, as the environment returns).
        reward: the built-in reward of the step (float32 ``(n,)``), as the config defines it.
        terminated: bool ``(n,)``.
        truncated: bool ``(n,)``.
        info: every metric of the step by name, float32 ``(n,)`` (NaN where SocNavGym has
            ``None``).
        stepped: bool ``(n,)``; false where the call was not a step of that environment but the
            reset of the NEXT_STEP autoreset (or a finished environment waiting under DISABLED).
            Those environments get reward 0 whatever the function returns.
    """

    actions: np.ndarray
    obs: Any
    reward: np.ndarray
    terminated: np.ndarray
    truncated: np.ndarray
    info: dict[str, np.ndarray]
    stepped: np.ndarray


RewardFn = Callable[[RewardInputs], Any]


def custom_reward(fn: RewardFn, inputs: RewardInputs, out: np.ndarray) -> np.ndarray:
    """Call ``fn`` and write its rewards into ``out`` (float32 ``(n,)``), 0 where the
    environment did not step. Anything but ``n`` finite real numbers is a ``ValueError``
    naming the problem."""
    n = out.shape[0]
    got = np.asarray(fn(inputs))
    if got.shape not in ((n,), ()):
        raise ValueError(f"reward_fn must return {n} rewards (shape ({n},)), got shape {got.shape}")
    if not np.issubdtype(got.dtype, np.number) or np.issubdtype(got.dtype, np.complexfloating):
        raise ValueError(f"reward_fn must return real numbers, got dtype {got.dtype}")
    out[:] = got
    if not np.isfinite(out).all():
        k = int(np.argmax(~np.isfinite(out)))
        raise ValueError(
            f"reward_fn's reward for environment {k} is {out[k]} as float32: rewards must be finite"
        )
    out[~inputs.stepped] = 0.0
    return out
