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


def _cuda_or_skip() -> None:
    """Run where CUDA exists; skip loudly elsewhere (REQUIRE_CUDA=1 makes its absence a failure)."""
    if torch.cuda.is_available():
        return
    if os.environ.get("REQUIRE_CUDA") == "1":
        pytest.fail("REQUIRE_CUDA=1 but torch sees no CUDA device")
    pytest.skip(f"SKIPPED LOUDLY: no CUDA device (torch {torch.__version__}); pinned buffers untested here")


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_pinned_buffers_feed_asynchronous_copies_to_cuda(backend: str) -> None:
    _cuda_or_skip()
    try:
        env = socnav.make_vec("exp2", num_envs=64, seed=3, obs_mode="flat", action_type="discrete", backend=backend)
    except socnav.BackendUnavailableError as e:
        pytest.skip(f"SKIPPED LOUDLY: no GPU adapter for the gpu backend: {e}")
    obs, _ = env.reset(seed=3)
    obs_t = torch.from_numpy(obs)
    assert not obs_t.is_pinned()
    pinned = env.pin_memory()
    assert pinned >= obs.nbytes and env.pin_memory() == pinned, "idempotent"
    reward_t = None
    policy = torch.nn.Linear(obs.shape[1], 7).cuda()
    for _ in range(30):
        obs_cuda = obs_t.to("cuda", non_blocking=True)
        assert obs_t.is_pinned(), "the batch's buffer is page-locked"
        expected = obs.copy()
        # Bringing the actions back waits for the stream, so the copy is done before the step.
        actions = policy(obs_cuda).argmax(1).cpu().numpy()
        np.testing.assert_array_equal(obs_cuda.cpu().numpy(), expected)
        obs, reward, *_ = env.step(actions)
        assert obs.ctypes.data == obs_t.data_ptr(), "the same buffer, refilled in place"
        if reward_t is None:
            reward_t = torch.from_numpy(reward)
            assert reward_t.is_pinned()
        np.testing.assert_array_equal(reward_t.to("cuda", non_blocking=True).cpu().numpy(), reward)
    env.unpin_memory()
    assert not obs_t.is_pinned()
    env.pin_memory()
    env.close()  # unpins before the batch can be freed
    assert not obs_t.is_pinned()
