"""Page-locked ("pinned") host buffers for a CUDA trainer.

A vector environment's arrays are the batch's own output buffers: the CPU backend writes them,
the GPU backend reads its results back into them after every step. Copying pageable memory to a
CUDA device goes through a driver staging buffer and blocks the host; copying page-locked memory
is a direct DMA that ``tensor.to("cuda", non_blocking=True)`` can queue and forget.
``SocNavVectorEnv.pin_memory()`` page-locks the batch's buffers in place with
``cudaHostRegister`` (through torch's CUDA runtime bindings, so socnav itself stays free of
CUDA), so the tensors ``torch.from_numpy`` makes over them are pinned (``tensor.is_pinned()``).

The registration keeps the buffers alive and is undone by ``unpin_memory()``, ``close()`` or
garbage collection, before the memory could be freed. torch is imported only here, when pinning
is asked for.
"""

from __future__ import annotations

import mmap
from typing import Any, Iterable

import numpy as np

from socnav._socnav import BackendUnavailableError

# cudaHostRegisterPortable: the pages are pinned for every CUDA context, not just the current one.
_PORTABLE = 1


def page_ranges(arrays: Iterable[np.ndarray], page: int = mmap.PAGESIZE) -> list[tuple[int, int]]:
    """``(address, bytes)`` of the whole pages that hold ``arrays``, with ranges that overlap or
    touch merged: CUDA pins whole pages and refuses a range overlapping one already registered,
    and small buffers of one batch often share a page."""
    spans = sorted(
        (a.ctypes.data // page * page, -(-(a.ctypes.data + a.nbytes) // page) * page)
        for a in arrays
        if a.nbytes > 0
    )
    merged: list[list[int]] = []
    for lo, hi in spans:
        if merged and lo <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    return [(lo, hi - lo) for lo, hi in merged]


def _cudart() -> Any:
    """torch's CUDA runtime bindings, or a clear error saying what is missing."""
    try:
        import torch
    except ImportError as e:
        raise BackendUnavailableError(
            "pin_memory needs torch with CUDA (pip install torch); torch is not installed"
        ) from e
    if not torch.cuda.is_available():
        raise BackendUnavailableError(
            f"pin_memory needs a CUDA device: torch {torch.__version__} sees none "
            "(torch.cuda.is_available() is False)"
        )
    return torch.cuda.cudart()


class PinnedBuffers:
    """The CUDA registration of a set of host arrays; ``release()`` undoes it."""

    def __init__(self, arrays: Iterable[np.ndarray]) -> None:
        # Holding the arrays holds the batch that owns their memory: it cannot be freed while
        # the pages are registered.
        self._arrays: list[np.ndarray] | None = list(arrays)
        self.ranges: list[tuple[int, int]] = []
        cudart = _cudart()
        for address, size in page_ranges(self._arrays):
            error = int(cudart.cudaHostRegister(address, size, _PORTABLE))
            if error != 0:
                self.release()
                raise BackendUnavailableError(
                    f"cudaHostRegister of {size} bytes at {address:#x} failed with cudaError {error}"
                )
            self.ranges.append((address, size))

    @property
    def bytes(self) -> int:
        """Bytes page-locked (whole pages)."""
        return sum(size for _, size in self.ranges)

    def release(self) -> None:
        """Unregister every range (idempotent); the arrays are then pageable again."""
        if self.ranges:
            cudart = _cudart()
            for address, _ in self.ranges:
                cudart.cudaHostUnregister(address)
            self.ranges = []
        self._arrays = None

    def __del__(self) -> None:
        try:
            self.release()
        except Exception:  # interpreter shutdown: torch may already be gone
            pass
