"""PPO over a batch of environments, discrete or continuous actions (in the manner of CleanRL's
``ppo.py`` and ``ppo_continuous_action.py``: one readable file).

Rollouts of ``rollout_steps`` steps of every environment, generalised advantage estimation
(gamma 0.99, lambda 0.95; truncated episodes bootstrap from the value of their last
observation), ``epochs`` passes of clipped-objective updates over ``minibatches`` minibatches, a
learning rate annealed linearly to 0, observations normalised by running statistics (kept in the
checkpoint and shipped with the agent). Actor and critic are separate MLPs (256, 256, tanh), or
with ``--network entity`` the entity network of :mod:`socnav.train.entity` (one encoder, a policy
and a value head; fixed input scales instead of running statistics; rewards over the running sd
of the discounted return); discrete actions are a categorical over the 7, continuous ones a Gaussian with a learned
state-independent standard deviation (the batch clips actions to [-1, 1]).

Resumes from ``checkpoint.pt`` in ``--out`` like ``socnav.train.dqn``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from torch import nn
from torch.distributions import Categorical, Normal

from socnav.train import _common as common
from socnav.train import entity

HIDDEN = 256


class RunningNorm:
    """Running mean and variance of the observations (Welford over batches), clipped to ±10."""

    def __init__(self, dim: int) -> None:
        self.mean = np.zeros(dim, np.float64)
        self.var = np.ones(dim, np.float64)
        self.count = 1e-4

    def update(self, x: np.ndarray) -> None:
        mean, var, n = x.mean(axis=0), x.var(axis=0), x.shape[0]
        delta = mean - self.mean
        total = self.count + n
        self.mean = self.mean + delta * n / total
        self.var = (self.var * self.count + var * n + delta**2 * self.count * n / total) / total
        self.count = total

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return np.clip((x - self.mean) / np.sqrt(self.var + 1e-8), -10.0, 10.0).astype(np.float32)

    def state(self) -> dict[str, Any]:
        return {"mean": self.mean, "var": self.var, "count": self.count}

    def load(self, s: dict[str, Any]) -> None:
        self.mean, self.var, self.count = np.asarray(s["mean"]), np.asarray(s["var"]), float(s["count"])


def _mlp(inputs: int, outputs: int, out_gain: float) -> nn.Sequential:
    def layer(i: int, o: int, gain: float) -> nn.Linear:
        lin = nn.Linear(i, o)
        nn.init.orthogonal_(lin.weight, gain)
        nn.init.zeros_(lin.bias)
        return lin

    return nn.Sequential(
        layer(inputs, HIDDEN, np.sqrt(2)), nn.Tanh(), layer(HIDDEN, HIDDEN, np.sqrt(2)), nn.Tanh(), layer(HIDDEN, outputs, out_gain)
    )


class ActorCritic(nn.Module):
    def __init__(self, obs_dim: int, action_type: str) -> None:
        super().__init__()
        self.action_type = action_type
        self.critic = _mlp(obs_dim, 1, 1.0)
        if action_type == "discrete":
            self.actor = _mlp(obs_dim, 7, 0.01)
        else:
            self.actor = _mlp(obs_dim, 3, 0.01)
            self.log_std = nn.Parameter(torch.full((3,), -0.5))

    def actor_critic(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.actor(obs), self.critic(obs).squeeze(-1)


def dist_of(agent: nn.Module, out: torch.Tensor) -> Categorical | Normal:
    """The action distribution of a policy head's output."""
    if agent.action_type == "discrete":
        return Categorical(logits=out)
    return Normal(out, agent.log_std.exp().expand_as(out))


def log_prob(agent: nn.Module, d: Categorical | Normal, a: torch.Tensor) -> torch.Tensor:
    lp = d.log_prob(a)
    return lp if agent.action_type == "discrete" else lp.sum(-1)


def entropy(agent: nn.Module, d: Categorical | Normal) -> torch.Tensor:
    e = d.entropy()
    return e if agent.action_type == "discrete" else e.sum(-1)


