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


def _ending_state(robot_vel, robot_theta, human_speed, human_theta, gap=0.0):
    """A terminal state document: the robot (radius 0.25 m) at the origin, one person (radius
    0.36 m) on the +x axis at contact distance plus ``gap``."""
    return {
        "state": {
            "robot": {"x": 0.0, "y": 0.0, "theta": robot_theta, "vel": list(robot_vel), "radius": 0.25},
            "humans": [
                {"x": 0.61 + gap, "y": 0.0, "radius": 0.36, "speed": human_speed, "theta": human_theta},
                {"x": -5.0, "y": 0.0, "radius": 0.36, "speed": 1.0, "theta": 0.0},
            ],
        }
    }


def test_a_collisions_cause_is_who_approached_faster():
    """Hand-computed: the robot drives at 0.1 m/s toward a person who walks at 0.05 m/s toward it
    (robot-caused); the robot at 0.02 m/s (person-caused); a robot facing away but driving in
    reverse into the person, whose heading turns the command (robot-caused); a person grazing a
    still robot while walking past, perpendicular (0 against 0: person-caused, a still robot
    causes nothing); the person 4 m away walking into the robot is not the contact."""
    human = {k: 0.0 for k in EPISODE_KEYS} | {"collision": 1.0, "collision_human": 1.0}
    classify = socnav.evaluation.classify_ending
    pi = float(np.pi)
    assert classify(human, lambda: _ending_state([0.1, 0, 0], 0.0, 0.05, pi)) == "robot-caused"
    assert classify(human, lambda: _ending_state([0.02, 0, 0], 0.0, 0.05, pi)) == "person-caused"
    assert classify(human, lambda: _ending_state([-0.1, 0, 0], pi, 0.05, pi)) == "robot-caused"
    assert classify(human, lambda: _ending_state([0.0, 0, 0], 0.0, 0.1, pi / 2)) == "person-caused"
    # A robot backing away from a person who catches it up.
    assert classify(human, lambda: _ending_state([-0.02, 0, 0], 0.0, 0.05, pi)) == "person-caused"
    # Equal speeds: the robot caused it (it was not slower).
    assert classify(human, lambda: _ending_state([0.05, 0, 0], 0.0, 0.05, pi)) == "robot-caused"
    # Objects and walls do not move: always the robot; no state is read for them.
    objects = human | {"collision_object": 1.0}
    assert classify(objects, lambda: pytest.fail("not read")) == "robot-caused"
    timeout = {k: 0.0 for k in EPISODE_KEYS} | {"timeout": 1.0}
    assert classify(timeout, lambda: pytest.fail("not read")) == "timeout"
    assert classify({k: 0.0 for k in EPISODE_KEYS} | {"success": 1.0}, lambda: None) == "success"


def test_a_still_robot_causes_no_collision():
    """The stop policy's collisions are all people walking into it (the two test seeds where a
    person grazes it while walking past included); every episode is classified."""
    result = socnav.evaluate("stop", "exp2", episodes=120, seed=700_000)
    grazes = socnav.evaluate("stop", "exp2", episodes=40, seed=1_000_388 - 5)
    assert grazes.ending_counts()["robot-caused"] == 0 and grazes.endings[5] == "person-caused"
    counts = result.ending_counts()
    assert sum(counts.values()) == 120 and counts["robot-caused"] == 0 and counts["success"] == 0
    assert counts["person-caused"] > 10, counts
    rows = result.episode_rows()
    np.testing.assert_array_equal(result.endings == "person-caused", rows["collision"] == 1)
    goal = socnav.evaluate("goal", "exp2", episodes=120, seed=700_000)
    assert goal.ending_counts()["robot-caused"] > 0
