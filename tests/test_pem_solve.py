"""The MIP solve's multigrid-preconditioned bounded CG (pem/bake/infer.py, seed 003 §4)."""

from __future__ import annotations

import numpy as np
from scipy import sparse

from envstudio.methods.pem.bake.bake import MULTIGRID_RTOL, SOLVE_RTOL, _part_header, plan_bake
from envstudio.methods.pem.bake.infer import (
    MULTIGRID_SIZE,
    ChainMultigrid,
    bounded_cg,
    mip_regulariser,
    solve_mip,
)
from envstudio.methods.pem.bake.mip import level_offsets, mip_sizes
from envstudio.methods.pem.bake.views import arc_views


def _chain_problem(size: int, pixels: int, seed: int = 0):
    """A random rendering matrix over a chain (8 texels a row, rows summing to 1) and b."""
    rng = np.random.default_rng(seed)
    n = int(level_offsets(size)[-1])
    cols = rng.integers(0, n, (pixels, 8))
    vals = rng.random((pixels, 8))
    vals /= vals.sum(axis=1, keepdims=True)
    rows = np.repeat(np.arange(pixels), 8)
    A = sparse.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(pixels, n))
    b = rng.normal(0.3, 0.5, (pixels, 3))  # some targets below 0: the bound is active
    return A, b


def test_the_v_cycle_is_symmetric_positive_definite():
    A, _ = _chain_problem(8, 100)
    M = (A.T @ A + mip_regulariser(8, 4, 1e-3, 1e-3)).tocsr()
    mg = ChainMultigrid(M, mip_sizes(8), coarsest=50)
    assert len(mg.prolongations) == 2  # 510 → 132 → 42 texels
    B = np.column_stack([mg(e) for e in np.eye(M.shape[0])])
    np.testing.assert_allclose(B, B.T, atol=1e-10 * np.abs(B).max())
    assert np.linalg.eigvalsh((B + B.T) / 2).min() > 0


def test_multigrid_and_jacobi_reach_the_same_bounded_solution():
    size = 32
    A, b = _chain_problem(size, 1200, seed=1)
    M = (A.T @ A + mip_regulariser(size, 6, 1e-3, 1e-3)).tocsr()
    rhs = A.T @ b[:, 0]
    x0 = np.full(M.shape[0], 0.3)
    mg = ChainMultigrid(M, mip_sizes(size), coarsest=50)
    kw = {"rtol": 1e-12, "active_rounds": 20}  # rounds enough for the active set to settle
    x_j, it_j = bounded_cg(M, rhs, x0, 0.0, 1.0, **kw)
    x_m, it_m = bounded_cg(M, rhs, x0, 0.0, 1.0, preconditioner=mg, **kw)
    assert it_m < 0.6 * it_j
    np.testing.assert_allclose(x_m, x_j, atol=1e-8 * np.abs(x_j).max())
    assert x_m.min() >= 0.0 and x_m.max() <= 1.0
    assert (x_m == 0.0).any() and (x_m == 1.0).any()  # both bounds held somewhere
    free = (x_m > 0.0) & (x_m < 1.0)
    gradient = M @ x_m - rhs  # zero on the free entries: the free system is solved
    assert np.abs(gradient[free]).max() < 1e-9 * np.abs(rhs).max()


def test_solve_mip_is_the_jacobi_solve_of_before():
    size = 16
    A, b = _chain_problem(size, 300, seed=2)
    levels, _ = solve_mip(A, b, size, rtol=1e-10)
    x = np.concatenate([lv.reshape(-1, 3) for lv in levels])
    M = (A.T @ A + mip_regulariser(size, 5, 1e-3, 1e-3)).tocsr()
    rhs = A.T @ b
    for c in range(3):
        start = np.full(M.shape[0], max(b[:, c].mean(), 0.0))
        jacobi, _ = bounded_cg(M, rhs[:, c], start, 0.0, np.inf, rtol=1e-10)
        np.testing.assert_allclose(x[:, c], jacobi, atol=1e-7 * np.abs(jacobi).max())
    assert x.min() == 0.0


def test_parts_solved_with_the_multigrid_are_not_the_parts_of_before():
    """A bake part's identity names the solver from 128² EMs, so a bake interrupted before
    the multigrid does not resume with parts of other bits; below, the identity of before."""
    parts = {}
    for em_size in (MULTIGRID_SIZE // 2, MULTIGRID_SIZE):
        plan = plan_bake(
            "room", lambda c: arc_views(c, 1), em_size=em_size, lookups="cpu", probe=False
        )
        parts[em_size] = _part_header(plan.key, plan.tasks[0])["task"]
    assert "solver" not in parts[MULTIGRID_SIZE // 2]
    assert parts[MULTIGRID_SIZE]["solver"] == "multigrid"
    # its default tolerance is its own too (studies/pem-paper-scale/README.md: 10⁻⁶'s playback
    # to 0.015 dB)
    assert "rtol" not in parts[MULTIGRID_SIZE // 2]
    assert parts[MULTIGRID_SIZE]["rtol"] == MULTIGRID_RTOL > SOLVE_RTOL
