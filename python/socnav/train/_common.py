"""What the training scripts share: the run directory (CSV and TensorBoard scalars, checkpoints
written atomically), where the time goes, seeding, and the environment they train on."""

from __future__ import annotations

import csv
import json
import os
import random
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
import torch

import socnav
from socnav.metrics import EPISODE_KEYS

#: Stages of the step that compute the reward (their time is reported as "reward").
REWARD_STAGES = ("reward", "sngnn_graph", "sngnn_score")
#: Episode statistics logged as means over the episodes finished since the last log line.
LOGGED_EPISODE_KEYS = (
    "return",
    "length",
    "success",
    "collision",
    "timeout",
    "DISCOMFORT_SNGNN",
    "DISCOMFORT_DSRNN",
    "PERSONAL_SPACE_COMPLIANCE",
    "MINIMUM_DISTANCE_TO_HUMAN",
    "STL",
    "SPL",
)


@dataclass
class RunArgs:
    """The arguments every training run takes (each algorithm's ``Args`` adds its own)."""

    config: str = "exp1"
    steps: int = 1_000_000
    out: str = "runs/run"
    seed: int = 0
    num_envs: int = 64
    threads: int = 2
    log_every: int = 50_000
    checkpoint_minutes: float = 10.0
    max_minutes: float | None = None
    chunk_steps: int | None = None

    def problems(self) -> list[str]:
        """What is wrong with these arguments, every problem at once (empty when none); each
        algorithm's ``Args`` adds its own."""
        out = [f"--{name.replace('_', '-')} must be at least 1, got {value!r}"
               for name, value in self._counts() if not (_is_int(value) and value >= 1)]
        if not (_is_int(self.seed) and 0 <= self.seed < 1 << 64):
            out.append(f"--seed must be an integer in 0..2**64, got {self.seed!r}")
        for name, value in (("checkpoint_minutes", self.checkpoint_minutes), ("max_minutes", self.max_minutes)):
            if value is not None and not (isinstance(value, (int, float)) and 0 < value < float("inf")):
                out.append(f"--{name.replace('_', '-')} must be a positive number of minutes, got {value!r}")
        return out

    def _counts(self) -> list[tuple[str, Any]]:
        """The arguments that count something (at least 1), ``None`` for the unset optional ones."""
        counts = [("steps", self.steps), ("num_envs", self.num_envs), ("threads", self.threads), ("log_every", self.log_every)]
        return counts + ([("chunk_steps", self.chunk_steps)] if self.chunk_steps is not None else [])

    def check(self) -> None:
        """Raise a ``ValueError`` listing every problem of :meth:`problems`, before anything runs."""
        problems = self.problems()
        if problems:
            raise ValueError("invalid training arguments:\n  - " + "\n  - ".join(problems))


def _is_int(value: Any) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def fraction_problems(**values: float) -> list[str]:
    """A problem for each value outside [0, 1], by its flag."""
    return [f"--{k.replace('_', '-')} must be in [0, 1], got {v!r}" for k, v in values.items()
            if not (isinstance(v, (int, float)) and 0.0 <= v <= 1.0)]


def positive_problems(**values: float) -> list[str]:
    """A problem for each value that is not a positive finite number, by its flag."""
    return [f"--{k.replace('_', '-')} must be a positive number, got {v!r}" for k, v in values.items()
            if not (isinstance(v, (int, float)) and 0.0 < v < float("inf"))]


def seed_everything(seed: int, threads: int) -> np.random.Generator:
    """Seed torch and Python and fix torch's thread count; the run's numpy generator."""
    random.seed(seed)
    torch.manual_seed(seed)
    torch.set_num_threads(threads)
    torch.use_deterministic_algorithms(True, warn_only=True)
    return np.random.default_rng(seed)


