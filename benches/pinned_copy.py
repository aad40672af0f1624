"""What pinning the batch's buffers buys a CUDA trainer (``SocNavVectorEnv.pin_memory``).

A rollout loop as a CUDA learner runs it: ``env.step``, then the flat observations and rewards
copied to the GPU (``tensor.to("cuda", non_blocking=True)`` over ``torch.from_numpy`` views of the
batch's own buffers) and a small network's forward pass there, whose greedy actions come back for
the next step. Three figures per backend, each for ``--seconds``:

- ``step``: ``env.step`` alone;
- ``pageable``: the loop with the buffers as they are (the copy goes through the driver's
  staging buffer and blocks the host);
- ``pinned``: the same loop after ``env.pin_memory()`` (a direct DMA, queued).

    python benches/pinned_copy.py --config exp2 --envs 16384 --backend gpu --seconds 5

Needs the package, torch and a CUDA device.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import torch

import socnav


def timed(loop, seconds: float) -> float:
    """Calls of ``loop`` per second, after two warm-up calls."""
    loop()
    loop()
    torch.cuda.synchronize()
    calls, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        loop()
        calls += 1
    torch.cuda.synchronize()
    return calls / (time.perf_counter() - start)


def measure(config: str, n: int, backend: str, seconds: float) -> dict[str, object]:
    env = socnav.make_vec(config, num_envs=n, seed=0, obs_mode="flat", action_type="discrete", backend=backend)
    obs, _ = env.reset(seed=0)
    policy = torch.nn.Sequential(torch.nn.Linear(obs.shape[1], 256), torch.nn.ReLU(), torch.nn.Linear(256, 7)).cuda()
    fixed = np.full(n, 2)
    actions = [fixed]

    def step() -> None:
        env.step(fixed)

    def rollout() -> None:
        o, r, *_ = env.step(actions[0])
        with torch.no_grad():
            obs_cuda = torch.from_numpy(o).to("cuda", non_blocking=True)
            torch.from_numpy(r).to("cuda", non_blocking=True)
            actions[0] = policy(obs_cuda).argmax(1).cpu().numpy()

    row: dict[str, object] = {"config": config, "envs": n, "backend": backend}
    row["step"] = timed(step, seconds) * n
    row["pageable"] = timed(rollout, seconds) * n
    row["pinned_bytes"] = env.pin_memory()
    row["pinned"] = timed(rollout, seconds) * n
    env.close()
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="exp2")
    ap.add_argument("--envs", type=int, default=16384)
    ap.add_argument("--backend", default="gpu", choices=["cpu", "gpu"])
    ap.add_argument("--seconds", type=float, default=5.0)
    args = ap.parse_args()
    row = measure(args.config, args.envs, args.backend, args.seconds)
    row["cuda_device"] = torch.cuda.get_device_name()
    print(json.dumps(row))


if __name__ == "__main__":
    main()
