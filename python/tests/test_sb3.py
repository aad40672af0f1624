"""socnav.sb3 against Stable-Baselines3's VecEnv contract: SB3's space and NaN checks, fresh
arrays at every step, terminal observations equal to the batch's final ones, Monitor-style
episode infos, and short PPO and DQN runs that log episodes.

Skipped when stable_baselines3 is not importable, unless REQUIRE_SB3=1 (then it fails)."""

import os
import warnings

import numpy as np
import pytest

if os.environ.get("REQUIRE_SB3") == "1":
    import stable_baselines3  # noqa: F401  (REQUIRE_SB3=1: a missing SB3 is a failure)
else:
    pytest.importorskip(
        "stable_baselines3",
        reason="stable-baselines3 is not installed (pip install stable-baselines3; "
        "set REQUIRE_SB3=1 to make its absence a failure)",
    )

import gymnasium as gym
from stable_baselines3 import DQN, PPO
from stable_baselines3.common import env_checker
from stable_baselines3.common.logger import configure
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.preprocessing import check_for_nested_spaces
from stable_baselines3.common.vec_env import VecCheckNan, VecEnv

import socnav
from socnav import _batch
from socnav.metrics import EPISODE_KEYS, EpisodeLog
from socnav.sb3 import SocNavSB3VecEnv, evaluate, make_sb3

@pytest.fixture(autouse=True, scope="module")
def one_torch_thread():
    """torch's busy-waiting OpenMP threads and the batch's threads compete for the cores (the
    short PPO run takes several times longer with both at all cores of a small machine)."""
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


# Short episodes (20 steps, truncated at step 21) so that short runs finish many.
SHORT = {"base": "exp1", "episode": {"length": 20}}


def random_actions(env, rng):
    space = env.action_space
    if isinstance(space, gym.spaces.Discrete):
        return rng.integers(0, space.n, env.num_envs)
    return rng.uniform(space.low, space.high, (env.num_envs, 3)).astype(np.float32)


def env_obs(obs, i, keys=None):
    """Environment ``i``'s observation; of a dict, only ``keys`` (default all)."""
    if isinstance(obs, dict):
        return {k: obs[k][i] for k in (keys or obs)}
    return obs[i]


def assert_obs_equal(a, b):
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)
    else:
        np.testing.assert_array_equal(a, b)


def batch_buffers(env):
    # The Rust batch's own output buffers, to compare the adapter's results with.
    return env.venv._batch.buffers()


@pytest.mark.parametrize(
    "config, obs_mode, action_type",
    [("exp1", "dict", "continuous"), ("exp2", "flat", "discrete"), ("exp3", "dict", "discrete")],
)
def test_sb3_checks_and_step_contract(config, obs_mode, action_type):
    env = make_sb3(config, num_envs=6, seed=1, obs_mode=obs_mode, action_type=action_type)
    assert isinstance(env, VecEnv) and env.num_envs == 6
    # SB3's env_checker space checks, as far as they apply to a VecEnv: no warning at all.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        if hasattr(env_checker, "_check_unsupported_spaces"):
            assert env_checker._check_unsupported_spaces(env, env.observation_space, env.action_space) is False
        check_for_nested_spaces(env.observation_space)
    full = env.venv.single_observation_space
    if obs_mode == "flat":
        assert env.observation_space == full
    else:
        # Every non-empty block of the batch's dict, and only those (SB3 cannot take empty ones).
        kept = [k for k, s in full.spaces.items() if np.prod(s.shape) > 0]
        assert list(env.observation_space.spaces) == kept and "robot" in kept
        assert all(env.observation_space[k] == full[k] for k in kept)
        if config == "exp1":
            assert set(full.spaces) - set(kept) == {"laptops", "tables"}
    assert env.action_space == (gym.spaces.Discrete(7) if action_type == "discrete" else env.venv.single_action_space)

    rng = np.random.default_rng(0)
    obs = env.reset()
    assert not isinstance(obs, tuple), "SB3's reset returns the observations only"
    for _ in range(3):
        for i in range(env.num_envs):
            assert env.observation_space.contains(env_obs(obs, i))
        obs, rewards, dones, infos = env.step(random_actions(env, rng))
        assert rewards.shape == (6,) and rewards.dtype == np.float32
        assert dones.shape == (6,) and dones.dtype == np.bool_
        assert isinstance(infos, list) and len(infos) == 6 and all(isinstance(d, dict) for d in infos)
    # SB3's NaN/inf check over whole episodes (exp* episodes end by step 201).
    checked = VecCheckNan(env, raise_exception=True)
    checked.reset()
    for _ in range(210):
        checked.step(random_actions(env, rng))


