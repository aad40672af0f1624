"""Expert data at scale: episodes/s and bytes/episode of ``socnav.datasets.collect`` streaming the
ORCA-driven robot's episodes to a Minari dataset, and the process's memory as the dataset grows.

    python benches/collect.py --config exp2 --envs 1024 --episodes 10000

Needs the ``datasets`` extra (``pip install './python[datasets]'``). Writes the dataset under a
temporary Minari root (deleted at the end). Prints the resident memory (RSS) every tenth of the
episodes: it should stay flat after the first batch of episodes, whatever the dataset's size.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

from socnav.datasets import MinariWriter, estimate_bytes, iter_episodes
from socnav.registration import env_spec


def rss_mb() -> float:
    """The process's resident memory now (MB), from /proc (Linux); the peak where that is missing."""
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 1e6
    except (OSError, ValueError):
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", default="exp2")
    parser.add_argument("--envs", type=int, default=1024)
    parser.add_argument("--episodes", type=int, default=10_000)
    parser.add_argument("--policy", default="orca")
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--info-keys", default="all",
                        help="info arrays kept: all, none, or a comma-separated list (default all)")
    args = parser.parse_args()
    import socnav

    with tempfile.TemporaryDirectory() as root:
        os.environ["MINARI_DATASETS_PATH"] = root
        probe = socnav.make(args.config, obs_mode="flat")
        writer = MinariWriter(f"socnav/{args.config}-{args.policy}-bench-v0", env_spec(args.config, obs_mode="flat"),
                              probe.observation_space, probe.action_space, flush_every=256)
        probe.close()
        bound = estimate_bytes(args.config, episodes=args.episodes)
        print(f"{args.episodes} episodes of {args.config} by {args.policy}, {args.envs} environments: "
              f"at most {bound / 1e9:.2f} GB", file=sys.stderr)
        start = time.perf_counter()
        steps = count = nbytes = 0
        report = max(1, args.episodes // 10)
        rss = [(0, rss_mb())]
        keys = None if args.info_keys == "all" else [k for k in args.info_keys.split(",") if k and k != "none"]
        for ep in iter_episodes(args.policy, args.config, episodes=args.episodes, num_envs=args.envs,
                                threads=args.threads, info_keys=keys):
            writer.add(ep)
            count += 1
            steps += len(ep)
            nbytes += ep.nbytes()
            if count % report == 0:
                rss.append((count, rss_mb()))
                print(f"  {count:>6} episodes  {time.perf_counter() - start:7.1f} s  RSS {rss[-1][1]:7.0f} MB",
                      file=sys.stderr)
        writer.close()
        seconds = time.perf_counter() - start
        disk = sum(p.stat().st_size for p in Path(root).rglob("*") if p.is_file())
    print(f"episodes/s {count / seconds:.0f}  env-steps/s {steps / seconds:.0f}  "
          f"steps/episode {steps / count:.1f}  bytes/episode {nbytes / count / 1e3:.1f} kB in memory, "
          f"{disk / count / 1e3:.1f} kB on disk (HDF5)  total {disk / 1e9:.2f} GB in {seconds:.0f} s")
    # Warm-up: the first fifth (the builders of every environment fill, HDF5's caches grow).
    warm = [m for k, m in rss if k >= args.episodes // 5]
    print(f"RSS after the first fifth: {min(warm):.0f}-{max(warm):.0f} MB "
          f"(growth {100 * (max(warm) / min(warm) - 1):.1f} %)")


if __name__ == "__main__":
    main()