def make_train_env(
    config: str, num_envs: int, seed: int, threads: int, action_type: str, overrides: Mapping[str, Any] | None = None
) -> Any:
    """The batch a run trains on: flat observations, SAME_STEP autoreset (a finished
    environment's last observation is in ``info["final_obs"]``), no per-step metrics (the
    learners read the finished episodes' statistics alone), stage timing on; ``overrides``
    (the TOML layout) applied to the config."""
    env = socnav.make_vec(
        socnav.with_overrides(config, overrides) if overrides else config,
        num_envs=num_envs,
        seed=seed,
        obs_mode="flat",
        action_type=action_type,
        autoreset_mode="same_step",
        threads=threads,
        step_info=False,
    )
    env.unwrapped._batch.set_stage_timing(True)
    return env


def reward_seconds(env: Any) -> float:
    """Seconds the batch spent in the reward stages so far."""
    stages = env.unwrapped._batch.stage_seconds()
    return float(sum(stages.get(s, 0.0) for s in REWARD_STAGES))


def simulation_seconds(env: Any) -> float:
    """Seconds the batch spent in every stage so far."""
    return float(sum(env.unwrapped._batch.stage_seconds().values()))


@dataclass
class Clock:
    """Wall time per part of the loop: ``act`` (the network choosing actions), ``env`` (the
    step call, simulation and reward together), ``learn`` (gradient steps), plus the
    simulation's own per-stage split read from the batch."""

    parts: dict[str, float] = field(default_factory=lambda: {"act": 0.0, "env": 0.0, "learn": 0.0})
    _start: float = 0.0

    def start(self) -> None:
        self._start = time.perf_counter()

    def stop(self, part: str) -> None:
        now = time.perf_counter()
        self.parts[part] = self.parts.get(part, 0.0) + now - self._start
        self._start = now


class EpisodeStats:
    """The statistics of the episodes finished since the last :meth:`flush`."""

    def __init__(self) -> None:
        self.rows: list[np.ndarray] = []
        self.total = 0

    def add(self, info: Mapping[str, Any]) -> None:
        done = info.get("_episode")
        if done is None or not done.any():
            return
        ep = info["episode"]
        self.rows.append(np.stack([np.asarray(ep[k])[done] for k in EPISODE_KEYS], axis=1))
        self.total += int(done.sum())

    def flush(self) -> dict[str, float]:
        """The means since the last flush; NaN with ``episodes_logged`` 0 when none finished,
        so that every log row has the same columns (``progress.csv``'s header is the first
        row's)."""
        if not self.rows:
            return {"episodes_logged": 0.0, **{key: float("nan") for key in LOGGED_EPISODE_KEYS}}
        rows = np.concatenate(self.rows).astype(np.float64)
        self.rows.clear()
        out: dict[str, float] = {"episodes_logged": float(rows.shape[0])}
        for key in LOGGED_EPISODE_KEYS:
            col = rows[:, EPISODE_KEYS.index(key)]
            col = col[np.isfinite(col)]
            out[key] = float(col.mean()) if col.size else float("nan")
        return out


#: Arguments that may change between the chunks of one run (``out`` too: a run's directory may
#: be moved or copied and resumed there).
_CHUNK_ARGS = ("steps", "max_minutes", "chunk_steps", "checkpoint_minutes", "log_every", "snapshot_every", "out")


