"""``socnav.socnavgym`` against SocNavGym 0.1.1 itself: the golden episodes replayed through the
compatible environment, which must return 0.1.1's observation dict (same keys in the same order,
same vector lengths, same values within the f32 tolerances of docs/fidelity.md) and its info dict
(same keys, same Python types, ``None`` where 0.1.1 has ``None``, the same interaction pairs).

The published golden set is in the repository (``tests/data/golden/socnavgym``);
``SOCNAV_GOLDEN_DIR`` points elsewhere, and without the directory these tests skip and say so."""

from __future__ import annotations

import gzip
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import socnav
from socnav.socnavgym import DiscreteActions, SocNavGymEnv, load_socnavgym_yaml

GOLDEN = Path(os.environ.get("SOCNAV_GOLDEN_DIR", Path(__file__).resolve().parents[2] / "tests/data/golden/socnavgym"))
needs_golden = pytest.mark.skipif(not GOLDEN.is_dir(), reason=f"no golden episodes at {GOLDEN}")

# docs/fidelity.md: observations within 3e-5, rewards within 1.2e-5 (f32 against 0.1.1's f64).
OBS_TOL = 3e-5
REWARD_TOL = 1.2e-5
# Info values: accumulated metrics (path length, running means) of a whole episode in f32.
INFO_TOL = 1e-4
# Info values where socnav fixes a bug of 0.1.1 (docs/fidelity.md; the Rust golden replay checks
# them against the corrected values): only their types are compared here.
FIXED_INFO = {"DISCOMFORT_DSRNN", "TIME_TO_COLLISION", "STL", "SPL"}


def _number(v):
    """The golden files write non-finite numbers as strings."""
    return float(v) if isinstance(v, str) else v


def _episode(config: str, seed: int) -> dict:
    with gzip.open(GOLDEN / f"{config}_seed{seed}.json.gz", "rt") as f:
        return json.load(f)


def _document(header: dict, state: dict, step: dict) -> str:
    """The state document that starts ``step`` from ``state`` (the golden README, section 8),
    with the group noise the step drew."""
    state = dict(state)
    if "group_noise" in step:
        state["group_noise"] = step["group_noise"]
    keys = ("room", "walls", "spawn_blockers", "human_params", "counts")
    return json.dumps({**{k: header[k] for k in keys}, "state": state})


@needs_golden
@pytest.mark.parametrize("config", ["exp1_no_sngnn", "exp2_no_sngnn", "exp3_no_sngnn"])
def test_golden_steps_return_socnavgym_outputs(config):
    env = SocNavGymEnv(GOLDEN / "configs" / f"{config}.yaml")
    env.reset(seed=0)
    compared = 0
    for seed in range(3):
        rec = _episode(config, seed)
        header, state = rec["header"], rec["initial"]["state"]
        for step in rec["steps"]:
            env.set_state(_document(header, state, step))
            obs, reward, terminated, truncated, info = env.step(np.array(step["action"], dtype=np.float32))
            state = step["state"]
            if not step.get("outputs_replayable", True):
                continue
            where = f"{config} seed {seed} step {step['t']}"
            assert list(obs) == list(step["obs"]), where
            for key, expected in step["obs"].items():
                assert obs[key].dtype == np.float32 and obs[key].ndim == 1, where
                got = obs[key].astype(np.float64)
                want = np.float32(expected).astype(np.float64)
                if key == "humans":
                    _unwrap_angular_speeds(got, want)
                np.testing.assert_allclose(got, want, rtol=0, atol=OBS_TOL, err_msg=f"{where} {key}")
            # The discomfort term is 0.1.1's with two bugs fixed (docs/fidelity.md): the rest of
            # the reward must match.
            disc, want_disc = info["DISCOMFORT_DSRNN"], step["info"]["DISCOMFORT_DSRNN"]
            if not (terminated or truncated):
                assert abs((reward - disc) - (step["reward"] - want_disc)) <= REWARD_TOL, f"{where}: reward {reward}"
            else:
                assert reward == step["reward"], where
            assert (terminated, truncated) == (step["terminated"], step["truncated"]), where
            _check_info(info, step["info"], where)
            compared += 1
    assert compared > 300


def _unwrap_angular_speeds(got: np.ndarray, want: np.ndarray) -> None:
    """docs/fidelity.md: a human's relative angular speed (record index 12) is wrapped here,
    where 0.1.1 can jump by 2π/dt (dt = 1 s in these configs). Move 0.1.1's value by whole
    turns to the one it means."""
    k = np.arange(12, want.shape[0], 14)
    turns = np.round((want[k] - got[k]) / (2 * np.pi))
    want[k] -= turns * 2 * np.pi


def _check_info(info: dict, expected: dict, where: str) -> None:
    assert set(info) == set(expected), f"{where}: {set(info) ^ set(expected)}"
    assert info["interactions"] == {k: [tuple(p) for p in v] for k, v in expected["interactions"].items()}, where
    for key, want in expected.items():
        if key == "interactions":
            continue
        got = info[key]
        want = _number(want)
        if isinstance(want, bool):
            assert got is want, f"{where} {key}: {got!r} != {want!r}"
        elif want is None:
            assert got is None, f"{where} {key}: {got!r}, 0.1.1 has None"
        elif key in ("FAILURE_TO_PROGRESS", "TIME_TO_COLLISION"):
            assert isinstance(got, int), f"{where} {key}: {got!r} is not an int"
            assert key in FIXED_INFO or got == want, f"{where} {key}: {got!r} != {want!r}"
        elif key in FIXED_INFO:
            assert isinstance(got, float), f"{where} {key}: {got!r} is not a float"
        elif math.isinf(want):
            assert got == want, f"{where} {key}: {got!r} != {want!r}"
        else:
            assert isinstance(got, float) and abs(got - want) <= INFO_TOL * max(1.0, abs(want)), (
                f"{where} {key}: {got!r} != {want!r}"
            )