@pytest.mark.parametrize("obs_mode", ["dict", "flat"])
def test_observations_and_rewards_are_fresh_copies(obs_mode):
    env = make_sb3("exp2", num_envs=8, seed=2, obs_mode=obs_mode)
    rng = np.random.default_rng(1)
    first = env.reset()
    kept = {k: v.copy() for k, v in first.items()} if obs_mode == "dict" else first.copy()
    second, rewards, dones, _ = env.step(random_actions(env, rng))
    buffers = batch_buffers(env)
    for a, b in zip(
        first.values() if obs_mode == "dict" else [first],
        second.values() if obs_mode == "dict" else [second],
    ):
        assert not np.shares_memory(a, b)
        assert not np.shares_memory(a, buffers["obs"]) and not np.shares_memory(b, buffers["obs"])
    assert not np.shares_memory(rewards, buffers["reward"])
    env.step(random_actions(env, rng))
    assert_obs_equal(first, kept)  # SB3's _last_obs survives the next step unchanged
    # ... while the batch did move on: the copy is not simply stale in the same way.
    flat_now = buffers["obs"]
    flat_first = (
        np.concatenate([kept[k].reshape(8, -1) for k in ["robot", "humans", "laptops", "tables", "plants", "walls"] if k in kept], 1)
        if obs_mode == "dict"
        else kept
    )
    assert not np.array_equal(flat_now, flat_first)


@pytest.mark.parametrize("obs_mode", ["dict", "flat"])
def test_terminal_observation_is_the_batchs_final_observation(obs_mode):
    n = 16
    env = make_sb3(SHORT, num_envs=n, seed=4, obs_mode=obs_mode, action_type="discrete")
    # The same rollout in NEXT_STEP mode returns the final observation as the step's own, up to
    # each environment's first episode end (after it the two modes' resets differ in timing).
    ref = socnav.make_vec(SHORT, n, seed=4, obs_mode=obs_mode, action_type="discrete", copy=True)
    rng = np.random.default_rng(3)
    env.reset()
    ref.reset(seed=4)
    steps = np.zeros(n, int)
    returns = np.zeros(n, np.float32)
    first_done = np.zeros(n, bool)
    finished = truncations = 0
    for _ in range(60):
        actions = rng.integers(0, 7, n)
        obs, rewards, dones, infos = env.step(actions)
        ref_obs, ref_rewards, ref_term, ref_trunc, _ = ref.step(actions)
        steps += 1
        returns += rewards
        b = batch_buffers(env)
        np.testing.assert_array_equal(b["has_final"].astype(bool), dones)
        final = b["final_obs"] if obs_mode == "flat" else _batch.split_obs(b["final_obs"], env.venv._layout)
        for i in range(n):
            info = infos[i]
            if not dones[i]:
                assert "terminal_observation" not in info and "episode" not in info
                assert info["TimeLimit.truncated"] is False
                continue
            finished += 1
            terminal = info["terminal_observation"]
            keys = list(env.observation_space.spaces) if obs_mode == "dict" else None
            assert_obs_equal(terminal, env_obs(final, i, keys))
            if not first_done[i]:
                assert_obs_equal(terminal, env_obs(ref_obs, i, keys))
                assert ref_term[i] | ref_trunc[i]
                assert info["TimeLimit.truncated"] == bool(ref_trunc[i] and not ref_term[i])
                first_done[i] = True
            # The returned observation already starts the next episode.
            assert not np.array_equal(
                terminal["robot"] if obs_mode == "dict" else terminal,
                obs["robot"][i] if obs_mode == "dict" else obs[i],
            )
            ep = info["episode"]
            assert ep["l"] == steps[i] and ep["l"] <= 21
            assert ep["r"] == pytest.approx(float(returns[i]), rel=1e-5, abs=1e-6)
            assert set(EPISODE_KEYS) <= set(ep) and ep["length"] == ep["l"]
            assert info["is_success"] == (ep["success"] == 1.0)
            truncations += info["TimeLimit.truncated"]
            assert info["TimeLimit.truncated"] == (ep["timeout"] == 1.0)
            steps[i] = 0
            returns[i] = 0.0
    assert first_done.all() and finished >= 2 * n and truncations > 0


