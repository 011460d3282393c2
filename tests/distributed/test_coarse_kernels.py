"""The core's coarse-level kernels of the distributed cycle (cpp/mg/distributed_galerkin.hpp) on one
rank against scipy: the Galerkin rows P^T M A M P with Hessian blocks, an incremental rebuild equal
bit for bit to a fresh one, restriction, prolongation, the level residual and the bound restriction."""
import numpy as np
import pytest
import scipy.sparse as sp

from contactmg import _core


def block(M, d):
    B = sp.csr_matrix(M).tobsr(blocksize=(d, d))
    B.sort_indices()
    cls = _core.BlockMatrix2D if d == 2 else _core.BlockMatrix3D
    return cls(M.shape[0] // d, M.shape[1] // d, B.indptr.astype(np.int64), B.indices.astype(np.int64),
               np.ascontiguousarray(B.data.reshape(-1, d, d)))


def case(d, nf=14, nc=5, seed=0):
    rng = np.random.default_rng(seed)
    # a symmetric fine matrix with a node graph of a few neighbours, full d x d blocks
    G = sp.random(nf, nf, density=0.3, random_state=seed) + sp.identity(nf)
    G = ((G + G.T) > 0).astype(float)
    A = sp.kron(G, np.ones((d, d))).toarray() * rng.standard_normal((nf * d, nf * d))
    A = A + A.T + 4 * d * nf * np.eye(nf * d)
    Pn = (sp.random(nf, nc, density=0.5, random_state=seed + 1) > 0).toarray()
    Pn[np.arange(nf), np.arange(nf) % nc] = True
    P = np.kron(Pn, np.ones((d, d))) * rng.standard_normal((nf * d, nc * d))
    return rng, sp.csr_matrix(A), sp.csr_matrix(P)


def kernel(P, d):
    nf, nc = P.shape[0] // d, P.shape[1] // d
    cls = _core.DistributedTransfer2D if d == 2 else _core.DistributedTransfer3D
    return cls(block(P, d), np.ones(nf, np.uint8), np.ones(nc, np.uint8))


def galerkin(T, A, mask, hess_nodes, hess, d):
    rows = (_core.CoarseRows2D if d == 2 else _core.CoarseRows3D)()
    B = block(A, d)
    T.set_fine(B, mask, hess_nodes, hess)
    if not T.has_ghost_pattern:
        T.set_ghost_pattern(np.zeros(0, np.int64), np.zeros(1, np.int64), np.zeros(0, np.int64))
    T.form_coarse(B, rows, np.arange(T.coarse_nodes))
    return rows


def dense(rows, d):
    indptr, indices, blocks = rows.blocks()
    n = rows.n
    return sp.bsr_matrix((blocks, indices, indptr), shape=(n * d, n * d)).toarray()


@pytest.mark.parametrize("d", [2, 3])
def test_galerkin_rows_are_the_triple_product_and_an_update_has_the_bits_of_a_fresh_build(d):
    rng, A, P = case(d)
    nf = A.shape[0] // d
    mask = (rng.random(nf * d) > 0.3).astype(np.uint8)
    hn = np.array([1, 4], np.int64)
    H = rng.standard_normal((2, d, d))
    T = kernel(P, d)
    rows = galerkin(T, A, np.ones(nf * d, np.uint8), np.zeros(0, np.int64), np.zeros((0, d, d)), d)
    assert np.allclose(dense(rows, d), (P.T @ A @ P).toarray(), rtol=1e-12, atol=1e-12 * abs(A).max())
    assert rows.changed.all()
    # a new truncation and Hessian blocks on the same kernel: only the rows they reach are formed again
    T.set_fine(block(A, d), mask, hn, H)
    T.form_coarse(block(A, d), rows, np.arange(T.coarse_nodes)[::-1].copy())
    Hf = np.zeros((nf * d, nf * d))
    for k, i in enumerate(hn):
        Hf[i * d:(i + 1) * d, i * d:(i + 1) * d] = H[k]
    M = np.diag(mask.astype(float))
    want = P.T.toarray() @ M @ (A.toarray() + Hf) @ M @ P.toarray()
    assert np.allclose(dense(rows, d), want, rtol=1e-12, atol=1e-12 * abs(A).max())
    fresh = galerkin(kernel(P, d), A, mask, hn, H, d)
    assert np.array_equal(rows.blocks()[2], fresh.blocks()[2])
    # the same inputs again change nothing
    T.set_fine(block(A, d), mask, hn, H)
    T.form_coarse(block(A, d), rows, np.arange(T.coarse_nodes)[::-1].copy())
    assert not rows.changed.any()


