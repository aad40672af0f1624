"""Custom rewards: the weighted terms of the config (``reward.*_weight``) and the vectorised
``reward_fn`` of ``make_vec``."""

from __future__ import annotations

import numpy as np
import pytest

import socnav

STOP = 6  # the discrete "stop" action
N = 16


def _rollout(env, steps: int, seed: int = 3):
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.integers(0, 7, N))
        out.append((reward.copy(), terminated | truncated, info))
    return out


def test_stalled_weight_is_added_to_every_non_terminal_stalled_step():
    plain = socnav.make_vec("exp1", N, action_type="discrete", copy=True)
    weighted = socnav.make_vec(
        {"base": "exp1", "reward": {"stalled_weight": -0.5}}, N, action_type="discrete", copy=True
    )
    stop = np.full(N, STOP)
    for env in (plain, weighted):
        env.reset(seed=1)
    for _ in range(5):
        r0, term, trunc, _ = plain.step(stop)[1:]
        r1 = weighted.step(stop)[1]
        ended = term | trunc
        np.testing.assert_allclose(r1[~ended] - r0[~ended], -0.5, atol=1e-6)
        np.testing.assert_array_equal(r1[ended], r0[ended])


def test_bad_reward_weights_are_listed():
    with pytest.raises(socnav.ConfigError) as e:
        socnav.make_vec({"base": "exp1", "reward": {"obstacle_distance": -1.0, "stalled_weight": -2e39}}, 2)
    assert "reward.obstacle_distance" in str(e.value) and "reward.stalled_weight" in str(e.value)
    # JSON carries no NaN: every non-finite override is named before the config is read.
    with pytest.raises(socnav.ConfigError) as e:
        socnav.make_vec({"base": "exp1", "reward": {"alive": float("nan"), "reach": float("inf")}}, 2)
    assert "reward.alive" in str(e.value) and "reward.reach" in str(e.value)


def test_reward_fn_replaces_the_reward_and_the_episode_return():
    seen = []

    def doubled(inputs: socnav.RewardInputs):
        seen.append(inputs.stepped.copy())
        return 2.0 * inputs.reward + 0.25 * inputs.stepped

    builtin = _rollout(socnav.make_vec("exp1", N, action_type="discrete", copy=True), 300)
    custom_env = socnav.make_vec("exp1", N, action_type="discrete", reward_fn=doubled)
    custom = _rollout(custom_env, 300)
    returns = np.zeros(N)
    episodes = 0
    for t, ((r0, ended0, _), (r1, ended1, info)) in enumerate(zip(builtin, custom)):
        np.testing.assert_array_equal(ended0, ended1)
        stepped = seen[t]
        # NEXT_STEP: the step after an episode ended is its reset and scores 0.
        if t > 0:
            np.testing.assert_array_equal(stepped, ~custom[t - 1][1])
        np.testing.assert_allclose(r1[stepped], 2.0 * r0[stepped] + 0.25, rtol=1e-6)
        assert (r1[~stepped] == 0).all()
        returns += r1
        if "episode" in info:
            done = info["_episode"]
            np.testing.assert_allclose(info["episode"]["return"][done], returns[done], rtol=1e-5)
            returns[done] = 0
            episodes += done.sum()
    assert episodes > 10


def test_reward_fn_sees_the_final_observation_under_same_step():
    finals = []

    def record(inputs):
        finals.append(inputs.obs.copy())
        return np.zeros(N)

    env = socnav.make_vec("exp1", N, obs_mode="flat", action_type="discrete", autoreset_mode="same_step", reward_fn=record)
    env.reset(seed=2)
    rng = np.random.default_rng(2)
    checked = 0
    for _ in range(300):
        obs, _, term, trunc, info = env.step(rng.integers(0, 7, N))
        ended = term | trunc
        np.testing.assert_array_equal(finals[-1][~ended], obs[~ended])
        if ended.any():
            np.testing.assert_array_equal(finals[-1][ended], info["final_obs"][ended])
            checked += ended.sum()
    assert checked > 10


@pytest.mark.parametrize(
    "bad, message",
    [
        (lambda i: np.zeros(3), r"shape \(16,\)"),
        (lambda i: np.full(N, np.nan), "must be finite"),
        (lambda i: np.array(["a"] * N), "real numbers"),
    ],
)
def test_reward_fn_results_are_checked(bad, message):
    env = socnav.make_vec("exp1", N, action_type="discrete", reward_fn=bad)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(np.zeros(N, dtype=np.int64))
