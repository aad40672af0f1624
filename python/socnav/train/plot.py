"""Learning curves of training runs: ``python -m socnav.train plot RUN... --out curves.png``.

A run is a run directory of :mod:`socnav.train` (``progress.csv`` and ``args.json``) or a progress
CSV on its own (``NAME.progress.csv``, with ``NAME.args.json`` beside it when there is one, as
docs/results/ keeps them). Each metric is a row of panels and each world a column: runs whose
configs differ only in the reward (``exp2`` and ``exp2_sngnn``) share a panel, so the two rewards
of one experiment are compared where they meet. A run's line keeps its colour in every panel.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

# What the results page shows: outcomes and the DSRNN discomfort, which every config logs (a
# config without the SNGNN-v2 reward logs DISCOMFORT_SNGNN as 0; returns of two rewards do not
# compare).
DEFAULT_METRICS = ("success", "collision", "timeout", "DISCOMFORT_DSRNN")
_REWARD_SUFFIXES = ("_sngnn",)


@dataclass
class Run:
    """One run's logged rows."""

    name: str
    config: str
    columns: dict[str, list[float]]

    @property
    def world(self) -> str:
        """The config's name without a reward suffix: the runs a panel compares."""
        for suffix in _REWARD_SUFFIXES:
            if self.config.endswith(suffix):
                return self.config[: -len(suffix)]
        return self.config

    @property
    def series(self) -> str:
        """The run's name without its world: the key of its colour across panels."""
        parts = [p for p in self.name.replace("_", "-").split("-") if p != self.world]
        return "-".join(parts) or self.name


def load_run(path: str | Path) -> Run:
    """The rows of a run directory or progress CSV (see the module's doc)."""
    path = Path(path)
    if path.is_dir():
        progress, args_file, name = path / "progress.csv", path / "args.json", path.name
    else:
        progress = path
        name = path.name.removesuffix(".csv").removesuffix(".progress")
        args_file = path.with_name(name + ".args.json")
    if not progress.is_file():
        raise FileNotFoundError(f"{progress}: no progress CSV (a socnav.train run directory holds one)")
    config = json.loads(args_file.read_text()).get("config", "") if args_file.is_file() else ""
    columns: dict[str, list[float]] = {}
    with progress.open(newline="") as f:
        for row in csv.DictReader(f):
            for key, value in row.items():
                columns.setdefault(key, []).append(float(value) if value not in ("", None) else math.nan)
    if "step" not in columns:
        raise ValueError(f"{progress}: no 'step' column")
    return Run(name=name, config=config, columns=columns)


def plot_runs(
    runs: Sequence[str | Path],
    out: str | Path,
    metrics: Sequence[str] = DEFAULT_METRICS,
    title: str | None = None,
) -> Path:
    """Draw ``metrics`` (rows) against environment steps for every run, one column per world,
    into the image ``out`` (PNG, SVG or PDF by its suffix). Needs matplotlib (the ``train``
    extra)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    loaded = [load_run(r) for r in runs]
    if not loaded:
        raise ValueError("no runs to plot")
    missing = [m for m in metrics if not any(m in r.columns for r in loaded)]
    if missing:
        known = sorted({k for r in loaded for k in r.columns} - {"step"})
        raise ValueError(f"no run logs {missing}; the runs log {known}")
    worlds = sorted({r.world for r in loaded})
    series = sorted({r.series for r in loaded})
    colours = {s: plt.get_cmap("tab10")(k % 10) for k, s in enumerate(series)}
    fig, axes = plt.subplots(
        len(metrics), len(worlds), figsize=(4.2 * len(worlds), 2.6 * len(metrics)), squeeze=False, sharex="col"
    )
    for col, world in enumerate(worlds):
        for row, metric in enumerate(metrics):
            ax = axes[row][col]
            for run in (r for r in loaded if r.world == world and metric in r.columns):
                steps = [s / 1e6 for s in run.columns["step"]]
                ax.plot(steps, run.columns[metric], color=colours[run.series], label=run.series, linewidth=1.4)
            ax.grid(alpha=0.3)
            if row == 0:
                ax.set_title(world or "(config unknown)")
            if col == 0:
                ax.set_ylabel(metric)
            if row == len(metrics) - 1:
                ax.set_xlabel("environment steps (millions)")
    handles = [plt.Line2D([], [], color=colours[s], linewidth=2) for s in series]
    top = 0.93 if title else 0.95
    fig.tight_layout(rect=(0, 0, 1, top))
    fig.legend(handles, series, loc="lower center", bbox_to_anchor=(0.5, top), ncol=min(len(series), 6), frameon=False)
    if title:
        fig.suptitle(title, y=0.995)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
