"""socnav.jax: copies by default, views through DLPack on request, and the view's rule (the
next step overwrites it) shown to hold.

Skipped when jax is not importable, unless REQUIRE_JAX=1 (then it fails); scripts/test-trainers
runs it."""

import os

import numpy as np
import pytest

if os.environ.get("REQUIRE_JAX") == "1":
    import jax  # noqa: F401  (REQUIRE_JAX=1: a missing JAX is a failure)
else:
    pytest.importorskip("jax", reason="jax is not installed (pip install './python[jax]')")

import jax
import jax.numpy as jnp

import socnav
import socnav.jax as sj

ZERO = np.zeros((8, 3), dtype=np.float32)


def _env(**kwargs):
    return socnav.make_vec("exp2", num_envs=8, obs_mode="flat", **kwargs)


def test_copies_by_default_keep_their_values_past_the_next_step():
    env = sj.wrap(_env())
    obs, _ = env.reset(seed=0)
    assert isinstance(obs, jax.Array) and obs.shape == (8, 695) and obs.dtype == jnp.float32
    kept = np.array(obs)
    buffer = env.unwrapped._batch.buffers()["obs"]
    assert not sj.shares_memory(obs, buffer)
    obs2, reward, terminated, truncated, info = env.step(jnp.asarray(ZERO))
    assert not np.array_equal(np.asarray(obs2), kept), "the robot's step moves the records"
    np.testing.assert_array_equal(np.asarray(obs), kept)
    np.testing.assert_array_equal(np.asarray(obs2), buffer)
    assert reward.shape == (8,) and terminated.dtype == jnp.bool_ and truncated.shape == (8,)
    assert isinstance(info, dict)


def test_a_view_is_the_batch_buffer_and_the_next_step_overwrites_it():
    env = sj.wrap(_env(), view=True)
    obs, _ = env.reset(seed=0)
    buffer = env.unwrapped._batch.buffers()["obs"]
    assert sj.shares_memory(obs, buffer), "the observation buffer is 64-byte aligned: no copy"
    before = np.array(obs)
    env.step(ZERO)
    now = np.asarray(obs)
    assert not np.array_equal(now, before), "the rule: a view changes at the next step"
    np.testing.assert_array_equal(now, buffer)
    # What was computed and finished before the step keeps its value.
    env2 = sj.wrap(_env(), view=True)
    obs, _ = env2.reset(seed=0)
    total = jax.block_until_ready(jnp.sum(obs))
    env2.step(ZERO)
    assert float(total) == float(jnp.sum(jnp.asarray(before)))


def test_views_of_small_or_strided_buffers_are_copies():
    dict_env = socnav.make_vec("exp2", num_envs=8)
    env = sj.wrap(dict_env, view=True)  # the dict's blocks: strided slices of the rows
    obs, _ = env.reset(seed=0)
    blocks = dict_env._obs(dict_env.unwrapped._batch.buffers()["obs"], copy=False)
    assert set(obs) == set(blocks)
    assert not any(sj.shares_memory(obs[k], blocks[k]) for k in obs if blocks[k].size)
    _, reward, _, _, _ = env.step(ZERO)
    assert not sj.shares_memory(reward, env.unwrapped._batch.buffers()["reward"])  # 32 bytes
    with pytest.raises(ValueError, match="copy=True"):
        sj.wrap(_env(copy=True), view=True)
    with pytest.raises(ValueError, match="C-contiguous"):
        sj.asarray(np.zeros((4, 4), np.float32)[:, :2], view=True)
