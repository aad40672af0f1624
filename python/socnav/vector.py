"""``SocNavVectorEnv``: a gymnasium vector environment over a Rust batch.

Observations, rewards and the info arrays are views of buffers the batch owns and overwrites
at every ``step`` and ``reset`` (``np.shares_memory`` holds between two steps' results); pass
``copy=True`` to get fresh arrays instead, e.g. to keep observations in a replay buffer.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np
import gymnasium as gym
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from socnav import _batch
from socnav._socnav import Batch, UsageError
from socnav.pinned import PinnedBuffers
from socnav.render import RENDER_MODES, HumanView, Trails, check_render_mode, tile

_AUTORESET = {
    "next_step": AutoresetMode.NEXT_STEP,
    "same_step": AutoresetMode.SAME_STEP,
    "disabled": AutoresetMode.DISABLED,
}


class SocNavVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` environments of one config stepping together (see ``make_vec``)."""

    # Class-level defaults, so that ``close`` (which gymnasium's ``__del__`` calls) finds them on
    # an environment whose ``__init__`` raised before setting them (a bad config or backend).
    _human: HumanView | None = None
    _pinned: PinnedBuffers | None = None

    def __init__(
        self,
        config: str | Mapping[str, Any] = "exp1",
        num_envs: int = 1,
        *,
        seed: int | None = None,
        obs_mode: str = "dict",
        action_type: str = "continuous",
        autoreset_mode: str | AutoresetMode = "next_step",
        backend: str = "cpu",
        threads: int | None = None,
        copy: bool = False,
        reward_fn: _batch.RewardFn | None = None,
        render_mode: str | None = None,
        render_envs: Sequence[int] | None = None,
        render_size: int = 400,
        step_info: bool = True,
    ) -> None:
        mode = autoreset_mode.value if isinstance(autoreset_mode, AutoresetMode) else autoreset_mode
        _batch.check_choice("autoreset_mode", mode, tuple(_AUTORESET))
        self.obs_mode = _batch.check_choice("obs_mode", obs_mode, _batch.OBS_MODES)
        self.action_type = _batch.check_choice("action_type", action_type, _batch.ACTION_TYPES)
        self.copy = copy
        self.config = config
        if reward_fn is not None and not callable(reward_fn):
            raise TypeError(f"reward_fn must be callable (a function of RewardInputs), got {reward_fn!r}")
        if reward_fn is not None and not step_info:
            raise ValueError("step_info=False leaves out the metrics that a reward_fn reads (its inputs' info)")
        self.step_info = bool(step_info)
        size = _batch.check_count("render_size", render_size)
        self._batch: Batch = _batch.build_batch(config, num_envs, seed, mode, threads, backend)
        # What this env hands out of a step: the observation, reward and flags, the metrics
        # unless ``step_info=False``, never the interactions or events; the GPU backend reads
        # back nothing else.
        self._batch.set_step_outputs(info=self.step_info, interactions=False, events=False)
        self.num_envs = self._batch.num_envs
        self.metadata = {
            "autoreset_mode": _AUTORESET[mode],
            "render_modes": list(RENDER_MODES),
            "render_fps": 1.0 / self._batch.time_step,
        }
        self.render_mode = check_render_mode(render_mode)
        self._human = None
        self._steps = 0
        self.render_size = size
        self.render_envs = list(range(min(self.num_envs, 4))) if render_envs is None else [int(e) for e in render_envs]
        bad = [e for e in self.render_envs if not 0 <= e < self.num_envs]
        if bad:
            raise ValueError(f"render_envs {bad} out of range 0..{self.num_envs}")
        self._trails = Trails(self.num_envs)
        self._layout = self._batch.layout()
        self._keys = Batch.keys()
        self.single_observation_space = _batch.observation_space(self._batch, obs_mode)
        self.single_action_space = _batch.action_space(self._batch, action_type)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._buf = self._batch.buffers()
        self._all = np.ones(self.num_envs, dtype=bool)
        self._reward_fn = reward_fn
        # With a reward function: its rewards and their running episode returns.
        self._reward = np.zeros(self.num_envs, dtype=np.float32)
        self._returns = np.zeros(self.num_envs, dtype=np.float64)
        #: Steps each environment's current episode has taken: 0 at its first observation (an
        #: agent with memory reads it to forget the previous episode).
        self.episode_steps = np.zeros(self.num_envs, dtype=np.int64)
        # Environments whose episode ended and has not restarted yet: their next step is a reset
        # under NEXT_STEP, nothing under DISABLED until `reset_mask` restarts them.
        self._over = np.zeros(self.num_envs, dtype=bool)
        # The actions of a step sent and not yet received.
        self._sent: Any = None
        self._pinned = None

    @property
    def backend(self) -> str:
        """The backend stepping the batch: ``"cpu"`` or ``"gpu"``."""
        return self._batch.backend

    @property
    def device(self) -> str:
        """What runs the batch: the CPU threads, or the GPU adapter."""
        return self._batch.device

    def pin_memory(self) -> int:
        """Page-lock the batch's output buffers for CUDA (``cudaHostRegister``, through torch),
        so that tensors over them (``torch.from_numpy(obs)``) are pinned and
        ``tensor.to("cuda", non_blocking=True)`` is an asynchronous DMA. Returns the bytes
        pinned; idempotent; undone by ``unpin_memory()`` or ``close()``.

        The next ``step`` overwrites the buffers, so the copy must have finished by then: a
        loop that brings the policy's actions back to the host (``.cpu()``) before stepping
        has waited for it. ``BackendUnavailableError`` without torch or a CUDA device."""
        if self.closed:
            raise UsageError("pin_memory on a closed environment")
        if self._pinned is None:
            self._pinned = PinnedBuffers(self._buf.values())
        return self._pinned.bytes

    def unpin_memory(self) -> None:
        """Undo ``pin_memory`` (nothing when the buffers are not pinned)."""
        if self._pinned is not None:
            self._pinned.release()
            self._pinned = None

    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[Any, dict[str, Any]]:
        """Reset every environment, or with ``options={"reset_mask": mask}`` only those where
        the boolean ``mask`` is true (the DISABLED autoreset mode's way to restart them).

        Every episode has one 64-bit episode seed, and the episode of seed ``e`` is the same in
        any batch, at any index, on any backend. ``seed=s`` gives environment ``i`` the episode
        of seed ``s + i`` (gymnasium's convention); a list gives each environment its own
        (``None``: its next one); without a seed each environment plays the next episode of
        its sequence. With a mask, only the masked environments' seeds are used.
        ``info["episode"]["seed"]`` reports the seed of every episode that ends."""
        if options is not None and not isinstance(options, Mapping):
            raise TypeError(f"options must be a dict (or None), got {type(options).__name__}")
        mask = (options or {}).get("reset_mask")
        if mask is not None:
            mask = np.asarray(mask)
            if mask.shape != (self.num_envs,) or mask.dtype != np.bool_:
                raise ValueError(
                    f"reset_mask must be a bool array of shape ({self.num_envs},), "
                    f"got {mask.dtype} {mask.shape}"
                )
        seeds = _batch.episode_seeds(seed, self.num_envs)
        if mask is not None:
            if seeds is not None:
                self._batch.set_next_seeds([s if m else None for s, m in zip(seeds, mask)])
            self._batch.reset_envs(np.ascontiguousarray(mask))
            self._returns[mask] = 0.0
            self.episode_steps[mask] = 0
            self._over[mask] = False
            self._track(restart=mask)
        else:
            if seeds is not None:
                self._batch.set_next_seeds(seeds)
            self._batch.reset(None)
            self._returns[:] = 0.0
            self.episode_steps[:] = 0
            self._over[:] = False
            self._track(restart=self._all)
            self._steps = 0
        if self.render_mode == "human":
            self._show(np.zeros(self.num_envs, dtype=np.float32))
        return self._obs(self._buf["obs"], self.copy), self._info(final=False)

    def step(self, actions: Any):
        _batch.step_batch(self._batch, self.action_type, actions, self.num_envs)
        return self._results(actions)

    def send(self, actions: Any) -> None:
        """Start a step with ``actions`` and return at once: the batch steps on its own threads
        (the GIL released) while the caller works, e.g. on a policy's next forward pass; ``recv``
        returns what ``step`` would have. Same seed and actions, same trajectory as ``step``.

        Between ``send`` and ``recv`` every other call on the environment raises
        ``socnav.UsageError``, and the arrays of the last results (views, unless ``copy=True``)
        are being overwritten: read them before ``send``. Bad actions raise here, and nothing is
        sent. To overlap a whole batch's inference with its simulation, split it in two
        environments and alternate: send one half's actions, then compute the other's
        (``benches/send_recv.py``; docs/scaling.md)."""
        _batch.step_batch(self._batch, self.action_type, actions, self.num_envs, send=True)
        self._sent = actions

    def recv(self):
        """Wait for the step ``send`` started and return ``(obs, reward, terminated, truncated,
        info)`` as ``step`` does (``socnav.UsageError`` when nothing was sent)."""
        self._batch.recv()
        actions, self._sent = self._sent, None
        return self._results(actions)

    def _results(self, actions: Any):
        """The step's results from the batch's buffers (``actions``: what the step was given,
        for a custom reward)."""
        b = self._buf
        terminated = b["terminated"].astype(bool)
        truncated = b["truncated"].astype(bool)
        ended = terminated | truncated
        same_step = self.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
        # From the episodes' state before this step: which environments it stepped, and which it
        # restarted instead (NEXT_STEP: those that had ended).
        stepped = self._all if same_step else ~self._over
        if self.render_mode is not None:
            next_step = self.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
            self._track(restart=ended if same_step else self._over & next_step)
        self._count_steps(ended)
        info = self._info(final=True)
        if self._reward_fn is None:
            reward = b["reward"].copy() if self.copy else b["reward"]
        else:
            reward = self._custom_reward(self._reward_fn, actions, stepped, terminated, truncated, info)
        self._steps += 1
        if self.render_mode == "human":
            self._show(reward)
        return self._obs(b["obs"], self.copy), reward, terminated, truncated, info

    def _count_steps(self, ended: np.ndarray) -> None:
        """``episode_steps`` after a step that ended the episodes ``ended``."""
        mode = self.metadata["autoreset_mode"]
        if mode == AutoresetMode.SAME_STEP:
            self.episode_steps += 1
            self.episode_steps[ended] = 0
        elif mode == AutoresetMode.NEXT_STEP:
            self.episode_steps = np.where(self._over, 0, self.episode_steps + 1)
            self._over = ended.copy()
        else:  # DISABLED: an ended environment waits for a masked reset
            self.episode_steps += ~self._over
            self._over |= ended

    # gymnasium 1.1 types the result as an unbound TypeVar (RenderFrame), which no concrete
    # type matches; later releases accept this one.
    def render(self) -> tuple[np.ndarray, ...] | None:  # type: ignore[override]
        """Frames of the environments ``render_envs`` (uint8 ``(H, W, 3)`` each, with the robot's
        path since its episode began) when ``render_mode="rgb_array"``; ``socnav.render.tile``
        puts them in one image. With ``"human"`` they are shown tiled in a window as the batch
        steps, paced at ``render_fps``."""
        if self.render_mode is None:
            return None
        frames = tuple(self._batch.render(e, self.render_size, self._trails.of(e)) for e in self.render_envs)
        return frames if self.render_mode == "rgb_array" else None

    def _show(self, reward: np.ndarray) -> None:
        frames = tuple(self._batch.render(e, self.render_size, self._trails.of(e)) for e in self.render_envs)
        if self._human is None:
            self._human = HumanView("socnav", self.metadata["render_fps"])
        lines = [f"socnav: environments {self.render_envs}", f"step {self._steps}"]
        lines += [f"env {e}: reward {float(reward[e]):+.4f}" for e in self.render_envs]
        self._human.show(tile(frames), lines)

    def close_extras(self, **kwargs: Any) -> None:
        if self._human is not None:
            self._human.close()
            self._human = None
        self.unpin_memory()
        batch: Batch | None = getattr(self, "_batch", None)  # None when __init__ raised before it
        if batch is not None:
            batch.close()

    def _track(self, restart: np.ndarray) -> None:
        """Record the robot poses for drawing (restarting the paths of ``restart``)."""
        if self.render_mode is None:
            return
        self._trails.restart(restart)
        self._trails.add(self._batch.robot_poses(), self.render_envs)

    def _custom_reward(
        self,
        reward_fn: _batch.RewardFn,
        actions: Any,
        stepped: np.ndarray,
        terminated: np.ndarray,
        truncated: np.ndarray,
        info: dict[str, Any],
    ) -> np.ndarray:
        """``reward_fn``'s rewards for this step (``stepped``: the environments it stepped); the
        episode returns in ``info`` become theirs."""
        b = self._buf
        flat = b["obs"]
        has_final = b["has_final"].astype(bool)
        if has_final.any():
            # SAME_STEP already reset these: score the observation the step reached.
            flat = np.where(has_final[:, None], b["final_obs"], flat)
        inputs = _batch.RewardInputs(
            actions=np.asarray(actions),
            obs=self._obs(flat, copy=False),
            reward=b["reward"],
            terminated=terminated,
            truncated=truncated,
            info={key: info[key] for key in self._keys["info"]},
            stepped=stepped,
        )
        reward = _batch.custom_reward(reward_fn, inputs, self._reward)
        self._returns += reward
        if "episode" in info:
            done = info["_episode"]
            info["episode"]["return"] = np.where(done, self._returns, info["episode"]["return"]).astype(np.float32)
            self._returns[done] = 0.0
        return reward.copy() if self.copy else reward

    def _obs(self, flat: np.ndarray, copy: bool) -> Any:
        """``flat`` (``(n, dim)``) as this env's observations: the row or the dict blocks."""
        if copy:
            flat = flat.copy()
        if self.obs_mode == "flat":
            return flat
        return _batch.split_obs(flat, self._layout)

    def _info(self, *, final: bool) -> dict[str, Any]:
        """Every metric as an array with its ``_key`` mask (all true: every environment reports
        every metric; none with ``step_info=False``); the statistics of episodes that just
        ended under ``"episode"``; under SAME_STEP the finishing steps' observation and info as
        ``final_obs`` / ``final_info``."""
        b = self._buf
        info: dict[str, Any] = {}
        if self.step_info:
            values = b["info"].copy() if self.copy else b["info"]
            for k, key in enumerate(self._keys["info"]):
                info[key] = values[:, k]
                info["_" + key] = self._all
        if final:
            done = b["episode_done"].astype(bool)
            if done.any():
                stats = b["episode"].copy()
                info["episode"] = {key: stats[:, k] for k, key in enumerate(self._keys["episode"])}
                info["episode"]["seed"] = _batch.seeds_of(b["episode_seed_lo"], b["episode_seed_hi"])
                info["_episode"] = done
            if self.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP:
                has_final = b["has_final"].astype(bool)
                if has_final.any():
                    # Copied: the finishing observation is kept past the next step.
                    info["final_obs"] = self._obs(b["final_obs"], copy=True)
                    info["_final_obs"] = has_final
                    final_info = b["final_info"].copy()
                    info["final_info"] = {
                        key: final_info[:, k] for k, key in enumerate(self._keys["info"])
                    }
                    info["_final_info"] = has_final
        return info


