"""What a reduced body will cost before it is built, against its full-FE body: memory and the
bytes a Newton iteration streams (its time), both from what each model holds.

A reduced (Craig-Bampton MVM) body of nq elastic coordinates holds dense matrices: its basis
Psi (3 n x nq), m_hat and k_hat (nq x nq), the six distinct G2 inertia blocks (nq x nq each)
of the floating frame's invariants (bodies.invariants) and one dense Cholesky factor of its
iteration matrix per step size (integrate.moreau_jean.body_solver caches one per size): 8 nq^2 + 3 n nq +
s nq^2 numbers for s step sizes. A Newton iteration streams m_hat, k_hat and the G2 blocks
and solves with the factor: ~9 nq^2 numbers.

The full-FE body holds sparse M and K (CSR: 12 bytes an entry), its iteration matrix W = M +
(theta h)^2 K while it is factored, and one L D L^T factor of W per step size, whose stored
entries are read off the symbolic analysis (fe.solvers.symbolic, with the elimination order
the integrator uses: fe.solvers.ordering.elimination_order) -- the fill, not a guess: 4.2 x
nnz(K) on sphere_block's tet10 block, 2.6 x on sphere_beam's beam -- and, while the last one
is made, the multifrontal fronts beside it, read off the same analysis
(fe.solvers.cholesky.held_entries: about the factor's size again on a big part). A Newton
iteration solves with the factor (forward and backward: L read twice) and multiplies by M
and K.

Measured against these estimates (2-core AMD EPYC, docs/notes/2026-11-29-warm-command.md):
the shipped reduced scenarios estimate the reduced body both smaller and cheaper a step than
full FE, as their runs measure (peak RSS and simulation time of `flexmvm run --model full` /
`--model mvm`). The time estimate leaves out the per-step work both models share (contact
search, Python between kernels, ~10 ms a step on sphere_block), so it overstates either
side's share; the comparison is what it is used for.

Kind ``mvm-sparse`` keeps a large region sparse (its dense part is the region's ring, not its
volume, docs/concepts.md): assembly/cost_sparse.py estimates what its body holds and streams
from the mesh and the region, and the peak of its cold set-up (K_EE's factor beside psi's
exterior rows), on which its fit is judged (BodyCost.peak_bytes).

A body estimated to cost more than MARGIN x its full-FE body's memory or time a step is built
with a ReducedCostWarning that says so, and refused only when it would not fit: more than
REFUSE_SHARE of the machine's memory (an mvm-sparse body's set-up peak: whatever full FE
would take), unless ``model.allow_costly`` is set. The right size of a region is a few Hertz contact radii (DESIGN.md, "Sizing a reduced
region").
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError

#: Stored entries of the L D L^T factor per nonzero of K where no symbolic analysis was made
#: (reduced_cost without ``full``: the studies' quick estimates): measured 4.2 on
#: sphere_block's tet10 block, 2.6 on sphere_beam's, 2.5 on the seed's rods; taken as 4.
FILL_PER_NNZ = 4.0
_BYTES = 8
#: Bytes of one CSR entry (value and column index).
_CSR_BYTES = 12

#: A reduced body is warned about when its estimated memory or time a step exceeds this
#: multiple of its full-FE body's: the estimates leave out what both models share (module
#: doc) and were measured within this factor of the runs' differences.
MARGIN = 1.5

#: Streaming rate [bytes/s] that turns the bytes a Newton iteration reads into a time, for
#: the messages only (the comparison is of bytes): a 2-core AMD EPYC's measured order.
STREAM_BYTES_PER_S = 5e9

#: Factors the integrator keeps per body (integrate.moreau_jean.body_solver.MAX_CACHED): the step sizes
#: whose factors a run holds at once.
MAX_FACTORS = 10


#: Version of full_factor's counting, in its cache entries' key (the code version covers
#: fe/, mesh/, reduction/, not this module): bump when full_factor counts differently.
COUNTS_VERSION = 2  # 2: the factor as stored and the fronts (held_entries)


@dataclass(frozen=True)
class FullFactor:
    """Nonzeros of a full-FE body's K and M and the stored entries of its iteration matrix's
    L D L^T factor (the symbolic analysis's, or estimated: FullFactor.estimated); with the
    analysis, the numbers its factorization holds (fe.solvers.cholesky.held_entries): the
    packed factor as stored (``factor_entries``: each supernode's triangle as a square) and,
    besides it at the worst moment, the multifrontal fronts (``front_entries``). On the
    263,685-DOF plate in the integrator's order: L 304 M entries, stored 422 M, fronts 419 M:
    6.7 GB at the factorization's peak, where the fill alone said 2.4 GB (full FE measured
    8.9 GB with its FE model and body)."""

    k_nnz: int
    m_nnz: int
    l_nnz: int
    factor_entries: int = 0  # 0: not analysed (taken as l_nnz)
    front_entries: int = 0  # 0: not analysed (taken as the factor's: measured 0.7-1.0 x)

    @classmethod
    def estimated(cls, k_nnz: int) -> FullFactor:
        """Without a symbolic analysis: L FILL_PER_NNZ x nnz(K), M a third of K (lumped by
        node blocks)."""
        return cls(int(k_nnz), int(k_nnz) // 3, int(FILL_PER_NNZ * k_nnz))

    @property
    def stored(self) -> int:
        """Numbers one factor holds."""
        return self.factor_entries or self.l_nnz

    @property
    def fronts(self) -> int:
        """Numbers the fronts hold beside the factor at the factorization's peak."""
        return self.front_entries or self.stored

    def as_dict(self) -> dict:
        return {
            "k_nnz": self.k_nnz,
            "m_nnz": self.m_nnz,
            "l_nnz": self.l_nnz,
            "factor_entries": self.factor_entries,
            "front_entries": self.front_entries,
        }


def full_factor(fe, fixed_dofs=(), integrator_order: bool = True) -> FullFactor:
    """The FullFactor of FE model ``fe`` (its M and K) without its reference condition's
    ``fixed_dofs`` (the full-FE body's coordinates): the symbolic analysis of the pattern of
    W = M + (theta h)^2 K in the order the integrator factors it with: from SPLIT_MIN_N rows
    the one a full-FE run keeps in the setup cache under W's pattern (assembly.solver_choice:
    ~1.7 s for a 25,000-DOF rod, made once for the reduced and the full runs). Without
    ``integrator_order``: in the minimum-degree order (fe.solvers.ordering.mmd_order), the one
    fe.solvers.spd_solver factors K_EE with for kind mvm-sparse's basis; the integrator's
    dissection order makes its separator a dense clique for SuperLU, 8.3 GB of set-up on the
    263,685-DOF plate, against 1.5 GB (its fill there 304 M entries, minimum degree's 218 M)."""
    from flexmvm import setup_cache
    from flexmvm.fe.solvers import ldl
    from flexmvm.fe.solvers.cholesky import held_entries, packed_entries
    from flexmvm.fe.solvers.ordering import elimination_order, iteration_pattern
    from flexmvm.fe.solvers.symbolic import SymbolicFactor

    free = np.setdiff1d(np.arange(fe.K.shape[0]), np.asarray(fixed_dofs, np.int64))
    m, k = (sp.csr_matrix(a)[free][:, free] for a in (fe.M, fe.K))
    w = iteration_pattern(m, k)
    if not integrator_order:
        order = None  # SymbolicFactor's own: mmd_order
    elif w.shape[0] >= ldl.SPLIT_MIN_N:
        order = setup_cache.cached_elimination_order(w, elimination_order)
    else:
        order = elimination_order(w)
    symbolic = SymbolicFactor(w, order if order is not None and order.size else None)
    factor = packed_entries(symbolic)
    fronts = held_entries(symbolic) - factor
    return FullFactor(int(k.nnz), int(m.nnz), int(symbolic.nnz), factor, fronts)


def cached_full_factor(
    source: Mapping | None,
    fixed_dofs: np.ndarray,
    load_fe: Callable[[], object],
    integrator_order: bool = True,
) -> FullFactor:
    """full_factor(load_fe(), fixed_dofs, integrator_order) through the setup cache under the
    FE model's key inputs ``source`` (assembly.cache_keys.mesh_source; None: not cached) and
    the fixed DOFs: a warm run neither loads M and K for it nor repeats the analysis (0.3 s
    on sphere_block's 11,748 DOF)."""
    from flexmvm import setup_cache

    fixed = [int(i) for i in np.asarray(fixed_dofs).ravel()]
    inputs = None
    if source is not None:
        inputs = {**source, "fixed_dofs": fixed, "v": COUNTS_VERSION}
        if not integrator_order:
            inputs["order"] = "minimum degree"
    counts = setup_cache.cached_factor_counts(
        inputs, lambda: full_factor(load_fe(), fixed, integrator_order).as_dict()
    )
    return FullFactor(**counts)


def step_sizes(dt_s: float, dt_max_s: float | None) -> int:
    """Step sizes of a run, each with its own factor (integrate.run_result.TimeGrid.ticks:
    dt_s 2^k up to dt_max_s), at most MAX_FACTORS."""
    if not dt_max_s or not dt_s > 0 or dt_max_s <= dt_s:
        return 1
    return min(MAX_FACTORS, math.floor(math.log2(dt_max_s / dt_s) + 1e-9) + 1)


@dataclass(frozen=True)
class BodyCost:
    """Generalized coordinates, the estimated memory [bytes] of one body's matrices and the
    bytes a Newton iteration streams, reduced as asked and as full FE (module doc)."""

    name: str
    dof: int
    bytes: float
    full_dof: int
    full_bytes: float
    step_bytes: float = 0.0
    full_step_bytes: float = 0.0
    # the peak the fit is judged on (None: ``bytes``); what ``bytes`` is, for the messages
    peak_bytes: float | None = None
    held: str = "of dense matrices"

    @property
    def fit_bytes(self) -> float:
        """The memory the guard's fit is judged on: the peak if estimated, else ``bytes``."""
        return self.bytes if self.peak_bytes is None else self.peak_bytes

    def line(self) -> str:
        return (
            f"body {self.name!r}: reduced model {self.dof} DOF, ~{_mb(self.bytes)} "
            f"{self.held}, ~{_ms(self.step_bytes)} a Newton iteration; full FE "
            f"{self.full_dof} DOF, ~{_mb(self.full_bytes)}, ~{_ms(self.full_step_bytes)}"
        )

    def as_dict(self) -> dict:
        return {
            "dof": self.dof,
            "memory_MB": self.bytes / 1e6,
            "iteration_MB": self.step_bytes / 1e6,
            "full_fe_dof": self.full_dof,
            "full_fe_memory_MB": self.full_bytes / 1e6,
            "full_fe_iteration_MB": self.full_step_bytes / 1e6,
        }

    def costlier(self, margin: float = MARGIN) -> bool:
        """Whether the reduced body is estimated larger or slower a step than full FE by more
        than ``margin``."""
        return self.bytes > margin * self.full_bytes or (
            self.step_bytes > margin * self.full_step_bytes
        )


def _mb(x: float) -> str:
    return f"{x / 1e9:.1f} GB" if x >= 1e9 else f"{x / 1e6:.0f} MB"


def _ms(x: float) -> str:
    return f"{1e3 * x / STREAM_BYTES_PER_S:.2g} ms"


def reduced_cost(
    name: str,
    n_nodes: int,
    nq: int,
    k_nnz: int,
    *,
    full: FullFactor | None = None,
    sizes: int = 1,
) -> BodyCost:
    """The cost of a reduced body of nq elastic coordinates on a mesh of n_nodes nodes whose
    stiffness matrix has k_nnz nonzeros, and of its full-FE body (``full``: its symbolic
    analysis, else FullFactor.estimated), for a run of ``sizes`` step sizes (module doc)."""
    full = FullFactor.estimated(k_nnz) if full is None else full
    dense = _BYTES * ((8.0 + sizes) * nq * nq + 3.0 * n_nodes * nq)
    # one factor per step size, the last one made beside its fronts (FullFactor)
    sparse = _CSR_BYTES * (2.0 * full.k_nnz + full.m_nnz) + _BYTES * (
        sizes * full.stored + full.fronts
    )
    step = _BYTES * 9.0 * nq * nq
    full_step = _BYTES * 2.0 * full.l_nnz + _CSR_BYTES * (full.k_nnz + full.m_nnz)
    return BodyCost(name, 6 + nq, dense, 6 + 3 * n_nodes - 6, sparse, step, full_step)


#: The share of the machine's physical memory above which a reduced body is refused (it
#: would not fit beside the run's other arrays); below it a body that costs more than its
#: full-FE body is built with a ReducedCostWarning.
REFUSE_SHARE = 0.5


def _physical_bytes() -> float:
    """The machine's physical memory [bytes] (os.sysconf; 16 GB where it cannot be read)."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 16e9


#: Above this much memory [bytes] a reduced body is refused unless model.allow_costly is set.
REFUSE_ABOVE_BYTES = REFUSE_SHARE * _physical_bytes()


class ReducedCostWarning(UserWarning):
    """A reduced body estimated larger or slower a step than its full-FE body by more than
    MARGIN (small enough to be built)."""


def check_cost(cost: BodyCost, allow: bool, where: str) -> None:
    """Nothing when ``allow`` (model.allow_costly) is set or the reduced body is estimated
    within MARGIN of its full-FE body's memory and time a step; InputError (one line) when it
    would take more than REFUSE_ABOVE_BYTES (REFUSE_SHARE of the machine's memory) and is
    either larger than full FE or has an estimated peak (``peak_bytes``: kind mvm-sparse,
    assembly.cost_sparse, refused on it before it allocates); else a ReducedCostWarning
    saying how it costs more."""
    if allow:
        return
    if cost.peak_bytes is not None and cost.peak_bytes > REFUSE_ABOVE_BYTES:
        raise _refused(cost, where)
    if not cost.costlier():
        return
    if cost.fit_bytes <= REFUSE_ABOVE_BYTES or cost.bytes <= cost.full_bytes:
        import warnings

        how = " and ".join(
            word
            for word, more in (
                ("memory", cost.bytes > MARGIN * cost.full_bytes),
                ("time a step", cost.step_bytes > MARGIN * cost.full_step_bytes),
            )
            if more
        )
        warnings.warn(
            f"{where}: the reduced model costs more than full FE (its {how} more than "
            f"{MARGIN:g} x; {cost.line()}); kind 'mvm-sparse' keeps a large region sparse, "
            "kind 'full' is as cheap",
            ReducedCostWarning,
            stacklevel=3,
        )
        return
    raise _refused(cost, where)


def _refused(cost: BodyCost, where: str) -> InputError:
    """The one-line refusal of a reduced body that would not fit."""
    return InputError(
        f"{where}: the reduced model would not fit ({cost.dof} DOF, ~{_mb(cost.fit_bytes)} "
        f"{cost.held}, more than {REFUSE_SHARE:.0%} of this machine's "
        f"{_mb(REFUSE_ABOVE_BYTES / REFUSE_SHARE)}; full FE {cost.full_dof} DOF, "
        f"~{_mb(cost.full_bytes)}); expected a smaller region (a few Hertz contact radii), "
        "kind 'mvm-sparse' or 'full', or allow_costly = true"
    )
