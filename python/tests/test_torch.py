"""Torch without copies: on the CPU backend, the arrays a vector environment returns are views of
the batch's own buffers (``copy=False``, the default), so ``torch.from_numpy`` and
``torch.from_dlpack`` give tensors over the same memory, which every step refills in place.

Skipped when torch is not importable, unless REQUIRE_TORCH=1; scripts/test-sb3 runs it."""

import os

import numpy as np
import pytest

if os.environ.get("REQUIRE_TORCH") == "1":
    import torch  # noqa: F401  (REQUIRE_TORCH=1: a missing torch is a failure)
else:
    pytest.importorskip("torch", reason="torch is not installed (pip install './python[train]')")

import torch

import socnav


@pytest.mark.parametrize("convert", [torch.from_numpy, torch.from_dlpack], ids=["from_numpy", "dlpack"])
def test_tensors_over_the_batch_buffers_see_every_step_without_a_copy(convert) -> None:
    env = socnav.make_vec("exp2", num_envs=8, seed=1, obs_mode="flat", action_type="discrete")
    obs, _ = env.reset(seed=1)
    obs_t = convert(obs)
    reward_t = None
    assert obs_t.data_ptr() == obs.ctypes.data, "the tensor is the batch's buffer"
    assert obs_t.dtype == torch.float32 and tuple(obs_t.shape) == obs.shape
    for t in range(40):
        obs, reward, *_ = env.step(np.full(8, t % 7))
        if reward_t is None:
            reward_t = convert(reward)
        # The same memory, refilled: the tensors read this step's values with no new conversion.
        assert obs_t.data_ptr() == obs.ctypes.data
        np.testing.assert_array_equal(obs_t.numpy(), obs)
        np.testing.assert_array_equal(reward_t.numpy(), reward)
    # A policy reads the tensor directly.
    logits = torch.nn.Linear(obs_t.shape[1], 7)(obs_t)
    assert torch.isfinite(logits).all()


def test_copy_true_gives_tensors_a_step_does_not_overwrite() -> None:
    env = socnav.make_vec("exp1", num_envs=4, seed=0, obs_mode="flat", action_type="discrete", copy=True)
    obs, _ = env.reset(seed=0)
    kept = torch.from_numpy(obs)
    before = kept.clone()
    for _ in range(5):
        env.step(np.full(4, 2))
    assert torch.equal(kept, before)