class RunDir:
    """A run's directory: ``args.json``, ``progress.csv`` (one row per log, appended across
    resumes), TensorBoard events when ``tensorboard`` is installed, ``checkpoint.pt``."""

    def __init__(self, path: str | os.PathLike[str], args: Mapping[str, Any]) -> None:
        self.path = Path(path)
        self.path.mkdir(parents=True, exist_ok=True)
        self.args = dict(args)
        args_file = self.path / "args.json"
        if args_file.exists() and self.checkpoint.exists():
            try:
                previous = json.loads(args_file.read_text())
            except ValueError as e:
                raise ValueError(f"{args_file}: not the arguments of a run ({e}); remove it to resume from the checkpoint's") from None
            if not isinstance(previous, dict):
                raise ValueError(f"{args_file}: not the arguments of a run (a JSON object); remove it to resume from the checkpoint's")
            self._check_same_run(previous, args_file)
        self._csv_fields: list[str] | None = None
        self._tb: Any = None
        try:
            from torch.utils.tensorboard import SummaryWriter

            self._tb = SummaryWriter(str(self.path / "tb"))
        except Exception:  # tensorboard is optional
            self._tb = None

    @property
    def checkpoint(self) -> Path:
        return self.path / "checkpoint.pt"

    def log(self, step: int, scalars: Mapping[str, float]) -> None:
        row = {"step": step, **scalars}
        path = self.path / "progress.csv"
        if self._csv_fields is None:
            if path.exists():
                with path.open() as f:
                    header = f.readline().strip()
                self._csv_fields = header.split(",") if header else None
            if self._csv_fields is None:
                self._csv_fields = list(row)
                with path.open("w", newline="") as f:
                    csv.writer(f).writerow(self._csv_fields)
        with path.open("a", newline="") as f:
            csv.writer(f).writerow([_fmt(row.get(k, "")) for k in self._csv_fields])
        if self._tb is not None:
            for k, v in scalars.items():
                if isinstance(v, (int, float)) and np.isfinite(v):
                    self._tb.add_scalar(k, v, step)

    def save(self, payload: Mapping[str, Any]) -> None:
        """Write ``checkpoint.pt`` atomically (a crash mid-write keeps the previous one)."""
        _save_atomically(payload, self.checkpoint)

    def snapshot(self, step: int, agent: Mapping[str, Any]) -> Path:
        """Write an agent file (``socnav.train.agent_file``) as ``snapshots/step-<step>.pt``."""
        path = self.path / "snapshots" / f"step-{step:010d}.pt"
        path.parent.mkdir(exist_ok=True)
        _save_atomically(agent, path)
        return path

    def load(self) -> dict[str, Any] | None:
        """The checkpoint to resume from, or None for a fresh run. The progress log is cut back to
        match: rows a stopped run logged after its last checkpoint (or before its first) would
        otherwise appear twice on the learning curve, once from each pass over those steps."""
        saved = None
        if self.checkpoint.exists():
            try:
                saved = torch.load(self.checkpoint, weights_only=False)
            except Exception as e:  # torch raises what its reader or unpickler met
                raise ValueError(f"{self.checkpoint}: cannot resume from it ({type(e).__name__}: {e})") from None
            if not (isinstance(saved, dict) and isinstance(saved.get("args"), dict) and "step" in saved):
                raise ValueError(f"{self.checkpoint}: not a socnav.train checkpoint")
            # The checkpoint's own arguments decide (args.json may be missing or edited); the run
            # directory is written only once they agree.
            self._check_same_run(saved["args"], self.checkpoint)
        (self.path / "args.json").write_text(json.dumps(self.args, indent=2, sort_keys=True) + "\n")
        self._truncate_progress(after_step=int(saved["step"]) if saved is not None else -1)
        return saved

    def _check_same_run(self, previous: Mapping[str, Any], source: Path) -> None:
        """Refuse to resume a run made with other arguments (those of ``_CHUNK_ARGS`` may
        change)."""
        changed = {k: (previous.get(k), v) for k, v in self.args.items() if k not in _CHUNK_ARGS and previous.get(k) != v}
        if changed:
            raise ValueError(f"{self.path} holds a run with other arguments {changed} ({source.name}); use another --out")

    def _truncate_progress(self, after_step: int) -> None:
        path = self.path / "progress.csv"
        self._csv_fields = None
        if not path.exists():
            return
        if after_step < 0:
            path.unlink()
            return
        with path.open(newline="") as f:
            rows = list(csv.reader(f))
        kept = rows[:1] + [r for r in rows[1:] if r and int(float(r[0])) <= after_step]
        if len(kept) != len(rows):
            with path.open("w", newline="") as f:
                csv.writer(f).writerows(kept)

    def close(self) -> None:
        if self._tb is not None:
            self._tb.close()


