"""The overhead of each trainer's entry point over the bare batch: env-steps/s through
``socnav.make_vec`` (gymnasium), ``socnav.sb3``, ``socnav.pufferlib``, ``socnav.torchrl`` and ``socnav.jax``
(copies and views), each against the extension's bare ``Batch.step_discrete`` on a batch of the
same config, size and threads.

Blocks of 10 steps of the adapter alternate with blocks of 10 bare steps in the same process
and the same seconds, so a machine's slow spells move both; the overhead of a round is
1 - adapter / bare, and the median over rounds is printed. Discrete action 4 (forward) for
every environment; ended episodes restart as each adapter restarts them.

    python benches/trainers.py --config exp2 --envs 1024 --threads 1 --rounds 7

Needs the package; each adapter its extra (those not installed are left out, and say so).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from typing import Any, Callable

import numpy as np

import socnav
from socnav import _batch

BLOCK = 10


def bare_stepper(config: str, envs: int, threads: int) -> Callable[[], None]:
    batch = _batch.build_batch(config, envs, 0, "same_step", threads)
    batch.set_step_outputs(info=False, interactions=False, events=False)
    batch.reset(None)
    actions = np.full(envs, 4, dtype=np.uint32)
    return lambda: batch.step_discrete(actions)


def adapters(config: str, envs: int, threads: int) -> dict[str, Callable[[], Any]]:
    """Each installed adapter's step, with the restart its users' loops make."""
    out: dict[str, Callable[[], Any]] = {}
    act = np.full(envs, 4, dtype=np.uint32)
    gym_env = socnav.make_vec(config, num_envs=envs, seed=0, obs_mode="flat", action_type="discrete",
                              autoreset_mode="same_step", threads=threads, step_info=False)
    gym_env.reset(seed=0)
    out["gymnasium (make_vec)"] = lambda: gym_env.step(act)
    try:
        from socnav.sb3 import make_sb3

        sb3 = make_sb3(config, envs, seed=0, obs_mode="flat", action_type="discrete", threads=threads)
        sb3.reset()
        out["stable-baselines3"] = lambda: sb3.step(act)
    except ImportError as e:
        print(f"left out: stable-baselines3 ({e})")
    try:
        import socnav.pufferlib as sp

        puffer = sp.make(config, num_envs=envs, seed=0, threads=threads)
        puffer.reset(0)
        act32 = act.astype(np.int32)
        out["pufferlib"] = lambda: puffer.step(act32)
    except ImportError as e:
        print(f"left out: pufferlib ({e})")
    try:
        import torch

        import socnav.torchrl as st

        trl = st.make_env(config, num_envs=envs, seed=0, threads=threads)
        state = {"td": trl.reset()}
        action = torch.full((envs,), 4, dtype=torch.int64)

        def trl_step() -> None:
            td = state["td"]
            td["action"] = action
            _, state["td"] = trl.step_and_maybe_reset(td)

        out["torchrl"] = trl_step
    except ImportError as e:
        print(f"left out: torchrl ({e})")
    try:
        import jax

        import socnav.jax as sj

        for view in (False, True):
            env = sj.wrap(socnav.make_vec(config, num_envs=envs, seed=0, obs_mode="flat", action_type="discrete",
                                          autoreset_mode="same_step", threads=threads, step_info=False), view=view)
            env.reset(seed=0)
            out[f"jax ({'view' if view else 'copy'})"] = (lambda e: lambda: jax.block_until_ready(e.step(act)[0]))(env)
    except ImportError as e:
        print(f"left out: jax ({e})")
    return out


def measure(adapter: Callable[[], Any], bare: Callable[[], None], envs: int, seconds: float) -> tuple[float, float]:
    """Env-steps/s of the adapter and of the bare batch, alternating blocks for ``seconds``."""
    spent = {"adapter": 0.0, "bare": 0.0}
    steps = 0
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        for name, fn in (("adapter", adapter), ("bare", bare)):
            start = time.perf_counter()
            for _ in range(BLOCK):
                fn()
            spent[name] += time.perf_counter() - start
        steps += BLOCK * envs
    return steps / spent["adapter"], steps / spent["bare"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default="exp2")
    parser.add_argument("--envs", type=int, default=1024)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--seconds", type=float, default=2.0, help="per round and adapter")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    bare = bare_stepper(args.config, args.envs, args.threads)
    for _ in range(20):
        bare()
    rows = []
    for name, step in adapters(args.config, args.envs, args.threads).items():
        for _ in range(20):
            step()
        rounds = [measure(step, bare, args.envs, args.seconds) for _ in range(args.rounds)]
        rate = statistics.median(a for a, _ in rounds)
        overhead = statistics.median(1.0 - a / b for a, b in rounds)
        rows.append({"adapter": name, "env_steps_per_s": rate, "bare_env_steps_per_s": statistics.median(b for _, b in rounds),
                     "overhead": overhead})
        print(f"{name:22s} {rate:12,.0f} env-steps/s   overhead {100 * overhead:5.1f} % of the bare batch")
    if args.json:
        print(json.dumps({"config": args.config, "envs": args.envs, "threads": args.threads, "rows": rows}))


if __name__ == "__main__":
    main()
