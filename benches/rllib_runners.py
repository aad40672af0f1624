"""Env-steps/s through Ray RLlib's env runners, and where RLlib's own per-step time goes.

Three measurements on one machine:

1. One env runner in this process (no Ray actors), sampling ``--steps`` steps of a socnav batch of
   ``--envs`` environments with RLlib's default PPO module, against the bare ``env.step`` loop of
   the same batch: with the adapter's empty info (``info_keys=[]``, its default) and with every
   metric (``info_keys=None``), which RLlib turns into one dict per environment per step.
   RLlib's timers split a sampled step into the environment's step and the module's forward pass;
   the rest is its per-step bookkeeping (episodes, connectors).
2. ``--runners`` remote env runners (1 and 2 by default) sampling at once through Ray, env-steps/s
   of the whole group.

    python benches/rllib_runners.py --config exp1 --envs 256 --steps 20000

Needs the ``rllib`` extra. On a 2-core machine two runners share the cores with the driver, so the
second runner cannot double the figure; the same commands on a machine with more cores (or a
cluster: docs/scaling.md) show the scaling.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

os.environ.setdefault("RAY_AUTH_MODE", "disabled")  # a local, single-process Ray for the benchmark

import ray
from ray.rllib.env.single_agent_env_runner import SingleAgentEnvRunner

import socnav
import socnav.rllib


def bare(config: str, envs: int, steps: int) -> float:
    env = socnav.make_vec(config, envs, seed=0, obs_mode="flat", action_type="discrete", threads=1)
    env.reset(seed=0)
    actions = np.full(envs, 2)
    for _ in range(20):
        env.step(actions)
    start = time.perf_counter()
    for _ in range(max(1, steps // envs)):
        env.step(actions)
    return max(1, steps // envs) * envs / (time.perf_counter() - start)


def local_runner(config: str, envs: int, steps: int, info_keys) -> dict[str, float]:
    cfg = socnav.rllib.ppo_config(config, num_env_runners=0, num_envs_per_env_runner=envs, info_keys=info_keys)
    runner = SingleAgentEnvRunner(config=cfg)
    runner.sample(num_timesteps=2 * envs)
    start = time.perf_counter()
    sampled = sum(len(e) for e in runner.sample(num_timesteps=steps))
    seconds = time.perf_counter() - start
    # RLlib's timers: seconds per vector step (smoothed), the environment's and the module's.
    timers = {k: float(runner.metrics.peek(k)) for k in ("env_step_timer", "rlmodule_inference_timer")}
    runner.stop()
    vector_steps = sampled / envs
    return {
        "env_steps_per_s": sampled / seconds,
        "seconds_per_vector_step": seconds / vector_steps,
        **{f"{k}_s": v for k, v in timers.items()},
    }


def group(config: str, envs: int, steps: int, runners: int) -> float:
    cfg = socnav.rllib.ppo_config(config, num_env_runners=runners, num_envs_per_env_runner=envs)
    algo = cfg.build_algo()
    try:
        each = max(1, steps // runners)
        algo.env_runner_group.foreach_env_runner(lambda r: r.sample(num_timesteps=2 * envs), local_env_runner=False)
        start = time.perf_counter()
        counts = algo.env_runner_group.foreach_env_runner(
            lambda r: sum(len(e) for e in r.sample(num_timesteps=each)), local_env_runner=False
        )
        return sum(counts) / (time.perf_counter() - start)
    finally:
        algo.stop()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="exp1")
    ap.add_argument("--envs", type=int, default=256, help="environments per runner")
    ap.add_argument("--steps", type=int, default=20000, help="environment steps per measurement")
    ap.add_argument("--runners", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    ray.init(include_dashboard=False, log_to_driver=False)
    result = {
        "config": args.config,
        "envs_per_runner": args.envs,
        "bare_env_step": round(bare(args.config, args.envs, args.steps)),
        "runner_no_info": local_runner(args.config, args.envs, args.steps, []),
        "runner_all_info": local_runner(args.config, args.envs, args.steps, None),
        "remote_runners": {n: round(group(args.config, args.envs, args.steps, n)) for n in args.runners},
    }
    ray.shutdown()
    print(json.dumps(result, indent=1, default=float))


if __name__ == "__main__":
    main()
