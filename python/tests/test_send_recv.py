"""Asynchronous stepping: ``send`` starts a step on the batch's threads and returns, ``recv``
waits for it. Within the batch's one concurrency model (idle, busy, closed): between the two,
every other call is refused; and the trajectory is the one ``step`` gives."""

import threading

import numpy as np
import pytest

import socnav
from socnav._socnav import Batch


def _rollout(env, actions, asynchronous: bool) -> list[np.ndarray]:
    """Every step's observation, reward, flags and metrics, as copies."""
    seen = []
    env.reset(seed=5)
    for a in actions:
        if asynchronous:
            env.send(a)
            obs, reward, terminated, truncated, info = env.recv()
        else:
            obs, reward, terminated, truncated, info = env.step(a)
        seen += [obs.copy(), reward.copy(), terminated.copy(), truncated.copy(), info["COLLISION"].copy(), info["PATH_LENGTH"].copy()]
        if "episode" in info:
            seen.append(info["episode"]["seed"].copy())
    return seen


@pytest.mark.parametrize("action_type", ["continuous", "discrete"])
def test_send_and_recv_give_the_trajectory_step_gives(action_type: str) -> None:
    # exp1's episodes end within the 260 steps (time limit 200), so autoresets are covered.
    make = lambda: socnav.make_vec("exp1", num_envs=16, seed=5, obs_mode="flat", action_type=action_type, threads=2)
    rng = np.random.default_rng(3)
    if action_type == "continuous":
        actions = rng.uniform(-1, 1, size=(260, 16, 3)).astype(np.float32)
        actions[:, :, 1] = 0.0
    else:
        actions = rng.integers(0, 7, size=(260, 16))
    stepped = _rollout(make(), actions, asynchronous=False)
    sent = _rollout(make(), actions, asynchronous=True)
    assert len(stepped) == len(sent) > 5 * 260, "episodes ended"
    for k, (a, b) in enumerate(zip(stepped, sent)):
        np.testing.assert_array_equal(a, b, err_msg=f"item {k}")


def test_between_send_and_recv_every_other_call_is_refused() -> None:
    env = socnav.make_vec("exp1", num_envs=4, seed=0, action_type="discrete")
    env.reset(seed=0)
    env.send(np.zeros(4, dtype=np.int64))
    for call in (
        lambda: env.step(np.zeros(4, dtype=np.int64)),
        lambda: env.send(np.zeros(4, dtype=np.int64)),
        lambda: env.reset(),
        lambda: env._batch.get_state(0),
        lambda: env._batch.buffers(),
    ):
        with pytest.raises(socnav.UsageError, match=r"not yet received: call recv\(\)"):
            call()
    obs, reward, *_ = env.recv()
    assert np.isfinite(reward).all()
    with pytest.raises(socnav.UsageError, match=r"recv\(\) without a step in flight"):
        env.recv()
    env.step(np.ones(4, dtype=np.int64))  # idle again


def test_a_bad_action_is_refused_by_send_and_nothing_is_sent() -> None:
    batch = Batch("exp1", 2, seed=0)
    batch.reset(0)
    with pytest.raises(socnav.ActionError, match="environment 1: discrete action 9"):
        batch.send_discrete(np.array([0, 9], dtype=np.uint32))
    with pytest.raises(socnav.UsageError, match="without a step in flight"):
        batch.recv()
    diff = np.zeros((2, 3), dtype=np.float32)
    diff[1, 1] = 0.5
    with pytest.raises(socnav.ActionError, match="lateral component"):
        batch.send_continuous(diff)
    batch.step_discrete(np.array([0, 1], dtype=np.uint32))


def test_closing_waits_for_a_sent_step_and_recv_from_another_thread_works() -> None:
    batch = Batch("exp3", 2048, seed=1, threads=1)
    batch.reset(1)
    batch.send_discrete(np.zeros(2048, dtype=np.uint32))
    batch.close()
    assert batch.closed
    with pytest.raises(socnav.UsageError, match="the batch is closed"):
        batch.recv()

    other = Batch("exp1", 8, seed=2)
    other.reset(2)
    other.send_discrete(np.full(8, 3, dtype=np.uint32))
    errors: list[Exception] = []
    receiver = threading.Thread(target=lambda: _catch(errors, other.recv))
    receiver.start()
    receiver.join()
    assert errors == []
    assert np.isfinite(other.buffers()["obs"]).all()


def _catch(errors: list[Exception], call) -> None:
    try:
        call()
    except Exception as e:  # noqa: BLE001 - reported by the caller's assertion
        errors.append(e)
