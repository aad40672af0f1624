"""The Python package against its contract: gymnasium's API, zero-copy outputs, errors that
name the bad value, and agreement between the dict and flat observations."""

import json
import math
import os

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode

import socnav
from socnav._socnav import Batch

FORWARD = np.array([0.8, 0.0, 0.3], dtype=np.float32)


def test_make_vec_steps_a_batch():
    env = socnav.make_vec("exp1", num_envs=64, seed=0)
    obs, info = env.reset(seed=0)
    assert obs["robot"].shape == (64, 9)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert reward.shape == (64,) and reward.dtype == np.float32
    assert terminated.dtype == np.bool_ and truncated.shape == (64,)
    assert info["PATH_LENGTH"].shape == (64,) and info["_PATH_LENGTH"].all()
    assert env.observation_space["humans"].shape == (64,) + env.single_observation_space["humans"].shape


def test_step_info_false_leaves_the_metrics_out_and_keeps_the_episode_statistics():
    lean = socnav.make_vec({"base": "exp1", "episode": {"length": 5}}, num_envs=4, seed=2, step_info=False)
    full = socnav.make_vec({"base": "exp1", "episode": {"length": 5}}, num_envs=4, seed=2)
    assert lean.step_info is False and full.step_info is True
    _, info = lean.reset()
    assert "PATH_LENGTH" not in info and "_PATH_LENGTH" not in info
    full.reset()
    ended = False
    for _ in range(6):
        a = np.zeros((4, 3), np.float32)
        lo, lr, lt, lu, linfo = lean.step(a)
        fo, fr, ft, fu, finfo = full.step(a)
        for key in fo:
            np.testing.assert_array_equal(lo[key], fo[key])
        np.testing.assert_array_equal(lr, fr)
        assert not any(key in linfo for key in Batch.keys()["info"])
        if "episode" in finfo:
            ended = True
            np.testing.assert_array_equal(linfo["_episode"], finfo["_episode"])
            for key, values in finfo["episode"].items():
                np.testing.assert_array_equal(linfo["episode"][key], values, err_msg=key)
    assert ended
    with pytest.raises(ValueError, match="step_info=False"):
        socnav.make_vec("exp1", num_envs=2, step_info=False, reward_fn=lambda inputs: inputs.reward)


def test_outputs_are_views_overwritten_in_place_unless_copied():
    env = socnav.make_vec("exp2", num_envs=8, obs_mode="flat")
    first, _ = env.reset(seed=1)
    kept = first.copy()
    second = env.step(np.tile(FORWARD, (8, 1)))[0]
    assert np.shares_memory(first, second)
    assert not np.array_equal(kept, second), "the robot moved: the buffer holds the new step"
    copied = socnav.make_vec("exp2", num_envs=8, obs_mode="flat", copy=True)
    a, _ = copied.reset(seed=1)
    b = copied.step(np.tile(FORWARD, (8, 1)))[0]
    assert not np.shares_memory(a, b)
    np.testing.assert_array_equal(a, kept)


def test_dict_blocks_are_the_flat_row():
    flat_env = socnav.make_vec("exp2", num_envs=4, obs_mode="flat", seed=5)
    dict_env = socnav.make_vec("exp2", num_envs=4, obs_mode="dict", seed=5)
    flat, _ = flat_env.reset(seed=5)
    blocks, _ = dict_env.reset(seed=5)
    joined = np.concatenate([blocks[k].reshape(4, -1) for k in ["robot", "humans", "laptops", "tables", "plants", "walls"]], axis=1)
    np.testing.assert_array_equal(joined, flat)
    assert dict_env.single_observation_space.contains({k: v[0] for k, v in blocks.items()})


def test_same_seed_same_rollout():
    runs = []
    for _ in range(2):
        env = socnav.make_vec("exp3", num_envs=16, obs_mode="flat", copy=True)
        env.reset(seed=7)
        rng = np.random.default_rng(0)
        rewards = [env.step(rng.uniform(-1, 1, (16, 3)).astype(np.float32) * [1, 0, 1])[1] for _ in range(50)]
        runs.append(np.stack(rewards))
    np.testing.assert_array_equal(runs[0], runs[1])


def test_autoreset_modes():
    env = socnav.make_vec({"base": "exp1", "episode": {"length": 5}}, num_envs=4, autoreset_mode="same_step")
    assert env.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    env.reset(seed=0)
    for _ in range(6):
        _, _, terminated, truncated, info = env.step(np.zeros((4, 3), dtype=np.float32))
        if (terminated | truncated).any():
            break
    done = terminated | truncated
    assert done.any()
    np.testing.assert_array_equal(info["_final_obs"], done)
    assert info["final_obs"]["robot"].shape == (4, 9)
    assert "episode" in info and info["_episode"].any()

    disabled = socnav.make_vec({"base": "exp1", "episode": {"length": 3}}, num_envs=2, autoreset_mode="disabled", obs_mode="flat")
    disabled.reset(seed=0)
    for _ in range(5):
        _, _, terminated, truncated, _ = disabled.step(np.zeros((2, 3), dtype=np.float32))
    assert (terminated | truncated).all()
    obs, _ = disabled.reset(options={"reset_mask": np.array([True, False])})
    with pytest.raises(ValueError, match="reset_mask"):
        disabled.reset(options={"reset_mask": np.array([1, 0])})


