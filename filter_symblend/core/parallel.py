"""Work spread over the cores with threads: numpy's ufuncs, BLAS and scipy's sparse products
release the GIL, so threads run them in parallel without copying the data."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
import contextlib
import os

import numpy as np
import scipy.linalg  # noqa: F401  (loads scipy's own BLAS, so that _BLAS finds it too)
import scipy.sparse as sp
from threadpoolctl import ThreadpoolController

WORKERS = os.cpu_count() or 1
# numpy's and scipy's BLAS, found once: threadpool_limits() looks for them again on every call (1.1 ms; a solve
# with automatic pairs holds BLAS to one thread about 20 times), a controller's limit() does not (0.01 ms).
_BLAS = ThreadpoolController()


def one_blas_thread():
    """BLAS held to one thread until the returned limiter's ``restore_original_limits()`` (or the end of its
    ``with`` block): the limits are process-wide."""
    return _BLAS.limit(limits=1, user_api="blas")


def in_threads(task: Callable, items: Iterable, limit_blas: bool = True):
    """``task(item)`` for every item, in order, on every core. With ``limit_blas`` BLAS is held
    to one thread per call (threadpoolctl) so the threads do not oversubscribe the cores (the
    warp: 1.7x faster on 2 cores than one thread with a multithreaded BLAS, measured); that
    setting is process-wide, so callers that may run concurrently (the sparse products of the
    global solve, inside ``side_by_side``) leave it off. An exception (Ctrl-C) cancels the
    items not started."""
    pool = ThreadPoolExecutor(WORKERS)
    try:
        with one_blas_thread() if limit_blas else contextlib.nullcontext():
            yield from pool.map(task, items)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def blockwise(task: Callable, items: Sequence, parallel: bool = True, limit_blas: bool = True):
    """``task(item)`` for every item, in order: :func:`in_threads` when ``parallel`` and there are two items or
    more, else in this thread (one item: no pool to start; ``parallel`` False: a caller already in threads)."""
    return in_threads(task, items, limit_blas) if parallel and len(items) > 1 else map(task, items)


def side_by_side(first: Callable, second: Callable):
    """(first(), second()), the first in a thread beside the second, BLAS held to one thread
    around both (set once here, so no concurrent caller changes it)."""
    pool = ThreadPoolExecutor(1)
    try:
        with one_blas_thread():
            future = pool.submit(first)
            second_result = second()
            return future.result(), second_result
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


class Beside:
    """``task()`` started in a thread beside the caller's own work, BLAS held to one thread (threadpoolctl) until
    the result is taken or ``close`` is called, so the two do not oversubscribe the cores and nested
    ``in_threads`` calls in either thread save and restore that same one thread. Measured on 2 cores: the
    intrinsic mirror beside a posed body's other candidates, its first map 0.2-1.0 s faster (of 5-7 s)."""

    def __init__(self, task: Callable):
        self._limits = one_blas_thread()
        self._pool = ThreadPoolExecutor(1)
        self._future = self._pool.submit(task)

    def result(self):
        """The task's result (its exception raised here), once it is done; BLAS restored."""
        try:
            return self._future.result()
        finally:
            self.close()

    def close(self) -> None:
        """Wait for the task (its result kept for ``result``), restore BLAS."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._limits.restore_original_limits()
            self._pool = None


def _row_block(matrix: sp.csr_matrix, start: int, end: int) -> sp.csr_matrix:
    """Rows ``start``..``end`` of ``matrix`` sharing its data and indices: at 10^5 pairs a copy of the global
    solve's matrices is 2 GB. (Slicing copies them, and so does scipy's constructor for a view of less than half
    of an array: its arrays are set on an empty matrix of the block's shape instead.)"""
    first, last = matrix.indptr[start], matrix.indptr[end]
    block = sp.csr_matrix((end - start, matrix.shape[1]), dtype=matrix.dtype)
    block.data, block.indices = matrix.data[first:last], matrix.indices[first:last]
    block.indptr = (matrix.indptr[start:end + 1] - first).astype(matrix.indices.dtype)
    return block


# Below this many nonzeros a product in the caller's thread is faster than one split over the cores (pair weights
# on 2 cores, 3 and 12 columns: 0.3 against 0.7 ms at 9 x 10^4, 3.4 against 4.0 ms at 10^6, 7.7 against 6.8 ms and
# 8.0 against 5.0 ms at 2.3 x 10^6).
THREADED_NONZEROS = 2**20


def row_blocks(matrix: sp.csr_matrix) -> Callable[[np.ndarray], np.ndarray]:
    """``v -> matrix @ v`` with the rows cut into one block of equal nonzeros per core (in this thread below
    THREADED_NONZEROS). Measured on 2 cores: 1.9x faster on a random 10^5 x 10^5 matrix with 295 nonzeros per row,
    but only 1.08x in the global solve at 10^5 pairs, which memory bandwidth bounds."""
    if matrix.nnz < THREADED_NONZEROS:
        return lambda vectors: matrix @ vectors
    bounds = np.searchsorted(matrix.indptr, np.linspace(0, matrix.nnz, WORKERS + 1)).clip(0, matrix.shape[0])
    bounds[0], bounds[-1] = 0, matrix.shape[0]
    blocks = [(a, b, _row_block(matrix, a, b)) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]

    def product(vectors: np.ndarray) -> np.ndarray:
        out = np.empty((matrix.shape[0],) + vectors.shape[1:])

        def block_product(block):
            a, b, rows = block
            out[a:b] = rows @ vectors
        for _ in in_threads(block_product, blocks, limit_blas=False):  # no BLAS in sparse products
            pass
        return out
    return product
