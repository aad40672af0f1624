"""Baseline agents trained over the batch, and the agents that ship with socnav.

Needs the ``train`` extra (``pip install './python[train]'``, which brings torch and matplotlib); ``import
socnav`` never imports this module.

- ``python -m socnav.train dqn --config exp2_sngnn --steps 2000000 --out runs/dqn-exp2-sngnn``
  trains the paper's Dueling DQN (:mod:`socnav.train.dqn`); ``ppo`` trains PPO
  (:mod:`socnav.train.ppo`, ``--action-type discrete|continuous``, ``--network mlp|entity``: the
  entity network of :mod:`socnav.train.entity` reads the records as a set with attention). A run logs to
  ``progress.csv`` (and TensorBoard when installed), checkpoints every ``--checkpoint-minutes``
  and resumes when run again with the same ``--out``; ``--max-minutes`` ends a chunk in time.
- ``python -m socnav.train export runs/dqn-exp2-sngnn/checkpoint.pt agents/dqn-exp2-sngnn.pt``
  writes the agent alone (float16 weights and the observation normalisation, a plain
  ``torch.save`` dict of tensors: ``format``, ``kind``, ``config``, ``obs_dim``, ``action_type``,
  ``state_dict``, optional ``obs_mean``/``obs_var``).
- ``python -m socnav.train plot runs/ppo-exp1-dsrnn runs/dqn-exp1-dsrnn --out curves.png`` draws
  learning curves (:mod:`socnav.train.plot`, matplotlib): a panel per metric and experiment.
- :func:`load` gives a policy for :func:`socnav.evaluate` and :mod:`socnav.policies` users:
  ``socnav.train.load("dqn-exp2-sngnn")`` (a shipped agent, :func:`shipped`) or a path.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

try:
    import torch
except ImportError as e:  # the train extra is not installed
    raise ImportError("socnav.train needs torch: pip install './python[train]' (or torch itself)") from e

__all__ = ["Agent", "export", "load", "shipped"]

FORMAT = "socnav-agent/1"
#: Where the shipped agents live (``<name>.pt``).
AGENTS_DIR = Path(__file__).with_name("agents")


class Agent:
    """A trained agent as a batched policy: ``agent(obs, env) -> actions`` (greedy: the best Q
    value for DQN, the mode of the action distribution for PPO). ``obs_mode`` is ``"flat"``;
    ``action_type`` says which actions it gives; ``config`` names what it was trained on."""

    obs_mode = "flat"
    #: What the agent needs of the config it plays (the TOML layout; ``socnav.evaluate`` applies
    #: it): the entity agents read the robot's velocity.
    config_overrides: dict[str, Any] | None = None

    def __init__(self, saved: dict[str, Any], name: str) -> None:
        if not isinstance(saved, dict):
            raise ValueError(f"{name}: not a socnav agent (a {type(saved).__name__})")
        if saved.get("format") != FORMAT:
            raise ValueError(f"{name}: not a socnav agent (format {saved.get('format')!r}, expected {FORMAT!r})")
        self.name = name
        self.kind: str = saved["kind"]
        self.config: str = saved.get("config", "")
        self.obs_dim = int(saved["obs_dim"])
        self.action_type: str = saved.get("action_type", "discrete")
        state = {k: v.float() for k, v in saved["state_dict"].items()}
        # The entity agents' memory of the last observations (none for the others).
        self.memory: Any = None
        if self.kind == "dqn":
            from socnav.train.dqn import make_q

            self.network: str = saved.get("network", "dueling")
            self.net: torch.nn.Module = make_q(self.network, self.obs_dim)
            self.net.load_state_dict(state)
        elif self.kind == "ppo" and saved.get("network") == "entity":
            from socnav.train import entity

            self.network = "entity"
            self.layout = dict(saved["layout"])
            self.config_overrides = saved.get("config_overrides", entity.CONFIG_OVERRIDES)
            self.net = entity.EntityPolicy(entity.Layout.of(self.layout), self.action_type)
            state.pop("log_std", None)
            self.net.load_state_dict(state)
            self.memory = entity.FrameMemory()
        elif self.kind == "ppo":
            from socnav.train.ppo import _mlp

            self.network = "mlp"
            self.net = _mlp(self.obs_dim, 7 if self.action_type == "discrete" else 3, 0.01)
            state.pop("log_std", None)
            self.net.load_state_dict(state)
        else:
            raise ValueError(f"{name}: unknown agent kind {self.kind!r}")
        self.net.eval()
        self.obs_mean = saved.get("obs_mean")
        self.obs_var = saved.get("obs_var")

    def __call__(self, obs: Any, env: Any = None) -> np.ndarray:
        x = np.asarray(obs, dtype=np.float32)
        if x.ndim != 2 or x.shape[1] != self.obs_dim:
            raise ValueError(
                f"{self.name} takes flat observations of {self.obs_dim} floats (obs_mode='flat'), got shape {x.shape}"
            )
        if self.memory is not None:
            x = self._remembering(x, env)
        elif self.obs_mean is not None and self.obs_var is not None:
            x = np.clip((x - self.obs_mean.numpy()) / np.sqrt(self.obs_var.numpy() + 1e-8), -10.0, 10.0).astype(np.float32)
        with torch.no_grad():
            out = self.net(torch.from_numpy(x)).numpy()
        if self.action_type == "discrete":
            return out.argmax(axis=1).astype(np.uint32)
        a = np.clip(out, -1.0, 1.0).astype(np.float32)
        holonomic = env is not None and getattr(getattr(env, "unwrapped", env), "_batch").holonomic
        if not holonomic:
            a[:, 1] = 0.0
        return a

    def _remembering(self, obs: np.ndarray, env: Any) -> np.ndarray:
        """The entity network's input: ``obs`` with its change since this agent's last call,
        forgotten where ``env.episode_steps`` says an episode starts (``socnav.make_vec``'s
        environments count them). Without that count, call ``reset_memory()`` between episodes."""
        steps = getattr(getattr(env, "unwrapped", env), "episode_steps", None)
        if steps is not None and self.memory.prev is not None and self.memory.prev.shape == obs.shape:
            self.memory.restart(np.asarray(steps) == 0, obs)
        x = self.memory.features(obs)
        self.memory.remember(obs)
        return x

    def reset_memory(self) -> None:
        """Forget the observations seen (an agent with memory; nothing otherwise)."""
        if self.memory is not None:
            self.memory.prev = None

    def __repr__(self) -> str:
        return f"Agent({self.name!r}, {self.kind}, {self.action_type}, trained on {self.config!r})"


def shipped() -> list[str]:
    """Names of the agents that ship with socnav."""
    return sorted(p.stem for p in AGENTS_DIR.glob("*.pt"))


def load(name_or_path: str | Path) -> Agent:
    """A shipped agent by name (``"dqn-exp2-sngnn"``) or an agent file by path (see
    :func:`export`)."""
    path = Path(name_or_path)
    if not path.exists():
        candidate = AGENTS_DIR / f"{name_or_path}.pt"
        if not candidate.exists():
            raise ValueError(
                f"no agent {str(name_or_path)!r}: not a file, and not a shipped agent "
                f"({', '.join(shipped()) or 'none shipped'})"
            )
        path = candidate
    if path.is_dir():
        raise ValueError(f"{str(path)!r} is a directory, not an agent file")
    try:
        saved = torch.load(path, weights_only=True, map_location="cpu")
    except Exception as e:  # torch raises what its reader or unpickler met
        hint = " (a training checkpoint: export its agent first)" if path.name == "checkpoint.pt" else ""
        raise ValueError(f"{path}: not a socnav agent file{hint}: {type(e).__name__}: {e}") from None
    return Agent(saved, path.stem)


def agent_file(saved: dict[str, Any], dtype: str = "float16") -> dict[str, Any]:
    """The agent file's contents (see :func:`export`) of a checkpoint's payload."""
    if saved["algo"] == "dqn":
        from socnav.train.dqn import policy_state
    else:
        from socnav.train.ppo import policy_state
    agent = policy_state(saved)
    agent["state_dict"] = {k: v.detach().to(getattr(torch, dtype)) for k, v in agent["state_dict"].items()}
    agent["format"] = FORMAT
    agent["config"] = saved["args"]["config"]
    agent["steps"] = int(saved["step"])
    agent.setdefault("action_type", "discrete")
    return agent


def export(checkpoint: str | Path, out: str | Path, dtype: str = "float16") -> Path:
    """Write the agent of a training checkpoint alone to ``out``, its weights ``float16`` (what
    ships) or ``float32`` (what evaluations read: the weights as trained); never over the
    checkpoint itself, nor over a run's checkpoint (the run could not resume)."""
    if dtype not in ("float16", "float32"):
        raise ValueError(f"dtype must be 'float16' or 'float32', got {dtype!r}")
    checkpoint, out = Path(checkpoint), Path(out)
    # realpath takes `a/missing/../b` to `a/b` as opening the file would.
    target = Path(os.path.realpath(out))
    if target == Path(os.path.realpath(checkpoint)) or (target.name == "checkpoint.pt" and (target.parent / "args.json").exists()):
        raise ValueError(f"{out}: a training checkpoint; write the agent to another file")
    try:
        saved = torch.load(checkpoint, weights_only=False, map_location="cpu")
    except OSError:
        raise
    except Exception as e:  # torch raises what its reader or unpickler met
        raise ValueError(f"{checkpoint}: not a socnav.train checkpoint ({type(e).__name__}: {e})") from None
    algo = saved.get("algo") if isinstance(saved, dict) else None
    if algo not in ("dqn", "ppo"):
        raise ValueError(f"{checkpoint}: not a socnav.train checkpoint (algo {algo!r})")
    agent = agent_file(saved, dtype)
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.save(agent, out)
    return out
