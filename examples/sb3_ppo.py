#!/usr/bin/env python3
"""Train Stable-Baselines3 PPO on a socnav batch, then evaluate the policy deterministically (one
episode per environment) and print the paper's metric table.

    python examples/sb3_ppo.py --config exp1 --envs 16 --total-timesteps 20000

The defaults make a short demonstration (well under a minute on two cores), not a trained
policy: the paper trains for millions of steps (docs/spec.md 9.3).
"""

from __future__ import annotations

import argparse
import sys
import time

try:
    import torch
    from stable_baselines3 import PPO
except ImportError:
    sys.exit("this example needs Stable-Baselines3 and torch: pip install stable-baselines3")

from socnav.sb3 import evaluate, make_sb3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default="exp1", help="shipped config name or TOML path (default exp1)")
    parser.add_argument("--envs", type=int, default=16, help="environments in the training batch (default 16)")
    parser.add_argument("--total-timesteps", type=int, default=32768, help="env steps to train for (default 32768)")
    parser.add_argument("--n-steps", type=int, default=128, help="PPO rollout length per environment (default 128)")
    parser.add_argument("--eval-envs", type=int, default=32, help="environments evaluated, one episode each (default 32)")
    parser.add_argument("--discrete", action="store_true", help="the 7 discrete actions instead of Box(3)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--torch-threads", type=int, default=1, help="torch's CPU threads (default 1)")
    parser.add_argument("--verbose", type=int, default=1, help="SB3's verbosity: 1 prints the training log")
    args = parser.parse_args()

    # torch's busy-waiting OpenMP threads and the batch's threads share the cores: one torch
    # thread keeps the many small forward passes of the rollouts fast (see torch_rollout.py).
    torch.set_num_threads(args.torch_threads)
    action_type = "discrete" if args.discrete else "continuous"
    env = make_sb3(args.config, num_envs=args.envs, seed=args.seed, action_type=action_type)
    model = PPO(
        "MultiInputPolicy",
        env,
        n_steps=args.n_steps,
        batch_size=256,
        n_epochs=4,
        seed=args.seed,
        device="cpu",
        verbose=args.verbose,
    )
    start = time.perf_counter()
    model.learn(total_timesteps=args.total_timesteps)
    train_s = time.perf_counter() - start

    # A fresh batch with another seed: evaluation episodes the training never saw.
    eval_env = make_sb3(args.config, num_envs=args.eval_envs, seed=args.seed + 1, action_type=action_type)
    start = time.perf_counter()
    log = evaluate(model, eval_env, episodes_per_env=1, deterministic=True)
    eval_s = time.perf_counter() - start

    print(
        f"PPO on {args.config}: {model.num_timesteps} env steps in {train_s:.1f} s "
        f"({model.num_timesteps / train_s:.0f} env-steps/s with training)"
    )
    print(f"deterministic evaluation, one episode in each of {args.eval_envs} environments ({eval_s:.1f} s):")
    print(log.summary())


if __name__ == "__main__":
    main()
