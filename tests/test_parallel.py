"""Work beside the caller's: the result, its errors, and BLAS restored."""

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from filter_symblend.core.parallel import Beside


def _blas_threads():
    return sorted(module["num_threads"] for module in threadpool_info() if module["user_api"] == "blas")


def test_work_beside_gives_its_result_with_blas_held_to_one_thread_and_restores_it():
    before = _blas_threads()
    matrix = np.random.default_rng(0).normal(size=(200, 200))
    beside = Beside(lambda: (matrix @ matrix.T, _blas_threads()))
    product, threads = beside.result()
    np.testing.assert_allclose(product, np.einsum("ij,kj->ik", matrix, matrix), rtol=1e-12, atol=1e-12)
    assert all(count == 1 for count in threads)
    assert _blas_threads() == before


def test_an_error_beside_is_raised_to_the_caller_and_blas_is_restored():
    before = _blas_threads()

    def fails():
        raise ValueError("no spectrum")
    beside = Beside(fails)
    with pytest.raises(ValueError, match="no spectrum"):
        beside.result()
    assert _blas_threads() == before
    beside.close()  # closing again does nothing
    assert _blas_threads() == before