def test_attributes_methods_seeding_and_monitor():
    env = make_sb3("exp1", num_envs=4, seed=0)
    assert env.get_attr("render_mode") == [None] * 4
    assert env.get_attr("observation_space", indices=[1, 3]) == [env.observation_space] * 2
    assert env.get_attr("action_type", indices=2) == ["continuous"]
    assert env.has_attr("obs_mode") and not env.has_attr("np_random")
    with pytest.raises(AttributeError, match="rows of one Rust batch"):
        env.get_attr("np_random")
    with pytest.raises(AttributeError, match="rows of one Rust batch"):
        env.set_attr("render_mode", "human")
    with pytest.raises(AttributeError, match="per environment"):
        env.env_method("compute_reward", 0, 1, {})
    with pytest.raises(ValueError, match="no reset options"):
        env.set_options({"difficulty": 2})
    env.set_options(None)
    with pytest.raises(RuntimeError, match="step_async"):
        env.step_wait()
    # The adapter reports episodes as Monitor does, and is no other wrapper.
    assert env.env_is_wrapped(Monitor) == [True] * 4
    assert env.env_is_wrapped(gym.Wrapper) == [True] * 4
    assert env.env_is_wrapped(gym.wrappers.TimeLimit, indices=[0]) == [False]

    # seed(s) names the episodes s + i: then reset reproduces a fresh adapter seeded with s.
    assert env.seed(5) == [5, 6, 7, 8]
    a = env.reset()
    b = make_sb3("exp1", num_envs=4, seed=5).reset()
    assert_obs_equal(a, b)
    env.seed(5)
    assert_obs_equal(env.reset(), b)
    assert not np.array_equal(env.reset()["robot"], b["robot"]), "unseeded resets move on"
    # A seed outside 0..2**64 or with a fraction is refused, not wrapped or rounded.
    with pytest.raises(ValueError, match="a seed must be in 0..2\\*\\*64, got -5"):
        env.seed(-5)
    with pytest.raises(TypeError, match="a seed must be an int, got 2.5"):
        env.seed(2.5)
    # evaluate counts whole episodes (1.5 left a fraction that never reached 0: a hang).
    with pytest.raises(TypeError, match="episodes_per_env must be an int, got 1.5"):
        evaluate(lambda obs: np.zeros((4, 3), np.float32), env, 1.5)


def test_make_vec_arguments_pass_through_except_the_fixed_ones():
    with pytest.raises(ValueError, match="backend"):
        make_sb3("exp1", num_envs=2, backend="tpu")
    assert make_sb3("exp1", num_envs=2, backend="cpu").venv.backend == "cpu"
    with pytest.raises(TypeError, match="autoreset_mode"):
        make_sb3("exp1", num_envs=2, autoreset_mode="next_step")
    with pytest.raises(TypeError, match="copy"):
        SocNavSB3VecEnv("exp1", 2, copy=True)


def test_discrete_actions_accept_a_column():
    env = make_sb3("exp1", num_envs=3, seed=0, action_type="discrete")
    env.reset()
    env.step(np.array([[0], [4], [6]]))
    with pytest.raises(ValueError, match=r"actions\[1\] is 9"):
        env.step(np.array([0, 9, 1]))


