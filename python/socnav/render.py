"""Watching: frames of environments as images, and animations of a policy's episodes.

``socnav.make(config, render_mode="rgb_array")`` and ``socnav.make_vec(..., render_mode="rgb_array")``
draw environments from above with socnav's renderer (the one of ``socnav render``: humans by role,
groups, laptops, tables, plants, walls, the robot with its trail and goal, the ORCA shadow robot);
``render()`` returns uint8 ``(H, W, 3)`` frames. ``metadata["render_fps"]`` is one frame per
simulated time step, so ``gymnasium.wrappers.RecordVideo`` plays episodes in real time.
``render_mode="human"`` shows the same frames in a window (socnav's viewer, the one of
``socnav play``) as the environment steps, paced at ``render_fps``, with a panel of the step,
reward and return beside them; without a display the first frame raises ``socnav.DisplayError``.

:func:`record` writes a GIF (or an MP4 when ``imageio`` with its ffmpeg plugin is installed) of
one or several policies playing the same episodes, side by side::

    socnav.record({"goal": "goal", "orca": "orca"}, "exp2", "exp2.gif", seed=3)
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from socnav import _socnav

__all__ = ["HumanView", "Trails", "record", "tile"]

#: The render modes of socnav's environments.
RENDER_MODES = ("human", "rgb_array")


def check_render_mode(mode: str | None) -> str | None:
    if mode not in (None, *RENDER_MODES):
        raise ValueError(f"render_mode must be None, 'human' or 'rgb_array', got {mode!r}")
    return mode


class HumanView:
    """A window that shows frames as an environment steps (``render_mode="human"``), no faster
    than ``fps`` frames per second of wall time."""

    def __init__(self, title: str, fps: float) -> None:
        self._viewer = _socnav.Viewer(title)
        self._period = 1.0 / fps if fps > 0 else 0.0
        self._next = 0.0

    def show(self, frame: np.ndarray, lines: Sequence[str]) -> None:
        wait = self._next - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
        self._viewer.show(np.ascontiguousarray(frame), list(lines))
        self._next = max(time.perf_counter(), self._next) + self._period

    def poll(self) -> tuple[list[str], list[str]]:
        """The keys held and the commands pressed since the last call (``Viewer.poll``)."""
        return self._viewer.poll()

    def close(self) -> None:
        self._viewer.close()

#: Default longer side of a frame (px).
DEFAULT_SIZE = 400


class Trails:
    """The robot's path since its episode began, per environment, for drawing."""

    def __init__(self, num_envs: int) -> None:
        self._points: list[list[tuple[float, float]]] = [[] for _ in range(num_envs)]

    def restart(self, envs: Any = None) -> None:
        """Forget the paths of ``envs`` (all when None)."""
        for e in range(len(self._points)) if envs is None else np.flatnonzero(envs):
            self._points[e].clear()

    def add(self, poses: np.ndarray, envs: Sequence[int] | None = None) -> None:
        """Append the (x, y) of ``envs`` (all when None) from ``poses`` (``(n, 3)``)."""
        for e in range(len(self._points)) if envs is None else envs:
            self._points[e].append((float(poses[e, 0]), float(poses[e, 1])))

    def of(self, env: int) -> np.ndarray:
        return np.asarray(self._points[env], dtype=np.float32).reshape(-1, 2)


def tile(frames: Sequence[np.ndarray], columns: int | None = None, gap: int = 4) -> np.ndarray:
    """Frames of one size side by side in a grid of ``columns`` (default: a near-square grid),
    separated by ``gap`` white pixels."""
    if not frames:
        raise ValueError("tile needs at least one frame")
    h, w, _ = frames[0].shape
    for i, f in enumerate(frames):
        if f.shape != frames[0].shape:
            raise ValueError(f"frame {i} has shape {f.shape}, frame 0 {frames[0].shape}")
    cols = columns or math.ceil(math.sqrt(len(frames)))
    rows = math.ceil(len(frames) / cols)
    out = np.full((rows * h + (rows - 1) * gap, cols * w + (cols - 1) * gap, 3), 255, np.uint8)
    for i, f in enumerate(frames):
        r, c = divmod(i, cols)
        out[r * (h + gap) : r * (h + gap) + h, c * (w + gap) : c * (w + gap) + w] = f
    return out