class NormInputs:
    """The MLP's input: the observation normalised by running statistics (updated as it goes)."""

    def __init__(self, obs_dim: int) -> None:
        self.norm = RunningNorm(obs_dim)

    def features(self, raw: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        if rows is None:
            self.norm.update(raw)
        return self.norm(raw)

    def remember(self, raw: np.ndarray) -> None:
        pass

    def restart(self, new: np.ndarray, raw: np.ndarray) -> None:
        pass

    def state(self) -> dict[str, Any]:
        return {"norm": self.norm.state()}

    def load(self, saved: dict[str, Any]) -> None:
        self.norm.load(saved["norm"])


class MemoryInputs:
    """The entity network's input: the observation with its change since the last step."""

    def __init__(self) -> None:
        self.memory = entity.FrameMemory()
        self.features, self.remember, self.restart = self.memory.features, self.memory.remember, self.memory.restart

    def state(self) -> dict[str, Any]:
        return {"memory": self.memory.prev}

    def load(self, saved: dict[str, Any]) -> None:
        self.memory.prev = saved["memory"]


class ReturnScale:
    """Rewards divided by the running standard deviation of the discounted return (as SB3's
    ``VecNormalize`` and CleanRL's ``NormalizeReward`` do): the value targets stay near unit
    scale whichever reward a cell uses."""

    def __init__(self, n: int, gamma: float) -> None:
        self.gamma = gamma
        self.ret = np.zeros(n, np.float64)
        self.stats = RunningNorm(1)

    def __call__(self, reward: np.ndarray, ended: np.ndarray) -> np.ndarray:
        self.ret = self.ret * self.gamma + reward
        self.stats.update(self.ret[:, None])
        self.ret[ended] = 0.0
        return (reward / np.sqrt(self.stats.var[0] + 1e-8)).astype(np.float32)

    def state(self) -> dict[str, Any]:
        return {"ret": self.ret, **self.stats.state()}

    def load(self, s: dict[str, Any]) -> None:
        self.ret = np.asarray(s["ret"])
        self.stats.load(s)


@dataclass
class Args(common.RunArgs):
    steps: int = 5_000_000
    out: str = "runs/ppo"
    action_type: str = "discrete"
    #: ``mlp`` (the observation row, normalised) or ``entity`` (socnav.train.entity: records,
    #: attention, memory and the robot's velocity).
    network: str = "mlp"
    #: Write the agent (float32) to ``snapshots/step-<N>.pt`` every this many steps, for choosing
    #: a checkpoint on validation episodes afterwards (``socnav.train.select``); none when unset.
    snapshot_every: int | None = None
    #: ``off`` or ``return`` (rewards over the running sd of the discounted return); default:
    #: ``return`` for the entity network, ``off`` for the MLP (as its shipped agents trained).
    reward_norm: str = "auto"
    rollout_steps: int = 128
    learning_rate: float = 3e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    epochs: int = 4
    minibatches: int = 4
    clip: float = 0.2
    entropy_coef: float = 0.01
    value_coef: float = 0.5
    max_grad_norm: float = 0.5

    def _counts(self) -> list[tuple[str, Any]]:
        snapshots = [("snapshot_every", self.snapshot_every)] if self.snapshot_every is not None else []
        return super()._counts() + snapshots + [
            ("rollout_steps", self.rollout_steps),
            ("epochs", self.epochs),
            ("minibatches", self.minibatches),
        ]

    def problems(self) -> list[str]:
        out = super().problems()
        if self.action_type not in ("discrete", "continuous"):
            out.append(f"--action-type must be 'discrete' or 'continuous', got {self.action_type!r}")
        if self.network not in ("mlp", "entity"):
            out.append(f"--network must be 'mlp' or 'entity', got {self.network!r}")
        if self.reward_norm not in ("auto", "off", "return"):
            out.append(f"--reward-norm must be 'auto', 'off' or 'return', got {self.reward_norm!r}")
        counts = (self.rollout_steps, self.num_envs, self.minibatches)
        if all(common._is_int(n) and n >= 1 for n in counts) and self.minibatches > self.rollout_steps * self.num_envs:
            out.append(
                f"--minibatches {self.minibatches} is more than a rollout's "
                f"{self.rollout_steps * self.num_envs} samples (--rollout-steps x --num-envs)"
            )
        out += common.fraction_problems(gamma=self.gamma, gae_lambda=self.gae_lambda)
        out += common.positive_problems(learning_rate=self.learning_rate, clip=self.clip, max_grad_norm=self.max_grad_norm)
        return out + [
            f"--{k.replace('_', '-')} must be a number >= 0, got {v!r}"
            for k, v in (("entropy_coef", self.entropy_coef), ("value_coef", self.value_coef))
            if not (isinstance(v, (int, float)) and 0.0 <= v < float("inf"))
        ]


def _make_agent(args: Args, env: Any, obs_dim: int) -> tuple[nn.Module, Any]:
    """The network and its input pipeline for ``args.network``."""
    if args.network == "entity":
        layout = entity.Layout.of(env.unwrapped._batch.layout())
        return entity.EntityActorCritic(layout, args.action_type), MemoryInputs()
    return ActorCritic(obs_dim, args.action_type), NormInputs(obs_dim)


def train(args: Args) -> dict[str, Any]:
    """Train (or resume) a run; returns its last logged scalars."""
    args.check()
    rng = common.seed_everything(args.seed, args.threads)
    overrides = entity.CONFIG_OVERRIDES if args.network == "entity" else None
    env = common.make_train_env(args.config, args.num_envs, args.seed, args.threads, args.action_type, overrides)
    holonomic = env.unwrapped._batch.holonomic
    run = common.RunDir(args.out, vars(args))
    n, T = env.num_envs, args.rollout_steps
    raw, _ = env.reset(seed=args.seed)
    raw = raw.copy()
    obs_dim = raw.shape[1]
    agent, inputs = _make_agent(args, env, obs_dim)
    in_dim = inputs.features(raw).shape[1]
    opt = torch.optim.Adam(agent.parameters(), lr=args.learning_rate, eps=1e-5)
    norm_reward = args.reward_norm == "return" or (args.reward_norm == "auto" and args.network == "entity")
    scale = ReturnScale(n, args.gamma) if norm_reward else None
    step, last_log = 0, 0
    clock = common.Clock()
    wall_before = 0.0
    saved = run.load()
    if saved is not None:
        agent.load_state_dict(saved["agent"])
        opt.load_state_dict(saved["optimizer"])
        inputs.load(saved["inputs"])
        if scale is not None:
            scale.load(saved["reward_scale"])
        wall_before = common.resume(saved, rng, env, clock)
        raw = saved["obs"]
        step, last_log = saved["step"], saved["last_log"]
    adim = () if args.action_type == "discrete" else (3,)
    b_obs = np.zeros((T, n, in_dim), np.float32)
    b_act = np.zeros((T, n, *adim), np.float32)
    b_logp = np.zeros((T, n), np.float32)
    b_rew = np.zeros((T, n), np.float32)
    b_term = np.zeros((T, n), np.float32)
    b_val = np.zeros((T, n), np.float32)
    b_trunc = np.zeros((T, n), np.float32)
    b_boot = np.zeros((T, n), np.float32)  # value of the truncated episodes' last observations
    stats = common.EpisodeStats()
    schedule = common.Schedule("ppo", args, step)
    start = time.perf_counter()
    scalars: dict[str, Any] = {}

    def payload() -> dict[str, Any]:
        return {
                "algo": "ppo",
                "network": args.network,
                "agent": agent.state_dict(),
                "optimizer": opt.state_dict(),
                "inputs": inputs.state(),
                "norm": inputs.state().get("norm"),
                "reward_scale": None if scale is None else scale.state(),
                "layout": env.unwrapped._batch.layout(),
                "rng": common.rng_states(rng),
                "envs": common.env_documents(env),
                "obs": raw,
                "step": step,
                "last_log": last_log,
                "clock": clock.parts,
                "wall": wall_before + time.perf_counter() - start,
                "obs_dim": obs_dim,
                "action_type": args.action_type,
                "args": vars(args),
            }

    def checkpoint() -> None:
        run.save(payload())

    def snapshot_due(before: int) -> bool:
        return args.snapshot_every is not None and step // args.snapshot_every > before // args.snapshot_every

    losses: dict[str, list[float]] = {"policy": [], "value": [], "entropy": []}
    while step < args.steps:
        frac = 1.0 - step / args.steps
        for g in opt.param_groups:
            g["lr"] = frac * args.learning_rate
        for t in range(T):
            clock.start()
            x = inputs.features(raw)
            with torch.no_grad():
                out, value = agent.actor_critic(torch.from_numpy(x))
                d = dist_of(agent, out)
                a = d.sample()
                b_logp[t] = log_prob(agent, d, a).numpy()
                b_val[t] = value.numpy()
            b_obs[t] = x
            b_act[t] = a.numpy()
            if args.action_type == "discrete":
                actions = a.numpy().astype(np.uint32)
            else:
                actions = np.clip(a.numpy(), -1.0, 1.0).astype(np.float32)
                if not holonomic:
                    actions[:, 1] = 0.0
            inputs.remember(raw)
            clock.stop("act")
            next_raw, reward, terminated, truncated, info = env.step(actions)
            clock.stop("env")
            ended = terminated | truncated
            b_rew[t] = reward if scale is None else scale(reward, ended)
            b_term[t] = terminated
            b_boot[t] = 0.0
            trunc = truncated & ~terminated
            b_trunc[t] = trunc
            if trunc.any() and "_final_obs" in info:
                with torch.no_grad():
                    last = inputs.features(info["final_obs"][trunc], rows=trunc)
                    b_boot[t, trunc] = agent.actor_critic(torch.from_numpy(last))[1].numpy()
            inputs.restart(ended, next_raw)
            stats.add(info)
            raw = next_raw.copy()
            step += n
        clock.start()
        with torch.no_grad():
            next_value = agent.actor_critic(torch.from_numpy(inputs.features(raw, rows=np.ones(n, bool))))[1].numpy()
        # GAE: an episode end (terminated or truncated) cuts the recursion; a truncated one
        # bootstraps from its last observation's value instead of the next episode's.
        adv = np.zeros((T, n), np.float32)
        gae = np.zeros(n, np.float32)
        for t in reversed(range(T)):
            ended = (b_term[t] > 0) | (b_trunc[t] > 0)
            v_next = next_value if t == T - 1 else b_val[t + 1]
            v_next = np.where(ended, b_boot[t], v_next)
            delta = b_rew[t] + args.gamma * v_next * (1.0 - b_term[t]) - b_val[t]
            gae = delta + args.gamma * args.gae_lambda * np.where(ended, 0.0, gae)
            adv[t] = gae
        ret = adv + b_val
        f_obs = torch.from_numpy(b_obs.reshape(T * n, in_dim))
        f_act = torch.from_numpy(b_act.reshape(T * n, *adim))
        if args.action_type == "discrete":
            f_act = f_act.long()
        f_logp, f_adv, f_ret = (torch.from_numpy(x.reshape(-1)) for x in (b_logp, adv, ret))
        size = T * n
        mb = size // args.minibatches
        for _ in range(args.epochs):
            order = torch.from_numpy(rng.permutation(size))
            for k in range(args.minibatches):
                idx = order[k * mb : (k + 1) * mb]
                out, value = agent.actor_critic(f_obs[idx])
                d = dist_of(agent, out)
                logp = log_prob(agent, d, f_act[idx])
                ratio = (logp - f_logp[idx]).exp()
                a_mb = f_adv[idx]
                a_mb = (a_mb - a_mb.mean()) / (a_mb.std() + 1e-8)
                pg = torch.max(-a_mb * ratio, -a_mb * ratio.clamp(1 - args.clip, 1 + args.clip)).mean()
                v_loss = 0.5 * ((value - f_ret[idx]) ** 2).mean()
                ent = entropy(agent, d).mean()
                loss = pg - args.entropy_coef * ent + args.value_coef * v_loss
                opt.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), args.max_grad_norm)
                opt.step()
                losses["policy"].append(float(pg.detach()))
                losses["value"].append(float(v_loss.detach()))
                losses["entropy"].append(float(ent.detach()))
        clock.stop("learn")
        if snapshot_due(step - n * T):
            from socnav.train import agent_file

            run.snapshot(step, agent_file(payload(), "float32"))
        if step - last_log >= args.log_every or step >= args.steps:
            last_log = step
            wall = wall_before + time.perf_counter() - start
            scalars = {
                **common.progress(env, step, wall, stats, clock),
                "loss_policy": float(np.mean(losses["policy"])),
                "loss_value": float(np.mean(losses["value"])),
                "entropy": float(np.mean(losses["entropy"])),
            }
            for v in losses.values():
                v.clear()
            run.log(step, scalars)
            common.report("ppo", args, step, scalars)
        if schedule.save_due():
            checkpoint()
        if schedule.chunk_over(step):
            break
    checkpoint()
    run.close()
    return scalars


def policy_state(saved: dict[str, Any]) -> dict[str, Any]:
    """The shippable agent of a checkpoint (see ``socnav.train.export``)."""
    weights = saved["agent"]
    if saved.get("network", "mlp") == "entity":
        policy = {k: v for k, v in weights.items() if k.startswith(("encoder.", "pi.")) or k == "log_std"}
        return {
            "kind": "ppo",
            "network": "entity",
            "layout": saved["layout"],
            "config_overrides": entity.CONFIG_OVERRIDES,
            "obs_dim": saved["obs_dim"],
            "action_type": saved["action_type"],
            "state_dict": policy,
        }
    actor = {k[len("actor.") :]: v for k, v in weights.items() if k.startswith("actor.")}
    if "log_std" in weights:
        actor["log_std"] = weights["log_std"]
    return {
        "kind": "ppo",
        "obs_dim": saved["obs_dim"],
        "action_type": saved["action_type"],
        "state_dict": actor,
        "obs_mean": torch.as_tensor(saved["norm"]["mean"], dtype=torch.float32),
        "obs_var": torch.as_tensor(saved["norm"]["var"], dtype=torch.float32),
    }
