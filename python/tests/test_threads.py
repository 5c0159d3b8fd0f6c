# SPDX-License-Identifier: MIT
# The GIL is released during solves and renders, so Python threads run them at once. ARPACK keeps
# state in Fortran SAVE variables (not re-entrant; scipy locks it too, scipy PR 5848): solves are
# serialized inside the engine (src/scene/exclusive_solve.hpp). Without that, this test dies of
# "double free or corruption". Threaded results equal sequential ones to solver precision (with
# OpenBLAS pinned to one thread they may differ in the last bits: its kernels are not bitwise
# independent of what else the process is doing).
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import strike

SHAPES = ["box:0.1,0.02,0.01", "box:0.08,0.05,0.004", "cylinder:0.01,0.1", "box:0.12,0.015,0.015"]


def solve(mesh):
    return strike.modes(mesh, material="steel", max_modes=10, error_estimate=False).eigenvalues


def test_threaded_solves_equal_sequential_ones():
    sequential = [solve(mesh) for mesh in SHAPES]
    with ThreadPoolExecutor(max_workers=4) as pool:
        threaded = list(pool.map(solve, SHAPES))
    for mesh, a, b in zip(SHAPES, sequential, threaded):
        assert a.size >= 3 and b.shape == a.shape, mesh
        np.testing.assert_allclose(b, a, rtol=1e-10, err_msg=mesh)
