"""The pieces of the compiled core: the friction Hessian slot, the bound restriction,
rows to smooth per level, per-solve cycle options, the progress callback, the frames returned with
the result, and the one table of cell types."""
import numpy as np
import pytest

from contactmg import _core
from contactmg.model.friction import Coulomb
from contactmg.mesh.generators import RECT_BOTTOM, RECT_TOP, rectangle
from contactmg.examples.hertz import hertz_problem
from contactmg.mesh.hierarchy import MeshHierarchy
from contactmg.model.material import Material
from contactmg.mesh.mesh import CELL_DIM, CELL_NODES, FACET_NODES, _LOCAL_FACETS
from contactmg.model.obstacle import PlaneObstacle
from contactmg.solve.options import resolve_options

INF = np.inf


# -- the Hessian of the friction term ---------------------------------------------------------
def friction_gradient(s, u):
    ut = u[1:]
    g = np.zeros_like(u)
    g[1:] = s * ut / np.linalg.norm(ut)
    return g


@pytest.mark.parametrize("seed", range(5))
def test_friction_hessian_3d_matches_finite_differences(seed):
    rng = np.random.default_rng(seed)
    u = rng.normal(size=3)
    s = abs(rng.normal()) + 0.1
    H = _core.testing.friction_hessian_3D(s, u)
    h = 1e-6
    fd = np.stack([(friction_gradient(s, u + h * e) - friction_gradient(s, u - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(H, fd, atol=1e-7 * s / np.linalg.norm(u[1:]))
    assert np.allclose(H, H.T)
    assert np.all(np.linalg.eigvalsh(H) >= -1e-14)  # convex friction term
    np.testing.assert_allclose(H @ np.r_[0.0, u[1:]], 0.0, atol=1e-12)  # no curvature along u_T


def test_friction_hessian_vanishes_with_one_tangential_direction():
    assert np.all(_core.testing.friction_hessian_2D(2.0, np.array([0.3, -0.7])) == 0)
    # 3D with one tangential component fixed: friction acts on one direction only
    assert np.all(_core.testing.friction_hessian_3D(2.0, np.array([0.3, -0.7, 0.2]), 0b01) == 0)
    assert np.all(_core.testing.friction_hessian_3D(2.0, np.array([0.3, 0.0, 0.0])) == 0)  # sticking: no Hessian


# -- bound restriction ------------------------------------------------------
def prolongation(n_fine, rows):
    """rows: per fine node a list of (coarse node, weight)."""
    ptr = np.cumsum([0] + [len(r) for r in rows]).astype(np.int64)
    parent = np.array([c for r in rows for c, _ in r], np.int64)
    weight = np.array([w for r in rows for _, w in r], float)
    return ptr, parent, weight


def test_bound_restriction_empty_and_last_columns():
    # 3 fine nodes, 4 coarse nodes: coarse node 1 is touched by no fine node (an empty column),
    # coarse node 3 (the last column) only by fine node 2
    rows = [[(0, 1.0)], [(0, 0.5), (2, 0.5)], [(3, 1.0)]]
    ptr, parent, weight = prolongation(3, rows)
    lo = np.full((3, 2), -INF)
    hi = np.full((3, 2), INF)
    hi[1, 0] = 0.2   # an inactive normal with slack 0.2 at a fine node between coarse 0 and 2
    lo[2, 1] = -0.1  # a sliding tangential at the fine node of the last column
    lc, hc = _core.testing.restrict_bounds_2D(3, 4, ptr, parent, weight, None, lo, hi)
    assert np.all(lc[1] == -INF) and np.all(hc[1] == INF)  # the empty column stays unbounded
    assert hc[0, 0] == 0.2 and hc[2, 0] == 0.2             # sum |w| = 1: the bound itself
    assert lc[3, 1] == -0.1 and hc[3, 1] == INF            # the last column gets its bound
    assert np.all(lc[:, 0] == -INF)
    # a truncated fine dof (mask 0) passes no bound down
    mask = np.ones((3, 2), np.uint8)
    mask[2, 1] = 0
    lc, hc = _core.testing.restrict_bounds_2D(3, 4, ptr, parent, weight, mask, lo, hi)
    assert lc[3, 1] == -INF


def test_bound_restriction_is_monotone_on_random_transfers():
    """Any coarse correction within the restricted bounds keeps every fine dof within its bounds."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        nf, nc = 12, 5
        rows = [[(int(c), float(rng.uniform(-1, 1))) for c in rng.choice(nc, size=rng.integers(1, 4), replace=False)]
                for _ in range(nf)]
        ptr, parent, weight = prolongation(nf, rows)
        lo = np.where(rng.random((nf, 2)) < 0.5, -rng.random((nf, 2)), -INF)
        hi = np.where(rng.random((nf, 2)) < 0.5, rng.random((nf, 2)), INF)
        lc, hc = _core.testing.restrict_bounds_2D(nf, nc, ptr, parent, weight, None, lo, hi)
        assert np.all(lc <= 0) and np.all(hc >= 0)
        for _ in range(50):
            c = np.clip(rng.normal(size=(nc, 2)), np.maximum(lc, -10), np.minimum(hc, 10))
            v = np.zeros((nf, 2))
            for i, r in enumerate(rows):
                for k, w in r:
                    v[i] += w * c[k]
            assert np.all(v >= lo - 1e-14) and np.all(v <= hi + 1e-14)


# -- rows to smooth, cycle options per solve, progress ---------------------------------------
@pytest.fixture(scope="module")
def hertz():
    return hertz_problem("triangle", 5, 0.4)


def test_rows_to_smooth_hook(hertz):
    p = hertz
    base = p.solver.core.solve()
    # listing every row explicitly is the default
    every = p.solver.new_core()
    for lvl in range(every.num_levels - 1):
        every.set_rows_to_smooth(lvl, np.arange(_core.testing.coarse_matrix(every, lvl).shape[0] // 2, dtype=np.int64))
    r_all = every.solve()
    np.testing.assert_array_equal(r_all["history"]["correction_norm"], base["history"]["correction_norm"])
    # smoothing only half of the rows of the second-finest level changes the cycle, not the answer
    sub = p.solver.new_core()
    top = sub.num_levels - 2
    n_top = _core.testing.coarse_matrix(sub, top).shape[0] // 2
    sub.set_rows_to_smooth(top, np.arange(0, n_top, 2, dtype=np.int64))
    r_sub = sub.solve()
    assert r_sub["converged"], r_sub["status"]
    assert not np.array_equal(r_sub["history"]["correction_norm"], base["history"]["correction_norm"])
    assert np.abs(r_sub["u"] - base["u"]).max() <= 1e-8 * np.abs(base["u"]).max()
    with pytest.raises(ValueError, match="row to smooth"):
        sub.set_rows_to_smooth(0, np.array([10 ** 7], np.int64))


def test_cycle_options_per_solve(hertz):
    p = hertz
    s = p.solver.core
    default = s.solve()
    v11 = s.solve(None, {"cycle": "V", "nu1": 1, "nu2": 1})
    ref = _core.ContactSolver2D(p.A, p.load, p.fixed, p.fixed_values, p.contact.nodes, p.contact.normals, p.contact.gaps,
                                p.coefficients, p.law, [t.as_tuple() for t in p.hierarchy.transfers],
                                {"cycle": "V", "nu1": 1, "nu2": 1, "ordering": resolve_options(p).ordering})
    # the same cycles as a solver built with V(1,1) (and the problem's ordering) (up to the round-off of incremental coarse updates,
    # which the Anderson mixing of settled Coulomb cycles amplifies: 1.4e-7 relative by cycle 10; where the
    # mixing continues across a state change -- V(1,1) here, from cycle 8 -- that can move the stop by a cycle)
    r_ref = ref.solve()
    assert abs(v11["cycles"] - r_ref["cycles"]) <= 1
    np.testing.assert_allclose(v11["history"]["correction_norm"][:10], r_ref["history"]["correction_norm"][:10], rtol=1e-6)
    assert v11["cycle_type"] == "V(1,1)" and default["cycle_type"] == "F(3,3)"
    assert v11["cycles"] > default["cycles"]
    again = s.solve()  # the constructor's options are back
    assert again["cycles"] == default["cycles"] and again["cycle_type"] == "F(3,3)"
    # the same bits: every solve starts from the coarse levels as the solver built them (it began from
    # the ones the solve before left, incrementally updated, and differed by their round-off)
    np.testing.assert_array_equal(again["history"]["correction_norm"], default["history"]["correction_norm"])
    np.testing.assert_array_equal(again["u"], default["u"])
    with pytest.raises(ValueError, match="cycle type"):
        s.solve(None, {"cycle": "X"})
    with pytest.raises(ValueError, match="smoothing steps"):
        s.solve(None, {"nu1": 0, "nu2": 0})


def test_progress_callback(hertz):
    s = hertz.solver.core
    seen = []
    r = s.solve(progress=lambda rec: seen.append((rec["cycle"], rec["correction_norm"], rec["active"])))
    assert [c for c, _, _ in seen] == list(range(1, r["cycles"] + 1))
    np.testing.assert_array_equal([cn for _, cn, _ in seen], r["history"]["correction_norm"])
    np.testing.assert_array_equal([a for _, _, a in seen], r["history"]["active"])

    class Stop(Exception):
        pass

    def stop_at_3(rec):
        if rec["cycle"] == 3:
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        s.solve(progress=stop_at_3)
    with pytest.raises(ValueError, match="callable"):
        s.solve(progress=3)
    assert s.solve()["cycles"] == r["cycles"]  # the solver is usable afterwards


# -- frames ------------------------------------------------------------------------------------
def test_frames_are_returned_and_orthonormal(hertz):
    s = hertz.solver.core
    r = s.solve(None, {"max_cycles": 1})
    Q = r["frames"]
    np.testing.assert_array_equal(Q, s.frames)
    assert Q.shape == (len(hertz.contact.nodes), 2, 2)
    np.testing.assert_allclose(np.einsum("cji,cjk->cik", Q, Q), np.broadcast_to(np.eye(2), Q.shape), atol=1e-15)
    n = hertz.contact.normals / np.linalg.norm(hertz.contact.normals, axis=1)[:, None]
    np.testing.assert_allclose(Q[:, :, 0], n, atol=1e-15)
    # the contact force of the result is the residual in these frames
    f = hertz.A.matvec(r["u"]) - hertz.load
    np.testing.assert_allclose(np.einsum("cji,cj->ci", Q, f[hertz.contact.nodes]), r["contact_force"],
                               atol=1e-9 * np.abs(r["contact_force"]).max())


# -- cell table --------------------------------------------------------------------------------
def test_cell_table_is_the_one_python_uses():
    table = _core.cell_table()
    body = {k: v for k, v in table.items() if v["body"]}
    assert set(body) == set(CELL_NODES)
    for name, e in body.items():
        assert e["dim"] == CELL_DIM[name] and e["nodes"] == CELL_NODES[name] and e["facet_nodes"] == FACET_NODES[name]
        assert [tuple(f) for f in e["facets"]] == [tuple(f) for f in _LOCAL_FACETS[name]]


def test_unknown_cell_type_is_an_error_not_a_hexahedron():
    pts = np.zeros((8, 3))
    cells = np.arange(8, dtype=np.int64)[None, :]
    with pytest.raises(ValueError, match="unknown cell type 'line'"):
        _core.check_cells(pts, cells, "line")
    with pytest.raises(ValueError, match="unknown cell type 'wedge'"):
        _core.assemble_elasticity(pts, cells, "wedge", 1.0, 0.3)