def _save_atomically(payload: Mapping[str, Any], path: Path) -> None:
    """``torch.save`` to ``path`` through a temporary file, so a crash mid-write keeps the old one."""
    tmp = path.with_suffix(".tmp")
    torch.save(dict(payload), tmp)
    os.replace(tmp, path)


def _fmt(v: Any) -> Any:
    return f"{v:.6g}" if isinstance(v, float) else v


def env_documents(env: Any) -> list[str]:
    """Every environment's state document (to resume a run mid-episode)."""
    batch = env.unwrapped._batch
    return [batch.get_state(e) for e in range(env.unwrapped.num_envs)]


def restore_env(env: Any, docs: Iterable[str]) -> None:
    """Load the documents of :func:`env_documents`. The environments then step exactly as they
    would have; the observation a load rewrites is not always the step's (the human records'
    relative angular speed needs the angle before the step), so a run keeps its own."""
    batch = env.unwrapped._batch
    for e, doc in enumerate(docs):
        batch.set_state(e, doc)


def resume(saved: Mapping[str, Any], rng: np.random.Generator, env: Any, clock: Clock) -> float:
    """Restore what every run keeps in its checkpoint (random states, the environments, the
    clock); the wall time the run had taken."""
    set_rng_states(rng, saved["rng"])
    restore_env(env, saved["envs"])
    clock.parts = saved["clock"]
    print(f"socnav.train {saved['algo']}: resumed at step {saved['step']:,}", flush=True)
    return float(saved["wall"])


def rng_states(rng: np.random.Generator) -> dict[str, Any]:
    return {"numpy": rng.bit_generator.state, "torch": torch.get_rng_state(), "python": random.getstate()}


def set_rng_states(rng: np.random.Generator, states: Mapping[str, Any]) -> None:
    rng.bit_generator.state = states["numpy"]
    torch.set_rng_state(states["torch"])
    random.setstate(states["python"])


class Schedule:
    """When a run saves its checkpoint (every ``checkpoint_minutes``) and when this chunk of it
    ends (``max_minutes`` of wall time, or ``chunk_steps`` more steps)."""

    def __init__(self, algo: str, args: Any, step: int) -> None:
        self.algo = algo
        self.every = 60.0 * args.checkpoint_minutes
        self.last_save = time.monotonic()
        self.end = None if args.max_minutes is None else time.monotonic() + 60.0 * args.max_minutes
        self.chunk_end = None if args.chunk_steps is None else step + args.chunk_steps

    def save_due(self) -> bool:
        if time.monotonic() - self.last_save < self.every:
            return False
        self.last_save = time.monotonic()
        return True

    def chunk_over(self, step: int) -> bool:
        over = (self.end is not None and time.monotonic() >= self.end) or (
            self.chunk_end is not None and step >= self.chunk_end
        )
        if over:
            print(f"socnav.train {self.algo}: chunk ended at step {step:,}; run again to resume", flush=True)
        return over


def progress(env: Any, step: int, wall: float, stats: EpisodeStats, clock: Clock) -> dict[str, float]:
    """The scalars every run logs: speed, the finished episodes' statistics, where the time went."""
    return {
        "wall_s": wall,
        "steps_per_s": step / max(wall, 1e-9),
        "episodes": float(stats.total),
        **stats.flush(),
        "time_act_s": clock.parts["act"],
        "time_env_s": clock.parts["env"],
        "time_learn_s": clock.parts["learn"],
        "time_sim_s": simulation_seconds(env),
        "time_reward_s": reward_seconds(env),
    }


def report(algo: str, args: Any, step: int, scalars: Mapping[str, float], extra: str = "") -> None:
    """One progress line on stdout."""
    nan = float("nan")
    print(
        f"socnav.train {algo} {args.config}: step {step:,}/{args.steps:,} "
        f"success {scalars.get('success', nan):.3f} return {scalars.get('return', nan):.2f} "
        f"{extra}{scalars['steps_per_s']:.0f} steps/s",
        flush=True,
    )
