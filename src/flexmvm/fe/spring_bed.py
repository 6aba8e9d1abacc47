"""An elastic support: a bed of springs on a facet set (a Winkler foundation, an elastomer
pad), as a consistent surface stiffness added to the body's K.

A bed of stiffness per area k [N/m^3] holding the displacement component along a unit
direction d (a fixed body axis, or the facet's outward normal n) stores the energy

    U_bed = 1/2 int_S k (d . u)^2 dA,   so   K_bed = sum_f int_f k N^T (d d^T) N dA   (3n x 3n)

with N the facet's shape functions (bilinear on a quad, linear on a triangle: the facets of a
FacetSet, quadratic faces split into linear sub-facets by mesh/subfacets.py), integrated by
2 x 2 Gauss points on a quad and 3 points on a triangle (exact for the flat facets of a
box; a curved quad's area element is taken at each point). K_bed is symmetric positive
semi-definite and adds k A_S to the stiffness of a uniform translation along d (a flat S).
Added to K, it enters every basis built from the model, k_hat = psi^T K psi and the strain
energy 1/2 q^T k_hat q (the bed's energy is part of it). The springs are grounded: a body on
a bed has its frame fixed (a ground joint), as a clamped body's.
"""

from __future__ import annotations

import dataclasses
from enum import StrEnum

import numpy as np
import scipy.sparse as sp

from flexmvm.errors import InputError
from flexmvm.fe.assembly import FEModel
from flexmvm.mesh.mesh import FacetSet, Mesh

_G = 1.0 / np.sqrt(3.0)
#: 2 x 2 Gauss points (xi, eta) in [-1, 1]^2 and weights of a quad.
_QUAD_POINTS = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])
#: 3-point rule on the unit triangle (area coordinates of the points; weight 1/3 each).
_TRI_POINTS = np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])


class BedDirection(StrEnum):
    """The displacement component a spring bed holds (values: a scenario's ``direction``)."""

    X = "x"
    Y = "y"
    Z = "z"
    NORMAL = "normal"  # the facet's outward normal at each point (a pad pressed on a face)


def _quad_points(xyz: np.ndarray):
    """Shape values (4, 4) and area vectors (f, 4, 3) (n dA at each Gauss point) of quads
    with corner coordinates xyz (f, 4, 3)."""
    xi, eta = _QUAD_POINTS[:, 0], _QUAD_POINTS[:, 1]
    n = 0.25 * np.stack([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta), (1 + xi) * (1 + eta),
                         (1 - xi) * (1 + eta)], axis=1)  # fmt: skip
    dxi = 0.25 * np.stack([-(1 - eta), 1 - eta, 1 + eta, -(1 + eta)], axis=1)
    deta = 0.25 * np.stack([-(1 - xi), -(1 + xi), 1 + xi, 1 - xi], axis=1)
    t1 = np.einsum("ga,fad->fgd", dxi, xyz)
    t2 = np.einsum("ga,fad->fgd", deta, xyz)
    return n, np.cross(t1, t2)  # weight 1 per point


def _tri_points(xyz: np.ndarray):
    """Shape values (3, 3) and area vectors (f, 3, 3) (n dA at each point) of triangles."""
    area = 0.5 * np.cross(xyz[:, 1] - xyz[:, 0], xyz[:, 2] - xyz[:, 0])
    return _TRI_POINTS, np.repeat(area[:, None, :] / 3.0, 3, axis=1)


def _facet_blocks(mesh: Mesh, facets: np.ndarray, points, k: float, direction: BedDirection):
    """Element matrices (f, 3v, 3v) of one facet shape and their DOF ids (f, 3v)."""
    xyz = mesh.nodes[facets]
    n, area_vec = points(xyz)  # n: (g, v); area_vec: (f, g, 3)
    da = np.linalg.norm(area_vec, axis=2)  # (f, g)
    if direction is BedDirection.NORMAL:
        d = area_vec / np.where(da > 0, da, 1.0)[..., None]
    else:
        d = np.zeros_like(area_vec)
        d[..., "xyz".index(direction.value)] = 1.0
    proj = k * da[..., None, None] * d[..., :, None] * d[..., None, :]  # (f, g, 3, 3)
    nn = n[:, :, None] * n[:, None, :]  # (g, v, v)
    blocks = np.einsum("gab,fgij->faibj", nn, proj)
    v = facets.shape[1]
    dofs = (3 * facets[:, :, None] + np.arange(3)).reshape(len(facets), 3 * v)
    return blocks.reshape(len(facets), 3 * v, 3 * v), dofs


def spring_bed_stiffness(
    mesh: Mesh, surface: FacetSet, stiffness_n_per_m3: float, direction: BedDirection
) -> sp.csr_matrix:
    """K_bed (3n x 3n csr) [N/m] of a spring bed of ``stiffness_n_per_m3`` [N/m^3] on the
    facets ``surface`` of ``mesh`` holding the component along ``direction`` (module doc).
    Raises InputError for a stiffness that is not finite and > 0 or a facet of zero area."""
    k = float(stiffness_n_per_m3)
    if not (np.isfinite(k) and k > 0.0):
        raise InputError(f"spring bed stiffness must be finite and > 0 N/m^3, got {k!r}")
    direction = BedDirection(direction)
    rows, cols, vals = [], [], []
    for facets, points in ((surface.quads, _quad_points), (surface.tris, _tri_points)):
        if not len(facets):
            continue
        blocks, dofs = _facet_blocks(mesh, facets, points, k, direction)
        if not np.all(np.einsum("fii->f", blocks) > 0.0):
            raise InputError("spring bed surface has a facet of zero area; expected none")
        rows.append(np.repeat(dofs, dofs.shape[1], axis=1).ravel())
        cols.append(np.tile(dofs, (1, dofs.shape[1])).ravel())
        vals.append(blocks.ravel())
    n = mesh.n_dof
    if not rows:
        return sp.csr_matrix((n, n))
    kb = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(n, n)).tocsr()  # fmt: skip
    return sp.csr_matrix(0.5 * (kb + kb.T))


def beds_stiffness(mesh: Mesh, beds) -> sp.csr_matrix:
    """The summed K_bed of ``beds``, each (facet set name of ``mesh``, stiffness [N/m^3],
    direction: a BedDirection value). MeshError for an unknown facet set."""
    total = sp.csr_matrix((mesh.n_dof, mesh.n_dof))
    for surface, k, direction in beds:
        total = total + spring_bed_stiffness(mesh, mesh.facet_set(surface), k, direction)
    return sp.csr_matrix(total)


def with_spring_bed(fe: FEModel, k_bed: sp.spmatrix) -> FEModel:
    """The FE model with the bed's stiffness added, K + K_bed (M unchanged)."""
    if k_bed.shape != fe.K.shape:
        raise InputError(f"spring bed stiffness has shape {k_bed.shape}, expected {fe.K.shape}")
    return dataclasses.replace(fe, K=sp.csr_matrix(fe.K + k_bed))


__all__ = ["BedDirection", "beds_stiffness", "spring_bed_stiffness", "with_spring_bed"]
