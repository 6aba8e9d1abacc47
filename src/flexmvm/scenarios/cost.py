"""What a reduced body will cost before it is built, against its full-FE body.

A reduced (Craig-Bampton MVM) body of nq elastic coordinates holds dense matrices: its basis
Psi (3 n x nq), m_hat and k_hat (nq x nq) and the six distinct G2 inertia blocks (nq x nq
each) of the floating frame's invariants (bodies.invariants) -- 8 nq^2 + 3 n nq numbers.
The full-FE body holds sparse M and K and the L D L^T factor of M + h^2/4 K, about
FILL_PER_NNZ times the nonzeros of K. A retained region of a few thousand nodes (a wide
ball on a fine tet10 mesh) makes the reduced body cost many times the full one: a 2 mm ball
on a 28,000-DOF block kept 3,090 nodes, 9,289 coordinates, 18.6 GB against 1.2 GB for full
FE. Such a body is built with a ReducedCostWarning that says so (kind ``mvm-sparse`` keeps a
large region sparse: its dense part is the region's ring, not its volume, docs/concepts.md),
and refused only when it would not fit: more than REFUSE_SHARE of the machine's memory,
unless ``model.allow_costly`` is set. The right size of a region is a few Hertz contact radii
(DESIGN.md, "Sizing a reduced region").
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from flexmvm.errors import InputError

#: Nonzeros of the L D L^T factor of M + h^2/4 K per nonzero of K (fe.cholesky's symbolic
#: analysis with the package's ordering): measured 3.7 on a tet10 beam of 29,340 DOF and 2.5
#: on the seed's rods (25,000 DOF); taken as 4, with M and K themselves (2 nnz) on top: an
#: estimate of the order of the memory, not a budget.
FILL_PER_NNZ = 4.0
_BYTES = 8


@dataclass(frozen=True)
class BodyCost:
    """Generalized coordinates and the estimated memory [bytes] of one body's matrices,
    reduced as asked and as full FE."""

    name: str
    dof: int
    bytes: float
    full_dof: int
    full_bytes: float

    def line(self) -> str:
        return (
            f"body {self.name!r}: reduced model {self.dof} DOF, ~{_mb(self.bytes)} of "
            f"dense matrices; full FE {self.full_dof} DOF, ~{_mb(self.full_bytes)}"
        )

    def as_dict(self) -> dict:
        return {
            "dof": self.dof,
            "memory_MB": self.bytes / 1e6,
            "full_fe_dof": self.full_dof,
            "full_fe_memory_MB": self.full_bytes / 1e6,
        }


def _mb(x: float) -> str:
    return f"{x / 1e9:.1f} GB" if x >= 1e9 else f"{x / 1e6:.0f} MB"


def reduced_cost(name: str, n_nodes: int, nq: int, k_nnz: int) -> BodyCost:
    """The cost of a reduced body of nq elastic coordinates on a mesh of n_nodes nodes whose
    stiffness matrix has k_nnz nonzeros (module doc)."""
    dense = _BYTES * (8.0 * nq * nq + 3.0 * n_nodes * nq)
    full = _BYTES * (2.0 + FILL_PER_NNZ) * k_nnz
    return BodyCost(name, 6 + nq, dense, 6 + 3 * n_nodes - 6, full)


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
    """A reduced body that costs more than its full-FE body (small enough to be built)."""


def check_cost(cost: BodyCost, allow: bool, where: str) -> None:
    """InputError (one line) when the reduced body would take more than REFUSE_ABOVE_BYTES
    (REFUSE_SHARE of the machine's memory) and ``allow`` (model.allow_costly) is not set; a
    ReducedCostWarning when it costs more than its full-FE body."""
    if allow or cost.bytes <= cost.full_bytes:
        return
    if cost.bytes <= REFUSE_ABOVE_BYTES:
        import warnings

        warnings.warn(
            f"{where}: the reduced model costs more than full FE ({cost.line()}); kind "
            "'mvm-sparse' keeps a large region sparse, kind 'full' is as cheap",
            ReducedCostWarning,
            stacklevel=3,
        )
        return
    raise InputError(
        f"{where}: the reduced model would not fit ({cost.dof} DOF, ~{_mb(cost.bytes)} of "
        f"dense matrices, more than {REFUSE_SHARE:.0%} of this machine's "
        f"{_mb(REFUSE_ABOVE_BYTES / REFUSE_SHARE)}; full FE {cost.full_dof} DOF, "
        f"~{_mb(cost.full_bytes)}); expected a smaller region (a few Hertz contact radii), "
        "kind 'mvm-sparse' or 'full', or allow_costly = true"
    )