@pytest.mark.parametrize("mode", ["same_step", "next_step", "disabled"])
def test_episode_steps_count_what_the_episode_statistics_say(mode):
    """``episode_steps``: 0 at every episode's first observation, and at an episode's end the
    length the core reports for it (``info["episode"]["length"]``), in each autoreset mode."""
    env = socnav.make_vec({"base": "exp1", "episode": {"length": 3}}, num_envs=4, autoreset_mode=mode, obs_mode="flat")
    env.reset(seed=0)
    np.testing.assert_array_equal(env.episode_steps, 0)
    ends = 0
    restarted = np.zeros(4, dtype=bool)
    for _ in range(10):
        before = env.episode_steps.copy()
        _, _, terminated, truncated, info = env.step(np.zeros((4, 3), dtype=np.float32))
        ended = terminated | truncated
        if mode == "next_step":
            np.testing.assert_array_equal(env.episode_steps[restarted], 0)
            restarted = ended & ~restarted
        if ended.any() and "episode" in info:
            done = info["_episode"]
            length = info["episode"]["length"][done]
            counted = before[done] + 1 if mode == "same_step" else env.episode_steps[done]
            np.testing.assert_array_equal(counted, length)
            ends += int(done.sum())
        if mode == "same_step":
            np.testing.assert_array_equal(env.episode_steps[ended], 0)
    assert ends >= 4
    if mode == "disabled":
        assert (env.episode_steps > 0).all()
        env.reset(options={"reset_mask": np.array([True, False, True, False])})
        np.testing.assert_array_equal(env.episode_steps == 0, [True, False, True, False])


def test_with_overrides_merges_tables():
    merged = socnav.with_overrides({"base": "exp2", "observation": {"frame": "robot"}}, {"observation": {"robot_velocity": True}})
    assert merged == {"base": "exp2", "observation": {"frame": "robot", "robot_velocity": True}}
    assert socnav.with_overrides("exp1", {"episode": {"length": 5}}) == {"base": "exp1", "episode": {"length": 5}}
    env = socnav.make_vec(socnav.with_overrides("exp2", {"observation": {"robot_velocity": True}}), num_envs=2)
    assert env.single_observation_space["robot"].shape == (12,)
    with pytest.raises(TypeError, match="config must be"):
        socnav.with_overrides(3, {})


@pytest.mark.parametrize(
    "actions, message",
    [
        (np.zeros((4, 2), dtype=np.float32), r"shape \(4, 3\)"),
        (np.full((4, 3), np.nan, dtype=np.float32), "finite"),
        (np.array([["a", "b", "c"]] * 4), "real numbers"),
        (np.tile([0.5, 0.5, 0.0], (4, 1)), "lateral"),
    ],
)
def test_bad_continuous_actions_are_value_errors(actions, message):
    env = socnav.make_vec("exp1", num_envs=4)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(actions)
    env.step(np.zeros((4, 3), dtype=np.float32))  # the batch is still usable


def test_bad_discrete_actions_are_value_errors():
    env = socnav.make_vec("exp1", num_envs=3, action_type="discrete")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions\[1\] is 7"):
        env.step(np.array([0, 7, 2]))
    with pytest.raises(ValueError, match="integers"):
        env.step(np.array([0.0, 1.0, 2.0]))
    env.step(np.array([0, 6, 2]))


def test_config_errors_name_every_problem():
    with pytest.raises(socnav.ConfigError) as err:
        socnav.make_vec({"base": "exp2", "counts": {"plants": [3, 1]}, "episode": {"lenght": 9}}, num_envs=2)
    assert "plants" in str(err.value) and "lenght" in str(err.value)
    assert issubclass(socnav.ConfigError, socnav.SocNavError)
    with pytest.raises(FileNotFoundError, match="no_such_config"):
        socnav.make_vec("no_such_config", num_envs=2)
    with pytest.raises(ValueError, match="num_envs"):
        socnav.make_vec("exp1", num_envs=0)
    with pytest.raises(ValueError, match="obs_mode"):
        socnav.make_vec("exp1", num_envs=1, obs_mode="image")
    with pytest.raises(ValueError, match="backend must be one of"):
        socnav.make_vec("exp1", num_envs=1, backend="tpu")


