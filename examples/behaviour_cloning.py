#!/usr/bin/env python3
"""Behaviour cloning from an expert dataset: collect the ORCA-driven robot's episodes as a Minari
dataset, fit an MLP to its actions, and evaluate the clone with the paper's metrics beside the
expert, on test episodes neither has seen.

    python examples/behaviour_cloning.py --config exp1 --episodes 400 --epochs 20

Needs torch and the ``datasets`` extra (``pip install './python[train,datasets]'``). The dataset
goes to a temporary Minari root unless ``--root`` names one (it is then kept, as
``socnav/<config>-orca-expert-v0``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time

import numpy as np

try:
    import minari
    import torch
    from torch import nn
except ImportError as e:
    sys.exit(f"this example needs torch and minari: pip install './python[train,datasets]' ({e})")

import socnav
from socnav.datasets import collect


class Clone:
    """The fitted MLP as a batched socnav policy (flat observations, continuous actions)."""

    obs_mode = "flat"
    action_type = "continuous"
    name = "clone"

    def __init__(self, net: nn.Module, mean: np.ndarray, std: np.ndarray) -> None:
        self.net, self.mean, self.std = net, mean, std

    def __call__(self, obs: np.ndarray, env: object) -> np.ndarray:
        with torch.no_grad():
            x = torch.from_numpy((obs - self.mean) / self.std)
            actions = self.net(x).clamp(-1.0, 1.0).numpy()
        if not getattr(env, "unwrapped", env)._batch.holonomic:  # type: ignore[attr-defined]
            actions[:, 1] = 0.0  # a differential-drive robot has no lateral action
        return actions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default="exp1")
    parser.add_argument("--episodes", type=int, default=400, help="expert episodes to collect (default 400)")
    parser.add_argument("--epochs", type=int, default=20)
    parser.add_argument("--test-episodes", type=int, default=200)
    parser.add_argument("--root", help="Minari root to keep the dataset in (default: a temporary one)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    torch.manual_seed(args.seed)
    torch.set_num_threads(1)

    with tempfile.TemporaryDirectory() as tmp:
        root = args.root or tmp
        dataset_id = f"socnav/{args.config}-orca-expert-v0"
        print(collect("orca", args.config, episodes=args.episodes, dataset_id=dataset_id, root=root, seed=args.seed,
                      progress=False))
        dataset = minari.load_dataset(dataset_id)
        # Every step's observation (not the final one) with the action the expert took there.
        obs = np.concatenate([ep.observations[:-1] for ep in dataset.iterate_episodes()]).astype(np.float32)
        act = np.concatenate([ep.actions for ep in dataset.iterate_episodes()]).astype(np.float32)
    print(f"{len(obs)} (observation, action) pairs from {dataset.total_episodes} episodes")

    mean, std = obs.mean(0), obs.std(0) + 1e-6
    x, y = torch.from_numpy((obs - mean) / std), torch.from_numpy(act)
    net = nn.Sequential(nn.Linear(x.shape[1], 256), nn.Tanh(), nn.Linear(256, 256), nn.Tanh(), nn.Linear(256, 3))
    opt = torch.optim.Adam(net.parameters(), lr=1e-3)
    start = time.perf_counter()
    for epoch in range(args.epochs):
        order = torch.randperm(len(x))
        total = 0.0
        for k in range(0, len(x), 256):
            idx = order[k : k + 256]
            loss = ((net(x[idx]) - y[idx]) ** 2).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(idx)
        if epoch % 5 == 4 or epoch == args.epochs - 1:
            print(f"epoch {epoch + 1}: mean squared action error {total / len(x):.4f}")
    print(f"fitted in {time.perf_counter() - start:.1f} s")

    # Test episodes far from the training seeds.
    test_seed = 1_000_000
    for name, policy in (("expert (orca)", "orca"), ("clone", Clone(net.eval(), mean, std))):
        result = socnav.evaluate(policy, args.config, episodes=args.test_episodes, seed=test_seed)
        table = result.table(["success", "collision", "timeout", "DISCOMFORT_DSRNN", "PATH_LENGTH"])
        print(f"{name:>14}: " + ", ".join(f"{k} {v['mean']:.3f}" for k, v in table.items()))


if __name__ == "__main__":
    main()
