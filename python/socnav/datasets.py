"""Recorded episodes as datasets: Minari datasets for offline RL and imitation, and SocNavGym
0.1.1's ``episode_recordings/NNNNNNNN.json`` for its users.

- :func:`collect` runs a policy (``"goal"``, ``"orca"``, ``"random"``, a trained agent or any
  ``policy(obs, env)``) over a batch on the episodes of seeds ``seed .. seed + episodes - 1`` (the
  same episodes whatever ``num_envs``) and streams every finished episode to a Minari dataset
  and/or JSON files: memory stays bounded by the batch (about ``num_envs`` episodes in flight),
  whatever the number of episodes.
- :func:`iter_episodes` is the same stream as :class:`Episode` objects, for your own sink.
- :class:`RecordEpisodes` records the episodes of one ``socnav.make`` environment as they are
  played (a person at the viewer, a script).
- :class:`MinariWriter` and :class:`JsonWriter` are the two sinks.
- :func:`played_episodes` rebuilds the episodes ``socnav play --record DIR`` recorded (from their
  seeds and actions), e.g. to write them as a Minari dataset.

An :class:`Episode` holds everything needed to replay it: its episode seed and config (a fresh
environment reset with that seed and stepped with its actions reproduces its observations
exactly), the observations (the reset's first, the final one last: ``T + 1``), the ``T``
actions, rewards, terminations and truncations kept apart, and the info arrays (every metric of
``info``, ``T + 1`` values: the reset's, then each step's; NaN where 0.1.1 has ``None``).

Minari datasets need the ``datasets`` extra (``pip install './python[datasets]'``: minari with
HDF5). The dataset's environment spec names the socnav environment (``gymnasium.make("socnav/Exp2-v0",
obs_mode=..., action_type=...)``, :mod:`socnav.registration`), so ``dataset.recover_environment()``
builds it; each episode's ``seed`` is its socnav episode seed and its options hold the config.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, Sequence

import gymnasium as gym
import numpy as np

from socnav import _batch
from socnav._socnav import DISCRETE_ACTIONS, Batch, socnavgym_episode_json

_SEED_LIMIT = 1 << 64


@dataclass
class Episode:
    """One recorded episode (see the module's doc). ``observations`` is a ``(T + 1, dim)``
    float32 array (``obs_mode="flat"``) or a dict of ``(T + 1, ...)`` blocks (``"dict"``)."""

    seed: int
    config: Any
    observations: Any
    actions: np.ndarray
    rewards: np.ndarray
    terminations: np.ndarray
    truncations: np.ndarray
    infos: dict[str, np.ndarray] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.rewards)

    @property
    def outcome(self) -> str:
        """``"success"``, ``"collision"``, ``"timeout"``, ``"out_of_map"`` (SocNavGym's info
        flags at the last step), or ``"unfinished"``."""
        if len(self) == 0 or not (self.terminations[-1] or self.truncations[-1]):
            return "unfinished"
        for key, outcome in (("SUCCESS", "success"), ("COLLISION", "collision"), ("TIMEOUT", "timeout"),
                             ("OUT_OF_MAP", "out_of_map")):
            values = self.infos.get(key)
            if values is not None and values[-1] > 0:
                return outcome
        return "ended"

    def nbytes(self) -> int:
        """Bytes of its arrays."""
        obs = self.observations
        obs_bytes = sum(v.nbytes for v in obs.values()) if isinstance(obs, dict) else obs.nbytes
        arrays = (self.actions, self.rewards, self.terminations, self.truncations, *self.infos.values())
        return obs_bytes + sum(a.nbytes for a in arrays)


class _Builder:
    """The rows of one episode in flight."""

    def __init__(self, seed: int, obs: np.ndarray, info: np.ndarray) -> None:
        self.seed = seed
        self.obs = [obs]
        self.info = [info]
        self.actions: list[Any] = []
        self.rewards: list[float] = []
        self.terminated: list[bool] = []
        self.truncated: list[bool] = []

    def add(self, action: Any, obs: np.ndarray, reward: float, terminated: bool, truncated: bool, info: np.ndarray) -> None:
        self.actions.append(action)
        self.obs.append(obs)
        self.rewards.append(reward)
        self.terminated.append(terminated)
        self.truncated.append(truncated)
        self.info.append(info)

    def finish(self, config: Any, layout: Mapping[str, Any], obs_mode: str, info_keys: Sequence[str]) -> Episode:
        flat = np.stack(self.obs).astype(np.float32, copy=False)
        observations: Any = flat if obs_mode == "flat" else _batch.split_obs(flat, layout)
        info = np.stack(self.info)
        return Episode(
            seed=self.seed,
            config=config,
            observations=observations,
            actions=np.asarray(self.actions),
            rewards=np.asarray(self.rewards, dtype=np.float32),
            terminations=np.asarray(self.terminated, dtype=bool),
            truncations=np.asarray(self.truncated, dtype=bool),
            infos={key: info[:, k].copy() for k, key in enumerate(Batch.keys()["info"]) if key in info_keys},
        )


def _plain_config(config: Any) -> Any:
    """``config`` as a dataset stores it: a name or path as text, overrides as plain JSON data."""
    if isinstance(config, os.PathLike):
        return os.fspath(config)
    try:
        return json.loads(json.dumps(config))
    except TypeError as e:
        raise ValueError(f"a recorded config must be a name, a path or JSON-like overrides: {e}") from e


def _resolve_policy(policy: Any, seed: int) -> tuple[Callable[[Any, Any], Any], str]:
    from socnav.evaluation import resolve_policy

    return resolve_policy(policy, seed=seed)


def iter_episodes(
    policy: Any,
    config: str | Mapping[str, Any] = "exp1",
    *,
    episodes: int,
    seed: int = 0,
    num_envs: int | None = None,
    obs_mode: str = "flat",
    backend: str = "cpu",
    threads: int | None = None,
    info_keys: Sequence[str] | None = None,
) -> Iterator[Episode]:
    """The episodes of seeds ``seed .. seed + episodes - 1`` of ``config`` played by ``policy``,
    as each finishes (in finishing order; ``Episode.seed`` names each). ``num_envs`` (default
    ``min(episodes, 64)``) changes the speed and the memory, not the episodes. A policy acts on
    ``obs_mode`` observations unless it says otherwise (``policy.obs_mode``, as trained agents
    do); the episodes hold ``obs_mode`` observations either way. ``info_keys`` picks the info
    arrays kept (default: every one; each is a dataset of its own in a Minari file, so fewer
    make writing faster)."""
    import socnav

    episodes = _batch.check_count("episodes", episodes)
    config = _plain_config(config)
    obs_mode = _batch.check_choice("obs_mode", obs_mode, _batch.OBS_MODES)
    seed = _batch.check_seed(seed)
    act, _ = _resolve_policy(policy, seed)
    n = min(episodes, _batch.check_count("num_envs", num_envs) if num_envs is not None else 64)
    policy_obs = getattr(act, "obs_mode", obs_mode)
    env = socnav.make_vec(
        config,
        num_envs=n,
        obs_mode=policy_obs,
        action_type=getattr(act, "action_type", "continuous"),
        autoreset_mode="disabled",
        backend=backend,
        threads=threads,
    )
    try:
        inner: Any = env.unwrapped
        layout = inner._layout
        known = list(Batch.keys()["info"])
        info_keys = known if info_keys is None else list(info_keys)
        unknown = [k for k in info_keys if k not in known]
        if unknown:
            raise ValueError(f"unknown info keys {unknown}; the info has {known}")
        buf = inner._buf
        obs, _ = env.reset(seed=[(seed + k) % _SEED_LIMIT for k in range(n)])
        building: list[_Builder | None] = [
            _Builder((seed + k) % _SEED_LIMIT, buf["obs"][k].copy(), buf["info"][k].copy()) for k in range(n)
        ]
        next_k = n
        while any(b is not None for b in building):
            actions = np.asarray(act(obs, env))
            obs, reward, terminated, truncated, _ = env.step(actions)
            rows, infos = buf["obs"], buf["info"]
            ended = []
            for e, b in enumerate(building):
                if b is None:
                    continue
                b.add(actions[e].copy(), rows[e].copy(), float(reward[e]), bool(terminated[e]), bool(truncated[e]), infos[e].copy())
                if terminated[e] or truncated[e]:
                    ended.append(e)
            if not ended:
                continue
            restart = np.zeros(n, dtype=bool)
            seeds: list[int | None] = [None] * n
            for e in ended:
                done = building[e]
                assert done is not None
                yield done.finish(config, layout, obs_mode, info_keys)
                building[e] = None
                if next_k < episodes:
                    seeds[e] = (seed + next_k) % _SEED_LIMIT
                    restart[e] = True
                    next_k += 1
            if restart.any():
                obs, _ = env.reset(seed=seeds, options={"reset_mask": restart})
                for r in np.flatnonzero(restart).tolist():
                    s = seeds[r]
                    assert s is not None
                    building[r] = _Builder(s, buf["obs"][r].copy(), buf["info"][r].copy())
    finally:
        env.close()


def estimate_bytes(config: str | Mapping[str, Any] = "exp1", *, episodes: int, obs_mode: str = "flat",
                   action_type: str = "continuous") -> int:
    """An upper bound of the bytes ``episodes`` episodes take in memory and, uncompressed, on
    disk: every episode at the config's longest (``episode.length + 1`` steps), observations
    (float32, the same for both modes), actions, rewards, flags and info arrays."""
    import socnav

    env = socnav.make(config, obs_mode=obs_mode, action_type=action_type)
    try:
        dim = env._layout["dim"]
        steps = _episode_steps(env._batch.config_toml())
    finally:
        env.close()
    action = 3 * 4 if action_type == "continuous" else 8
    info = len(Batch.keys()["info"]) * 4
    per_step = dim * 4 + action + 4 + 2 + info
    return int(episodes) * ((steps + 1) * (dim * 4 + info) + steps * (per_step - dim * 4 - info))


def _episode_steps(toml_text: str) -> int:
    """The most steps an episode of a config takes: ``episode.length + 1`` (configs/README.md)."""
    if sys.version_info >= (3, 11):
        import tomllib

        length = int(tomllib.loads(toml_text)["episode"]["length"])
    else:  # Python 3.10 has no TOML reader: the one key, by hand
        section = re.search(r"^\[episode\](.*?)(?=^\[|\Z)", toml_text, re.M | re.S)
        found = re.search(r"^length\s*=\s*(\d+)", section.group(1) if section else "", re.M)
        length = int(found.group(1)) if found else 200
    return length + 1


# ---- sinks ---------------------------------------------------------------------------------------


class JsonWriter:
    """SocNavGym 0.1.1's ``manual_control_js.py -r`` recordings (docs/spec.md 9.2; written by
    socnav's Rust writer, the one ``socnav play --record`` uses): one file
    ``NNNNNNNN.json`` per episode in ``directory``, numbered on from the largest file already
    there; each a dict from the step index (``"0"`` for the observation the first step returned)
    to ``{observation key: list, ..., "action": [a0, a1, a2], "reward": [r]}``. Observation keys
    are 0.1.1's (``robot``, ``humans``, ``laptops``, ``plants``, ``tables``, ``walls``), each a
    flat list of the entities present (0.1.1's unpadded observation: zero records dropped).
    Discrete actions are written as 0.1.1's ``DiscreteActions`` maps them."""

    def __init__(self, directory: str | os.PathLike[str], layout: Mapping[str, Any]) -> None:
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self._layout = layout
        taken = [int(p.stem) for p in self.directory.glob("*.json") if p.stem.isdigit()]
        self._next = max(taken) + 1 if taken else 0
        self.written: list[Path] = []

    def add(self, episode: Episode) -> Path:
        flat = episode.observations
        if isinstance(flat, dict):
            raise ValueError("JsonWriter takes flat observations (obs_mode='flat')")
        lay = self._layout
        keys = ("humans", "laptops", "tables", "plants", "walls")
        doc = socnavgym_episode_json(
            np.ascontiguousarray(flat[1:], dtype=np.float32),
            np.ascontiguousarray(_continuous(episode.actions), dtype=np.float32),
            np.ascontiguousarray(episode.rewards, dtype=np.float32),
            int(lay["robot"]),
            [int(lay["entities"][k][0]) for k in keys],
            [int(lay["entities"][k][1]) for k in keys],
            int(lay["dim"]),
        )
        path = self.directory / f"{self._next:08d}.json"
        tmp = path.with_suffix(".json.part")
        try:
            tmp.write_text(doc)
            tmp.replace(path)  # a file is either whole or absent
        except OSError:
            tmp.unlink(missing_ok=True)  # a full disk keeps no half file (and no space taken)
            raise
        self._next += 1
        self.written.append(path)
        return path

    def close(self) -> None:
        pass


# 0.1.1's DiscreteActions table (docs/spec.md 9.1): the continuous action of each discrete one.
_DISCRETE_TO_CONTINUOUS = np.array(DISCRETE_ACTIONS, dtype=np.float32)


def _continuous(actions: np.ndarray) -> np.ndarray:
    """An episode's actions as 0.1.1 records them: ``(T, 3)`` floats, discrete ones (``(T,)``
    in 0..7) mapped through its table; anything else is a ``ValueError`` (a negative index
    would pick an action from the table's end)."""
    if actions.ndim == 1:
        if not np.issubdtype(actions.dtype, np.integer) or actions.size and not (
            0 <= actions.min() and actions.max() < len(_DISCRETE_TO_CONTINUOUS)
        ):
            raise ValueError(
                f"discrete actions are integers in 0..{len(_DISCRETE_TO_CONTINUOUS) - 1}, got {actions!r}"
            )
        return _DISCRETE_TO_CONTINUOUS[actions.astype(np.int64)]
    if actions.ndim != 2 or actions.shape[1] != 3:
        raise ValueError(f"continuous actions are (T, 3), got shape {actions.shape}")
    return actions.astype(np.float32, copy=False)


class MinariWriter:
    """Episodes into a new Minari dataset ``dataset_id`` (under ``root``, default Minari's
    ``MINARI_DATASETS_PATH`` or ``~/.minari/datasets``; Minari reads that variable only, so a
    ``root`` sets it for the process), written in chunks of ``flush_every``
    episodes: what was flushed is a complete, loadable dataset, so an interrupted collection
    keeps every episode up to the last flush (``close`` flushes the rest). Needs minari."""

    def __init__(
        self,
        dataset_id: str,
        spec: gym.envs.registration.EnvSpec,
        observation_space: gym.Space[Any],
        action_space: gym.Space[Any],
        *,
        root: str | os.PathLike[str] | None = None,
        algorithm_name: str | None = None,
        description: str | None = None,
        flush_every: int = 32,
    ) -> None:
        try:
            import minari
            from minari.data_collector.episode_buffer import EpisodeBuffer
        except ImportError as e:
            raise ImportError(f"Minari datasets need minari: pip install './python[datasets]' ({e})") from e
        if root is not None:
            os.environ["MINARI_DATASETS_PATH"] = str(Path(root).resolve())
        self._minari = minari
        self._buffer_type = EpisodeBuffer
        from minari.storage.datasets_root_dir import get_dataset_path

        path = Path(get_dataset_path(dataset_id))
        if path.exists():
            raise FileExistsError(f"a Minari dataset {dataset_id!r} already exists at {path}; delete it or choose another id")
        self.dataset_id = dataset_id
        self._spec = spec
        self._spaces = (observation_space, action_space)
        self._meta = {"algorithm_name": algorithm_name, "description": description}
        self._pending: list[Any] = []
        self._flush_every = max(1, int(flush_every))
        self._dataset: Any = None
        self.episodes = 0
        self.steps = 0

    def add(self, episode: Episode) -> None:
        self._pending.append(
            self._buffer_type(
                seed=int(episode.seed),
                options={"config": json.dumps(episode.config)},
                observations=episode.observations,
                actions=episode.actions,
                rewards=episode.rewards,
                terminations=episode.terminations,
                truncations=episode.truncations,
                infos=episode.infos,
            )
        )
        self.episodes += 1
        self.steps += len(episode)
        if len(self._pending) >= self._flush_every:
            self.flush()

    def flush(self) -> None:
        if not self._pending:
            return
        chunk, self._pending = self._pending, []
        if self._dataset is None:
            obs_space, act_space = self._spaces
            with warnings.catch_warnings():
                # Minari asks for a contact address and a link to versioned code; a collection
                # run has neither to give (the dataset's description names policy, config, seeds).
                warnings.filterwarnings("ignore", message=".*(author_email|code_permalink).*")
                self._dataset = self._minari.create_dataset_from_buffers(
                    dataset_id=self.dataset_id,
                    buffer=chunk,
                    env=self._spec,
                    eval_env=self._spec,
                    observation_space=obs_space,
                    action_space=act_space,
                    algorithm_name=self._meta["algorithm_name"],
                    description=self._meta["description"],
                    author="socnav.datasets",
                    data_format="hdf5",
                )
        else:
            self._dataset.storage.update_episodes(chunk)

    def close(self) -> Any:
        """Flush the rest; the dataset (``minari.MinariDataset``), or None without episodes."""
        self.flush()
        return self._dataset


# ---- collecting ----------------------------------------------------------------------------------


@dataclass
class Collection:
    """What :func:`collect` wrote."""

    episodes: int
    steps: int
    seconds: float
    bytes: int
    outcomes: dict[str, int]
    dataset_id: str | None = None
    json_dir: Path | None = None

    def __str__(self) -> str:
        rate = self.episodes / self.seconds if self.seconds > 0 else float("inf")
        where = ", ".join(x for x in (f"Minari {self.dataset_id}" if self.dataset_id else "",
                                      f"JSON {self.json_dir}" if self.json_dir else "") if x)
        return (f"{self.episodes} episodes, {self.steps} steps in {self.seconds:.1f} s ({rate:.0f} episodes/s, "
                f"{self.bytes / max(self.episodes, 1) / 1e3:.0f} kB each) -> {where}; outcomes {self.outcomes}")


def collect(
    policy: Any,
    config: str | Mapping[str, Any] = "exp1",
    *,
    episodes: int,
    dataset_id: str | None = None,
    json_dir: str | os.PathLike[str] | None = None,
    seed: int = 0,
    num_envs: int | None = None,
    obs_mode: str = "flat",
    backend: str = "cpu",
    threads: int | None = None,
    root: str | os.PathLike[str] | None = None,
    flush_every: int = 32,
    progress: bool = True,
    info_keys: Sequence[str] | None = None,
) -> Collection:
    """Play ``episodes`` episodes (seeds ``seed ..``) of ``config`` with ``policy`` and stream them
    to a Minari dataset ``dataset_id`` and/or 0.1.1's JSON files in ``json_dir`` (module docs).

    Before it starts it says (``progress``) how much the request needs at most and how much disk
    is free; a full disk or an interruption ends it with what was flushed intact (Minari: every
    ``flush_every`` episodes; JSON: every episode). ``info_keys`` as :func:`iter_episodes`."""
    import socnav
    from socnav.registration import env_spec

    if dataset_id is None and json_dir is None:
        raise ValueError("collect needs a sink: dataset_id (Minari) and/or json_dir (SocNavGym JSON)")
    # Everything is checked before a directory is made.
    episodes = _batch.check_count("episodes", episodes)
    if json_dir is not None and obs_mode != "flat":
        raise ValueError("json_dir needs obs_mode='flat' (the writer drops 0.1.1's padding itself)")
    act, name = _resolve_policy(policy, _batch.check_seed(seed))
    action_type = getattr(act, "action_type", "continuous")
    probe = socnav.make(config, obs_mode=obs_mode, action_type=action_type)
    layout = probe._layout
    spaces = (probe.observation_space, probe.action_space)
    probe.close()
    if dataset_id is not None and isinstance(spaces[0], gym.spaces.Dict):
        # Minari writes a block of no records and then cannot read its space back.
        empty = [key for key, space in spaces[0].spaces.items() if 0 in (space.shape or ())]
        if empty:
            raise ValueError(
                f"{_name(config)} holds no records of {', '.join(empty)}: a Minari dataset of dict "
                "observations could not be read back; collect with obs_mode='flat'"
            )
    need = estimate_bytes(config, episodes=episodes, obs_mode=obs_mode, action_type=action_type)
    if json_dir is not None:
        target = Path(json_dir)
    else:
        target = Path(root or os.environ.get("MINARI_DATASETS_PATH") or Path.home())
    target.mkdir(parents=True, exist_ok=True)
    free = shutil.disk_usage(target).free
    if progress:
        print(f"socnav.datasets: {episodes} episodes of {_name(config)} by {name}: at most {need / 1e6:.1f} MB "
              f"({obs_mode} observations), {free / 1e9:.1f} GB free", file=sys.stderr)
    sinks: list[Any] = []
    minari_writer = None
    if dataset_id is not None:
        spec = env_spec(config, obs_mode=obs_mode, action_type=action_type)
        minari_writer = MinariWriter(dataset_id, spec, *spaces, root=root, algorithm_name=name,
                                     description=f"socnav {_name(config)}, policy {name}, episode seeds {seed}..{seed + episodes - 1}",
                                     flush_every=flush_every)
        sinks.append(minari_writer)
    json_writer = JsonWriter(json_dir, layout) if json_dir is not None else None
    if json_writer is not None:
        sinks.append(json_writer)
    start = time.perf_counter()
    count = steps = nbytes = 0
    outcomes: dict[str, int] = {}
    report = max(1, int(episodes) // 10)
    try:
        for ep in iter_episodes(act, config, episodes=episodes, seed=seed, num_envs=num_envs,
                                obs_mode=obs_mode, backend=backend, threads=threads, info_keys=info_keys):
            for sink in sinks:
                sink.add(ep)
            count += 1
            steps += len(ep)
            nbytes += ep.nbytes()
            outcomes[ep.outcome] = outcomes.get(ep.outcome, 0) + 1
            if progress and count % report == 0:
                print(f"socnav.datasets: {count}/{episodes} episodes", file=sys.stderr)
    except OSError as e:
        raise OSError(e.errno, f"collecting stopped after {count} episodes ({e.strerror}); the episodes "
                               f"written before stay readable", e.filename) from e
    finally:
        for sink in sinks:
            try:
                sink.close()
            except OSError:
                pass  # the error above says it
    return Collection(count, steps, time.perf_counter() - start, nbytes, outcomes,
                      dataset_id=dataset_id, json_dir=json_writer.directory if json_writer else None)


def _name(config: Any) -> str:
    from socnav.evaluation import _config_name

    return _config_name(config)


# ---- recording one environment -------------------------------------------------------------------


class RecordEpisodes(gym.Wrapper):  # type: ignore[type-arg]
    """Records every episode of a ``socnav.make`` environment into ``sinks`` (writers with
    ``add(episode)``; ``close()`` closes them), as it is played: by a person at the viewer, by a
    script. An episode is written when it terminates or truncates (one abandoned by a reset is
    dropped). Episode seeds come from the environment (the seed a reset used, or the next of its
    sequence)."""

    def __init__(self, env: gym.Env[Any, Any], sinks: Sequence[Any]) -> None:
        inner: Any = env.unwrapped
        if getattr(inner, "_batch", None) is None:
            raise TypeError(f"RecordEpisodes records a socnav.make environment, got {type(inner).__name__}")
        # What the sinks cannot take is refused now, not at the end of the first episode.
        for sink in sinks:
            if not callable(getattr(sink, "add", None)):
                raise TypeError(f"a sink has add(episode) (and close()), got {type(sink).__name__}")
            if isinstance(sink, JsonWriter) and inner.obs_mode != "flat":
                raise ValueError("JsonWriter takes flat observations: make the environment with obs_mode='flat'")
        super().__init__(env)
        self._batch = inner._batch
        self._config = _plain_config(getattr(inner, "config", None))
        self._layout = inner._layout
        self._obs_mode = inner.obs_mode
        self._keys = list(Batch.keys()["info"])
        self._sinks = list(sinks)
        self._building: _Builder | None = None

    def _seed(self) -> int:
        doc = json.loads(self._batch.get_state(0))
        return int(doc["socnav"]["seed"])

    def reset(self, **kwargs: Any) -> Any:
        obs, info = self.env.reset(**kwargs)
        buf = self._batch.buffers()
        self._building = _Builder(self._seed(), buf["obs"][0].copy(), buf["info"][0].copy())
        return obs, info

    def step(self, action: Any) -> Any:
        obs, reward, terminated, truncated, info = self.env.step(action)
        if self._building is not None:
            buf = self._batch.buffers()
            self._building.add(np.asarray(action).copy(), buf["obs"][0].copy(), float(reward), terminated, truncated,
                               buf["info"][0].copy())
            if terminated or truncated:
                ep = self._building.finish(self._config, self._layout, self._obs_mode, self._keys)
                self._building = None
                for sink in self._sinks:
                    sink.add(ep)
        return obs, reward, terminated, truncated, info

    def close(self) -> None:
        for sink in self._sinks:
            sink.close()
        super().close()


class _Keep:
    """A sink that keeps the last episode it was given."""

    def __init__(self) -> None:
        self.episode: Episode | None = None

    def add(self, episode: Episode) -> None:
        self.episode = episode

    def close(self) -> None:
        pass


def played_episodes(directory: str | os.PathLike[str], *, obs_mode: str = "flat") -> Iterator[Episode]:
    """The episodes ``socnav play --record directory`` recorded, in file order, rebuilt whole
    (observations, infos) by replaying each one's actions from its seed in its config (the
    sidecar ``NNNNNNNN.socnav.json`` holds them); a sidecar whose replay ends elsewhere than it
    did raises ``ValueError``."""
    import socnav

    paths = sorted(Path(directory).glob("*.socnav.json"))
    if not paths:
        raise FileNotFoundError(f"{directory}: no socnav play recordings (NNNNNNNN.socnav.json)")
    for path in paths:
        try:
            side = json.loads(path.read_text())
        except ValueError as e:
            raise ValueError(f"{path}: not a socnav play recording ({e})") from None
        if not isinstance(side, dict) or side.get("format") != "socnav-played/1":
            found = side.get("format") if isinstance(side, dict) else type(side).__name__
            raise ValueError(f"{path}: not a socnav play recording (format {found!r})")
        missing = [k for k in ("config", "action_type", "seed", "actions", "steps") if k not in side]
        if missing:
            raise ValueError(f"{path}: a socnav play recording without {', '.join(missing)}")
        yield _replay(path, side, obs_mode)


def _replay(path: Path, side: Mapping[str, Any], obs_mode: str) -> Episode:
    """The episode a play recording's sidecar ``side`` (read from ``path``) names, replayed; any
    problem of its content is a ``ValueError`` naming the file."""
    import socnav

    keep = _Keep()
    try:
        env = RecordEpisodes(socnav.make(side["config"], obs_mode=obs_mode, action_type=side["action_type"]), [keep])
    except (TypeError, ValueError, socnav.SocNavError) as e:
        raise ValueError(f"{path}: {e}") from None
    try:
        env.reset(seed=_batch.check_seed(side["seed"]))
        dtype = np.uint32 if side["action_type"] == "discrete" else np.float32
        for action in side["actions"]:
            if keep.episode is not None:
                raise ValueError("it holds actions past the episode's end")
            env.step(np.asarray(action, dtype=dtype))
    except (TypeError, ValueError, socnav.SocNavError) as e:
        raise ValueError(f"{path}: {e}") from None
    finally:
        env.close()
    if keep.episode is None or len(keep.episode) != int(side["steps"]):
        raise ValueError(f"{path}: the replay did not end after {side['steps']} steps as the recording did")
    return keep.episode

