#!/usr/bin/env python3
"""A batched rollout whose observations reach torch without a copy: a tiny randomly initialised
MLP policy acts on every environment at once.

    python examples/torch_rollout.py --config exp2 --envs 1024 --steps 500

``torch.from_numpy`` over the vector environment's observation array makes a tensor that shares
the Rust batch's buffer: it is made once, and every ``step`` rewrites its contents in place. The
policy therefore reads each step's observations with no transfer at all (on the CPU; a GPU policy
would copy them with ``obs.to(device)``).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

try:
    import torch
    from torch import nn
except ImportError:
    sys.exit("this example needs torch: pip install torch (see https://pytorch.org for the CPU-only wheels)")

import socnav
from socnav.metrics import EpisodeLog


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default="exp1", help="shipped config name or TOML path (default exp1)")
    parser.add_argument("--envs", type=int, default=256, help="environments in the batch (default 256)")
    parser.add_argument("--steps", type=int, default=1000, help="steps of the whole batch (default 1000)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--hidden", type=int, default=64, help="width of the MLP's hidden layers (default 64)")
    parser.add_argument("--torch-threads", type=int, default=1, help="torch's CPU threads (default 1, see below)")
    parser.add_argument("--threads", type=int, default=None, help="the batch's CPU threads (default: all cores)")
    args = parser.parse_args()

    torch.manual_seed(args.seed)
    # The batch's worker threads and torch's OpenMP threads take turns on the same cores, and
    # OpenMP workers busy-wait after each operation: with both at all cores, every small forward
    # pass was ~20x slower on a 2-core machine (10 ms instead of 0.5 ms). One torch thread (or
    # OMP_WAIT_POLICY=PASSIVE) avoids it; a small MLP gains little from more threads anyway.
    torch.set_num_threads(args.torch_threads)
    env = socnav.make_vec(args.config, num_envs=args.envs, seed=args.seed, obs_mode="flat", threads=args.threads)
    obs, _ = env.reset(seed=args.seed)
    obs_t = torch.from_numpy(obs)  # shares memory with the batch: no copy, now or later
    dim = obs.shape[1]
    policy = nn.Sequential(
        nn.Linear(dim, args.hidden), nn.Tanh(), nn.Linear(args.hidden, args.hidden), nn.Tanh(), nn.Linear(args.hidden, 3)
    )
    # tanh keeps the actions in [-1, 1]; the mask zeroes the lateral one of a diff-drive robot.
    high = torch.from_numpy(env.single_action_space.high.copy())
    log = EpisodeLog()
    policy_time = step_time = 0.0
    with torch.inference_mode():
        for _ in range(args.steps):
            t0 = time.perf_counter()
            actions = (torch.tanh(policy(obs_t)) * high).numpy()
            t1 = time.perf_counter()
            obs, _, _, _, info = env.step(actions)
            t2 = time.perf_counter()
            policy_time += t1 - t0
            step_time += t2 - t1
            log.add(info)
    assert obs_t.data_ptr() == obs.__array_interface__["data"][0], "the tensor is a view of the batch"

    env_steps = args.envs * args.steps
    print(f"torch rollout: {args.config} | {args.envs} envs x {args.steps} steps | obs dim {dim} | MLP {args.hidden}x2")
    print(log.summary())
    print(
        f"throughput: {env_steps / step_time:.0f} env-steps/s stepping, "
        f"{env_steps / (step_time + policy_time):.0f} env-steps/s with the policy "
        f"({policy_time:.2f} s policy, {step_time:.2f} s stepping; torch threads {torch.get_num_threads()})"
    )


if __name__ == "__main__":
    main()
