"""Episode seeds from Python: ``reset(seed=s)`` gives environment i the episode of seed s + i, a
list gives each its own, ``info["episode"]["seed"]`` reports every finished episode's seed, and
a single environment reset with that seed plays the same episode."""

import numpy as np
import pytest

import socnav

SHORT = {"base": "exp1", "episode": {"length": 12}}
STEP = 0x9E3779B97F4A7C15


def _actions(t: int, n: int) -> np.ndarray:
    k = np.arange(n)
    forward = ((k * 5 + t * 3) % 11) / 5.0 - 1.0
    turn = ((k * 3 + t // 3) % 7) / 3.0 - 1.0
    return np.stack([forward, np.zeros(n), turn], axis=1).astype(np.float32)


def test_finished_episodes_report_their_seeds():
    n = 4
    env = socnav.make_vec(SHORT, num_envs=n, obs_mode="flat")
    env.reset(seed=100)
    seen: dict[int, list[int]] = {k: [] for k in range(n)}
    for t in range(40):
        info = env.step(_actions(t, n))[4]
        if "_episode" in info:
            assert info["episode"]["seed"].dtype == np.uint64
            for k in np.flatnonzero(info["_episode"]):
                seen[k].append(int(info["episode"]["seed"][k]))
    for k, seeds in seen.items():
        assert len(seeds) >= 2
        assert seeds[0] == 100 + k
        assert seeds[1] == (100 + k + STEP) % (1 << 64), "the next seed of the sequence"


def test_a_vector_episode_replays_in_a_single_environment():
    n = 3
    env = socnav.make_vec(SHORT, num_envs=n, obs_mode="flat", copy=True)
    obs, _ = env.reset(seed=[7, 2**64 - 1, 12345])
    single = socnav.make(SHORT, obs_mode="flat")
    for k, seed in enumerate([7, 2**64 - 1, 12345]):
        first, _ = single.reset(seed=seed)
        np.testing.assert_array_equal(first, obs[k])
    # The middle environment's episode, step by step, alone.
    single.reset(seed=2**64 - 1)
    for t in range(12):
        a = _actions(t, n)
        vec_obs = env.step(a)[0]
        one = single.step(a[1])[0]
        np.testing.assert_array_equal(one, vec_obs[1], err_msg=f"step {t}")


def test_seeds_with_a_reset_mask_and_errors():
    env = socnav.make_vec(SHORT, num_envs=3, obs_mode="flat", autoreset_mode="disabled", copy=True)
    env.reset(seed=50)
    ref = socnav.make_vec(SHORT, num_envs=3, obs_mode="flat", copy=True)
    expected, _ = ref.reset(seed=[50, 9, 52])
    obs, _ = env.reset(seed=[None, 9, 1], options={"reset_mask": np.array([False, True, False])})
    np.testing.assert_array_equal(obs, expected, "only the masked environment took its seed")
    with pytest.raises(ValueError, match="2 seeds given for 3 environments"):
        env.reset(seed=[1, 2])
    with pytest.raises(ValueError, match="-1"):
        env.reset(seed=-1)
    with pytest.raises(ValueError, match="in 0..2\\*\\*64"):
        socnav.make(SHORT).reset(seed=2**64)
    with pytest.raises(TypeError, match="1.5"):
        env.reset(seed=1.5)
