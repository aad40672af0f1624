"""Episode metrics aggregated over many episodes as the paper's table does (docs/spec.md 8.3).

The per-episode statistics are computed in Rust when an episode ends and reach Python in the
vector environment's ``info["episode"]`` (one ``(num_envs,)`` array per key) on the steps where
``info["_episode"]`` marks finished episodes. :class:`EpisodeLog` collects those rows;
:func:`aggregate` averages them exactly as the Rust ``episodes::Aggregate`` (and so the
``socnav run`` command) does::

    env = socnav.make_vec("exp1", num_envs=64)
    log = EpisodeLog()
    obs, info = env.reset(seed=0)
    for _ in range(1000):
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        log.add(info)
    print(log.summary())

The statistics, in :data:`EPISODE_KEYS` order, and their units:

- ``return``: sum of the episode's rewards (reward units).
- ``length``: steps of the episode.
- ``success``, ``collision``, ``collision_human``, ``collision_object``, ``collision_wall``,
  ``timeout``, ``out_of_map``: outcome flags, 0 or 1, so their means are rates (a wall
  collision is also an object collision).
- ``time_taken``: steps; the config's episode length on collision.
- ``FAILURE_TO_PROGRESS``: steps that increased the distance to the goal.
- ``STALLED_TIME``: s with a zero linear command.
- ``TIME_TO_REACH_GOAL``: s on success, else the episode length *in steps* (0.1.1's
  evaluation script mixes the units).
- ``PATH_LENGTH``: m, the integrated commanded speed.
- ``V_MIN``, ``V_AVG``, ``V_MAX`` (m/s), ``A_MIN``, ``A_AVG``, ``A_MAX`` (m/s²),
  ``JERK_MIN``, ``JERK_AVG``, ``JERK_MAX`` (m/s³): the running statistics at the final step.
- ``PERSONAL_SPACE_COMPLIANCE``: fraction of the steps, in [0, 1].
- ``STL``, ``SPL``: in [0, 1], of the success step; 0 otherwise.
- ``MINIMUM_DISTANCE_TO_HUMAN``: m, minimum over the steps; +inf in an episode without humans.
- ``MINIMUM_OBSTACLE_DISTANCE``: m, minimum over the steps; +inf without obstacles.
- ``AVERAGE_OBSTACLE_DISTANCE``: m, mean over the steps.
- ``TIME_TO_COLLISION``: steps, mean over the steps (-1, no collision course, counted as the
  episode length).
- ``DISCOMFORT_DSRNN``, ``DISCOMFORT_SNGNN``: sums over the episode's steps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from socnav._socnav import Batch

#: The per-episode statistics, in the order of the Rust ``spec::EPISODE_KEYS``.
EPISODE_KEYS: tuple[str, ...] = tuple(Batch.keys()["episode"])

#: The statistics the ``socnav run`` command prints as the paper's metrics, in its order.
TABLE_KEYS: tuple[str, ...] = tuple(Batch.keys()["table"])

#: The episode statistics that are outcome flags, whose means are the outcome rates (the Rust
#: ``spec::OUTCOME_KEYS``).
_OUTCOMES: tuple[str, ...] = tuple(Batch.keys()["outcomes"])


def _keys(keys: Sequence[str]) -> tuple[str, ...]:
    """Statistic names as a tuple; one name alone is refused, not read as its characters."""
    if isinstance(keys, str):
        raise TypeError(f"keys is a sequence of statistic names, got the string {keys!r} (use [{keys!r}])")
    return tuple(keys)


@dataclass(frozen=True)
class Summary:
    """Means of the episode statistics over a set of finished episodes.

    Attributes
    ----------
    episodes : int
        Number of episodes aggregated.
    means : dict[str, float]
        Per statistic, the mean over the episodes in which it is finite; NaN when it is finite
        in none (or there are no episodes). The means of the outcome flags are rates in [0, 1].
    finite : dict[str, int]
        Per statistic, the number of episodes in which it is finite (the mean's denominator).
    """

    episodes: int
    means: dict[str, float] = field(repr=False)
    finite: dict[str, int] = field(repr=False)

    def __getitem__(self, key: str) -> float:
        """The mean of statistic ``key``."""
        try:
            return self.means[key]
        except KeyError:
            raise KeyError(f"unknown episode statistic {key!r}; known: {', '.join(self.means)}") from None

    def to_dict(self) -> dict[str, float]:
        """``{"episodes": count, **means}``: flat, e.g. for a logger or a JSON line."""
        return {"episodes": float(self.episodes), **self.means}

    def format(self, keys: Sequence[str] = TABLE_KEYS) -> str:
        """The summary as the ``socnav run`` command prints it: episode count and mean length,
        outcome rates in percent, then the means of ``keys`` four to a line."""
        pct = {k: 100.0 * self.means.get(k, float("nan")) for k in _OUTCOMES}
        lines = [
            f"episodes finished: {self.episodes} (mean length {self.means.get('length', float('nan')):.1f} steps)",
            "outcomes: success {success:.1f} %, collision {collision:.1f} % (human {collision_human:.1f} %, "
            "object {collision_object:.1f} %, wall {collision_wall:.1f} %), timeout {timeout:.1f} %, "
            "out of map {out_of_map:.1f} %".format(**pct),
            "metrics (means over finished episodes, as the paper's table):",
        ]
        # The table's keys this summary holds (a log of a few statistics prints those).
        keys = [k for k in _keys(keys) if k in self.means]
        for start in range(0, len(keys), 4):
            lines.append("".join(f"{k:>26} {self[k]:>9.4f}" for k in keys[start : start + 4]))
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.format()


def aggregate(
    rows: np.ndarray | Mapping[str, Any] | Sequence[Sequence[float]],
    keys: Sequence[str] = EPISODE_KEYS,
) -> Summary:
    """Average episode statistics over episodes as the paper's table (docs/spec.md 8.3) does.

    The mean of each statistic skips the episodes in which it is not finite: e.g. the +inf
    ``MINIMUM_DISTANCE_TO_HUMAN`` of an episode without humans does not count towards that
    key's mean (it still counts in ``episodes`` and in every other key's mean). This is the
    rule of the Rust ``episodes::Aggregate::mean``, and the arithmetic is the same too: the
    float32 values are summed in float64 in episode order and divided by the number of finite
    values, so for the same episodes in the same order the means equal Rust's bit for bit.

    Parameters
    ----------
    rows : array_like of shape (n_episodes, len(keys)), or mapping
        One row per episode with the statistics in ``keys`` order, or a mapping from each key
        to an ``(n_episodes,)`` array (e.g. :meth:`EpisodeLog.table`); extra mapping keys are
        ignored.
    keys : sequence of str, default :data:`EPISODE_KEYS`
        Names of the columns.

    Returns
    -------
    Summary
        The episode count and the per-key means (NaN for a key finite in no episode).
    """
    keys = tuple(keys)
    data = _as_rows(rows, keys)
    n = data.shape[0]
    values = data.astype(np.float64)
    finite = np.isfinite(values)
    # Sequential sums (cumulative, not numpy's pairwise reduction) so that the rounding is
    # Rust's: adding 0.0 where a value is skipped leaves a float64 sum unchanged.
    sums = np.cumsum(np.where(finite, values, 0.0), axis=0)[-1] if n else np.zeros(len(keys))
    counts = finite.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = np.where(counts > 0, sums / np.maximum(counts, 1), np.nan)
    return Summary(
        episodes=n,
        means={k: float(m) for k, m in zip(keys, means)},
        finite={k: int(c) for k, c in zip(keys, counts)},
    )


def _as_rows(rows: Any, keys: tuple[str, ...]) -> np.ndarray:
    """``rows`` as a float32 ``(n, len(keys))`` array (a copy)."""
    if isinstance(rows, Mapping):
        missing = [k for k in keys if k not in rows]
        if missing:
            raise KeyError(f"episode statistics missing: {', '.join(missing)}")
        columns = [np.asarray(rows[k], dtype=np.float32).reshape(-1) for k in keys]
        lengths = {c.shape[0] for c in columns}
        if len(lengths) > 1:
            raise ValueError(f"episode statistics of different lengths: {sorted(lengths)}")
        return np.stack(columns, axis=1) if columns else np.zeros((0, 0), np.float32)
    data = np.array(rows, dtype=np.float32, copy=True)
    if data.ndim == 1 and data.shape[0] == len(keys):
        data = data.reshape(1, -1)
    if data.ndim != 2 or data.shape[1] != len(keys):
        raise ValueError(
            f"episode rows must have shape (n, {len(keys)}) (one value per key), got {data.shape}"
        )
    return data


class EpisodeLog:
    """The statistics of finished episodes, collected step by step.

    Parameters
    ----------
    keys : sequence of str, default :data:`EPISODE_KEYS`
        The statistics to keep, in column order.

    Notes
    -----
    Every ``add`` copies the rows: the vector environment's info arrays may be views of
    buffers the next step overwrites. Each episode takes ``4 * len(keys)`` bytes (128 bytes
    with every key).
    """

    def __init__(self, keys: Sequence[str] = EPISODE_KEYS) -> None:
        self.keys: tuple[str, ...] = _keys(keys)
        self._chunks: list[np.ndarray] = []
        self._rows: np.ndarray | None = np.zeros((0, len(self.keys)), np.float32)
        self._count = 0

    def __len__(self) -> int:
        """Number of episodes collected."""
        return self._count

    @property
    def episodes(self) -> int:
        """Number of episodes collected."""
        return self._count

    def add(self, info: Mapping[str, Any] | Sequence[Mapping[str, Any]]) -> int:
        """Collect the episodes that ended in one step.

        Parameters
        ----------
        info : dict or list of dict
            A ``socnav.make_vec`` environment's step ``info`` (episodes where
            ``info["_episode"]`` is true are taken from ``info["episode"]``; a step where none
            ended has no ``"_episode"`` and adds nothing), or the list of per-environment info
            dicts of a Stable-Baselines3 VecEnv (``socnav.sb3``), whose finished environments
            carry the statistics in ``infos[i]["episode"]``.

        Returns
        -------
        int
            Number of episodes added.
        """
        if isinstance(info, Mapping):
            mask = info.get("_episode")
            if mask is None:
                return 0
            mask = np.asarray(mask, dtype=bool)
            if not mask.any():
                return 0
            episode = info["episode"]
            return self.add_rows({k: np.asarray(episode[k])[mask] for k in self.keys})
        added = 0
        for env_info in info:
            episode = env_info.get("episode")
            if episode is not None:
                added += self.add_rows(episode)
        return added

    def add_rows(self, rows: np.ndarray | Mapping[str, Any] | Sequence[Sequence[float]]) -> int:
        """Collect episodes given as raw rows.

        Parameters
        ----------
        rows : array_like of shape (n, len(keys)) or (len(keys),), or mapping
            Rows in ``keys`` order (one 1-D row is one episode), or a mapping from each key to
            a scalar or an ``(n,)`` array; other mapping keys are ignored (e.g. SB3's
            ``"r"``, ``"l"``, ``"t"``).

        Returns
        -------
        int
            Number of episodes added.
        """
        data = _as_rows(rows, self.keys)
        if data.shape[0]:
            self._chunks.append(data)
            self._rows = None
            self._count += data.shape[0]
        return int(data.shape[0])

    def extend(self, other: EpisodeLog) -> None:
        """Append every episode of ``other`` (whose keys must be the same)."""
        if other.keys != self.keys:
            raise ValueError("the logs keep different statistics")
        self.add_rows(other.rows())

    def clear(self) -> None:
        """Forget every episode."""
        self._chunks.clear()
        self._rows = np.zeros((0, len(self.keys)), np.float32)
        self._count = 0

    def rows(self) -> np.ndarray:
        """All episodes as a float32 ``(episodes, len(keys))`` array, in the order added.

        The array is owned by the log; do not modify it."""
        if self._rows is None:
            self._rows = np.concatenate(self._chunks, axis=0)
            self._chunks = [self._rows]
        return self._rows

    def summary(self) -> Summary:
        """The means over the collected episodes (see :func:`aggregate`: statistics that are
        not finite in an episode, e.g. +inf minimum distances without humans, do not count
        towards that key's mean)."""
        return aggregate(self.rows(), self.keys)

    def mean(self, key: str) -> float:
        """The mean of one statistic over the episodes where it is finite (NaN if none)."""
        return self.summary()[key]

    def table(self, as_pandas: bool = False) -> Any:
        """Every collected episode, one row each, in the order added.

        Parameters
        ----------
        as_pandas : bool, default False
            ``False``: a dict from each key to a float32 ``(episodes,)`` array (a copy).
            ``True``: a ``pandas.DataFrame`` with one column per key; raises ``ImportError``
            when pandas is not installed. The return type depends on this argument only,
            never on what is installed.

        Returns
        -------
        dict[str, numpy.ndarray] or pandas.DataFrame
        """
        rows = self.rows()
        columns = {k: rows[:, j].copy() for j, k in enumerate(self.keys)}
        if not as_pandas:
            return columns
        try:
            import pandas as pd
        except ImportError as e:
            raise ImportError("EpisodeLog.table(as_pandas=True) needs pandas: pip install pandas") from e
        return pd.DataFrame(columns)

    def __repr__(self) -> str:
        return f"EpisodeLog({self._count} episodes, {len(self.keys)} statistics)"

