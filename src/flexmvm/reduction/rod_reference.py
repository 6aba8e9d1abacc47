"""The default floating-frame reference of a rod: an axis-aligned 3-2-1 support far from end A.

    A = centre of end B           x, y, z fixed
    B = axis node nearest L/2     y, z fixed   (lateral: no tilt from axial waves)
    C = end-B ring node on +y     z fixed      (torsion)

With B on the axis, axisymmetric (axial) deformation never tilts the frame: the frame of a rod
hit on its axis only translates, as in the seed case. A 3-2-1 support with all three nodes on
the end face would tilt the frame by (u_ring - u_centre)/r as an axial wave passes.
"""

from __future__ import annotations

import numpy as np

from flexmvm.errors import InputError
from flexmvm.reduction.reference_condition import ReferenceCondition


def rod_reference(rod) -> ReferenceCondition:
    """Axis-aligned 3-2-1 reference of a RodMesh (see module docstring)."""
    mesh = rod.mesh
    X = mesh.nodes
    a = int(mesh.node_set("end_b_centre")[0])
    axis = np.nonzero(rod.node_lap == 1)[0]
    target = 0.5 * (X[:, 0].min() + X[:, 0].max())
    b = int(axis[np.argmin(np.abs(X[axis, 0] - target))])
    end_b = mesh.node_set("end_b")
    on_y = end_b[np.isclose(X[end_b, 2], 0.0, atol=1e-12) & (X[end_b, 1] > 0)]
    if on_y.size == 0 or a == b:
        raise InputError("rod reference: end B has no ring node on the +y axis")
    c = int(on_y[np.argmax(X[on_y, 1])])
    dofs = np.array([3 * a, 3 * a + 1, 3 * a + 2, 3 * b + 1, 3 * b + 2, 3 * c + 2], dtype=np.int64)
    return ReferenceCondition.from_dofs(mesh, dofs)
