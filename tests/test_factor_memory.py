"""The memory a multifrontal factorization holds, as the cost guard estimates it
(fe.solvers.cholesky.held_entries: the packed factor and the fronts alive at the worst moment),
against the resident set a factorization measures in a process of its own."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import scipy.sparse as sp

from flexmvm.fe.solvers.cholesky import held_entries
from flexmvm.fe.solvers.symbolic import SymbolicFactor

#: A 3D grid of 22^3 nodes, 3 coupled DOFs a node (31,944 DOF: a solid's pattern), factored in
#: the integrator's dissection order with its two etree halves on two threads, as a full-FE
#: body's W and a ring basis's K_EE are. Its resident set grows as the fronts are made and
#: freed; sampled every 2 ms, the growth over the estimate measured 0.79-1.08 in repeated
#: runs of 20^3 to 26^3 grids (the allocator reuses freed fronts' pages, and the halves'
#: worst moments, taken as coinciding, need not).
_CHILD = textwrap.dedent(
    """
    import sys, threading, time
    from concurrent.futures import ThreadPoolExecutor
    from pathlib import Path
    import numpy as np, scipy.sparse as sp
    from flexmvm.fe.solvers.cholesky import held_entries, numeric_factor, warm_kernels
    from flexmvm.fe.solvers.ordering import elimination_order
    from flexmvm.fe.solvers.symbolic import SymbolicFactor
    sys.path.insert(0, sys.argv[2])
    from test_factor_memory import solid_pattern
    warm_kernels()
    A = solid_pattern(int(sys.argv[1]))
    s = SymbolicFactor(A, elimination_order(A))
    def rss():
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return float(line.split()[1]) * 1024
    peak = [0.0]
    def sample():
        while True:
            peak[0] = max(peak[0], rss())
            time.sleep(0.002)
    base = rss()
    threading.Thread(target=sample, daemon=True).start()
    with ThreadPoolExecutor(1) as pool:
        numeric_factor(s, A, pool)
    time.sleep(0.05)
    print((peak[0] - base) / (8 * held_entries(s)))
    """
)


def solid_pattern(n: int) -> sp.csc_matrix:
    """An SPD matrix with a solid's pattern: a 3D grid Laplacian of n^3 nodes, each node's
    3 DOFs coupled."""
    eye = sp.identity(n)
    t = sp.diags([-1.0, 2.001, -1.0], [-1, 0, 1], shape=(n, n))
    lap = sp.kron(sp.kron(t, eye), eye) + sp.kron(sp.kron(eye, t), eye)
    lap = lap + sp.kron(sp.kron(eye, eye), t)
    return sp.csc_matrix(sp.kron(lap, np.ones((3, 3)) + 3.0 * np.eye(3)))


def test_held_entries_is_the_factorizations_measured_peak():
    """The estimate within 0.7-1.2 of the measured growth (the spread of repeated runs above,
    with room for the sampling). ~5 s."""
    from pathlib import Path

    here = str(Path(__file__).parent)
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, "22", here], capture_output=True, text=True, check=True
    )
    ratio = float(out.stdout.split()[-1])
    assert 0.7 < ratio < 1.2, ratio


def test_held_entries_counts_the_factor_and_a_front():
    """Without fronts kept (a diagonal: every supernode a root of width 1), what is held is the
    factor alone plus the one front being made; a chain (tridiagonal) keeps one child's front
    at a time."""
    n = 50
    diag = SymbolicFactor(sp.identity(n, format="csc"), np.arange(n))
    factor = int(diag.t_off[-1] + diag.b_off[-1]) + n
    assert held_entries(diag) - factor == 1  # a 1 x 1 front
    chain = sp.csc_matrix(sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n)))
    s = SymbolicFactor(chain, np.arange(n))
    m = np.diff(s.starts) + np.diff(s.r_off)
    held = held_entries(s) - int(s.t_off[-1] + s.b_off[-1]) - n
    assert held <= 2 * int((m**2).max())
