"""Setup-cache entries of a reduced body built on its basis, keyed by what the body is made
of rather than by the scenario's names: the FE model's content (node positions, K and M_s)
and the basis's identity (kind, reference, retained nodes, columns, mode frequencies).
- ``ringparts``: the parts of a ring body (kind mvm-sparse, bodies/ring_body.py): its sparse
  G2 blocks, M_qq and k_hat, the dense S1, G1, and its corner. Warm, a run reads them back
  instead of the basis's exterior rows (GBs on a 263,691-DOF plate) and their products.
(The truncation guard's numbers: setup_cache/guard_entries.py.)
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.build import BodyParts
from flexmvm.bodies.invariants import InertiaInvariants
from flexmvm.setup_cache.store import (
    BODY_SOURCES,
    array_bytes,
    code_version,
    csr_arrays,
    csr_from,
    decoded,
    make_key,
    material_inputs,
    save,
)

#: Code version of a ring body's parts: its basis's and bodies/ring_body.py.
RING_SOURCES = BODY_SOURCES + ("bodies/ring_body.py",)


def _sha(*arrays) -> str:
    digest = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        digest.update(f"{a.dtype.str}{a.shape}".encode())
        digest.update(array_bytes(a))
    return digest.hexdigest()


def basis_identity(fe, basis) -> dict:
    """Key inputs of a body on ``basis`` of FE model ``fe``: the FE model's content (X, K,
    M_s: a redistributed mass or a spring bed changes it), the material, the basis's kind,
    fixed DOFs, retained nodes, modes, columns, non-zeros and mode frequencies (the eigen
    solve's: the basis entry it was read from)."""
    K, Ms = sp.csr_matrix(fe.K), sp.csr_matrix(fe.M_scalar)
    psi = basis.psi
    return {
        "fe_sha256": _sha(fe.mesh.nodes, K.indptr, K.indices, K.data, Ms.indptr, Ms.data),
        "material": material_inputs(fe.material),
        "kind": str(basis.kind),
        "fixed_sha256": _sha(np.asarray(basis.reference.fixed_dofs, np.int64)),
        "retained": [int(k) for k in basis.retained_nodes],
        "n_modes": int(basis.n_modes),
        "shape": [int(n) for n in psi.shape],
        "nnz": int(psi.nnz) if sp.issparse(psi) else None,
        "freqs_hz": [float(f) for f in np.asarray(basis.mode_freqs_hz)],
    }


def _ring_arrays(parts: BodyParts, corner: np.ndarray) -> dict[str, np.ndarray]:
    inv = parts.inv
    nq = inv.nq
    G1 = np.array([[inv.G1[a][b] for b in range(3)] for a in range(3)]).reshape(3, 3, nq)
    out = {
        "mass": np.array([inv.mass]),
        "S0": inv.S0,
        "S1": inv.S1,
        "G0": inv.G0,
        "G1": G1,
        "corner": np.asarray(corner, np.int64),
        **csr_arrays("M_qq", inv.M_qq),
        **csr_arrays("k_hat", parts.k_hat),
    }
    for a in range(3):
        for b in range(3):
            out |= csr_arrays(f"G2_{a}{b}", inv.G2[a][b])
    return out


def _ring_from(arrays, nq: int) -> tuple[BodyParts, np.ndarray]:
    a = arrays
    dense = {"mass": (1,), "S0": (3,), "S1": (3, nq), "G0": (3, 3), "G1": (3, 3, nq)}
    if any(a[name].shape != shape for name, shape in dense.items()):
        raise ValueError("stored ring parts are malformed")
    sparse = {name: csr_from(a, name) for name in ("M_qq", "k_hat")}
    G2 = tuple(tuple(csr_from(a, f"G2_{i}{j}") for j in range(3)) for i in range(3))
    if any(m.shape != (nq, nq) for m in (*sparse.values(), *(g for row in G2 for g in row))):
        raise ValueError("stored ring parts are malformed")
    G1 = tuple(tuple(a["G1"][i, j].copy() for j in range(3)) for i in range(3))
    inv = InertiaInvariants(float(a["mass"][0]), a["S0"], a["S1"], a["G0"], G1, G2, sparse["M_qq"])
    return BodyParts(inv, sparse["k_hat"]), np.asarray(a["corner"], np.int64)


def cached_ring_parts(
    fe, basis, build: Callable[[], tuple[BodyParts, np.ndarray]]
) -> tuple[BodyParts, np.ndarray]:
    """(parts, corner) of the ring body of ``basis`` on ``fe`` from the cache, else
    ``build()`` stored (skipped when the cache is off)."""
    key = make_key("ringparts", basis_identity(fe, basis), code_version(RING_SOURCES))
    hit = decoded(key, lambda arrays: _ring_from(arrays, basis.psi.shape[1]))
    if hit is not None:
        return hit
    parts, corner = build()
    save(key, _ring_arrays(parts, corner))
    return parts, corner