@pytest.mark.parametrize("d", [2, 3])
def test_transfers_and_residual_agree_with_scipy(d):
    rng, A, P = case(d, seed=3)
    nf, nc = A.shape[0] // d, P.shape[1] // d
    T = kernel(P, d)
    r = rng.standard_normal((nf, d))
    mask = (rng.random(nf * d) > 0.3).astype(np.uint8)
    assert np.allclose(T.restrict_residual(r).ravel(), P.T @ r.ravel(), rtol=1e-13, atol=1e-13)
    assert np.allclose(T.restrict_residual(r, mask).ravel(), P.T @ (r.ravel() * mask), rtol=1e-13, atol=1e-13)
    xc = rng.standard_normal((nc, d))
    assert np.allclose(T.prolong(xc, mask).ravel(), (P @ xc.ravel()) * mask, rtol=1e-13, atol=1e-13)
    xf = r.copy()
    T.prolong_add(xc, xf)
    assert np.allclose(xf.ravel(), r.ravel() + P @ xc.ravel(), rtol=1e-13, atol=1e-13)
    rows = galerkin(T, A, np.ones(nf * d, np.uint8), np.zeros(0, np.int64), np.zeros((0, d, d)), d)
    rows.invert(1.0)
    x, b = rng.standard_normal((nc, d)), rng.standard_normal((nc, d))
    owned = np.arange(nc) % 2 == 0
    res = rows.residual(x, b, owned.astype(np.uint8))
    want = (b.ravel() - dense(rows, d) @ x.ravel()).reshape(-1, d)
    assert np.allclose(res[owned], want[owned], rtol=1e-12, atol=1e-12 * abs(want).max())
    assert np.all(res[~owned] == 0)


@pytest.mark.parametrize("d", [2, 3])
def test_restricted_bounds_keep_every_prolonged_correction_within_the_fine_bounds(d):
    rng, A, P = case(d, seed=5)
    nf, nc = A.shape[0] // d, P.shape[1] // d
    T = kernel(P, d)
    lo = np.where(rng.random((nf, d)) > 0.5, -rng.random((nf, d)), -np.inf)
    hi = np.where(rng.random((nf, d)) > 0.5, rng.random((nf, d)), np.inf)
    x = 0.1 * rng.standard_normal((nf, d))
    x = np.clip(x, lo, hi)
    lc, hc = T.restrict_bounds(lo, hi, x=x)
    assert np.all(lc <= 0) and np.all(hc >= 0) and np.isfinite(lc).any()
    for _ in range(50):  # corners of the coarse box, where finite
        c = np.where(rng.random((nc, d)) > 0.5, lc, hc)
        c = np.where(np.isfinite(c), c, 0.0)
        v = x.ravel() + P @ c.ravel()
        assert np.all(v >= lo.ravel() - 1e-12) and np.all(v <= hi.ravel() + 1e-12)
    # rows left out and masked components impose nothing
    lc0, hc0 = T.restrict_bounds(lo, hi, mask=np.zeros(nf * d, np.uint8))
    assert np.all(lc0 == -np.inf) and np.all(hc0 == np.inf)
    lc1, hc1 = T.restrict_bounds(lo, hi, rows=np.zeros(nf, np.uint8))
    assert np.all(lc1 == -np.inf) and np.all(hc1 == np.inf)


def test_gathered_coarsest_factor_solves_and_follows_low_rank_changes():
    # an SPD matrix large enough for the low-rank path (4 x 96 rows and more), one inert dof
    rng = np.random.default_rng(7)
    n = 450
    G = sp.random(n, n, density=0.01, random_state=7)
    A = (G + G.T + sp.diags(np.full(n, 10.0))).tocsr()
    A.sort_indices()
    inert = np.zeros(n, np.uint8)
    inert[3] = 1
    f = _core.GatheredCoarsestFactor()

    def put(M, update):
        f.set(M.indptr.astype(np.int64), M.indices.astype(np.int64), M.data, inert, update)

    def reference(M):
        keep = sp.diags(1.0 - inert)
        S = (keep @ M @ keep + sp.diags(inert.astype(float))).toarray()
        return np.linalg.solve(S, b)

    b = rng.standard_normal(n)
    b[3] = 0.0
    put(A, False)
    assert np.allclose(f.solve(b), reference(A), rtol=1e-10, atol=1e-12)
    assert f.factorizations == 1 and not f.shifted
    # a few rows change: a low-rank correction of the kept factor, not a new one
    B = A.tolil()
    for i in (10, 11, 200):
        B[i, i] = B[i, i] + 5.0
    B = B.tocsr()
    B.sort_indices()
    put(B, True)
    assert f.factorizations == 1
    assert np.allclose(f.solve(b), reference(B), rtol=1e-10, atol=1e-12)
    put(B, False)
    assert f.factorizations == 2
