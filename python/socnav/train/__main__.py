"""``python -m socnav.train {dqn,ppo,export,select,plot}``: see :mod:`socnav.train`."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from typing import Any, Sequence


def _add_args(parser: argparse.ArgumentParser, defaults: Any) -> None:
    for f in dataclasses.fields(defaults):
        flag = "--" + f.name.replace("_", "-")
        value = getattr(defaults, f.name)
        # The annotation's type (``int | None`` takes ints), where a None default has none.
        annotation = str(f.type)
        kind = type(value) if value is not None else int if annotation.startswith("int") else float
        parser.add_argument(flag, type=kind, default=value, help=f"default: {value}")


def main(argv: Sequence[str] | None = None) -> int:
    from socnav.train import dqn, export, ppo

    parser = argparse.ArgumentParser(prog="python -m socnav.train", description="Train baseline agents over a socnav batch.")
    sub = parser.add_subparsers(dest="command", required=True)
    # A DQN preset gives the flags' defaults, so that an explicit flag still overrides it.
    mode = argparse.ArgumentParser(add_help=False)
    mode.add_argument("--mode", default="batched")
    known, _ = mode.parse_known_args(argv)
    try:
        dqn_defaults = dqn.Args.for_mode(known.mode)
    except ValueError as e:
        print(f"python -m socnav.train dqn: {e}", file=sys.stderr)
        return 2
    _add_args(sub.add_parser("dqn", help="the paper's DQN (socnav.train.dqn; --mode batched, paper or paper-text)"),
              dqn_defaults)
    _add_args(sub.add_parser("ppo", help="PPO, discrete or continuous actions (socnav.train.ppo)"), ppo.Args())
    ex = sub.add_parser("export", help="write the agent of a checkpoint alone (float16, or --float32)")
    ex.add_argument("checkpoint")
    ex.add_argument("out")
    ex.add_argument("--float32", action="store_true", help="keep the weights as trained (for evaluation)")
    se = sub.add_parser("select", help="choose a run's snapshot on validation episodes (socnav.train.select)")
    se.add_argument("run")
    se.add_argument("--episodes", type=int, default=300)
    se.add_argument("--seed", type=int, default=None, help="first validation seed (default: select.VALIDATION_SEED)")
    se.add_argument("--config", default=None, help="default: the config the run trained on")
    pl = sub.add_parser("plot", help="learning curves of runs (socnav.train.plot; needs matplotlib)")
    pl.add_argument("runs", nargs="+", help="run directories or NAME.progress.csv files")
    pl.add_argument("--out", required=True, help="image file (.png, .svg, .pdf)")
    pl.add_argument("--metric", action="append", help="a logged column (repeat); default: success, "
                    "collision, timeout, DISCOMFORT_DSRNN")
    pl.add_argument("--title")
    args = parser.parse_args(argv)
    if args.command == "export":
        try:
            print(export(args.checkpoint, args.out, "float32" if args.float32 else "float16"))
        except (OSError, ValueError) as e:
            print(f"python -m socnav.train export: {e}", file=sys.stderr)
            return 2
        return 0
    if args.command == "select":
        from socnav.train.select import VALIDATION_SEED, select

        try:
            chosen, _ = select(args.run, config=args.config, episodes=args.episodes,
                               seed=VALIDATION_SEED if args.seed is None else args.seed)
        except (OSError, ValueError) as e:
            print(f"python -m socnav.train select: {e}", file=sys.stderr)
            return 2
        print(chosen)
        return 0
    if args.command == "plot":
        from socnav.train.plot import DEFAULT_METRICS, plot_runs

        try:
            print(plot_runs(args.runs, args.out, args.metric or DEFAULT_METRICS, args.title))
        except (OSError, ValueError) as e:
            print(f"python -m socnav.train plot: {e}", file=sys.stderr)
            return 2
        return 0
    module = dqn if args.command == "dqn" else ppo
    values = {f.name: getattr(args, f.name) for f in dataclasses.fields(module.Args)}
    run_args = module.Args(**values)
    try:
        run_args.check()
    except ValueError as e:
        print(f"python -m socnav.train {args.command}: {e}", file=sys.stderr)
        return 2
    module.train(run_args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
