"""Evaluate a policy on a fixed set of episodes: the paper's table with 95 % confidence intervals.

Episode k of an evaluation with seed s is the episode of seed ``s + k`` (docs/spec.md, determinism),
whatever the number of environments stepping them: each environment plays one episode, then
takes the next unplayed seed. So the table is a function of (policy, config, seed, episodes)
alone for a deterministic policy, and any listed episode replays alone::

    result = socnav.evaluate("goal", "exp2", episodes=500, seed=1000)
    print(result.to_markdown())
    env = socnav.make("exp2")
    obs, _ = env.reset(seed=int(result.seeds[17]))   # the 18th episode, to watch or debug

From the shell: ``python -m socnav.evaluate goal --config exp2 --episodes 500 --seed 1000
--csv table.csv``. A policy is a built-in name (``"goal"``, ``"orca"``, ``"random"``,
:mod:`socnav.policies`), a shipped or saved checkpoint (``socnav.train.load``; needs the
``train`` extra), or any callable ``policy(obs, env) -> actions``; an object may say how it wants
the environment made with the attributes ``obs_mode`` (default ``"dict"``), ``action_type``
(default ``"continuous"``) and ``config_overrides`` (applied to the config, e.g. the robot's
velocity in its record; default none).
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from socnav import policies
from socnav._batch import check_count, check_seed, with_overrides
from socnav.metrics import EPISODE_KEYS, TABLE_KEYS, EpisodeLog, Summary, aggregate

__all__ = ["ENDINGS", "Evaluation", "classify_ending", "evaluate", "resolve_policy"]

#: The statistics of the table besides the paper's metrics: outcome rates and the return.
_LEADING = ("success", "collision", "collision_human", "collision_object", "collision_wall", "timeout", "return", "length")
#: How an episode ends, for the analysis of what any agent could avoid (``Evaluation.endings``):
#: a collision the robot caused (it approached what it touched, at least as fast as that approached
#: it; every contact with a table, laptop, plant or wall), one a person caused (a person walked
#: into a robot that was still, receding or slower: 0.1.1's humans ignore the robot in the paper's
#: configs), a timeout, leaving the map.
ENDINGS = ("success", "robot-caused", "person-caused", "timeout", "out-of-map")
#: Slack (m) on "in contact" between the robot's and a person's discs: the state is f32 at about
#: 10 m (ulp ~1e-6 m), and the polygon64 contact shape touches at 0.9988 times the radii's sum.
_CONTACT_SLACK = 2e-3
#: Two-sided 95 % normal quantile (the intervals are normal approximations: n >= 100 here).
_Z95 = 1.959963984540054


@dataclass
class Evaluation:
    """Episodes of one policy on one config, in seed order.

    Attributes
    ----------
    policy, config : str
        Names, as given (a callable's name for a callable).
    seed : int
        Episode k has the seed ``seed + k``.
    seeds : numpy.ndarray
        uint64 ``(episodes,)``: each row's episode seed.
    log : EpisodeLog
        The statistics of every episode, one row each, in seed order.
    wall_seconds : float
        Time the evaluation took.
    endings : numpy.ndarray
        str ``(episodes,)``: how each episode ended, one of :data:`ENDINGS` (a collision
        classified by :func:`classify_ending` from the state it ended in).
    """

    policy: str
    config: str
    seed: int
    seeds: np.ndarray
    log: EpisodeLog = field(repr=False)
    wall_seconds: float = 0.0
    endings: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U13"), repr=False)

    def ending_counts(self) -> dict[str, int]:
        """How many episodes ended each way (:data:`ENDINGS`), in that order."""
        return {e: int((self.endings == e).sum()) for e in ENDINGS}

    @property
    def episodes(self) -> int:
        return len(self.log)

    def summary(self) -> Summary:
        """Means of every statistic (see :func:`socnav.metrics.aggregate`)."""
        return self.log.summary()

    def table(self, keys: Sequence[str] | None = None) -> dict[str, dict[str, float]]:
        """Per statistic: ``mean``, ``ci95`` (half-width of the 95 % confidence interval of the
        mean, normal approximation, over the episodes where the statistic is finite) and ``n``
        (that number of episodes). Keys default to the outcome rates, return and length, then
        the paper's metrics (``socnav.metrics.TABLE_KEYS``)."""
        keys = list(keys) if keys is not None else list(_LEADING) + [k for k in TABLE_KEYS if k not in _LEADING]
        rows = self.log.table()
        out: dict[str, dict[str, float]] = {}
        for key in keys:
            values = rows[key].astype(np.float64)
            values = values[np.isfinite(values)]
            n = values.size
            mean = float(aggregate({key: values}, keys=(key,))[key]) if n else math.nan
            sd = float(values.std(ddof=1)) if n > 1 else math.nan
            out[key] = {"mean": mean, "ci95": _Z95 * sd / math.sqrt(n) if n > 1 else math.nan, "n": float(n)}
        return out

    def to_dataframe(self, keys: Sequence[str] | None = None) -> Any:
        """:meth:`table` as a ``pandas.DataFrame`` (one row per statistic); needs pandas."""
        try:
            import pandas as pd
        except ImportError as e:
            raise ImportError("Evaluation.to_dataframe needs pandas: pip install pandas") from e
        return pd.DataFrame.from_dict(self.table(keys), orient="index")

    def to_csv(self, path: str | None = None, keys: Sequence[str] | None = None) -> str:
        """:meth:`table` as CSV text (``statistic,mean,ci95,n``), also written to ``path``."""
        lines = ["statistic,mean,ci95,n"]
        for key, v in self.table(keys).items():
            lines.append(f"{key},{v['mean']:.6g},{v['ci95']:.6g},{int(v['n'])}")
        text = "\n".join(lines) + "\n"
        if path is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        return text

    def to_markdown(self, keys: Sequence[str] | None = None) -> str:
        """:meth:`table` as a Markdown table: ``mean ± ci95`` per statistic."""
        head = f"| statistic | {self.policy} on {self.config} ({self.episodes} episodes) |\n|---|---|"
        body = [f"| {k} | {_pm(v['mean'], v['ci95'])} |" for k, v in self.table(keys).items()]
        return "\n".join([head, *body])

    def episode_rows(self) -> dict[str, np.ndarray]:
        """Every episode's statistics and its ``seed``, one array per key, in seed order."""
        rows = self.log.table()
        rows["seed"] = self.seeds.copy()
        return rows


def _pm(mean: float, ci: float) -> str:
    if math.isnan(mean):
        return "n/a"
    if math.isnan(ci):
        return f"{mean:.4g}"
    return f"{mean:.4g} ± {ci:.2g}"


def resolve_policy(policy: Any, seed: int = 0) -> tuple[Callable[[Any, Any], Any], str]:
    """A policy callable and its name, from a built-in name, a checkpoint name or path, or a
    callable."""
    if isinstance(policy, str):
        if policy in policies.BUILTIN:
            return policies.get(policy, seed=seed), policy
        try:
            from socnav import train
        except ImportError as e:
            raise ValueError(
                f"{policy!r} is not a built-in policy ({', '.join(policies.BUILTIN)}); loading it "
                f"as a checkpoint needs the train extra: pip install 'socnav[train]' ({e})"
            ) from e
        return train.load(policy), policy
    if callable(policy):
        return policy, getattr(policy, "name", type(policy).__name__)
    raise TypeError(f"a policy is a name, a checkpoint or a callable, got {type(policy).__name__}")


def evaluate(
    policy: Any,
    config: str | Mapping[str, Any] = "exp1",
    *,
    episodes: int = 100,
    seed: int = 0,
    num_envs: int | None = None,
    backend: str = "cpu",
    threads: int | None = None,
    progress: bool = False,
) -> Evaluation:
    """Run ``policy`` on the episodes of seeds ``seed .. seed + episodes - 1`` of ``config``.

    Parameters
    ----------
    policy : str or callable
        A built-in name, a checkpoint (``socnav.train.load``), or ``policy(obs, env) -> actions``
        (module docs).
    config : str or mapping
        As ``socnav.make_vec``.
    episodes : int
        Number of episodes (at least 1).
    seed : int
        Episode k has seed ``seed + k``.
    num_envs : int, optional
        Environments stepping at once (default: ``min(episodes, 64)``); changes the speed only.
    backend, threads : as ``socnav.make_vec``.
    progress : bool
        Print a line to stderr about every 10 % of the episodes.

    Returns
    -------
    Evaluation
    """
    import socnav

    episodes = check_count("episodes", episodes)
    seed = check_seed(seed)
    act, name = resolve_policy(policy, seed=seed)
    n = min(episodes, check_count("num_envs", num_envs) if num_envs is not None else 64)
    env = socnav.make_vec(
        config_for(config, act),
        num_envs=n,
        obs_mode=getattr(act, "obs_mode", "dict"),
        action_type=getattr(act, "action_type", "continuous"),
        autoreset_mode="disabled",
        backend=backend,
        threads=threads,
        step_info=False,  # only the statistics of finished episodes are read
    )
    start = time.perf_counter()
    limit = 1 << 64
    rows = np.zeros((episodes, len(EPISODE_KEYS)), dtype=np.float32)
    endings = np.full(episodes, "", dtype="<U13")
    batch = policies.batch_of(env)
    obs, _ = env.reset(seed=[(seed + k) % limit for k in range(n)])
    playing = np.arange(n)  # the evaluation index each environment plays; -1 when idle
    next_k, done_count, report = n, 0, max(1, episodes // 10)
    while done_count < episodes:
        actions = act(obs, env)
        obs, _, _, _, info = env.step(actions)
        ended = info.get("_episode")
        if ended is None or not ended.any():
            continue
        ended = np.flatnonzero(ended & (playing >= 0))
        stats = np.stack([info["episode"][k] for k in EPISODE_KEYS], axis=1)
        for e in ended:
            k = int(playing[e])
            if int(info["episode"]["seed"][e]) != (seed + k) % limit:
                raise RuntimeError(f"environment {e} reported seed {info['episode']['seed'][e]}, expected {seed + k}")
            rows[k] = stats[e]
            # Before the restart: a collision's cause is read from the state it ended in.
            endings[k] = classify_ending(dict(zip(EPISODE_KEYS, stats[e])), functools.partial(_state_of, batch, int(e)))
            done_count += 1
            if progress and done_count % report == 0:
                print(f"socnav.evaluate: {name} on {_config_name(config)}: {done_count}/{episodes} episodes", file=sys.stderr)
        restart = np.zeros(n, dtype=bool)
        seeds: list[int | None] = [None] * n
        for e in ended:
            if next_k < episodes:
                playing[e] = next_k
                seeds[e] = (seed + next_k) % limit
                restart[e] = True
                next_k += 1
            else:
                playing[e] = -1
        if restart.any():
            obs, _ = env.reset(seed=seeds, options={"reset_mask": restart})
    log = EpisodeLog()
    log.add_rows(rows)
    return Evaluation(
        policy=name,
        config=_config_name(config),
        seed=int(seed),
        seeds=np.array([(seed + k) % limit for k in range(episodes)], dtype=np.uint64),
        log=log,
        wall_seconds=time.perf_counter() - start,
        endings=endings,
    )


def config_for(config: Any, act: Any) -> Any:
    """``config`` with what the policy ``act`` needs of it (its ``config_overrides``, e.g. the
    robot's velocity in its record)."""
    overrides = getattr(act, "config_overrides", None)
    return with_overrides(config, overrides) if overrides else config


def _state_of(batch: Any, env: int) -> dict[str, Any]:
    document: dict[str, Any] = json.loads(batch.get_state(env))
    return document


def classify_ending(stats: Mapping[str, float], state: Callable[[], Mapping[str, Any]]) -> str:
    """How an episode ended (:data:`ENDINGS`), from its statistics (``info["episode"]``) and,
    for a collision, ``state()``: the state document it ended in (``Batch.get_state``).

    A collision is robot-caused when the robot touches a table, laptop, plant or wall, or when,
    for some person it touches, the robot moved toward that person, at least as fast as the
    person moved toward the robot (both along the line between their centres, from the velocities
    of the step that ended in contact); person-caused otherwise: every person it touches walked
    into a robot that was still, receding or slower."""
    if stats["success"]:
        return "success"
    if stats["collision"]:
        if stats["collision_object"] or stats["collision_wall"] or not stats["collision_human"]:
            return "robot-caused"
        return _human_contact_cause(state())
    if stats["out_of_map"]:
        return "out-of-map"
    return "timeout"


def _human_contact_cause(document: Mapping[str, Any]) -> str:
    state = document["state"]
    robot = state["robot"]
    r = np.array([robot["x"], robot["y"]], dtype=np.float64)
    heading = float(robot["theta"])
    vx, vy = float(robot["vel"][0]), float(robot["vel"][1])
    # The command is in the robot's frame (x forward, y left).
    v_robot = np.array([vx * math.cos(heading) - vy * math.sin(heading), vx * math.sin(heading) + vy * math.cos(heading)])
    gaps = []
    for h in state["humans"]:
        p = np.array([h["x"], h["y"]], dtype=np.float64)
        gaps.append((float(np.linalg.norm(p - r)) - float(h["radius"]) - float(robot["radius"]), h, p))
    if not gaps:
        return "robot-caused"
    nearest = min(g for g, _, _ in gaps)
    touching = [(h, p) for g, h, p in gaps if g <= max(nearest, 0.0) + _CONTACT_SLACK]
    for h, p in touching:
        away = p - r
        u = away / max(float(np.linalg.norm(away)), 1e-12)
        v_human = float(h["speed"]) * np.array([math.cos(float(h["theta"])), math.sin(float(h["theta"]))])
        robot_toward = float(v_robot @ u)
        human_toward = float(v_human @ -u)
        # A still or receding robot causes nothing (a person grazing it while walking past, whose
        # own approach speed is 0 or less, walked into it all the same).
        if robot_toward > 0.0 and robot_toward >= human_toward:
            return "robot-caused"
    return "person-caused"


def _config_name(config: Any) -> str:
    if isinstance(config, str):
        return config
    if isinstance(config, Mapping) and "base" in config:
        return f"{config['base']}+overrides"
    return "custom"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m socnav.evaluate",
        description="The paper's table for a policy: means and 95 % confidence intervals over fixed episode seeds.",
    )
    parser.add_argument("policy", help="goal, orca, random, or a checkpoint name or path")
    parser.add_argument("--config", default="exp1")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0, help="episode k has seed SEED + k")
    parser.add_argument("--num-envs", type=int, default=None)
    parser.add_argument("--backend", default="cpu")
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--csv", default=None, help="write the table as CSV here")
    parser.add_argument("--episodes-csv", default=None, help="write every episode's statistics and seed here")
    args = parser.parse_args(argv)
    result = evaluate(
        args.policy,
        args.config,
        episodes=args.episodes,
        seed=args.seed,
        num_envs=args.num_envs,
        backend=args.backend,
        threads=args.threads,
        progress=True,
    )
    print(result.to_markdown())
    endings = ", ".join(f"{n} {e}" for e, n in result.ending_counts().items() if n)
    print(f"\nendings: {endings}")
    print(f"\n{result.episodes} episodes (seeds {args.seed}..{args.seed + result.episodes - 1}) in {result.wall_seconds:.1f} s")
    if args.csv:
        result.to_csv(args.csv)
    if args.episodes_csv:
        rows = result.episode_rows()
        keys = ["seed", *EPISODE_KEYS]
        with open(args.episodes_csv, "w", encoding="utf-8") as f:
            f.write(",".join(keys) + "\n")
            for i in range(result.episodes):
                f.write(",".join(str(int(rows["seed"][i])) if k == "seed" else f"{rows[k][i]:.9g}" for k in keys) + "\n")
    return 0

