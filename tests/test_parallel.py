"""Work beside the caller's: the result, its errors, and BLAS restored; a sparse product split over the cores."""

import numpy as np
import pytest
from threadpoolctl import threadpool_info

import scipy.sparse as sp

from filter_symblend.core.parallel import WORKERS, Beside, blockwise, in_threads, row_blocks


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


def test_threads_hold_every_loaded_blas_to_one_thread_and_restore_it():
    """The limit comes from a controller found once (at import); threadpoolctl's fresh inspection here must see
    every BLAS loaded (numpy's, and scipy's own where it has one) at one thread inside, as before after."""
    import scipy.linalg  # noqa: F401  (scipy's BLAS, if it has its own, is loaded)
    before = _blas_threads()
    seen = list(in_threads(lambda _: _blas_threads(), range(2 * WORKERS)))
    assert all(threads == [1] * len(before) for threads in seen), seen
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


def test_the_product_by_row_blocks_equals_the_whole_matrixs_and_shares_its_storage(monkeypatch):
    """The global solve's product, its rows cut into one block per core: the same values as scipy's product
    (rows of very different lengths, an empty one), and the blocks are views of the matrix, not copies; below
    THREADED_NONZEROS, scipy's product itself, in this thread."""
    from filter_symblend.core import parallel
    rng = np.random.default_rng(2)
    emptied = np.ones(2960)
    emptied[100] = 0.0  # an empty row
    sparse_rows = sp.diags(emptied) @ sp.random(2960, 3000, density=0.01, format="csr", random_state=3)
    matrix = sp.csr_matrix(sp.vstack([rng.normal(size=(40, 3000)), sparse_rows]))  # a few dense rows first
    vectors = rng.normal(size=(3000, 3))
    assert matrix.nnz < parallel.THREADED_NONZEROS
    direct = row_blocks(matrix)
    np.testing.assert_array_equal(direct(vectors), matrix @ vectors)
    assert not any(isinstance(cell.cell_contents, list) for cell in direct.__closure__ or ())  # no blocks
    monkeypatch.setattr(parallel, "THREADED_NONZEROS", 0)
    product = row_blocks(matrix)
    np.testing.assert_allclose(product(vectors), matrix @ vectors, rtol=1e-12, atol=1e-12)
    cells = product.__closure__  # the blocks the product holds
    blocks = next(cell.cell_contents for cell in cells if isinstance(cell.cell_contents, list))
    assert len(blocks) == WORKERS and all(np.shares_memory(rows.data, matrix.data) for _, _, rows in blocks)


def test_blockwise_keeps_the_order_and_starts_no_pool_for_one_item_or_when_told_not_to():
    import threading

    here = threading.get_ident()
    assert list(blockwise(lambda k: k * k, range(50))) == [k * k for k in range(50)]
    assert list(blockwise(lambda _: threading.get_ident(), range(1))) == [here]
    assert set(blockwise(lambda _: threading.get_ident(), range(8), parallel=False)) == {here}
