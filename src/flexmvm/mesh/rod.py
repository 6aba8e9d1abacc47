"""Structured O-grid rod of triquadratic hexahedra (meshio ``hexahedron27``).

The rod lies along +x: end A (the contact end, graded finest) at x = 0, end B at x = L, radius r.
The cross-section (y, z) is a central square of quadratic quads surrounded by an O-grid whose
rings blend from the square to the circle; it is swept along x through graded stations. A
hemispherical end is a cap block mapped from the same cross-section grid onto the sphere.

Triquadratic cells are used because linear hexahedra/wedges shear-lock in bending unless the
axial elements are very short. The node indexing follows the seed paper's selection scheme
(Wang, Hong, Liu 2014): "layers" are axial node stations (1 = end A face or cap surface),
"laps" concentric node rings of the cross-section (1 = the axis node).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from types import MappingProxyType

import numpy as np

from flexmvm.errors import InputError
from flexmvm.mesh.mesh import CellBlock, CellType, FacetSet, Mesh
from flexmvm.mesh.quality import HEX27_IJK

#: Largest number of axial elements a spec may produce (guards growth = 1 with tiny elements).
MAX_AXIAL_ELEMENTS = 100_000

# VTK quad9 order in a 3x3 node grid [u, v]: corners, edge mid-nodes, centre.
_QUAD9_U = np.array([0, 2, 2, 0, 1, 2, 1, 0, 1])
_QUAD9_V = np.array([0, 0, 2, 2, 0, 1, 2, 1, 1])
# The four linear sub-quads [u, v] of a 3x3 node grid, counter-clockwise in (u, v).
_SUB_U = np.array([[0, 1, 1, 0], [1, 2, 2, 1], [0, 1, 1, 0], [1, 2, 2, 1]])
_SUB_V = np.array([[0, 0, 1, 1], [0, 0, 1, 1], [1, 1, 2, 2], [1, 1, 2, 2]])


class EndShape(StrEnum):
    """Shape of a rod end (values: the scenario file's ``end_a`` / ``end_b``)."""

    FLAT = "flat"
    HEMISPHERE = "hemisphere"


@dataclass(frozen=True)
class RodSpec:
    """Geometry and grading of a rod mesh. Lengths in metres.

    length_m includes hemispherical caps. The cap block of a hemispherical end reaches
    cap_depth_m (default radius/2) beyond the hemisphere's base plane. Axial elements (measured
    on the axis) start at first_element_m at end A and grow by at most `growth` up to
    max_element_m (see graded_lengths); a cap block's interface with the cylinder is an element
    boundary. Raises InputError on invalid values, naming the field.
    """

    radius_m: float = 0.01
    length_m: float = 1.0
    end_a: EndShape = EndShape.FLAT
    end_b: EndShape = EndShape.FLAT
    core_elements: int = 2
    core_half_width_m: float = 0.3e-3
    n_rings: int = 3
    first_element_m: float = 0.3e-3
    growth: float = 1.6
    max_element_m: float = 0.04
    cap_depth_m: float | None = None

    def __post_init__(self) -> None:
        for name in ("end_a", "end_b"):
            value = getattr(self, name)
            if not isinstance(value, EndShape):
                try:
                    object.__setattr__(self, name, EndShape(value))
                except ValueError:
                    raise InputError(
                        f"RodSpec.{name} = {value!r}; expected one of "
                        f"{', '.join(e.value for e in EndShape)}"
                    ) from None
        sizes = ["radius_m", "length_m", "core_half_width_m", "first_element_m", "max_element_m"]
        if self.cap_depth_m is not None:
            sizes.append("cap_depth_m")
        for name in sizes:
            _require(name, getattr(self, name), "a finite number > 0", lambda v: v > 0)
        _require("growth", self.growth, "a finite number >= 1", lambda v: v >= 1)
        for name in ("core_elements", "n_rings"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise InputError(f"RodSpec.{name} = {value!r}; expected an integer >= 1")
        self._check_relations()

    def _check_relations(self) -> None:
        r = self.radius_m
        if self.core_half_width_m >= r / 2:
            raise InputError(
                f"RodSpec.core_half_width_m = {self.core_half_width_m:g}; expected < radius/2 "
                f"= {r / 2:g}"
            )
        if self.first_element_m > self.max_element_m:
            raise InputError(
                f"RodSpec.first_element_m = {self.first_element_m:g}; expected <= "
                f"max_element_m = {self.max_element_m:g}"
            )
        caps = self.cap_length_a_m + self.cap_length_b_m
        if self.length_m <= caps:
            raise InputError(
                f"RodSpec.length_m = {self.length_m:g}; expected > {caps:g} (radius + cap depth "
                f"for each hemispherical end)"
            )

    @property
    def cap_depth(self) -> float:
        """Depth [m] of a cap block beyond the hemisphere's base plane."""
        return self.radius_m / 2 if self.cap_depth_m is None else float(self.cap_depth_m)

    @property
    def cap_length_a_m(self) -> float:
        """Axial extent [m] of the cap block at end A (0 for a flat end)."""
        return self.radius_m + self.cap_depth if self.end_a is EndShape.HEMISPHERE else 0.0

    @property
    def cap_length_b_m(self) -> float:
        """Axial extent [m] of the cap block at end B (0 for a flat end)."""
        return self.radius_m + self.cap_depth if self.end_b is EndShape.HEMISPHERE else 0.0


def _require(name: str, value: object, expected: str, ok) -> None:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"RodSpec.{name} = {value!r}; expected {expected}") from None
    if not (math.isfinite(v) and ok(v)):
        raise InputError(f"RodSpec.{name} = {value!r}; expected {expected}")


@dataclass(frozen=True)
class RodMesh:
    """A rod mesh with the seed paper's layer/lap node indexing.

    node_layer (n,) int: axial node station, 1 = end A face (cap surface for a hemisphere).
    node_lap (n,) int: concentric cross-section node ring, 1 = the axis node.
    faces9: surface name -> (n_faces, 9) node ids of the quadratic faces (VTK quad9 order,
    outward normals), the exact surfaces of which the mesh's facet sets are 2x2 subdivisions.
    """

    spec: RodSpec
    mesh: Mesh
    node_layer: np.ndarray
    node_lap: np.ndarray
    n_layers: int
    n_laps: int
    faces9: Mapping[str, np.ndarray] = field(default_factory=dict)

    def selection(self, layers: int, laps: int) -> np.ndarray:
        """Seed "i-j" node selection: sorted ids of nodes with layer <= i and lap <= j.

        Raises InputError if i is not in 1..n_layers or j not in 1..n_laps.
        """
        for name, value, top in (("layers", layers, self.n_layers), ("laps", laps, self.n_laps)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise InputError(f"selection {name} = {value!r}; expected an integer in 1..{top}")
            if not 1 <= value <= top:
                raise InputError(f"selection {name} = {value}; expected 1..{top} (the maximum)")
        return np.flatnonzero((self.node_layer <= layers) & (self.node_lap <= laps))


@dataclass(frozen=True)
class _Section:
    """Cross-section grid: points (m, 2) [m], lap (m,), quads (q, 3, 3) with [a, b] counter-
    clockwise in (y, z), rim (e, 3) node ids along the circle (counter-clockwise)."""

    points: np.ndarray
    lap: np.ndarray
    quads: np.ndarray
    rim: np.ndarray


def _ring_blend(spec: RodSpec) -> np.ndarray:
    """Blend parameters s (2 n_rings + 1,) of the O-grid node rings, 0 = square, 1 = circle.

    Ring boundary radii are geometric, R_k = h (r/h)^(k/n); mid rings lie halfway in s.
    """
    h, r, n = spec.core_half_width_m, spec.radius_m, spec.n_rings
    radii = h * (r / h) ** (np.arange(n + 1) / n)
    s = (radii - h) / (r - h)
    out = np.empty(2 * n + 1)
    out[0::2] = s
    out[1::2] = (s[:-1] + s[1:]) / 2
    return out


def _section(spec: RodSpec) -> _Section:
    """Build the cross-section grid, nodes numbered by lap (centre first).

    Laps: 1 = centre, 2..c+1 = the square node rings of the core grid (8k nodes each), then
    one lap per O-grid node ring (8c nodes each, mid rings included), the last on the circle at
    angles -45 + k * 180 / (4c) degrees (so 0, 90, 180, 270 degrees are nodes).
    """
    c, h, r = spec.core_elements, spec.core_half_width_m, spec.radius_m
    nc = 2 * c + 1
    ij = np.arange(nc)
    core_id = (ij[:, None] * nc + ij[None, :]).astype(np.int64)
    g1 = (ij - c) * (h / c)
    gy, gz = np.meshgrid(g1, g1, indexing="ij")
    core_pts = np.column_stack([gy.ravel(), gz.ravel()])
    core_lap = 1 + np.maximum(np.abs(ij[:, None] - c), np.abs(ij[None, :] - c)).ravel()
    # Perimeter node q (counter-clockwise from the corner (h, -h)) sits at angle theta_q.
    n_per = 8 * c
    q = np.arange(n_per)
    side, u = q // (2 * c), q % (2 * c)
    pi = np.choose(side, [np.full_like(u, 2 * c), 2 * c - u, np.zeros_like(u), u])
    pj = np.choose(side, [u, np.full_like(u, 2 * c), 2 * c - u, np.zeros_like(u)])
    theta = -np.pi / 4 + q * (2 * np.pi / n_per)
    circle = r * np.column_stack([np.cos(theta), np.sin(theta)])
    circle[np.abs(circle) < 1e-12 * r] = 0.0
    s = _ring_blend(spec)[1:]
    sq = core_pts[core_id[pi, pj]]
    ring_pts = (1 - s)[:, None, None] * sq[None] + s[:, None, None] * circle[None]
    ring_pts[-1] = circle
    ring_id = np.vstack(
        [core_id[pi, pj][None], nc * nc + np.arange(len(s) * n_per).reshape(-1, n_per)]
    )
    points = np.vstack([core_pts, ring_pts.reshape(-1, 2)])
    lap = np.concatenate([core_lap, np.repeat(c + 2 + np.arange(len(s)), n_per)])
    a = np.arange(3)
    e = np.arange(c)
    core_q = core_id[
        (2 * e[:, None, None, None] + a[None, None, :, None]),
        (2 * e[None, :, None, None] + a[None, None, None, :]),
    ].reshape(-1, 3, 3)
    k, sec = np.arange(spec.n_rings), np.arange(4 * c)
    ring_q = ring_id[
        2 * k[:, None, None, None] + a[None, None, :, None],
        (2 * sec[None, :, None, None] + a[None, None, None, :]) % n_per,
    ].reshape(-1, 3, 3)
    rim = ring_id[-1][(2 * sec[:, None] + a[None, :]) % n_per]
    order = np.argsort(lap, kind="stable")
    new = np.empty_like(order)
    new[order] = np.arange(len(order))
    return _Section(points[order], lap[order], new[np.vstack([core_q, ring_q])], new[rim])


def _capped_geometric(n: int, first: float, ratio: float, max_len: float) -> np.ndarray:
    """Lengths min(first * ratio**k, max_len), k = 0..n-1."""
    with np.errstate(over="ignore"):
        return np.minimum(first * np.exp(np.arange(n) * math.log(ratio)), max_len)


def _element_count(total: float, first: float, growth: float, max_len: float) -> int:
    """Fewest elements min(first * growth**k, max_len) whose lengths reach `total`."""
    tol = 1 - 1e-12
    if growth == 1 or first >= max_len:
        return max(1, math.ceil(total / first * tol))
    n_grow = math.ceil(math.log(max_len / first) / math.log(growth)) + 1
    cum = np.cumsum(_capped_geometric(n_grow, first, growth, max_len))
    if cum[-1] >= total * tol:
        return int(np.searchsorted(cum, total * tol)) + 1
    return n_grow + math.ceil((total - cum[-1]) / max_len * tol)


def graded_lengths(total: float, first: float, growth: float, max_len: float) -> np.ndarray:
    """Element lengths [m] filling `total` exactly, graded from `first`.

    n = the fewest elements of min(first * growth**k, max_len) reaching `total`; the ratio is
    then lowered to g' in [1, growth] so that min(first * g'**k, max_len), k < n, sums to total
    (first length kept, growth ratio <= growth, all lengths <= max_len). If n elements of
    `first` already reach total (growth 1, or total < ~2 first), ceil(total / first) equal
    elements are used. Raises InputError beyond MAX_AXIAL_ELEMENTS elements.
    """
    n = _element_count(total, first, growth, max_len)
    if n * first >= total * (1 - 1e-12):
        n = max(1, math.ceil(total / first * (1 - 1e-12)))
        uniform = True
    else:
        uniform = False
    if n > MAX_AXIAL_ELEMENTS:
        raise InputError(
            f"rod grading needs {n} axial elements (first {first:g} m, growth {growth:g}, max "
            f"{max_len:g} m); expected at most {MAX_AXIAL_ELEMENTS}"
        )
    if uniform:
        return np.full(n, total / n)

    def excess(g: float) -> float:
        return float(_capped_geometric(n, first, g, max_len).sum() - total)

    from scipy.optimize import brentq  # here, not at the top: scipy.optimize is ~0.3 s to import

    ratio = growth if excess(growth) <= 0 else brentq(excess, 1.0, growth, xtol=1e-15)
    lengths = _capped_geometric(n, first, ratio, max_len)
    lengths[-1] += total - lengths.sum()
    return lengths


def _axial_boundaries(spec: RodSpec) -> np.ndarray:
    """Element boundaries along the axis [m], graded from x = 0, with boundaries at the cap
    block interfaces; the grading continues across them."""
    cap_a, cap_b, L = spec.cap_length_a_m, spec.cap_length_b_m, spec.length_m
    pieces = [p for p in (cap_a, L - cap_a - cap_b, cap_b) if p > 0]
    lengths: list[np.ndarray] = []
    first = spec.first_element_m
    for piece in pieces:
        ell = graded_lengths(piece, first, spec.growth, spec.max_element_m)
        lengths.append(ell)
        first = min(spec.max_element_m, ell[-1] * spec.growth)
    b = np.concatenate([[0.0], np.cumsum(np.concatenate(lengths))])
    b[-1] = L
    return b


def _cap_surface(points: np.ndarray, r: float, apex_x: float, sign: float) -> np.ndarray:
    """Map cross-section points (m, 2) onto a hemisphere of radius r with apex at apex_x,
    bulging towards -sign*x: polar angle alpha = |p|/r * pi/2, azimuth atan2(z, y)."""
    rho = np.hypot(points[:, 0], points[:, 1])
    alpha = rho / r * (np.pi / 2)
    phi = np.arctan2(points[:, 1], points[:, 0])
    return np.column_stack(
        [
            apex_x + sign * r * (1 - np.cos(alpha)),
            r * np.sin(alpha) * np.cos(phi),
            r * np.sin(alpha) * np.sin(phi),
        ]
    )


def _node_coordinates(spec: RodSpec, sec: _Section, x: np.ndarray) -> np.ndarray:
    """Node coordinates (n_stations, m, 3) [m] for node stations x (axial position on the axis)."""
    p = sec.points
    nodes = np.empty((len(x), len(p), 3))
    nodes[:, :, 0] = x[:, None]
    nodes[:, :, 1:] = p[None]
    r, L = spec.radius_m, spec.length_m
    for cap, apex, sign in ((spec.cap_length_a_m, 0.0, 1.0), (spec.cap_length_b_m, L, -1.0)):
        if cap == 0:
            continue
        zeta = np.abs(x - apex) / cap
        k = np.flatnonzero(zeta < 1)
        surface = _cap_surface(p, r, apex, sign)
        inner = np.column_stack([np.full(len(p), apex + sign * cap), p])
        z = zeta[k, None, None]
        nodes[k] = (1 - z) * surface[None] + z * inner[None]
    return nodes


def _surface(grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear sub-quads (4 n, 4) and quad9 faces (n, 9) of node grids (n, 3, 3) [u, v]."""
    subs = grid[:, _SUB_U, _SUB_V].reshape(-1, 4)
    return subs, grid[:, _QUAD9_U, _QUAD9_V]


def rod_mesh(spec: RodSpec = RodSpec()) -> RodMesh:
    """Mesh a rod with triquadratic hexahedra; see the module docstring for the layout.

    Node id = station * m + section id (m section nodes, numbered by lap). Returns a RodMesh whose
    mesh has node sets end_a, end_b, end_a_centre, end_b_centre, side and facet sets end_a,
    end_b, side (2x2 linear sub-quads of the quadratic faces, outward normals), and the skin
    ``surface`` (the three together, node set and facet set) as read_mesh gives every mesh.
    """
    sec = _section(spec)
    m = len(sec.points)
    bounds = _axial_boundaries(spec)
    n_el = len(bounds) - 1
    x = np.empty(2 * n_el + 1)
    x[0::2] = bounds
    x[1::2] = (bounds[:-1] + bounds[1:]) / 2
    nodes = _node_coordinates(spec, sec, x).reshape(-1, 3)
    ii, jj, kk = HEX27_IJK.T
    zs = np.arange(n_el)
    conn = (2 * zs[:, None, None] + kk[None, None, :]) * m + sec.quads[None][:, :, ii, jj]
    last = (len(x) - 1) * m
    axial3 = 2 * zs[:, None, None, None] + np.arange(3)[None, None, None, :]
    side_grid = axial3 * m + sec.rim[None, :, :, None]  # [z, rim edge, perimeter, axial]
    surfaces = {
        "end_a": _surface(np.swapaxes(sec.quads, 1, 2)),
        "end_b": _surface(sec.quads + last),
        "side": _surface(side_grid.reshape(-1, 3, 3)),
    }
    surfaces["surface"] = (  # the skin, as read_mesh names it
        np.vstack([part[0] for part in surfaces.values()]),
        np.vstack([part[1] for part in surfaces.values()]),
    )
    outer = np.flatnonzero(sec.lap == sec.lap.max())
    node_sets = {
        "end_a": np.arange(m),
        "end_b": last + np.arange(m),
        "end_a_centre": np.array([0]),
        "end_b_centre": np.array([last]),
        "side": (np.arange(len(x))[:, None] * m + outer[None]).ravel(),
    }
    node_sets["surface"] = np.unique(
        np.concatenate([node_sets[k] for k in ("end_a", "end_b", "side")])
    )
    mesh = Mesh(
        nodes=nodes,
        cells=(CellBlock(CellType.HEX27, conn.reshape(-1, 27)),),
        node_sets=node_sets,
        facet_sets={name: FacetSet(quads=subs) for name, (subs, _) in surfaces.items()},
    )
    return RodMesh(
        spec=spec,
        mesh=mesh,
        node_layer=np.repeat(np.arange(1, len(x) + 1), m),
        node_lap=np.tile(sec.lap, len(x)),
        n_layers=len(x),
        n_laps=int(sec.lap.max()),
        faces9=MappingProxyType({name: f9 for name, (_, f9) in surfaces.items()}),
    )