@needs_golden
def test_reset_observation_has_socnavgym_keys_and_sizes():
    # Experiment 2: robot 9 + humans 7 x 14 + laptops 14 + tables 14 + walls 40 x 14
    # (docs/spec.md 5.2).
    env = SocNavGymEnv(GOLDEN / "configs" / "exp2_no_sngnn.yaml")
    obs, info = env.reset(seed=3)
    assert info == {}
    sizes = {k: v.shape[0] for k, v in obs.items()}
    assert list(obs)[0] == "robot" and sizes["robot"] == 9 and sizes["walls"] == 560
    assert sum(sizes.values()) == 695 and "plants" not in obs
    # gym's Dict sorts the keys (SB3 flattens in that order).
    assert list(env.observation_space.spaces) == sorted(obs)
    assert env.observation_space.contains(obs)


def test_padded_config_keeps_every_type_and_omits_walls():
    env = SocNavGymEnv({"base": "exp1", "observation": {"padded": True}})
    obs, _ = env.reset(seed=0)
    assert "walls" not in obs
    assert set(obs) == {"robot", "humans", "laptops", "tables", "plants"} - {
        k for k, (_, cap) in env._batch.layout()["entities"].items() if cap == 0
    }


def test_stepping_past_the_end_raises_and_state_round_trips():
    env = SocNavGymEnv("exp1")
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(3, dtype=np.float32))
    env.reset(seed=4)
    saved = env.get_state()
    backward = np.array([-1.0, 0.0, 0.0], dtype=np.float32)
    first = [env.step(backward)[1] for _ in range(3)]
    ended = False
    for _ in range(500):
        ended = any(env.step(backward)[2:4])
        if ended:
            break
    assert ended
    with pytest.raises(RuntimeError, match="reset"):
        env.step(backward)
    env.set_state(saved)
    assert [env.step(backward)[1] for _ in range(3)] == first


def test_discrete_actions_follow_socnavgym():
    env = DiscreteActions(SocNavGymEnv("exp1"))
    np.testing.assert_array_equal(env.action(4), [1, 0, 0])
    np.testing.assert_array_equal(env.action(0), [0, 0, 1])
    env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(4)
    assert isinstance(reward, float) and isinstance(info["SUCCESS"], bool)
    with pytest.raises(ValueError, match="0..6"):
        env.step(7)


def test_bad_yaml_config_names_the_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("- just\n- a list\n")
    with pytest.raises(Exception, match="bad.yaml") as err:
        load_socnavgym_yaml(bad)
    assert isinstance(err.value, socnav.ConfigError) and err.value.problems[0][1].startswith(str(bad))
    # The core's problems keep their keys behind the file's name.
    partial = tmp_path / "partial.yaml"
    partial.write_text("env:\n  margin: 0.5\n")
    with pytest.raises(socnav.ConfigError, match="partial.yaml") as err:
        load_socnavgym_yaml(partial)
    assert all(message.startswith(str(partial)) for _, message in err.value.problems)


@needs_golden
def test_a_yaml_path_is_a_config_everywhere():
    """The YAML file steps bit for bit as its shipped twin through ``make_vec``, and ``evaluate``
    and ``make`` take it too (the core converts it; no PyYAML)."""
    yaml = str(GOLDEN / "configs" / "exp2_no_sngnn.yaml")
    a = socnav.make_vec(yaml, num_envs=8, seed=4)
    b = socnav.make_vec("exp2", num_envs=8, seed=4)
    obs_a, _ = a.reset(seed=4)
    obs_b, _ = b.reset(seed=4)
    rng = np.random.default_rng(0)
    for _ in range(250):
        for key in obs_a:
            np.testing.assert_array_equal(obs_a[key], obs_b[key])
        actions = rng.uniform(-1, 1, (8, 3)).astype(np.float32)
        actions[:, 1] = 0
        obs_a, reward_a, term_a, trunc_a, _ = a.step(actions)
        obs_b, reward_b, term_b, trunc_b, _ = b.step(actions)
        np.testing.assert_array_equal(reward_a, reward_b)
        np.testing.assert_array_equal(term_a | trunc_a, term_b | trunc_b)
    ours = socnav.evaluate("goal", yaml, episodes=16, seed=3)
    twin = socnav.evaluate("goal", "exp2", episodes=16, seed=3)
    assert ours.to_markdown().split("\n")[2:] == twin.to_markdown().split("\n")[2:]
    assert socnav.make(yaml).observation_space == socnav.make("exp2").observation_space
    assert load_socnavgym_yaml(yaml) == socnav.config_toml("exp2")


def test_a_yaml_config_with_a_later_key_is_refused_by_name(tmp_path):
    source = GOLDEN / "configs" / "exp1_no_sngnn.yaml"
    if not source.is_file():
        pytest.skip(f"no golden configs at {source.parent}")
    bad = tmp_path / "later.yaml"
    bad.write_text(source.read_text().replace("episode:\n", "episode:\n  end_with_collision: True\n"))
    with pytest.raises(socnav.ConfigError, match="belongs to a later SocNavGym version") as err:
        socnav.make_vec(str(bad), num_envs=2)
    assert [key for key, _ in err.value.problems] == ["episode.end_with_collision"]
