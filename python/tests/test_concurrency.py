"""The Python batch's concurrency model: idle, busy, closed (`socnav._socnav.Batch`).

A call that arrives while another is in flight raises `UsageError` at once, a closed batch
refuses every call, a forked child may not use its parent's batch, and Ctrl-C during a rollout
interrupts it cleanly, leaving the batch usable.
"""

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import socnav
from socnav._socnav import Batch


def test_a_call_during_another_threads_step_is_refused_not_raced() -> None:
    # A batch large enough that each step takes a while with the GIL released.
    batch = Batch("exp3", 4096, seed=1, threads=1)
    batch.reset(1)
    actions = np.zeros(4096, dtype=np.uint32)
    started, done, errors = threading.Event(), threading.Event(), []

    def rollout() -> None:
        try:
            started.set()
            for _ in range(30):
                batch.step_discrete(actions)
        except Exception as e:  # noqa: BLE001 - reported by the assertion below
            errors.append(e)
        finally:
            done.set()

    worker = threading.Thread(target=rollout)
    worker.start()
    started.wait()
    refusals = 0
    while not done.is_set():
        try:
            batch.step_discrete(actions)
        except socnav.UsageError as e:
            assert "busy" in str(e) and "in flight" in str(e)
            refusals += 1
        time.sleep(0.001)
    worker.join()
    # The worker's steps were never refused: the main thread's calls either ran between them
    # (and then the worker's could be refused) or were refused themselves.
    assert all(isinstance(e, socnav.UsageError) for e in errors), errors
    assert refusals + len(errors) > 0, "no call ever overlapped a step"
    # Idle again: calls go through.
    batch.step_discrete(actions)
    assert np.isfinite(batch.buffers()["obs"]).all()


def test_a_closed_batch_refuses_every_call_and_closing_twice_is_harmless() -> None:
    batch = Batch("exp1", 2, seed=0)
    batch.reset(0)
    assert not batch.closed
    batch.close()
    batch.close()
    assert batch.closed
    for call in (
        lambda: batch.step_discrete(np.zeros(2, dtype=np.uint32)),
        lambda: batch.reset(1),
        lambda: batch.buffers(),
        lambda: batch.get_state(0),
    ):
        with pytest.raises(socnav.UsageError, match=r"the batch is closed \(close\(\) was called\)"):
            call()
    assert batch.num_envs == 2


def test_closing_the_gymnasium_environments_closes_their_batch() -> None:
    env = socnav.make("exp1")
    env.reset(seed=0)
    env.close()
    with pytest.raises(socnav.UsageError, match="closed"):
        env.step(env.action_space.sample())
    envs = socnav.make_vec("exp1", num_envs=2)
    envs.reset(seed=0)
    envs.close()
    with pytest.raises(socnav.UsageError, match="closed"):
        envs.step(envs.action_space.sample())


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs os.fork")
def test_a_forked_child_may_not_use_its_parents_batch() -> None:
    batch = Batch("exp1", 4, seed=0, threads=2)
    batch.reset(0)
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: report what using the batch did, then leave at once
        os.close(read)
        try:
            batch.step_discrete(np.zeros(4, dtype=np.uint32))
            verdict = b"stepped"
        except socnav.UsageError as e:
            verdict = b"refused: " + str(e).encode()
        except BaseException as e:  # noqa: BLE001 - reported to the parent
            verdict = b"other: " + repr(e).encode()
        os.write(write, verdict)
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as f:
        verdict = f.read().decode()
    _, status = os.waitpid(pid, 0)
    assert os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0
    assert verdict.startswith("refused: "), verdict
    assert "forked" in verdict and "'spawn'" in verdict, verdict
    # The parent's batch is untouched.
    batch.step_discrete(np.zeros(4, dtype=np.uint32))


def test_ctrl_c_during_a_rollout_interrupts_cleanly_and_leaves_the_batch_usable() -> None:
    script = textwrap.dedent(
        """
        import signal
        import sys
        import numpy as np
        from socnav._socnav import Batch

        # Python raises KeyboardInterrupt only where SIGINT was not ignored at its start, and a
        # shell's background jobs start with it ignored: restore Python's handler whatever the
        # test runner was started from.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        batch = Batch("exp3", 2048, seed=0, threads=1)
        batch.reset(0)
        actions = np.zeros(2048, dtype=np.uint32)
        print("ready", flush=True)
        try:
            while True:
                batch.step_discrete(actions)
        except KeyboardInterrupt:
            batch.step_discrete(actions)
            print("interrupted; usable:", bool(np.isfinite(batch.buffers()["obs"]).all()), flush=True)
        """
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert child.stdout is not None
    assert child.stdout.readline().strip() == "ready"
    time.sleep(0.3)
    child.send_signal(signal.SIGINT)
    try:
        out, err = child.communicate(timeout=60)
    finally:
        child.kill()
    assert child.returncode == 0, err
    assert "interrupted; usable: True" in out, (out, err)
