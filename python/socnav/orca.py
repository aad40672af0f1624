"""ORCA (optimal reciprocal collision avoidance) exactly as RVO2 2.0.3 computes it.

:func:`compute_velocities` gives the new velocities of one ``RVOSimulator::doStep`` on a scene
of agents and polygon obstacles: the same float32 arithmetic in the same order, and RVO2's k-d
tree neighbour order, so the result is RVO2's bit for bit. :func:`compute_velocities_batch`
solves many independent scenes in parallel. Both run in Rust with the GIL released.

Units: positions and lengths in metres (m), velocities in metres per second (m/s), times in
seconds (s).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from socnav import _socnav

__all__ = ["compute_velocities", "compute_velocities_batch"]

# compute_velocities' arguments, in the extension's order.
_ARGUMENTS = (
    "positions",
    "velocities",
    "pref_velocities",
    "radius",
    "max_speed",
    "neighbor_dist",
    "max_neighbors",
    "time_horizon",
    "time_horizon_obst",
    "time_step",
    "obstacles",
)
_REQUIRED = _ARGUMENTS[:-1]
# RVO2 stores maxNeighbors as a size_t; the Rust core keeps it as u32.
_MAX_NEIGHBORS_LIMIT = 2**32 - 1


def _short(value: Any) -> str:
    """A repr that stays readable in an error message."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _real(name: str, value: Any) -> np.ndarray:
    """``value`` as a numpy array of real numbers (bool, complex, object and text rejected)."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} must be an array of real numbers, got {_short(value)}") from e
    if arr.dtype.kind not in "iuf":
        raise ValueError(
            f"{name} must be an array of real numbers, got dtype {arr.dtype}: {_short(value)}"
        )
    return arr


def _float32(name: str, arr: np.ndarray) -> np.ndarray:
    """``arr`` as float32; finite values too large for float32 are an error here (they would
    become infinities and be reported as such, which is not what the caller passed)."""
    with np.errstate(over="ignore", invalid="ignore"):
        out = arr.astype(np.float32)
    overflow = np.isfinite(arr) & ~np.isfinite(out)
    if overflow.any():
        where = tuple(int(i) for i in np.argwhere(overflow)[0])
        index = "" if arr.ndim == 0 else str(list(where))
        raise ValueError(
            f"{name}{index} = {arr[where].item()!r} does not fit in float32 (|x| <= 3.4e38)"
        )
    return out


def _vectors(name: str, value: Any, n: int | None) -> np.ndarray:
    """An ``(n, 2)`` float32 array (``n`` free when None)."""
    arr = _real(name, value)
    if arr.ndim != 2 or arr.shape[1] != 2 or (n is not None and arr.shape[0] != n):
        want = "(n, 2)" if n is None else f"({n}, 2) like positions"
        raise ValueError(f"{name} must have shape {want}, got shape {arr.shape}")
    return _float32(name, arr)


def _per_agent(name: str, value: Any, n: int) -> np.ndarray:
    """A scalar broadcast to ``(n,)``, or an ``(n,)`` array, as float32."""
    arr = _real(name, value)
    if arr.ndim == 0:
        arr = np.full(n, arr)
    elif arr.shape != (n,):
        raise ValueError(
            f"{name} must be a scalar or have shape ({n},), one value per agent, "
            f"got shape {arr.shape}"
        )
    return _float32(name, arr)


def _max_neighbors(value: Any, n: int) -> np.ndarray:
    """A scalar broadcast to ``(n,)``, or an ``(n,)`` array, of whole numbers as int64."""
    arr = _real("max_neighbors", value)
    scalar = arr.ndim == 0
    if scalar:
        arr = np.full(n, arr)
    elif arr.shape != (n,):
        raise ValueError(
            f"max_neighbors must be a scalar or have shape ({n},), one value per agent, "
            f"got shape {arr.shape}"
        )
    with np.errstate(invalid="ignore"):
        whole = np.isfinite(arr) & (np.floor(arr) == arr) if arr.dtype.kind == "f" else True
        bad = ~(whole & (arr >= 0) & (arr <= _MAX_NEIGHBORS_LIMIT))
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        where = "" if scalar else f"[{i}]"
        raise ValueError(
            f"max_neighbors{where} = {arr[i].item()!r}: must be an integer in "
            f"[0, {_MAX_NEIGHBORS_LIMIT}]"
        )
    return arr.astype(np.int64)


def _obstacles(value: Any) -> list[np.ndarray]:
    """A list of ``(k, 2)`` float32 vertex arrays."""
    if value is None:
        return []
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, (Sequence, np.ndarray)):
        raise ValueError(
            f"obstacles must be a list of (k, 2) vertex arrays, got {type(value).__name__}"
        )
    polygons = []
    for p, polygon in enumerate(value):
        name = f"obstacles[{p}]"
        arr = _real(name, polygon)
        if arr.size == 0:
            # An empty polygon: the core says it has 0 vertices, which is the real problem.
            arr = arr.reshape(0, 2)
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise ValueError(
                f"{name} must have shape (k, 2), k vertices, got shape {arr.shape} "
                "(obstacles is a list of polygons, even for a single one)"
            )
        polygons.append(_float32(name, arr))
    return polygons


def _time_step(value: Any) -> float:
    arr = _real("time_step", value)
    if arr.ndim != 0:
        raise ValueError(f"time_step must be a scalar, got shape {arr.shape}")
    return float(_float32("time_step", arr))


def _prepare(
    positions: Any,
    velocities: Any,
    pref_velocities: Any,
    radius: Any,
    max_speed: Any,
    neighbor_dist: Any,
    max_neighbors: Any,
    time_horizon: Any,
    time_horizon_obst: Any,
    time_step: Any,
    obstacles: Any = None,
) -> tuple[Any, ...]:
    """The extension's arguments, in its order: shapes checked, scalars broadcast, float32
    (int64 for ``max_neighbors``). Values are checked in Rust."""
    pos = _vectors("positions", positions, None)
    n = pos.shape[0]
    return (
        pos,
        _vectors("velocities", velocities, n),
        _vectors("pref_velocities", pref_velocities, n),
        _per_agent("radius", radius, n),
        _per_agent("max_speed", max_speed, n),
        _per_agent("neighbor_dist", neighbor_dist, n),
        _max_neighbors(max_neighbors, n),
        _per_agent("time_horizon", time_horizon, n),
        _per_agent("time_horizon_obst", time_horizon_obst, n),
        _time_step(time_step),
        _obstacles(obstacles),
    )


def compute_velocities(
    positions: Any,
    velocities: Any,
    pref_velocities: Any,
    radius: Any,
    max_speed: Any,
    neighbor_dist: Any,
    max_neighbors: Any,
    time_horizon: Any,
    time_horizon_obst: Any,
    time_step: Any,
    obstacles: Sequence[Any] | None = None,
) -> np.ndarray:
    """New ORCA velocities of all agents: one RVO2 2.0.3 ``doStep``'s velocity computation.

    Every agent avoids its nearest agent neighbours (each taking half of the avoidance, the
    "reciprocal" in ORCA) and the obstacle edges near it, and gets the velocity closest to its
    preferred velocity that the resulting half-plane constraints and its speed limit allow.
    Every agent sees the others' state at the start of the step. The result equals
    ``RVOSimulator::doStep`` on a fresh simulator holding the same agents and obstacles, bit for
    bit (float32 arithmetic in RVO2's order, RVO2's k-d tree neighbour order). Positions are not
    advanced: RVO2 would then move each agent by ``new_velocity * time_step``.

    Inputs are converted to float32, the precision RVO2 computes in. Each per-agent parameter
    may be a scalar (shared by all agents) or an array of shape ``(n,)``.

    Parameters
    ----------
    positions : array_like, shape (n, 2)
        Agent centres (m).
    velocities : array_like, shape (n, 2)
        Current velocities (m/s): the velocities used in the previous step. Neighbours'
        velocities set how the avoidance is shared.
    pref_velocities : array_like, shape (n, 2)
        Preferred velocities (m/s), usually towards each agent's goal. Not clipped by RVO2 beyond
        the speed limit of the result.
    radius : float or array_like, shape (n,)
        Agent disc radii (m), >= 0. Two agents keep their centres ``radius_i + radius_j`` apart;
        an agent keeps ``radius_i`` from obstacle edges.
    max_speed : float or array_like, shape (n,)
        Speed limits (m/s), >= 0: every new velocity lies in the disc of this radius.
    neighbor_dist : float or array_like, shape (n,)
        Only agents whose centres are strictly closer than this (m), >= 0, are avoided.
    max_neighbors : int or array_like of int, shape (n,)
        At most this many nearest agents within ``neighbor_dist`` are avoided; 0 disables
        avoidance of other agents (obstacles are still avoided).
    time_horizon : float or array_like, shape (n,)
        RVO2's ``timeHorizon`` (s), > 0: velocities are safe with respect to other agents for at
        least this long. Larger values make agents react earlier.
    time_horizon_obst : float or array_like, shape (n,)
        RVO2's ``timeHorizonObst`` (s), > 0: the same for obstacles. Obstacle edges within
        ``time_horizon_obst * max_speed + radius`` (m) are considered.
    time_step : float
        Simulation time step (s), > 0. Only used when two agents already overlap: they then aim
        to separate within one step.
    obstacles : sequence of array_like, each of shape (k, 2), optional
        Obstacle polygons (m), RVO2 convention: vertices in **counter-clockwise** order for an
        obstacle that agents stay outside of (clockwise order makes the inside the free space,
        e.g. a room's walls); a polygon closes itself, so do not repeat the first vertex. A
        2-vertex polygon is a line segment that blocks from both sides. Polygons need not be
        convex. Default: no obstacles.

    Returns
    -------
    numpy.ndarray, shape (n, 2), float32
        The new velocities (m/s), a new array in agent order.

    Raises
    ------
    ValueError
        On any invalid input, with the argument, index and value in the message: a wrong shape,
        a value that is not a real number, NaN or infinity anywhere, a negative ``radius``,
        ``max_speed`` or ``neighbor_dist``, a non-positive time horizon or ``time_step``, a
        ``max_neighbors`` that is not a whole number >= 0, an obstacle with fewer than 2
        vertices. A repeated vertex (a zero-length edge) is taken as RVO2 takes it: that edge's
        direction is NaN and never reaches a velocity through RVO2's own arithmetic.

    See Also
    --------
    compute_velocities_batch : many independent scenes in parallel.

    Notes
    -----
    Agents at exactly the same position with the same velocity make RVO2 divide 0 by 0; the
    result is then NaN for them, as in RVO2. Agents already overlapping an obstacle or each
    other are pushed apart as RVO2 does. When the constraints cannot all be met, RVO2's third
    linear program picks the velocity that violates the agent constraints least while keeping
    the obstacle constraints.

    Examples
    --------
    Two agents walking head-on each turn to their right, symmetrically:

    >>> import numpy as np
    >>> from socnav.orca import compute_velocities
    >>> v = compute_velocities(
    ...     positions=[[-2.0, 0.0], [2.0, 0.0]],
    ...     velocities=[[1.0, 0.0], [-1.0, 0.0]],
    ...     pref_velocities=[[1.0, 0.0], [-1.0, 0.0]],
    ...     radius=0.3, max_speed=1.0, neighbor_dist=10.0, max_neighbors=10,
    ...     time_horizon=5.0, time_horizon_obst=5.0, time_step=0.25,
    ... )
    >>> v.round(4)
    array([[ 0.9775, -0.1483],
           [-0.9775,  0.1483]], dtype=float32)
    """
    args = _prepare(
        positions,
        velocities,
        pref_velocities,
        radius,
        max_speed,
        neighbor_dist,
        max_neighbors,
        time_horizon,
        time_horizon_obst,
        time_step,
        obstacles,
    )
    return _socnav.orca_compute_velocities(*args)


def compute_velocities_batch(scenes: Sequence[Mapping[str, Any]]) -> list[np.ndarray]:
    """:func:`compute_velocities` for many independent scenes, solved in parallel.

    Parameters
    ----------
    scenes : sequence of mappings
        One mapping per scene with the keyword arguments of :func:`compute_velocities`
        (``positions``, ``velocities``, ``pref_velocities``, ``radius``, ``max_speed``,
        ``neighbor_dist``, ``max_neighbors``, ``time_horizon``, ``time_horizon_obst``,
        ``time_step`` and optionally ``obstacles``), with the same units and broadcasting.
        Scenes may have different numbers of agents.

    Returns
    -------
    list of numpy.ndarray
        One float32 ``(n_s, 2)`` array of new velocities (m/s) per scene, in scene order. Each
        equals ``compute_velocities(**scene)`` exactly, whatever the number of threads.

    Raises
    ------
    ValueError
        As :func:`compute_velocities`, prefixed with ``scenes[i]:``; also for a missing or
        unknown key. Keys, types and shapes of all scenes are checked before any value, so the
        error names the first scene with a bad shape, else the first with a bad value.
    """
    if isinstance(scenes, (str, bytes, Mapping)) or not isinstance(scenes, Sequence):
        raise ValueError(f"scenes must be a list of dicts, got {type(scenes).__name__}")
    columns: list[list[Any]] = [[] for _ in _ARGUMENTS]
    for s, scene in enumerate(scenes):
        if not isinstance(scene, Mapping):
            raise ValueError(f"scenes[{s}] must be a dict of arguments, got {type(scene).__name__}")
        unknown = sorted(set(scene) - set(_ARGUMENTS))
        missing = [k for k in _REQUIRED if k not in scene]
        if unknown or missing:
            problems = [f"unknown keys {unknown}"] if unknown else []
            problems += [f"missing keys {missing}"] if missing else []
            raise ValueError(f"scenes[{s}]: " + ", ".join(problems))
        try:
            args = _prepare(**scene)
        except ValueError as e:
            raise ValueError(f"scenes[{s}]: {e}") from e
        for column, arg in zip(columns, args):
            column.append(arg)
    return _socnav.orca_compute_velocities_batch(*columns)
