"""SocNavGym 0.1.1's interface over socnav, for code written against SocNavGym.

``SocNavGymEnv`` returns what 0.1.1's ``SocNavEnv`` returns: the observation as a plain dict of
1-D float32 vectors in the order robot, humans, laptops, tables, plants, walls, each holding only
the entities that exist (a key is absent when its type has none; with ``padded = true`` in the
config every type is padded to its capacity and the walls are omitted, as 0.1.1's
``get_padded_observations``), and its info dict: the collision and outcome flags as ``bool``,
``FAILURE_TO_PROGRESS`` and ``TIME_TO_COLLISION`` as ``int``, ``None`` where 0.1.1 has ``None``,
and ``interactions`` as lists of index pairs. ``observation_space`` is recomputed from the current
episode's counts, and its ``Dict`` sorts the keys alphabetically as gym's does (which is the order
SB3's flattening uses).

The config may be a SocNavGym YAML file (``.yaml``/``.yml``, converted key by key in the core, as
everywhere a config is taken), or anything ``socnav.make`` takes. ``DiscreteActions`` is 0.1.1's
wrapper of the same name.

    env = DiscreteActions(SocNavGymEnv("exp1_no_sngnn.yaml"))
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(4)   # forward
"""

from __future__ import annotations

import json
import os
from typing import Any, Mapping

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from socnav import _batch
from socnav._socnav import DISCRETE_ACTIONS, Batch, ShapeError, config_toml

#: 0.1.1's boolean info keys (the Rust ``spec::BOOL_INFO_KEYS``).
BOOL_INFO = frozenset(Batch.keys()["bool_info"])
#: 0.1.1's integer info keys (the Rust ``spec::INT_INFO_KEYS``).
INT_INFO = frozenset(Batch.keys()["int_info"])


def load_socnavgym_yaml(path: str | os.PathLike[str]) -> str:
    """A SocNavGym 0.1.1 YAML config as socnav TOML text (every key converted; the missing ones,
    the ones 0.1.1 does not read and the values socnav cannot take listed in one
    ``ConfigError``, each message led by the file's name). Any config argument of socnav takes the
    YAML path itself; this shows what it becomes."""
    path = os.fspath(path)
    if not path.endswith((".yaml", ".yml")):
        raise ValueError(f"a SocNavGym config is a .yaml or .yml file, got {path!r}")
    return config_toml(path)


def _document_error(problems: list[tuple[str | None, str]]) -> ShapeError:
    """The ``ShapeError`` the core raises for a bad state document, for values that JSON
    cannot hold."""
    err = ShapeError("state document: " + "; ".join(message for _, message in problems))
    err.what = "state document"
    return err