def test_errors_carry_their_fields_and_keep_python_conventions(tmp_path):
    """Every core error is a SocNavError with what a caller branches on as attributes, and also
    the builtin exception Python code expects (ValueError, IndexError, the OSError of its kind)."""
    with pytest.raises(socnav.ConfigError) as err:
        socnav.make_vec({"base": "exp1", "robot": {"radius": -1.0}, "events": {"crowd_formation_probability": 2.0}})
    keys = {key for key, _ in err.value.problems}
    assert {"robot.radius", "events.crowd_formation_probability"} <= keys, err.value.problems
    env = socnav.make_vec("exp1", num_envs=3)  # kept: a collected environment closes its batch
    batch = env._batch
    with pytest.raises(socnav.EnvIndexError) as err:
        batch.get_state(5)
    assert isinstance(err.value, IndexError) and isinstance(err.value, ValueError)
    assert isinstance(err.value, socnav.SocNavError)
    assert (err.value.env, err.value.n_envs) == (5, 3)
    with pytest.raises(socnav.ShapeError) as err:
        batch.reset_envs(np.array([True, False]))
    assert isinstance(err.value, ValueError) and err.value.what == "reset mask"
    with pytest.raises(socnav.ShapeError) as err:
        batch.set_state(0, '{"format": "nope"}')
    assert err.value.what == "state document"
    with pytest.raises(socnav.ActionError) as err:
        batch.step_discrete(np.array([0, 9, 0], np.uint32))
    assert isinstance(err.value, ValueError) and err.value.env == 1
    # An I/O error keeps its kind: a directory where a file should be is IsADirectoryError (or
    # PermissionError), not FileNotFoundError; a missing one is FileNotFoundError.
    with pytest.raises(FileNotFoundError) as err:
        socnav.make_vec(str(tmp_path / "missing.toml"))
    with pytest.raises(OSError) as err:
        socnav.make_vec(str(tmp_path))
    assert not isinstance(err.value, FileNotFoundError), type(err.value)


def test_a_document_with_overlapping_tables_is_refused_not_a_panic():
    """Tables loaded across each other make RVO2 split their edges past the config's obstacle
    capacity: `set_state` raises a ShapeError naming both counts (it used to panic) and the
    environment keeps its state."""
    env = socnav.make_vec({"base": "exp2", "counts": {"tables": [4, 4], "laptops": [0, 0]}}, num_envs=2)
    env.reset(seed=0)
    batch = env._batch
    before = batch.get_state(0)
    doc = json.loads(before)
    for k, table in enumerate(doc["state"]["tables"]):
        table.update(x=0.0, y=0.0, theta=0.1 + k * math.pi / 4)
    with pytest.raises(socnav.ShapeError) as err:
        batch.set_state(0, json.dumps(doc))
    assert err.value.what == "state document"
    assert "ORCA obstacles need" in str(err.value) and "this config holds" in str(err.value)
    assert batch.get_state(0) == before


@pytest.mark.parametrize("config, obs_mode, action_type", [("exp1", "dict", "continuous"), ("exp3", "flat", "discrete")])
def test_single_env_passes_check_env(config, obs_mode, action_type):
    env = socnav.make(config, obs_mode=obs_mode, action_type=action_type)
    check_env(env, skip_render_check=True)
    _, info = env.reset(seed=0)
    assert info == {}
    info = env.step(env.action_space.sample())[4]
    assert info["TIME_TO_REACH_GOAL"] is None, "None before success, as in SocNavGym"


def test_shipped_configs_are_listed():
    assert {"exp1", "exp2", "exp3"} <= set(socnav.shipped_configs())


def test_single_env_cannot_step_past_the_end():
    env = socnav.make("exp1", action_type="discrete")
    with pytest.raises(RuntimeError, match="reset"):
        env.step(6)
    env.reset(seed=0)
    for _ in range(1000):
        _, _, terminated, truncated, _ = env.step(5)  # backward, until the episode ends
        if terminated or truncated:
            break
    assert terminated or truncated
    with pytest.raises(RuntimeError, match="reset"):
        env.step(6)
    env.reset()
    env.step(6)


def test_a_batch_too_large_for_the_machine_raises_memory_error_naming_its_bytes():
    """Refused before anything is allocated (an allocation failure would abort the interpreter);
    `device` is None for the host's memory, the adapter's name for a GPU's."""
    with pytest.raises(MemoryError, match="use fewer environments") as caught:
        socnav.make_vec("exp1", num_envs=2**40)
    assert caught.value.bytes > 2**40
    assert caught.value.device is None
    socnav.make_vec("exp1", num_envs=2).close()