def _write(path: Path, frames: list[np.ndarray], frame_ms: int) -> None:
    if path.suffix.lower() == ".gif":
        _socnav.write_gif(str(path), frames, frame_ms)
        return
    if path.suffix.lower() == ".mp4":
        try:
            import imageio.v2 as imageio
        except ImportError as e:
            raise ImportError("writing MP4 needs imageio and imageio-ffmpeg: pip install imageio imageio-ffmpeg") from e
        # H.264 wants even sides.
        frames = [f[: f.shape[0] // 2 * 2, : f.shape[1] // 2 * 2] for f in frames]
        imageio.mimwrite(str(path), frames, fps=1000.0 / frame_ms, macro_block_size=1)
        return
    raise ValueError(f"{path}: unknown extension (use .gif or .mp4)")


def _frame(env: Any) -> np.ndarray:
    """The one frame of a rendering one-environment vector env."""
    frames = env.render()
    assert frames is not None, "made with render_mode='rgb_array'"
    return frames[0]


def record(
    policies: Any,
    config: str | Mapping[str, Any],
    path: str | Path,
    *,
    seed: int = 0,
    episodes: int = 1,
    size: int = DEFAULT_SIZE,
    speedup: float = 10.0,
) -> Path:
    """Animate ``policies`` playing the episodes of seeds ``seed .. seed + episodes - 1``.

    Parameters
    ----------
    policies : policy, or mapping from a label to a policy
        As :func:`socnav.evaluate` takes them (a built-in name, an agent name or path, a
        callable); several are drawn side by side, each on the same episodes.
    config : str or mapping
        As ``socnav.make_vec``.
    path : str or Path
        ``.gif`` (always available) or ``.mp4`` (needs imageio and imageio-ffmpeg).
    speedup : float
        Simulated seconds per second of animation (the paper's configs step 1 s).

    Returns
    -------
    Path
        ``path``.
    """
    import socnav
    from socnav._batch import check_count, check_seed
    from socnav.evaluation import config_for, resolve_policy

    episodes = check_count("episodes", episodes)
    size = check_count("size", size)
    seed = check_seed(seed)
    if not speedup > 0:
        raise ValueError(f"speedup must be positive, got {speedup}")
    if not isinstance(policies, Mapping):
        policies = {"policy": policies}
    runs = []
    for label, p in policies.items():
        act, _ = resolve_policy(p, seed=seed)
        env = socnav.make_vec(
            config_for(config, act),
            num_envs=1,
            obs_mode=getattr(act, "obs_mode", "dict"),
            action_type=getattr(act, "action_type", "continuous"),
            autoreset_mode="disabled",
            render_mode="rgb_array",
            render_size=size,
        )
        runs.append((label, act, env))
    frames: list[np.ndarray] = []
    for k in range(episodes):
        states = []
        for _, act, env in runs:
            obs, _ = env.reset(seed=(seed + k) % (1 << 64))
            states.append({"obs": obs, "done": False, "frame": _frame(env)})
        while True:
            frames.append(tile([s["frame"] for s in states], columns=len(states)))
            if all(s["done"] for s in states):
                break
            for s, (_, act, env) in zip(states, runs):
                if s["done"]:
                    continue
                s["obs"], _, term, trunc, _ = env.step(act(s["obs"], env))
                s["frame"] = _frame(env)
                s["done"] = bool(term[0] or trunc[0])
    time_step = runs[0][2].unwrapped._batch.time_step
    path = Path(path)
    _write(path, frames, max(20, int(round(1000.0 * time_step / speedup))))
    return path
