"""socnav: a batched social-navigation simulator with SocNavGym 0.1.1's semantics.

``make_vec`` gives a ``gymnasium.vector.VectorEnv`` over a whole batch stepped in Rust;
``make`` a single ``gymnasium.Env``; ``socnav.socnavgym`` SocNavGym 0.1.1's own interface,
``socnav.metrics`` the paper's metric table, ``socnav.policies`` the built-in batched policies
(goal controller, ORCA-driven robot, random), ``socnav.datasets`` recorded episodes as Minari
datasets and SocNavGym JSON, ``socnav.orca`` RVO2's ORCA over numpy, and
``socnav.sb3`` (imported on its own: it needs Stable-Baselines3) an SB3 ``VecEnv``, and
``socnav.sngnn.install_weights()`` fetches the SNGNN-v2 weights the ``*_sngnn`` configs need. Configs are
the shipped names (``"exp1"``, ``"exp2"``, ...), TOML or SocNavGym YAML paths, or either with a dict of overrides;
the shipped ones are also gymnasium ids (``gymnasium.make("socnav/Exp2-v0")``, ``socnav.registration``).

Modules: ``vector`` (``make_vec``, the reward callback, seeds and rendering), ``env`` (``make``),
``_batch`` (spaces, action, seed and reward checks), ``socnavgym`` (0.1.1's observation dict and
info), ``metrics`` (the paper's table), ``policies`` (goal, ORCA, random, stop), ``evaluation``
(``socnav.evaluate``: fixed episode seeds, 95 % intervals, each episode's ending with a collision's
cause read from the state it ended in; ``evaluate`` is its ``python -m`` entry), ``render``
(trails, tiles, ``record``, ``HumanView``), ``datasets`` (episodes to Minari and 0.1.1 JSON,
``collect``, ``RecordEpisodes``, ``played_episodes``), ``registration`` (the gymnasium ids),
``sb3`` (the SB3 ``VecEnv``), ``pufferlib`` (a native ``PufferEnv`` over the batch's buffers),
``torchrl`` (a TorchRL ``EnvBase``, resets through masks), ``jax`` (JAX arrays: copies, or DLPack
views), ``rllib`` (Ray RLlib: one batch per env runner), ``pinned`` (``pin_memory``: the output
buffers page-locked for CUDA through torch), ``orca``, ``sngnn`` (the weights' path,
``install_weights``), ``train`` (the baseline agents; the ``train`` extra), and ``_socnav.pyi``
(the extension's stubs).
"""

from socnav._socnav import (
    ActionError,
    BackendUnavailableError,
    ConfigError,
    DeviceError,
    DisplayError,
    EnvIndexError,
    InternalError,
    ScenarioError,
    ShapeError,
    SngnnError,
    SocNavError,
    UsageError,
    config_toml,
    shipped_configs,
)
from socnav._batch import RewardInputs, with_overrides
from socnav.env import SocNavEnv, make
from socnav.vector import SocNavVectorEnv, make_vec
from socnav.evaluation import Evaluation, evaluate
from socnav import datasets, metrics, orca, policies, registration, render, sngnn, socnavgym
from socnav.render import record

registration.register_envs()

__version__ = "0.1.0"

__all__ = [
    "ActionError",
    "BackendUnavailableError",
    "ConfigError",
    "DeviceError",
    "DisplayError",
    "EnvIndexError",
    "Evaluation",
    "InternalError",
    "RewardInputs",
    "ScenarioError",
    "ShapeError",
    "SngnnError",
    "SocNavEnv",
    "SocNavError",
    "SocNavVectorEnv",
    "UsageError",
    "config_toml",
    "evaluate",
    "make",
    "make_vec",
    "record",
    "shipped_configs",
    "with_overrides",
]
