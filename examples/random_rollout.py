#!/usr/bin/env python3
"""A batched rollout with uniform random actions through ``socnav.make_vec``: prints the paper's
metric table over the finished episodes (``socnav.metrics``) and the throughput.

    python examples/random_rollout.py --config exp2 --envs 512 --steps 1000

The throughput counts the stepping alone (``env.step``), like ``socnav run``; the line below it
adds the time spent drawing actions and collecting episodes in Python.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import socnav
from socnav.metrics import EpisodeLog


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default="exp1", help="shipped config name or TOML path (default exp1)")
    parser.add_argument("--envs", type=int, default=256, help="environments in the batch (default 256)")
    parser.add_argument("--steps", type=int, default=1000, help="steps of the whole batch (default 1000)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--discrete", action="store_true", help="the 7 discrete actions instead of Box(3)")
    parser.add_argument("--threads", type=int, default=None, help="CPU threads (default: all cores)")
    parser.add_argument("--csv", default=None, help="also write one row per finished episode to this CSV file")
    args = parser.parse_args()

    env = socnav.make_vec(
        args.config,
        num_envs=args.envs,
        seed=args.seed,
        action_type="discrete" if args.discrete else "continuous",
        threads=args.threads,
    )
    rng = np.random.default_rng(args.seed)
    space = env.single_action_space
    log = EpisodeLog()
    env.reset(seed=args.seed)
    stepping = 0.0
    start = time.perf_counter()
    for _ in range(args.steps):
        if args.discrete:
            actions = rng.integers(0, space.n, args.envs)
        else:
            # Uniform in the Box; its lateral bound is [0, 0] for a differential-drive robot.
            actions = rng.uniform(space.low, space.high, (args.envs, 3)).astype(np.float32)
        t = time.perf_counter()
        _, _, _, _, info = env.step(actions)
        stepping += time.perf_counter() - t
        log.add(info)  # copies the finished episodes' rows; the buffers change next step
    total = time.perf_counter() - start

    env_steps = args.envs * args.steps
    print(
        f"random rollout: {args.config} | {args.envs} envs x {args.steps} steps | seed {args.seed} | "
        f"{env.backend} backend | {'discrete' if args.discrete else 'continuous'} actions"
    )
    print(log.summary())
    print(f"throughput: {env_steps / stepping:.0f} env-steps/s ({env_steps} env-steps in {stepping:.2f} s of stepping)")
    print(f"with the Python loop (actions, episode log): {env_steps / total:.0f} env-steps/s")
    if args.csv:
        np.savetxt(args.csv, log.rows(), fmt="%.9g", delimiter=",", header=",".join(log.keys), comments="")
        print(f"wrote {len(log)} episodes to {args.csv}")


if __name__ == "__main__":
    main()
