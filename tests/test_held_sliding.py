"""A held pair that slides (contact.held_pairs.hold_pairs, position law, frictionless): a slave
node sliding along a flat master never moves its linear gap away from the exact one, so the
drift test alone kept it on the facet and weights it closed with (the moving load stayed over
the support: docs/notes/2026-11-29-held-sliding.md). It now takes the scan's geometry when the
scan's closest facet is another one or its projection has moved by more than slide_max of the
held facet, with the offset that keeps its gap (no jump: no impulse, no work); a pair that
does not slide keeps its hold (what the hold protects: contact.pairs' module doc).
"""

from __future__ import annotations

import numpy as np
import pytest

from flexmvm.contact.held_pairs import hold_pairs
from flexmvm.contact.pairs import HOLD_SLIDE_MAX


def _rotation_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _strip():
    """Two quad facets of the master side by side in the plane x = 0 (body frame), y in
    [-1, 1] and [1, 3], z in [-1, 1], turned by A_m about z, moving along x at 0.05 m/s."""
    A = _rotation_z(0.3)
    X = np.array(
        [[0.0, y, z] for y, z in ((-1, -1), (1, -1), (1, 1), (-1, 1), (3, -1), (3, 1))],
        dtype=float,
    )
    xm = X @ A.T
    vm = np.tile(A @ [0.05, 0.0, 0.0], (6, 1))
    conn = np.array([[0, 1, 2, 3], [1, 4, 5, 2]], dtype=np.int64)
    return A, xm, vm, conn


def _quad_weights(xi: float, eta: float) -> np.ndarray:
    return 0.25 * np.array(
        [(1 - xi) * (1 - eta), (1 + xi) * (1 - eta), (1 + xi) * (1 + eta), (1 - xi) * (1 + eta)]
    )


def _hold(scan_facet: int, w_held, w_scan, gap_scan: float, slide_max: float):
    """One slave node held on facet 0 (weights w_held, normal +x, offset 1.5 nm, drift 1.5 nm) at
    the point of the scan's weights w_scan on facet scan_facet, 3 nm in front of it; the
    scan's row (exact gap gap_scan) and what hold_pairs returns and leaves. On the flat strip
    the linear gap is 4.5 nm wherever the node is: d stays at its 1.5 nm."""
    A, xm, vm, conn = _strip()
    n = A @ [1.0, 0.0, 0.0]
    xs = (w_scan @ xm[conn[scan_facet]] + 3e-9 * n)[None, :]
    vs = np.array([A @ [-0.2, 0.7, 0.0]])
    held, facet = np.array([0], dtype=np.int64), np.array([scan_facet], dtype=np.int64)
    held_w, held_n = np.asarray(w_held, float)[None, :].copy(), np.array([[1.0, 0.0, 0.0]])
    held_off, held_d = np.array([1.5e-9]), np.array([1.5e-9])
    out = np.zeros((1, 11))
    out[0, :4], out[0, 6:9], out[0, 9] = w_scan, n, gap_scan
    counts = hold_pairs(
        held, held_w, held_n, held_off, held_d, facet, out, xs, vs, xm, vm, A, conn,
        1e-9, 1e-8, slide_max,
    )  # fmt: skip
    return counts, held, held_w, held_off, held_d, facet, out


def test_held_pair_follows_the_node_onto_the_next_facet():
    """The node slid from facet 0 onto facet 1 (flat strip: the linear gap still equals the
    exact one to the held offset, d = 1.5 nm, unchanged since it was taken): the pair takes
    facet 1 and the scan's weights, its gap kept at the linear 4.5 nm (offset 1.5 nm: no
    jump, to round-off 1e-15 relative). Before, it stayed on facet 0 with its old weights
    (the moving load's defect)."""
    w1 = _quad_weights(-0.6, 0.2)
    counts, held, held_w, held_off, held_d, facet, out = _hold(
        1, _quad_weights(0.3, 0.2), w1, 3e-9, HOLD_SLIDE_MAX
    )
    assert counts == (1, 0) and held[0] == 1 and facet[0] == 1
    assert held_w[0] == pytest.approx(w1, abs=0)
    assert out[0, :4] == pytest.approx(w1, abs=0)
    assert out[0, 9] == pytest.approx(4.5e-9, rel=1e-6)  # the linear gap, no jump
    assert held_off[0] == pytest.approx(1.5e-9, rel=1e-6)
    assert held_d[0] == pytest.approx(1.5e-9, rel=1e-6)  # the drift is remembered
    assert out[0, 10] == pytest.approx(-0.25, rel=1e-12)


@pytest.mark.parametrize(("xi", "moves"), [(0.1, False), (0.29, False), (0.31, True), (0.9, True)])
def test_held_pair_follows_a_slide_on_its_facet(xi, moves):
    """Held at xi = -0.1 on facet 0, the projection now at xi: a move of (xi + 0.1) / 2 of the
    facet (half the L1 distance of the bilinear weights, exact along xi). Beyond
    slide_max = 0.2 (0.31 -> 0.205, 0.9 -> 0.5) the pair takes the scan's weights, the gap
    kept; within (0.1 -> 0.1, 0.29 -> 0.195) it keeps its hold, the weights it closed with
    (what the hold protects: a closed pair that does not slide stays a linear constraint)."""
    w_held, w_scan = _quad_weights(-0.1, 0.4), _quad_weights(xi, 0.4)
    assert 0.5 * np.abs(w_scan - w_held).sum() == pytest.approx((xi + 0.1) / 2, rel=1e-12)
    counts, held, held_w, _, _, facet, out = _hold(0, w_held, w_scan, 3e-9, 0.2)
    assert held[0] == 0 and facet[0] == 0
    assert counts == ((1, 0) if moves else (0, 0))
    assert held_w[0] == pytest.approx(w_scan if moves else w_held, abs=0)
    assert out[0, 9] == pytest.approx(4.5e-9, rel=1e-6)  # the linear gap either way