class SocNavGymEnv(gym.Env):
    """One environment with SocNavGym 0.1.1's observation and info (see the module)."""

    metadata = {"render_modes": []}

    def __init__(self, config: str | os.PathLike[str] | Mapping[str, Any] = "exp1", *, threads: int | None = 1) -> None:
        if isinstance(config, os.PathLike):
            config = os.fspath(config)
        self._batch: Batch = _batch.build_batch(config, 1, None, "disabled", threads)
        layout = self._batch.layout()
        self._robot = layout["robot"]
        self._record = layout["record"]
        self._blocks = [(key, offset, capacity) for key, (offset, capacity) in layout["entities"].items()]
        self._padded = bool(layout["padded"])
        self._info_keys = Batch.keys()["info"]
        self._buf = self._batch.buffers()
        self._ended = True  # until the first reset
        self.action_space = _batch.action_space(self._batch, "continuous")

    @property
    def observation_space(self) -> spaces.Dict:  # type: ignore[override]
        """Recomputed from the current episode's counts on every access, as in 0.1.1."""
        obs = self._obs()
        return spaces.Dict(
            {key: spaces.Box(-np.inf, np.inf, value.shape, np.float32) for key, value in obs.items()}
        )

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        _batch.reset_single(self._batch, seed)
        self._ended = False
        return self._obs(), {}

    def step(self, action: Any):
        a = np.asarray(action)
        if a.shape != (3,):
            raise ValueError(f"action must have shape (3,), got {a.shape}")
        _batch.check_running(self._ended)
        _batch.step_batch(self._batch, "continuous", a.reshape(1, 3), 1)
        b = self._buf
        terminated, truncated = bool(b["terminated"][0]), bool(b["truncated"][0])
        self._ended = terminated or truncated
        return self._obs(), float(b["reward"][0]), terminated, truncated, self._info()

    def get_state(self) -> dict[str, Any]:
        """The environment's complete state as a document (the format of the golden episodes'
        snapshots plus the room), e.g. to restore it later with :meth:`set_state`."""
        doc: dict[str, Any] = json.loads(self._batch.get_state(0))
        return doc

    def set_state(self, document: str | Mapping[str, Any]) -> None:
        """Load a state document (:meth:`get_state`'s, or a golden episode's header and snapshot);
        the episode continues from it."""
        if not isinstance(document, (str, Mapping)):
            raise TypeError(f"a state document is JSON text or a mapping, got {type(document).__name__}")
        self._batch.set_state(0, document if isinstance(document, str) else _batch.json_text(document, _document_error))
        self._ended = False

    def _obs(self) -> dict[str, np.ndarray]:
        """0.1.1's dict: the robot vector, then each type's real records (all of its capacity
        when padded), flattened; absent keys for types with no records."""
        row = self._buf["obs"][0]
        counts = self._buf["obs_count"][0]
        out = {"robot": row[: self._robot].copy()}
        for t, (key, offset, capacity) in enumerate(self._blocks):
            n = capacity if self._padded else int(counts[t])
            if n > 0:
                out[key] = row[offset : offset + n * self._record].copy()
        return out

    def _info(self) -> dict[str, Any]:
        values = self._buf["info"][0]
        info: dict[str, Any] = {}
        for k, key in enumerate(self._info_keys):
            v = float(values[k])
            if key in BOOL_INFO:
                info[key] = v != 0.0
            elif np.isnan(v):
                info[key] = None
            elif key in INT_INFO:
                info[key] = int(v)
            else:
                info[key] = v
        hh, hl = self._buf["pair_count"][0]
        info["interactions"] = {
            "human-human": _pairs(self._buf["hh_pairs"][0], int(hh)),
            "human-laptop": _pairs(self._buf["hl_pairs"][0], int(hl)),
        }
        return info


def _pairs(flat: np.ndarray, n: int) -> list[tuple[int, int]]:
    return [(int(flat[2 * i]), int(flat[2 * i + 1])) for i in range(n)]


class DiscreteActions(gym.ActionWrapper):
    """0.1.1's ``DiscreteActions``: ``Discrete(7)`` onto the continuous actions: 0 turn left,
    1 turn right, 2 forward + left, 3 forward + right, 4 forward, 5 backward, 6 stop."""

    ACTIONS = np.array(DISCRETE_ACTIONS, dtype=np.float32)

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.action_space = spaces.Discrete(len(self.ACTIONS))

    def action(self, action: Any) -> np.ndarray:
        a = np.asarray(action)
        if a.shape != () or not np.issubdtype(a.dtype, np.integer) or not 0 <= int(a) < len(self.ACTIONS):
            raise ValueError(f"a discrete action is an integer in 0..{len(self.ACTIONS) - 1}, got {action!r}")
        return self.ACTIONS[int(a)].copy()


def make(config: str | os.PathLike[str] | Mapping[str, Any] = "exp1", *, discrete: bool = False) -> gym.Env:
    """A ``SocNavGymEnv``, wrapped in ``DiscreteActions`` when ``discrete``."""
    env: gym.Env = SocNavGymEnv(config)
    return DiscreteActions(env) if discrete else env