def progress(tmp_path):
    """The rows of the CSV SB3's logger wrote."""
    import csv

    with open(tmp_path / "progress.csv") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("obs_mode, policy", [("dict", "MultiInputPolicy"), ("flat", "MlpPolicy")])
def test_short_ppo_run_logs_episodes(tmp_path, obs_mode, policy):
    env = make_sb3(SHORT, num_envs=16, seed=0, obs_mode=obs_mode)
    model = PPO(policy, env, n_steps=32, batch_size=128, n_epochs=2, seed=0, device="cpu")
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(total_timesteps=2 * 32 * 16)
    assert model.num_timesteps == 2 * 32 * 16
    assert len(model.ep_info_buffer) > 16 and all(-100 < e["r"] < 100 and 1 <= e["l"] <= 21 for e in model.ep_info_buffer)
    assert len(model.ep_success_buffer) == len(model.ep_info_buffer)
    rows = progress(tmp_path)
    assert len(rows) == 2 and all(np.isfinite(float(r["rollout/ep_rew_mean"])) for r in rows)
    assert all(1 <= float(r["rollout/ep_len_mean"]) <= 21 for r in rows)
    # Evaluation with the trained model: one episode per environment.
    log = evaluate(model, make_sb3(SHORT, num_envs=8, seed=1, obs_mode=obs_mode), episodes_per_env=1)
    assert isinstance(log, EpisodeLog) and len(log) == 8
    assert log.summary()["length"] <= 21


def test_short_dqn_run_stores_terminal_observations(tmp_path):
    n = 4
    env = make_sb3(SHORT, num_envs=n, seed=0, action_type="discrete")
    model = DQN(
        "MultiInputPolicy",
        env,
        learning_starts=40,
        buffer_size=1000,
        batch_size=16,
        train_freq=4,
        target_update_interval=50,
        policy_kwargs={"net_arch": [32, 32]},
        seed=0,
        device="cpu",
    )
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(total_timesteps=400, log_interval=1)
    assert model.num_timesteps == 400 and model._n_updates > 0
    assert len(model.ep_info_buffer) >= n * (400 // n // 21)
    assert any("rollout/ep_rew_mean" in r and r["rollout/ep_rew_mean"] for r in progress(tmp_path))
    # The replay buffer holds each step's observation and the next one: within an episode the
    # next observation is the following step's observation (it would not be if the adapter's
    # returned arrays were overwritten in place); at an episode end it is the terminal one.
    rb = model.replay_buffer
    size = rb.size() if not rb.full else rb.buffer_size
    assert size == 400 // n
    dones = rb.dones[:size] + rb.timeouts[:size]
    assert dones.sum() > 0
    within = ends = 0
    for t in range(size - 1):
        for i in range(n):
            same = all(
                np.array_equal(rb.next_observations[k][t, i], rb.observations[k][t + 1, i])
                for k in rb.observations
            )
            if dones[t, i]:
                ends += 1
                assert not same, "an episode's terminal observation is not the next episode's first"
            else:
                within += 1
                assert same
    assert within > 0 and ends > 0


def test_a_socnavgym_yaml_config_steps_as_its_shipped_twin():
    """The adapter takes a SocNavGym 0.1.1 YAML path as every config argument does (the core
    converts it), and plays the twin's episodes."""
    yaml = os.path.join(os.path.dirname(__file__), "..", "..", "tests/data/golden/socnavgym/configs/exp2_no_sngnn.yaml")
    ours, twin = (make_sb3(c, num_envs=4, seed=7, obs_mode="flat") for c in (yaml, "exp2"))
    np.testing.assert_array_equal(ours.reset(), twin.reset())
    actions = np.tile(np.array([[1.0, 0.0, 0.3]], dtype=np.float32), (4, 1))
    for _ in range(30):
        ours.step_async(actions)
        twin.step_async(actions)
        (obs_a, reward_a, done_a, _), (obs_b, reward_b, done_b, _) = ours.step_wait(), twin.step_wait()
        np.testing.assert_array_equal(obs_a, obs_b)
        np.testing.assert_array_equal(reward_a, reward_b)
        np.testing.assert_array_equal(done_a, done_b)
