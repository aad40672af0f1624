"""Env-steps/s of the Python package against the Rust step it wraps (issue: Python overhead < 20 %).

Each round runs `socnav bench --json` (the Rust CLI: fixed actions forward 0.8 / turn 0.3 after a
50-step warm-up, stage timing off), then the same loop through `socnav.make_vec` with a numpy
action array in each observation mode. Within that loop, blocks of 10 steps through `env.step`
alternate with blocks of 10 calls of the extension's bare `Batch.step_continuous` on the same
batch, so the overhead of the Python layer (1 - env.step / bare, in the same process and the
same seconds) does not depend on the machine's slow spells, which move the CLI's figure by
±25 % from run to run here. Prints the medians.

    cargo build --release && python benches/python_step.py --config exp1 --envs 4096

Needs the package installed (`pip install ./python`) and the CLI built (`target/release/socnav`).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import socnav

WARMUP_STEPS = 50
# Steps per alternating block.
BLOCK = 10
ROOT = Path(__file__).resolve().parents[1]


def rust_env_steps_per_s(cli: Path, config: str, envs: int, seconds: float, threads: int | None) -> float:
    cmd = [str(cli), "bench", "--config", config, "--envs", str(envs), "--seconds", str(seconds), "--json"]
    if threads is not None:
        cmd += ["--threads", str(threads)]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return float(json.loads(out)["rows"][0]["env_steps_per_s"])


def python_env_steps_per_s(
    config: str, envs: int, seconds: float, threads: int | None, obs_mode: str
) -> tuple[float, float]:
    """(through ``env.step``, through the bare extension call) env-steps/s, interleaved."""
    env = socnav.make_vec(config, envs, seed=0, obs_mode=obs_mode, threads=threads)
    env.reset(seed=0)
    bare = env.unwrapped._batch  # the extension object env.step drives
    actions = np.tile(np.array([0.8, 0.0, 0.3], dtype=np.float32), (envs, 1))
    for _ in range(WARMUP_STEPS):
        env.step(actions)
    times = {"env": 0.0, "bare": 0.0}
    steps = 0
    while times["env"] + times["bare"] < seconds:
        start = time.perf_counter()
        for _ in range(BLOCK):
            env.step(actions)
        times["env"] += time.perf_counter() - start
        start = time.perf_counter()
        for _ in range(BLOCK):
            bare.step_continuous(actions)
        times["bare"] += time.perf_counter() - start
        steps += BLOCK
    env.close()
    return envs * steps / times["env"], envs * steps / times["bare"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="exp1", help="config name or path (default exp1)")
    ap.add_argument("--envs", type=int, default=4096, help="batch size (default 4096)")
    ap.add_argument("--seconds", type=float, default=2.0, help="seconds per measurement (default 2)")
    ap.add_argument("--rounds", type=int, default=5, help="alternating rounds (default 5)")
    ap.add_argument("--threads", type=int, default=None, help="CPU threads (default: all cores)")
    ap.add_argument("--cli", type=Path, default=ROOT / "target" / "release" / "socnav", help="the socnav binary")
    args = ap.parse_args()
    if not args.cli.is_file():
        sys.exit(f"no socnav binary at {args.cli}: run `cargo build --release` first, or pass --cli")
    runs: dict[str, list[float]] = {"rust CLI": []}
    for mode in ("flat", "dict"):
        runs[f"python {mode}"] = []
        runs[f"bare {mode}"] = []
    for r in range(args.rounds):
        runs["rust CLI"].append(rust_env_steps_per_s(args.cli, args.config, args.envs, args.seconds, args.threads))
        for mode in ("flat", "dict"):
            wrapped, bare = python_env_steps_per_s(args.config, args.envs, 2 * args.seconds, args.threads, mode)
            runs[f"python {mode}"].append(wrapped)
            runs[f"bare {mode}"].append(bare)
        print(f"round {r + 1}/{args.rounds}: " + ", ".join(f"{k} {v[-1]:,.0f}" for k, v in runs.items()), file=sys.stderr)
    print(f"{args.config}, {args.envs} envs, {args.rounds} rounds, medians (min-max) of env-steps/s:")
    for name, values in runs.items():
        print(f"  {name:12s} {statistics.median(values):>12,.0f} ({min(values):,.0f}-{max(values):,.0f})")
    for mode in ("flat", "dict"):
        ratios = [w / b for w, b in zip(runs[f"python {mode}"], runs[f"bare {mode}"])]
        print(f"  overhead of make_vec's step ({mode}): {100 * (1 - statistics.median(ratios)):.1f} % "
              f"(rounds: {', '.join(f'{100 * (1 - x):.1f}' for x in ratios)})")


if __name__ == "__main__":
    main()
