"""The paper's Dueling DQN, vectorised over a batch of environments (in the manner of CleanRL's
``dqn.py``: one readable file).

The agent of the paper (its section "Use Cases"): a Dueling DQN whose MLP has 5 linear layers
(512, 256, 128 and 64 hidden units, LeakyReLU; the fifth layer is the dueling head: a value and
7 advantages), Adam with a fixed learning rate of 0.001, the 7 discrete actions of a
non-holonomic robot, flat observations. (The repository's ``stable_dqn.py`` trains plain SB3 DQN
with ReLU and a learning rate of 1e-4 instead, docs/spec.md 9.3; this is the paper's agent.)
The rest follows SB3's DQN defaults, which the paper's run used: gamma 0.99, Huber loss, gradient
norm clipped at 10, epsilon from 1 to 0.05 over the first 10 % of the steps, the target network
copied every 10,000 environment steps. Vectorised: each step of the batch (``num_envs``
environment steps) is followed by one gradient step on ``batch_size`` transitions, i.e.
``batch_size / num_envs`` replayed samples per environment step (SB3: 32 / 4 = 8).

``--mode`` picks a preset (explicit flags still override it):

- ``batched`` (default): the above, with one gradient step of ``batch_size`` (256) transitions
  per batch step, a 300,000-transition buffer.
- ``paper``: the paper's run as its repository's ``stable_dqn.py`` trained it, SB3 DQN's
  semantics per environment step whatever the batch size: one gradient step of 32 transitions
  every 4 environment steps (``train_freq``; ``num_envs / 4`` per batch step), learning from
  50,000 steps, the target copied every 10,000 environment steps, a 1,000,000-transition
  buffer, epsilon 1 to 0.05 over the first 10 %, Huber loss, gradient norm 10, Adam at 1e-4, and
  the network its README commands build: a plain Q-network, ReLU MLP
  ``obs -> 512 -> 256 -> 256 -> 256 -> 128 -> 128 -> 64 -> 7`` (``network = "sb3-deep"``).
- ``paper-text``: the same schedule with the network the paper's text describes: the dueling
  head, LeakyReLU, ``[512, 256, 128, 64]``, Adam at 1e-3.

The replay buffer is preallocated arrays (observations in float16, to halve the memory of
hundreds of thousands of 695-float observations) and is saved with the checkpoint, with the
network, the optimiser, the random states and every environment's state, so a run resumes
where it stopped: ``python -m socnav.train dqn --config exp1 --steps 10000000 --out runs/x
--max-minutes 110`` run again continues it.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from socnav.train import _common as common

HIDDEN = (512, 256, 128, 64)
#: The hidden widths of ``stable_dqn.py``'s deep variant, which its README commands train.
SB3_DEEP_HIDDEN = (512, 256, 256, 256, 128, 128, 64)
N_ACTIONS = 7
#: The Q-networks ``--network`` names.
NETWORKS = ("dueling", "sb3-deep")
#: ``--mode`` presets: each a set of argument values (module docs).
MODES: dict[str, dict[str, Any]] = {
    "batched": {},
    "paper": dict(network="sb3-deep", learning_rate=1e-4, buffer_size=1_000_000, batch_size=32, train_freq=4,
                  learning_starts=50_000, target_update=10_000),
    "paper-text": dict(network="dueling", learning_rate=1e-3, buffer_size=1_000_000, batch_size=32, train_freq=4,
                       learning_starts=50_000, target_update=10_000),
}


def _hidden_layers(obs_dim: int, hidden: tuple[int, ...], activation: type[nn.Module]) -> list[nn.Module]:
    """Linear layers of widths ``hidden`` from ``obs_dim`` inputs, each followed by ``activation``."""
    widths = (obs_dim, *hidden)
    return [m for a, b in zip(widths, widths[1:]) for m in (nn.Linear(a, b), activation())]


class DuelingQ(nn.Module):
    """Q(s, ·) = V(s) + A(s, ·) - mean A(s, ·) over the MLP ``obs -> 512 -> 256 -> 128 -> 64``
    (LeakyReLU)."""

    def __init__(self, obs_dim: int, n_actions: int = N_ACTIONS) -> None:
        super().__init__()
        self.body = nn.Sequential(*_hidden_layers(obs_dim, HIDDEN, nn.LeakyReLU))
        self.value = nn.Linear(HIDDEN[-1], 1)
        self.advantage = nn.Linear(HIDDEN[-1], n_actions)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        h = self.body(obs)
        a = self.advantage(h)
        return self.value(h) + a - a.mean(dim=1, keepdim=True)


class PlainQ(nn.Module):
    """Q(s, ·) from a ReLU MLP over ``hidden`` widths (SB3's ``QNetwork`` with a ``net_arch``)."""

    def __init__(self, obs_dim: int, hidden: tuple[int, ...] = SB3_DEEP_HIDDEN, n_actions: int = N_ACTIONS) -> None:
        super().__init__()
        self.q = nn.Sequential(*_hidden_layers(obs_dim, hidden, nn.ReLU), nn.Linear(hidden[-1], n_actions))

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        out: torch.Tensor = self.q(obs)
        return out


def make_q(network: str, obs_dim: int) -> nn.Module:
    """The Q-network ``network`` (:data:`NETWORKS`) for observations of ``obs_dim`` floats."""
    if network == "dueling":
        return DuelingQ(obs_dim)
    if network == "sb3-deep":
        return PlainQ(obs_dim)
    raise ValueError(f"unknown network {network!r}: one of {', '.join(NETWORKS)}")


class Replay:
    """A ring buffer of transitions in preallocated arrays."""

    def __init__(self, capacity: int, obs_dim: int) -> None:
        self.capacity = capacity
        self.obs = np.zeros((capacity, obs_dim), np.float16)
        self.next_obs = np.zeros((capacity, obs_dim), np.float16)
        self.action = np.zeros(capacity, np.int64)
        self.reward = np.zeros(capacity, np.float32)
        self.terminal = np.zeros(capacity, np.float32)
        self.pos = 0
        self.full = False

    def add(self, obs: np.ndarray, next_obs: np.ndarray, action: np.ndarray, reward: np.ndarray, terminal: np.ndarray) -> None:
        n = obs.shape[0]
        idx = (self.pos + np.arange(n)) % self.capacity
        self.obs[idx] = obs
        self.next_obs[idx] = next_obs
        self.action[idx] = action
        self.reward[idx] = reward
        self.terminal[idx] = terminal
        self.full = self.full or self.pos + n >= self.capacity
        self.pos = int((self.pos + n) % self.capacity)

    def __len__(self) -> int:
        return self.capacity if self.full else self.pos

    def sample(self, rng: np.random.Generator, batch: int) -> tuple[torch.Tensor, ...]:
        idx = rng.integers(0, len(self), size=batch)
        return (
            torch.from_numpy(self.obs[idx].astype(np.float32)),
            torch.from_numpy(self.next_obs[idx].astype(np.float32)),
            torch.from_numpy(self.action[idx]),
            torch.from_numpy(self.reward[idx]),
            torch.from_numpy(self.terminal[idx]),
        )

    def state(self) -> dict[str, Any]:
        n = len(self)
        return {
            "obs": self.obs[:n].copy(),
            "next_obs": self.next_obs[:n].copy(),
            "action": self.action[:n].copy(),
            "reward": self.reward[:n].copy(),
            "terminal": self.terminal[:n].copy(),
            "pos": self.pos,
            "full": self.full,
        }

    def load(self, s: dict[str, Any]) -> None:
        n = s["obs"].shape[0]
        for k in ("obs", "next_obs", "action", "reward", "terminal"):
            getattr(self, k)[:n] = s[k]
        self.pos, self.full = int(s["pos"]), bool(s["full"])


@dataclass
class Args(common.RunArgs):
    steps: int = 10_000_000
    out: str = "runs/dqn"
    learning_rate: float = 1e-3
    gamma: float = 0.99
    buffer_size: int = 300_000
    batch_size: int = 256
    learning_starts: int = 50_000
    target_update: int = 10_000
    exploration_fraction: float = 0.1
    final_epsilon: float = 0.05
    max_grad_norm: float = 10.0
    mode: str = "batched"
    network: str = "dueling"
    #: Environment steps per gradient step (SB3's ``train_freq``); ``None``: one gradient step
    #: per batch step.
    train_freq: int | None = None

    @classmethod
    def for_mode(cls, mode: str, **overrides: Any) -> "Args":
        """The arguments of preset ``mode`` (:data:`MODES`), then ``overrides``."""
        if mode not in MODES:
            raise ValueError(f"unknown --mode {mode!r}: one of {', '.join(MODES)}")
        return cls(**{**MODES[mode], "mode": mode, **overrides})

    def _counts(self) -> list[tuple[str, Any]]:
        return super()._counts() + [
            ("buffer_size", self.buffer_size),
            ("batch_size", self.batch_size),
            ("target_update", self.target_update),
        ] + ([("train_freq", self.train_freq)] if self.train_freq is not None else [])

    def problems(self) -> list[str]:
        out = super().problems()
        if not (common._is_int(self.learning_starts) and self.learning_starts >= 0):
            out.append(f"--learning-starts must be an integer >= 0, got {self.learning_starts!r}")
        if self.mode not in MODES:
            out.append(f"--mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        if self.network not in NETWORKS:
            out.append(f"--network must be one of {', '.join(NETWORKS)}, got {self.network!r}")
        out += common.fraction_problems(
            gamma=self.gamma, exploration_fraction=self.exploration_fraction, final_epsilon=self.final_epsilon
        )
        return out + common.positive_problems(learning_rate=self.learning_rate, max_grad_norm=self.max_grad_norm)


def epsilon(args: Args, step: int) -> float:
    span = max(1.0, args.exploration_fraction * args.steps)
    return max(args.final_epsilon, 1.0 - (1.0 - args.final_epsilon) * step / span)


def gradient_steps(args: Args, before: int, after: int) -> int:
    """Gradient steps due when the environment step count goes from ``before`` to ``after``:
    one per batch step, or with ``train_freq`` one per ``train_freq`` environment steps counted
    over the whole run (SB3's rule for a single environment, whatever the batch size)."""
    if args.train_freq is None:
        return 1
    return after // args.train_freq - before // args.train_freq


def train(args: Args) -> dict[str, Any]:
    """Train (or resume) a run; returns its last logged scalars."""
    args.check()
    rng = common.seed_everything(args.seed, args.threads)
    env = common.make_train_env(args.config, args.num_envs, args.seed, args.threads, "discrete")
    run = common.RunDir(args.out, vars(args))
    n = env.num_envs
    obs, _ = env.reset(seed=args.seed)
    obs = obs.copy()
    obs_dim = obs.shape[1]
    q = make_q(args.network, obs_dim)
    target = copy.deepcopy(q)
    # foreach: one kernel per step for all the parameters (Adam's own loop per tensor took half of
    # a paper-mode gradient step's time on the 2-core machine).
    opt = torch.optim.Adam(q.parameters(), lr=args.learning_rate, foreach=True)
    replay = Replay(args.buffer_size, obs_dim)
    step, last_target, last_log, updates = 0, 0, 0, 0
    clock = common.Clock()
    wall_before = 0.0
    saved = run.load()
    if saved is not None:
        q.load_state_dict(saved["q"])
        target.load_state_dict(saved["target"])
        opt.load_state_dict(saved["optimizer"])
        replay.load(saved["replay"])
        wall_before = common.resume(saved, rng, env, clock)
        obs = saved["obs"]
        step, last_target, last_log = saved["step"], saved["last_target"], saved["last_log"]
        updates = int(saved.get("updates", 0))
    stats = common.EpisodeStats()
    schedule = common.Schedule("dqn", args, step)
    start = time.perf_counter()
    losses: list[float] = []
    scalars: dict[str, Any] = {}

    def checkpoint() -> None:
        run.save(
            {
                "algo": "dqn",
                "q": q.state_dict(),
                "target": target.state_dict(),
                "optimizer": opt.state_dict(),
                "replay": replay.state(),
                "rng": common.rng_states(rng),
                "envs": common.env_documents(env),
                "obs": obs,
                "step": step,
                "last_target": last_target,
                "last_log": last_log,
                "updates": updates,
                "clock": clock.parts,
                "wall": wall_before + time.perf_counter() - start,
                "obs_dim": obs_dim,
                "args": vars(args),
            }
        )

    while step < args.steps:
        clock.start()
        eps = epsilon(args, step)
        with torch.no_grad():
            greedy = q(torch.from_numpy(obs)).argmax(dim=1).numpy()
        explore = rng.random(n) < eps
        actions = np.where(explore, rng.integers(0, N_ACTIONS, size=n), greedy).astype(np.uint32)
        clock.stop("act")
        next_obs, reward, terminated, truncated, info = env.step(actions)
        clock.stop("env")
        real_next = next_obs.copy()
        if "_final_obs" in info:
            done = info["_final_obs"]
            real_next[done] = info["final_obs"][done]
        replay.add(obs, real_next, actions.astype(np.int64), reward, terminated.astype(np.float32))
        stats.add(info)
        obs = next_obs.copy()
        step += n
        if step >= args.learning_starts and len(replay) >= args.batch_size:
            for _ in range(gradient_steps(args, step - n, step)):
                o, o2, a, r, term = replay.sample(rng, args.batch_size)
                with torch.no_grad():
                    target_q = r + args.gamma * (1.0 - term) * target(o2).max(dim=1).values
                current = q(o).gather(1, a.unsqueeze(1)).squeeze(1)
                loss = F.smooth_l1_loss(current, target_q)
                opt.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(q.parameters(), args.max_grad_norm)
                opt.step()
                losses.append(float(loss.detach()))
                updates += 1
            if step - last_target >= args.target_update:
                target.load_state_dict(q.state_dict())
                last_target = step
        clock.stop("learn")
        if step - last_log >= args.log_every or step >= args.steps:
            last_log = step
            wall = wall_before + time.perf_counter() - start
            scalars = {
                **common.progress(env, step, wall, stats, clock),
                "epsilon": eps,
                "loss": float(np.mean(losses)) if losses else float("nan"),
                "gradient_steps": updates,
            }
            losses.clear()
            run.log(step, scalars)
            common.report("dqn", args, step, scalars, extra=f"eps {eps:.3f} ")
        if schedule.save_due():
            checkpoint()
        if schedule.chunk_over(step):
            break
    checkpoint()
    run.close()
    return scalars


def policy_state(saved: dict[str, Any]) -> dict[str, Any]:
    """The shippable agent of a checkpoint (see ``socnav.train.export``)."""
    network = saved["args"].get("network", "dueling")
    return {"kind": "dqn", "network": network, "obs_dim": saved["obs_dim"], "state_dict": saved["q"]}
