"""Arguments are checked before anything runs: a bad one raises an exception that names it (and
what was found), never a panic, a hang or a silent misreading, and the object it was given to
is as it was."""

import json
import math
import re

import numpy as np
import pytest

import socnav
from socnav._socnav import Batch, socnavgym_config_toml, socnavgym_episode_json
from socnav.socnavgym import SocNavGymEnv, load_socnavgym_yaml


def holonomic_batch(n: int = 2) -> Batch:
    batch = Batch("exp1", n, seed=3, overrides='{"robot": {"kinematics": "holonomic"}}')
    batch.reset(3)
    return batch


def test_actions_are_rows_in_c_order_of_the_batchs_shape():
    """The core reads actions as one flat run of rows: a Fortran-ordered array would be read
    transposed, and a (1, 6) array as two rows, so both are refused with the shape or order."""
    batch = holonomic_batch()
    before = batch.get_state(0)
    rows = np.array([[1.0, 0.0, 0.5], [-1.0, 0.0, -0.5]], dtype=np.float32)
    for step in (batch.step_continuous, batch.send_continuous):
        with pytest.raises(socnav.ActionError, match=r"C order") as err:
            step(np.asfortranarray(rows))
        assert err.value.env is None
        for shape in ((1, 6), (6, 1), (3, 2)):
            with pytest.raises(socnav.ActionError, match=rf"shape \(2, 3\), got \({shape[0]}, {shape[1]}\)"):
                step(np.zeros(shape, dtype=np.float32))
    with pytest.raises(socnav.ActionError, match=r"C order"):
        batch.step_discrete(np.zeros(4, dtype=np.uint32)[::2])
    with pytest.raises(socnav.ActionError, match=r"shape \(2,\), got \(3,\)"):
        batch.send_discrete(np.zeros(3, dtype=np.uint32))
    with pytest.raises(socnav.ShapeError, match=r"C order") as err:
        batch.reset_envs(np.ones(4, dtype=bool)[::2])
    assert err.value.what == "reset mask"
    assert batch.get_state(0) == before, "a refused call changed the batch"
    # The same actions in C order step as they say: environment 0 forward, 1 backward.
    batch.step_continuous(np.ascontiguousarray(rows))
    same = holonomic_batch()
    same.step_continuous(rows.copy())
    assert batch.get_state(0) == same.get_state(0) and batch.get_state(1) == same.get_state(1)


def test_a_recording_layout_past_its_rows_is_refused():
    obs, actions, rewards = np.zeros((2, 10), np.float32), np.zeros((2, 3), np.float32), np.zeros(2, np.float32)
    cases = [
        ((50, [0] * 5, [0] * 5), "the robot record of 50 floats"),
        ((1, [5, 0, 0, 0, 0], [1, 0, 0, 0, 0]), "`humans` (offset 5, 1 records of 14)"),
        ((1, [0] * 5, [0, 0, 0, 0, 2**62]), "`walls`"),
    ]
    for (robot, offsets, capacities), needle in cases:
        with pytest.raises(socnav.ShapeError) as err:
            socnavgym_episode_json(obs, actions, rewards, robot, offsets, capacities, 10)
        assert err.value.what == "recording" and needle in str(err.value), str(err.value)
        assert "past the layout's 10 a row" in str(err.value)


def test_a_thread_count_past_the_bound_is_refused_at_once():
    for threads in (1025, 2**63):
        with pytest.raises(socnav.ShapeError, match=rf"`threads` must be in 1..=1024, got {threads}") as err:
            Batch("exp1", 2, threads=threads)
        assert err.value.what == "threads"
    with pytest.raises(socnav.ShapeError, match="got 5000"):
        socnav.make_vec("exp1", num_envs=2, threads=5000)


def test_every_config_error_carries_its_problems(tmp_path):
    for make in (lambda: Batch("exp1", 2, overrides="{"), lambda: socnavgym_config_toml("{")):
        with pytest.raises(socnav.ConfigError, match="not JSON") as err:
            make()
        assert len(err.value.problems) == 1 and "not JSON" in err.value.problems[0][1]
    # A YAML value JSON cannot hold, and a key 0.1.1 does not read, are named with the file.
    bad = tmp_path / "nan.yaml"
    bad.write_text("env:\n  margin: .nan\n  when: 2024-01-01\n")
    with pytest.raises(socnav.ConfigError) as err:
        load_socnavgym_yaml(bad)
    keys = [key for key, _ in err.value.problems]
    assert keys[0] == "env.margin" and "env.when" in keys
    assert all(message.startswith(str(bad)) for _, message in err.value.problems)
    assert "must be a finite number, got .nan" in str(err.value)
    assert "`env.when` is not a key of SocNavGym 0.1.1's config" in str(err.value)


