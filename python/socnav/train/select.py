"""Choose a run's agent on validation episodes: every snapshot of a run (``--snapshot-every``)
evaluated greedily on the same episodes of seeds disjoint from the test seeds of
docs/results.md, the best by success (then fewer collisions) copied to ``selected.pt``, every
row in ``selection.csv``.

    python -m socnav.train select runs/entity-exp2-dsrnn-s0 --episodes 300

Validation seeds start at ``VALIDATION_SEED``; docs/results.md's test episodes at 1,000,000;
training episodes have seeds ``seed + i + k * 0x9e3779b97f4a7c15`` (docs/spec.md,
determinism), which meet neither for any practical run.
"""

from __future__ import annotations

import csv
import shutil
from pathlib import Path
from typing import Any

import socnav

#: The first validation episode's seed.
VALIDATION_SEED = 2_000_000
#: The columns of ``selection.csv`` besides the snapshot's name and steps.
COLUMNS = ("success", "collision", "collision_human", "timeout", "DISCOMFORT_SNGNN", "DISCOMFORT_DSRNN")


def select(
    run: str | Path,
    *,
    config: Any = None,
    episodes: int = 300,
    seed: int = VALIDATION_SEED,
    num_envs: int = 64,
    threads: int | None = None,
) -> tuple[Path, list[dict[str, Any]]]:
    """Evaluate every snapshot of ``run`` on ``episodes`` validation episodes of ``config`` (the
    run's own by default); copy the best to ``selected.pt``; return its path and every row."""
    from socnav.train import load

    run = Path(run)
    snapshots = sorted((run / "snapshots").glob("step-*.pt"))
    if not snapshots:
        raise ValueError(f"{run}: no snapshots (train with --snapshot-every)")
    rows: list[dict[str, Any]] = []
    for path in snapshots:
        agent = load(path)
        summary = socnav.evaluate(agent, config or agent.config, episodes=episodes, seed=seed,
                                  num_envs=num_envs, threads=threads).summary()
        row: dict[str, Any] = {"snapshot": path.name, "steps": int(path.stem.split("-")[1]), **{k: float(summary[k]) for k in COLUMNS}}
        rows.append(row)
        print(f"socnav.train select: {path.name}: success {row['success']:.3f} collision {row['collision']:.3f}", flush=True)
    best = max(rows, key=lambda r: (r["success"], -r["collision"], r["steps"]))
    with (run / "selection.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["snapshot", "steps", *COLUMNS, "selected"])
        w.writeheader()
        for r in rows:
            w.writerow({**r, "selected": r is best})
    chosen = run / "selected.pt"
    shutil.copyfile(run / "snapshots" / best["snapshot"], chosen)
    return chosen, rows
