"""Built-in policies and ``socnav.evaluate``: the table is a function of (policy, config, seed,
episodes) whatever the batch size, and every listed episode replays alone from its seed."""

import numpy as np
import pytest

import socnav
from socnav.metrics import EPISODE_KEYS

SHORT = {"base": "exp1", "episode": {"length": 40}}


def test_evaluation_does_not_depend_on_the_batch_size():
    a = socnav.evaluate("goal", SHORT, episodes=10, seed=5, num_envs=3)
    b = socnav.evaluate("goal", SHORT, episodes=10, seed=5, num_envs=10)
    np.testing.assert_array_equal(a.seeds, np.arange(5, 15, dtype=np.uint64))
    np.testing.assert_array_equal(a.log.rows(), b.log.rows())
    table = a.table()
    assert table["success"]["n"] == 10 and 0.0 <= table["success"]["mean"] <= 1.0
    assert "| success |" in a.to_markdown()
    assert a.to_csv().splitlines()[0] == "statistic,mean,ci95,n"


def test_a_listed_episode_replays_alone():
    result = socnav.evaluate("goal", SHORT, episodes=6, seed=100, num_envs=4)
    k = 4
    env = socnav.make_vec(SHORT, num_envs=1, autoreset_mode="disabled")
    goal = socnav.policies.GoalPolicy()
    obs, _ = env.reset(seed=int(result.seeds[k]))
    for _ in range(41):
        obs, _, terminated, truncated, info = env.step(goal(obs, env))
        if terminated[0] or truncated[0]:
            break
    row = np.array([info["episode"][key][0] for key in EPISODE_KEYS], dtype=np.float32)
    np.testing.assert_array_equal(row, result.log.rows()[k])


def test_builtin_policies_act_in_range_and_goal_beats_random():
    env = socnav.make_vec("exp2", num_envs=8)
    obs, _ = env.reset(seed=3)
    for name in ("goal", "orca", "random"):
        a = socnav.policies.get(name)(obs, env)
        assert a.shape == (8, 3) and a.dtype == np.float32
        assert np.all(np.abs(a) <= 1.0) and np.all(a[:, 1] == 0.0), name
    goal = socnav.evaluate("goal", "exp1", episodes=24, seed=0)
    rand = socnav.evaluate("random", "exp1", episodes=24, seed=0)
    assert goal.summary()["success"] > rand.summary()["success"]


def test_policy_errors_name_the_problem():
    with pytest.raises(ValueError, match="unknown policy 'nope'"):
        socnav.policies.get("nope")
    with pytest.raises(ValueError, match="episodes must be at least 1, got 0"):
        socnav.evaluate("goal", "exp1", episodes=0)
    discrete = socnav.make_vec("exp1", num_envs=2, action_type="discrete")
    obs, _ = discrete.reset(seed=0)
    with pytest.raises(ValueError, match="action_type='continuous'"):
        socnav.policies.GoalPolicy()(obs, discrete)