def make_vec(
    config: str | Mapping[str, Any] = "exp1",
    num_envs: int = 1,
    *,
    seed: int | None = None,
    obs_mode: str = "dict",
    action_type: str = "continuous",
    autoreset_mode: str | AutoresetMode = "next_step",
    backend: str = "cpu",
    threads: int | None = None,
    copy: bool = False,
    reward_fn: _batch.RewardFn | None = None,
    render_mode: str | None = None,
    render_envs: Sequence[int] | None = None,
    render_size: int = 400,
    step_info: bool = True,
) -> SocNavVectorEnv:
    """A vector environment of ``num_envs`` environments.

    Args:
        config: a shipped config name (``socnav.shipped_configs()``), a TOML or SocNavGym YAML
            path, or a dict of overrides in the TOML layout with an optional ``"base"`` name.
        seed: environment i's first episode has the episode seed ``seed + i`` (``seed`` 0 when
            ``None``); ``reset(seed=...)`` names other episodes.
        obs_mode: ``"dict"`` (SocNavGym's blocks, zero-padded) or ``"flat"`` (one row).
        action_type: ``"continuous"`` (``Box(-1, 1, (3,))``) or ``"discrete"`` (``Discrete(7)``).
        autoreset_mode: ``"next_step"`` (default), ``"same_step"`` or ``"disabled"``.
        backend: ``"cpu"`` (default), ``"gpu"`` (any adapter, software ones included; an error
            without one) or ``"auto"`` (a hardware GPU when one exists, else the CPU with one
            line on stderr). ``env.backend`` and ``env.device`` say what runs the batch. The
            GPU choices load the machine's Vulkan drivers into the process; Mesa's software
            driver brings its own LLVM, which crashes torch when it later imports triton, so
            the default never probes for an adapter.
        threads: CPU threads (all cores when ``None``).
        copy: return fresh arrays instead of views of the batch's buffers.
        reward_fn: a vectorised reward: called after every step with the step's arrays
            (``socnav.RewardInputs``), it returns one reward per environment, which replaces
            the built-in one (also in the episode returns of ``info["episode"]``). Plain numpy
            over the batch costs microseconds; a Python loop over environments does not. It
            runs after the batch has stepped, so an exception it raises (or a ``ValueError``
            for what it returns) comes out of ``step`` with the step taken: the environments
            are where the step left them, and the step's rewards are lost.
        render_mode: ``"rgb_array"``: ``render()`` returns frames (``socnav.render``); the
            robot's path is then read from the state at every step.
        render_envs: the environments ``render()`` draws (default: the first four).
        render_size: the longer side of a frame (px).
        step_info: put every metric of the step in ``info`` (default). ``False`` leaves them
            out (``info`` then holds the statistics of episodes that ended and, under
            SAME_STEP, the finals): a learner that reads only observations, rewards and flags
            reads a fifth fewer bytes a step back from the GPU (exp2, padded observations: 580
            per environment instead of 708). A ``reward_fn`` reads the metrics, so it needs
            ``step_info``.
    """
    return SocNavVectorEnv(
        config,
        num_envs,
        seed=seed,
        obs_mode=obs_mode,
        action_type=action_type,
        autoreset_mode=autoreset_mode,
        backend=backend,
        threads=threads,
        copy=copy,
        reward_fn=reward_fn,
        render_mode=render_mode,
        render_envs=render_envs,
        render_size=render_size,
        step_info=step_info,
    )
