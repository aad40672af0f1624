"""Pinned host buffers (``SocNavVectorEnv.pin_memory``): the page arithmetic, and the errors where
CUDA is missing. The CUDA path itself is tested in test_torch.py, where a CUDA device exists."""

import importlib.util

import numpy as np
import pytest

import socnav
from socnav.pinned import page_ranges


class _At:
    """An array stand-in at a chosen address (page_ranges reads only the address and size)."""

    def __init__(self, address: int, nbytes: int) -> None:
        self.ctypes = type("ctypes", (), {"data": address})()
        self.nbytes = nbytes


def test_page_ranges_round_out_to_whole_pages_and_merge_shared_pages() -> None:
    page = 4096
    arrays = [
        _At(10 * page + 100, 50),  # inside page 10
        _At(10 * page + 3000, 2000),  # pages 10-11: shares page 10 with the first
        _At(12 * page, page),  # page 12: touches the range above, merged
        _At(20 * page + 1, 1),  # page 20 alone
        _At(30 * page, 0),  # empty: nothing to pin
    ]
    assert page_ranges(arrays, page) == [(10 * page, 3 * page), (20 * page, page)]  # type: ignore[arg-type]


def test_page_ranges_cover_every_buffer_of_a_batch() -> None:
    env = socnav.make_vec("exp1", num_envs=8, seed=0)
    buffers = list(env._buf.values())
    ranges = page_ranges(buffers)
    for a in buffers:
        if a.nbytes:
            lo, hi = a.ctypes.data, a.ctypes.data + a.nbytes
            assert any(r <= lo and hi <= r + n for r, n in ranges), "a buffer outside the ranges"
    ends = [r + n for r, n in ranges]
    assert all(ends[k] < ranges[k + 1][0] for k in range(len(ranges) - 1)), "ranges overlap or touch"
    env.close()


def _cuda_available() -> bool:
    if importlib.util.find_spec("torch") is None:
        return False
    import torch

    return bool(torch.cuda.is_available())


@pytest.mark.skipif(_cuda_available(), reason="CUDA is available: test_torch.py pins for real")
def test_pin_memory_without_cuda_says_what_is_missing() -> None:
    env = socnav.make_vec("exp1", num_envs=4, seed=0)
    with pytest.raises(socnav.BackendUnavailableError, match="pin_memory needs"):
        env.pin_memory()
    # Nothing was pinned, and the environment steps on.
    env.step(np.zeros((4, 3), dtype=np.float32))
    env.unpin_memory()  # nothing to undo
    env.close()
    with pytest.raises(socnav.UsageError, match="closed"):
        env.pin_memory()