def test_values_json_cannot_hold_are_named_by_their_key():
    nan = float("nan")
    with pytest.raises(socnav.ConfigError) as err:
        socnav.make_vec({"counts": {"dynamic_humans": [[nan]], "plants": [{"x": math.inf}]}}, num_envs=2)
    assert [key for key, _ in err.value.problems] == ["counts.dynamic_humans[0][0]", "counts.plants[0].x"]
    with pytest.raises(socnav.ConfigError, match=r"`episode.length` is a object \(<object"):
        socnav.make_vec({"episode": {"length": object()}}, num_envs=2)
    # numpy's numbers and arrays are numbers and lists: the same batch as Python's.
    made = [
        socnav.make_vec({"episode": {"length": length}, "counts": {"plants": plants}}, num_envs=2, obs_mode="flat")
        for length, plants in ((np.int64(9), np.array([0, 1])), (9, [0, 1]))
    ]
    runs = []
    for env in made:
        obs, _ = env.reset(seed=5)
        steps = [env.step(np.zeros((2, 3), dtype=np.float32)) for _ in range(10)]
        runs.append((obs, [(o.copy(), t.copy(), u.copy()) for o, _, t, u, _ in steps]))
    (obs_np, steps_np), (obs_py, steps_py) = runs
    assert np.array_equal(obs_np, obs_py)
    assert all(all(np.array_equal(a, b) for a, b in zip(x, y)) for x, y in zip(steps_np, steps_py))
    # The length took: the episodes are truncated at tick 10 (length + 1, as in 0.1.1), not 201.
    assert [k for k, (_, _, truncated) in enumerate(steps_py) if truncated.any()] == [9]
    single = SocNavGymEnv("exp1")
    single.reset(seed=0)
    doc = single.get_state()
    before = json.dumps(doc)
    doc["state"]["robot"]["x"] = nan
    with pytest.raises(socnav.ShapeError, match=r"`state.robot.x` must be finite, got nan") as err:
        single.set_state(doc)
    assert err.value.what == "state document"
    with pytest.raises(TypeError, match="JSON text or a mapping, got NoneType"):
        single.set_state(None)
    assert json.dumps(single.get_state()) == before


def test_a_document_is_a_json_object_of_socnavs_format():
    batch = holonomic_batch()
    before = batch.get_state(0)
    for text, found in (("null", "null"), ("[]", "a list"), ("1", "a number")):
        with pytest.raises(socnav.ShapeError, match=f"must be a JSON object, got {found}"):
            batch.set_state(0, text)
    doc = json.loads(before)
    doc["format"] = "junk"
    with pytest.raises(socnav.ShapeError, match='`format` is "junk"'):
        batch.set_state(0, json.dumps(doc))
    doc["state"]["tick"] = 2**32 + 5
    del doc["format"]
    with pytest.raises(socnav.ShapeError, match=r"0..=4294967295, got 4294967301"):
        batch.set_state(0, json.dumps(doc))
    assert batch.get_state(0) == before


def test_counts_seeds_and_callables_are_checked_before_anything_runs(tmp_path):
    with pytest.raises(ValueError, match="a seed must be in 0..2\\*\\*64, got -1"):
        socnav.evaluate("goal", "exp1", episodes=1, seed=-1)
    with pytest.raises(TypeError, match="a seed must be an int, got None"):
        socnav.evaluate("goal", "exp1", episodes=1, seed=None)
    with pytest.raises(TypeError, match=r"episodes must be an int, got 2.5"):
        socnav.evaluate("goal", "exp1", episodes=2.5)
    with pytest.raises(TypeError, match=r"num_envs must be an int, got True"):
        socnav.make_vec("exp1", num_envs=True)
    with pytest.raises(TypeError, match="reward_fn must be callable"):
        socnav.make_vec("exp1", num_envs=2, reward_fn=5)
    with pytest.raises(ValueError, match="render_size must be at least 1, got -5"):
        socnav.make_vec("exp1", num_envs=2, render_mode="rgb_array", render_size=-5)
    with pytest.raises(ValueError, match="episodes must be at least 1, got 0"):
        socnav.record("goal", "exp1", tmp_path / "none.gif", episodes=0)
    env = socnav.make_vec("exp1", num_envs=2)
    env.reset(seed=0)
    with pytest.raises(TypeError, match="options must be a dict"):
        env.reset(options=[1, 2])
    with pytest.raises(ValueError, match=r"shape \(2,\), got shape \(1, 2\)"):
        env.reset(seed=np.array([[1, 2]]))
    env.step(np.zeros((2, 3), dtype=np.float32))  # still usable


def test_recorded_actions_and_statistic_names_are_checked():
    from socnav.datasets import Episode, JsonWriter
    from socnav.metrics import EpisodeLog

    layout = socnav.make("exp1", obs_mode="flat").unwrapped._layout
    obs = np.zeros((3, layout["dim"]), np.float32)
    flags = np.zeros(2, bool)
    for actions, needle in ((np.array([0, -1], np.int64), "integers in 0..6"), (np.zeros((2, 2, 3)), "(T, 3)")):
        episode = Episode(seed=0, config="exp1", observations=obs, actions=actions, rewards=np.zeros(2, np.float32),
                          terminations=flags, truncations=flags)
        with pytest.raises(ValueError, match=re.escape(needle)):
            JsonWriter(tmp_dir(), layout).add(episode)
    with pytest.raises(TypeError, match=r"got the string 'return' \(use \['return'\]\)"):
        EpisodeLog(keys="return")
    log = EpisodeLog(keys=["return", "success"])
    log.add_rows(np.array([[1.0, 1.0], [3.0, 0.0]], np.float32))
    assert "episodes finished: 2" in str(log.summary())


def tmp_dir():
    import tempfile

    return tempfile.mkdtemp(prefix="socnav-test-")
