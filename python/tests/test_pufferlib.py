"""socnav.pufferlib: a native PufferEnv whose observation and reward arrays are the batch's own,
PufferLib's vectorisations over it, errors, and PufferLib's own PPO (``pufferl``) learning exp1.

Skipped when pufferlib is not importable, unless REQUIRE_PUFFERLIB=1 (then it fails);
scripts/test-trainers runs it."""

import contextlib
import io
import os

import numpy as np
import pytest

if os.environ.get("REQUIRE_PUFFERLIB") == "1":
    import pufferlib  # noqa: F401  (REQUIRE_PUFFERLIB=1: a missing PufferLib is a failure)
else:
    pytest.importorskip("pufferlib", reason="pufferlib is not installed (pip install './python[pufferlib]')")

import pufferlib
import pufferlib.vector

import socnav
import socnav.pufferlib as sp


def test_make_is_a_puffer_env_whose_buffers_are_the_batchs():
    env = sp.make("exp2", num_envs=16, seed=0)
    assert isinstance(env, pufferlib.PufferEnv)
    assert env.num_agents == 16 and env.single_observation_space.shape == (695,)
    assert env.single_action_space.n == 7 and env.shared
    obs, infos = env.reset(seed=0)
    assert obs is env.observations and infos == []
    out = env._batch.buffers()
    assert np.shares_memory(env.observations, out["obs"]) and np.shares_memory(env.rewards, out["reward"])
    before = obs.copy()
    obs2, rewards, terminals, truncations, infos = env.step(np.zeros(16, dtype=np.int32))
    assert obs2 is obs and not np.array_equal(obs, before), "the step wrote the observations in place"
    assert terminals.dtype == np.bool_ and truncations.dtype == np.bool_ and rewards.dtype == np.float32
    # The same episodes as the gymnasium vector env of the same seed (SAME_STEP autoreset).
    ref = socnav.make_vec("exp2", num_envs=16, seed=0, obs_mode="flat", action_type="discrete", autoreset_mode="same_step")
    ref.reset(seed=0)
    env.reset(seed=0)
    rng = np.random.default_rng(1)
    episodes = 0
    for _ in range(60):
        a = rng.integers(0, 7, 16)
        o, r, t, tr, infos = env.step(a.astype(np.int32))
        ro, rr, rt, rtr, rinfo = ref.step(a.astype(np.uint32))
        np.testing.assert_array_equal(o, ro)
        np.testing.assert_array_equal(r, rr)
        np.testing.assert_array_equal(t, rt)
        np.testing.assert_array_equal(tr, rtr)
        if infos:
            done = rinfo["_episode"]
            assert infos[0]["episodes"] == int(done.sum())
            assert infos[0]["return"] == pytest.approx(float(rinfo["episode"]["return"][done].mean()))
            episodes += infos[0]["episodes"]
    assert episodes > 0
    env.close()


def test_continuous_actions_and_the_serial_vectorisation_copy_into_puffers_buffers():
    env = sp.make("exp1", num_envs=4, seed=3, action_type="continuous")
    assert env.single_action_space.shape == (3,)
    env.reset(seed=3)
    env.step(np.tile(np.array([[1.0, 0.0, 0.5]], np.float32), (4, 1)))
    vec = pufferlib.vector.make(
        sp.SocNavPufferEnv, env_kwargs=dict(config="exp1", num_envs=4), backend=pufferlib.vector.Serial, num_envs=2
    )
    vec.async_reset(0)
    o, r, d, t, ta, info, ids, mask = vec.recv()
    assert o.shape == (8, 597) and list(ids) == list(range(8))
    drivers = vec.envs
    assert not any(e.shared for e in drivers), "PufferLib's shared buffers: copied into at each step"
    vec.send(np.zeros(8, dtype=np.int32))
    o, r, d, t, ta, info, ids, mask = vec.recv()
    np.testing.assert_array_equal(o[:4], drivers[0]._batch.buffers()["obs"])
    np.testing.assert_array_equal(o[4:], drivers[1]._batch.buffers()["obs"])
    assert pufferlib.vector.make(sp.SocNavPufferEnv, env_kwargs=dict(num_envs=2), backend=pufferlib.vector.PufferEnv).num_agents == 2
    vec.close()


