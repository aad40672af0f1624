"""Overlap of simulation and inference with ``send``/``recv`` (double buffering), against ``step``.

A rollout with a torch policy: the paper's Dueling DQN network (5 linear layers of 512, 256, 128
and 64 units, LeakyReLU) picks greedy discrete actions from flat observations. Four loops over the
same ``--envs`` environments, each for ``--seconds``:

- ``policy``: the forward pass alone, on the whole batch's observations;
- ``simulate``: ``env.step`` alone, with fixed actions;
- ``step``: forward pass, then ``env.step``, one after the other (what a plain rollout does);
- ``send/recv``: the batch split in two environments of half the size; while one half steps
  (``send``: on the batch's threads, the GIL released), the policy computes the other half's
  actions, then ``recv`` collects the first.

Overlap can at best bring a step of the whole batch from policy + simulate down to their maximum
(the overlap bound printed). With ``--sim-threads 1 --torch-threads 1`` on a 2-core machine each
side gets a core of its own.

    python benches/send_recv.py --config exp1 --envs 1024 --seconds 10

Needs the package and torch (the ``train`` extra).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import torch

import socnav
from socnav.train.dqn import DuelingQ


def timed(loop, seconds: float) -> float:
    """Calls of ``loop`` per second, after two warm-up calls."""
    loop()
    loop()
    calls, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        loop()
        calls += 1
    return calls / (time.perf_counter() - start)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="exp1")
    ap.add_argument("--envs", type=int, default=1024)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--sim-threads", type=int, default=1, help="threads of each batch")
    ap.add_argument("--torch-threads", type=int, default=1)
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args()
    torch.set_num_threads(args.torch_threads)
    n, half = args.envs, args.envs // 2

    def make(num: int, seed: int):
        env = socnav.make_vec(
            args.config, num, seed=seed, obs_mode="flat", action_type="discrete", threads=args.sim_threads
        )
        obs, _ = env.reset(seed=seed)
        return env, obs

    whole, obs = make(n, 0)
    net = DuelingQ(obs.shape[1], 7).eval()

    @torch.no_grad()
    def act(o: np.ndarray) -> np.ndarray:
        return net(torch.from_numpy(o)).argmax(dim=1).numpy()

    fixed = np.full(n, 2, dtype=np.int64)
    state = {"obs": obs}

    def plain() -> None:
        state["obs"] = whole.step(act(state["obs"]))[0]

    halves = [make(half, 0), make(n - half, half)]
    envs = [h[0] for h in halves]
    pending = [h[1] for h in halves]
    envs[0].send(act(pending[0]))

    def overlapped() -> None:
        # Half 0 is in flight: compute half 1's actions meanwhile, then swap roles.
        for k in (1, 0):
            actions = act(pending[k])
            pending[1 - k] = envs[1 - k].recv()[0]
            envs[k].send(actions)

    rates = {
        "policy": timed(lambda: act(state["obs"]), args.seconds) * n,
        "simulate": timed(lambda: whole.step(fixed), args.seconds) * n,
        "step": timed(plain, args.seconds) * n,
        "send/recv": timed(overlapped, args.seconds) * n,
    }
    envs[0].recv()
    bound = min(rates["policy"], rates["simulate"])
    serial = 1.0 / (1.0 / rates["policy"] + 1.0 / rates["simulate"])
    result = {
        "config": args.config,
        "envs": n,
        "sim_threads": args.sim_threads,
        "torch_threads": args.torch_threads,
        "env_steps_per_s": {k: round(v) for k, v in rates.items()},
        "serial_estimate": round(serial),
        "overlap_bound": round(bound),
        "speedup": round(rates["send/recv"] / rates["step"], 3),
    }
    if args.json:
        print(json.dumps(result))
        return
    print(f"{args.config}, {n} environments, {args.sim_threads} simulation / {args.torch_threads} torch threads")
    for k, v in rates.items():
        print(f"  {k:10s} {v:12,.0f} env-steps/s")
    print(f"  serial estimate {serial:,.0f}, overlap bound {bound:,.0f}; send/recv / step = {result['speedup']:.2f}")


if __name__ == "__main__":
    main()
