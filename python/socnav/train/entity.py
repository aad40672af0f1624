"""The entity agent: a network that reads a batch's observation as a set of entities.

Every record of the observation (humans, laptops, tables, plants, wall segments; 14 floats
each, SocNavGym's layout) goes through one shared MLP; an attention pooling whose query is the
robot-and-goal embedding, beside a masked max pooling, reduces them to a fixed size whatever the
counts, so the network is permutation-invariant over the records of a type and takes any config
(absent records, all zeros, are masked). The input carries a short memory: each record and the
goal together with their change since the previous step (``FrameMemory``), which with the
robot's own velocity (``observation.robot_velocity``) gives the people's motion. SARL (Chen et
al. 2019) and DSRNN (Liu et al. 2021) read a crowd the same way.

The features are scaled by fixed constants (metres / 5, angles / pi) rather than running
statistics, so that an agent's input does not depend on what it saw in training.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
import torch
from torch import nn

#: What an entity agent needs of the environment's config: the robot's command in its record.
CONFIG_OVERRIDES: dict[str, Any] = {"observation": {"robot_velocity": True}}
#: Floats of one entity record (SocNavGym's layout, docs/spec.md 5.2).
RECORD = 14
#: Metres to network units.
LENGTH_SCALE = 5.0
#: Per-entity features: one-hot type (6), x, y, sin, cos, radius, relative speed, relative
#: angular speed, gaze, distance, gap to the robot's disc, change of x and y since the last step.
ENTITY_FEATURES = 18
#: Robot features: goal x, y, distance, direction (2), robot radius, command (3), change of the
#: goal's x and y since the last step.
ROBOT_FEATURES = 11
EMBED = 64
HEADS = 4


@dataclass(frozen=True)
class Layout:
    """Where the robot block and the entity records lie in a flat observation row."""

    dim: int
    robot: int
    entities: int  # offset of the first record
    count: int  # records of all types together (capacity)

    @classmethod
    def of(cls, layout: Mapping[str, Any]) -> "Layout":
        """From ``Batch.layout()``; the entity blocks must follow the robot block back to back."""
        if layout.get("padded") is None or layout["record"] != RECORD:
            raise ValueError(f"not a socnav observation layout: {dict(layout)!r}")
        blocks = sorted(layout["entities"].values())
        offset = layout["robot"]
        for start, n in blocks:
            if start != offset:
                raise ValueError(f"entity blocks are not contiguous in the observation: {dict(layout['entities'])!r}")
            offset += n * RECORD
        if offset != layout["dim"]:
            raise ValueError(f"observation of {layout['dim']} floats, blocks end at {offset}")
        if layout["robot"] != 12:
            raise ValueError(
                f"the entity agent needs the robot's velocity in its record (observation.robot_velocity = true): "
                f"robot block of {layout['robot']} floats, expected 12"
            )
        return cls(dim=int(layout["dim"]), robot=int(layout["robot"]), entities=int(layout["robot"]),
                   count=(int(layout["dim"]) - int(layout["robot"])) // RECORD)


class FrameMemory:
    """The previous observation of every environment, for the input's change-since-last-step
    half. The loop: ``x = memory.features(obs)``, act, ``memory.remember(obs)``, step; then
    ``memory.restart(new, next_obs)`` for the environments whose episode starts anew (their
    first observation has no change)."""

    def __init__(self) -> None:
        self.prev: np.ndarray | None = None

    def features(self, obs: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """``(n, 2 * dim)``: ``obs`` and its change since the remembered observation (of the
        environments ``rows``, a mask or indices, when given: final observations of ended
        episodes)."""
        obs = np.asarray(obs, dtype=np.float32)
        if rows is None and (self.prev is None or self.prev.shape != obs.shape):
            self.prev = obs.copy()
        assert self.prev is not None
        prev = self.prev if rows is None else self.prev[rows]
        return np.concatenate([obs, obs - prev], axis=1)

    def remember(self, obs: np.ndarray) -> None:
        self.prev = np.array(obs, dtype=np.float32)

    def restart(self, new: np.ndarray, obs: np.ndarray) -> None:
        """Episodes that start anew where ``new``: their first observation is its own past."""
        if self.prev is not None and new.any():
            self.prev[new] = obs[new]


def _linear(i: int, o: int, gain: float = float(np.sqrt(2))) -> nn.Linear:
    lin = nn.Linear(i, o)
    nn.init.orthogonal_(lin.weight, gain)
    nn.init.zeros_(lin.bias)
    return lin


class EntityEncoder(nn.Module):
    """Features of a memory row (``FrameMemory``) to one embedding of ``3 * EMBED`` floats: the
    robot-and-goal embedding, the attention pooling of the entities (query: the robot), their
    masked max pooling."""

    def __init__(self, layout: Layout) -> None:
        super().__init__()
        self.layout = layout
        self.entity = nn.Sequential(_linear(ENTITY_FEATURES, EMBED), nn.ReLU(), _linear(EMBED, EMBED), nn.ReLU())
        self.robot = nn.Sequential(_linear(ROBOT_FEATURES, EMBED), nn.ReLU(), _linear(EMBED, EMBED), nn.ReLU())
        self.query = _linear(EMBED, EMBED, 1.0)
        self.key = _linear(EMBED, EMBED, 1.0)
        self.value = _linear(EMBED, EMBED, 1.0)

    out_dim = 3 * EMBED

    def split(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Robot features ``(B, ROBOT_FEATURES)``, entity features ``(B, N, ENTITY_FEATURES)``
        and the mask of present records ``(B, N)``."""
        L = self.layout
        obs, delta = x[:, : L.dim], x[:, L.dim :]
        robot = obs[:, : L.robot]
        rec = obs[:, L.entities :].reshape(-1, L.count, RECORD)
        rec_delta = delta[:, L.entities :].reshape(-1, L.count, RECORD)
        present = rec[:, :, :6].abs().sum(-1) > 0
        goal = robot[:, 6:8] / LENGTH_SCALE
        goal_dist = goal.norm(dim=-1, keepdim=True)
        goal_dir = robot[:, 6:8] / robot[:, 6:8].norm(dim=-1, keepdim=True).clamp_min(1e-6)
        # The goal's change since the last step stays in metres (at most ~0.2 m a step); the
        # division and product below cancel but are kept, as the shipped agents were trained so.
        goal_change = delta[:, 6:8] / LENGTH_SCALE * 5.0
        robot_f = torch.cat([goal, goal_dist, goal_dir, robot[:, 8:9], robot[:, 9:12], goal_change], dim=-1)
        xy = rec[:, :, 6:8]
        dist = xy.norm(dim=-1, keepdim=True)
        gap = dist - rec[:, :, 10:11] - robot[:, None, 8:9]
        entity_f = torch.cat(
            [
                rec[:, :, :6],
                xy / LENGTH_SCALE,
                rec[:, :, 8:10],
                rec[:, :, 10:11],
                rec[:, :, 11:12].clamp(-5.0, 5.0),
                (rec[:, :, 12:13] / np.pi).clamp(-3.0, 3.0),
                rec[:, :, 13:14],
                dist / LENGTH_SCALE,
                gap.clamp(-1.0, 5.0),
                rec_delta[:, :, 6:8].clamp(-3.0, 3.0),
            ],
            dim=-1,
        )
        return robot_f, entity_f * present[..., None], present

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        robot_f, entity_f, present = self.split(x)
        r = self.robot(robot_f)
        e = self.entity(entity_f)  # (B, N, EMBED)
        B, N, _ = e.shape
        d = EMBED // HEADS
        q = self.query(r).view(B, 1, HEADS, d).transpose(1, 2)  # (B, H, 1, d)
        k = self.key(e).view(B, N, HEADS, d).transpose(1, 2)  # (B, H, N, d)
        v = self.value(e).view(B, N, HEADS, d).transpose(1, 2)
        scores = (q @ k.transpose(-1, -2)) / np.sqrt(d)  # (B, H, 1, N)
        scores = scores.masked_fill(~present[:, None, None, :], -1e9)
        weights = torch.softmax(scores, dim=-1) * present.any(-1)[:, None, None, None]
        pooled = (weights @ v).reshape(B, EMBED)
        maxed = e.masked_fill(~present[..., None], 0.0).max(dim=1).values if N else torch.zeros_like(r)
        return torch.cat([r, pooled, maxed], dim=-1)


def _head(outputs: int, gain: float) -> nn.Sequential:
    return nn.Sequential(
        _linear(EntityEncoder.out_dim, 128), nn.ReLU(), _linear(128, 128), nn.ReLU(), _linear(128, outputs, gain)
    )


class EntityPolicy(nn.Module):
    """Encoder and policy head: what ships (``socnav.train.export``)."""

    def __init__(self, layout: Layout, action_type: str) -> None:
        super().__init__()
        self.action_type = action_type
        self.encoder = EntityEncoder(layout)
        self.pi = _head(7 if action_type == "discrete" else 3, 0.01)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.pi(self.encoder(x))


class EntityActorCritic(EntityPolicy):
    """The policy with a value head on the same encoder (PPO's shared trunk) and, for
    continuous actions, a learned state-independent log standard deviation."""

    def __init__(self, layout: Layout, action_type: str) -> None:
        super().__init__(layout, action_type)
        self.v = _head(1, 1.0)
        if action_type == "continuous":
            self.log_std = nn.Parameter(torch.full((3,), -0.5))

    def actor_critic(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        z = self.encoder(x)
        return self.pi(z), self.v(z).squeeze(-1)