def test_bad_input_is_a_clear_error():
    with pytest.raises(ValueError, match="action_type"):
        sp.make("exp1", num_envs=2, action_type="both")
    with pytest.raises(socnav.ConfigError):
        sp.make({"base": "exp1", "episode": {"length": -1}}, num_envs=2)
    env = sp.make("exp1", num_envs=2)
    env.reset(0)
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3, dtype=np.int32))
    with pytest.raises(ValueError):
        env.step(np.array([0, 9], dtype=np.int32))
    env.close()
    with pytest.raises(socnav.UsageError, match="closed"):
        env.step(np.zeros(2, dtype=np.int32))


#: Mean episode return over the last fifth of the run less that over the first fifth, measured
#: with this test's settings on the 2-core machine: seeds 0, 1, 2 gave 9.06, 6.83, 9.45 (first
#: fifths 1.9 to 3.0, last 9.6 to 12.0). The margin is half the smallest.
IMPROVEMENT_MARGIN = 3.4


def _pufferl_config(seed, data_dir):
    return dict(
        env="socnav/exp1", seed=seed, torch_deterministic=True, device="cpu", cpu_offload=False, compile=False,
        compile_mode="default", compile_fullgraph=False, precision="float32", optimizer="adam",
        learning_rate=3e-4, adam_beta1=0.9, adam_beta2=0.999, adam_eps=1e-8, anneal_lr=True,
        total_timesteps=300_000, batch_size="auto", bptt_horizon=64, minibatch_size=2048,
        max_minibatch_size=2048, update_epochs=4, gamma=0.99, gae_lambda=0.95, clip_coef=0.2, vf_coef=0.5,
        vf_clip_coef=0.2, ent_coef=0.01, max_grad_norm=0.5, vtrace_rho_clip=1.0, vtrace_c_clip=1.0,
        prio_alpha=0.0, prio_beta0=1.0, use_rnn=False, checkpoint_interval=10**9, data_dir=str(data_dir),
    )


def test_pufferls_ppo_learns_exp1(tmp_path):
    """PufferLib's trainer on 128 environments, 300 k steps (about 15 s): the mean return of the
    episodes ending in the last fifth of the run beats that of the first fifth by the margin."""
    import signal

    import torch

    import pufferlib.models

    handler = signal.getsignal(signal.SIGINT)
    import pufferlib.pufferl  # installs a SIGINT handler that exits the process at once

    signal.signal(signal.SIGINT, handler)  # Ctrl+C stops pytest as usual again

    torch.manual_seed(0)
    torch.set_num_threads(1)
    env = sp.make("exp1", num_envs=128, seed=0)
    ended = []  # (step, mean return, episodes)
    step = env.step

    def recording_step(actions):
        result = step(actions)
        if result[4]:
            ended.append((env.tick, result[4][0]["return"], result[4][0]["episodes"]))
        return result

    env.step = recording_step
    config = _pufferl_config(0, tmp_path)
    policy = pufferlib.models.Default(env, hidden_size=128)
    with contextlib.redirect_stdout(io.StringIO()):  # PufferLib's dashboard
        trainer = pufferlib.pufferl.PuffeRL(config, env, policy)
        while trainer.global_step < config["total_timesteps"]:
            trainer.evaluate()
            trainer.train()
        trainer.close()
    ticks = env.tick

    def mean_return(lo, hi):
        rows = [(r, n) for t, r, n in ended if lo <= t < hi]
        return sum(r * n for r, n in rows) / sum(n for _, n in rows)

    first, last = mean_return(0, ticks // 5), mean_return(ticks - ticks // 5, ticks + 1)
    print(f"pufferl on exp1: mean return {first:.2f} in the first fifth, {last:.2f} in the last")
    assert last - first >= IMPROVEMENT_MARGIN, (first, last)