def test_gpu_backend_steps_like_the_cpu_backend():
    """The GPU backend from Python: the same observations, rewards and flags as the CPU backend,
    through autoresets. Skips without an adapter unless REQUIRE_GPU=1 (as the Rust tests).
    256 environments of exp1, the batch shape of the Rust parity test, so that the shaders come
    from Mesa's cache there."""
    try:
        gpu = socnav.make_vec("exp1", num_envs=256, seed=3, backend="gpu", obs_mode="flat")
    except socnav.BackendUnavailableError as e:
        if os.environ.get("REQUIRE_GPU") == "1":
            raise
        pytest.skip(f"no GPU adapter: {e}")
    cpu = socnav.make_vec("exp1", num_envs=256, seed=3, backend="cpu", obs_mode="flat")
    assert (gpu.backend, cpu.backend) == ("gpu", "cpu")
    obs_g, _ = gpu.reset()
    obs_c, _ = cpu.reset()
    np.testing.assert_array_equal(obs_g, obs_c)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(120):
        a = rng.uniform(-1, 1, size=(256, 3)).astype(np.float32)
        a[:, 1] = 0.0
        og, rg, tg, ug, ig = gpu.step(a)
        oc, rc, tc, uc, ic = cpu.step(a)
        for key in Batch.keys()["info"]:  # read back without the interactions and events
            np.testing.assert_array_equal(ig[key], ic[key], err_msg=key)
        np.testing.assert_array_equal(og, oc)
        np.testing.assert_array_equal(rg, rc)
        np.testing.assert_array_equal(tg, tc)
        np.testing.assert_array_equal(ug, uc)
        ended += int(tc.sum() + uc.sum())
    assert ended > 0


def test_sngnn_reward_scores_steps():
    """The SNGNN-v2 reward from Python: `exp2_sngnn` steps and reports SNGNN-v2's discomfort in
    [0, 1], and the reward of a non-terminal step is (s − 1) + distance + alive (docs/spec.md 6.3).
    Skips without the weights unless REQUIRE_SNGNN=1 (as the Rust tests)."""
    try:
        env = socnav.make_vec("exp2_sngnn", num_envs=8, seed=5, obs_mode="flat")
    except socnav.SngnnError as e:
        if os.environ.get("REQUIRE_SNGNN") == "1":
            raise
        pytest.skip(f"no SNGNN-v2 weights: {e}")
    env.reset()
    rng = np.random.default_rng(1)
    scored = 0
    # NEXT_STEP autoreset: the step after an episode's end resets it (reward 0, nothing scored).
    resetting = np.zeros(8, dtype=bool)
    for _ in range(20):
        a = rng.uniform(-1, 1, size=(8, 3)).astype(np.float32)
        a[:, 1] = 0.0
        _, reward, terminated, truncated, info = env.step(a)
        done = terminated | truncated
        live = ~done & ~resetting
        resetting = done
        s = info["DISCOMFORT_SNGNN"][live]
        assert ((s >= 0) & (s <= 1)).all(), s
        expected = (s - 1) + info["distance_reward"][live] + info["alive_reward"][live]
        np.testing.assert_allclose(reward[live], expected, atol=1e-6)
        np.testing.assert_allclose(info["sngnn_reward"][live], s - 1, atol=1e-7)
        scored += int(live.sum())
    assert scored > 0


def test_sngnn_weights_path_and_install_errors(tmp_path, monkeypatch):
    """`socnav.sngnn`: the path follows SOCNAV_SNGNN_WEIGHTS, and a wheel without the weight
    file is refused with an SngnnError that says what is missing (no network needed)."""
    monkeypatch.setenv("SOCNAV_SNGNN_WEIGHTS", str(tmp_path / "w.tch"))
    assert socnav.sngnn.weights_path() == tmp_path / "w.tch"
    import zipfile

    wheel = tmp_path / "socnavgym-0.1.1-py3-none-any.whl"
    with zipfile.ZipFile(wheel, "w") as z:
        z.writestr("socnavgym/__init__.py", "")
    dest = tmp_path / "cache" / "SOCNAV_V2.tch"
    with pytest.raises(socnav.SngnnError, match="SOCNAV_V2.tch"):
        socnav._socnav.sngnn_install_from_wheel(str(wheel), str(dest))
    assert not dest.exists(), "a failed install leaves no file"


def test_closing_an_environment_whose_construction_failed_raises_nothing() -> None:
    # gymnasium 1.2's VectorEnv.__del__ calls close() on an object whose __init__ raised (a bad
    # config, no GPU adapter) before any of its attributes was set; close must find nothing to do.
    with pytest.raises(socnav.ConfigError):
        socnav.make_vec({"base": "exp1", "counts": {"plants": [5, 1]}}, num_envs=2)
    from socnav.vector import SocNavVectorEnv

    bare = SocNavVectorEnv.__new__(SocNavVectorEnv)
    bare.close()
    bare.close()
