"""The windows a moving region needs (kind ``mvm-moving``, issue 53), sized before any run as
`flexmvm region` sizes a fixed region: from the contact's Hertz radius and the size of the
body's contact facets (studies/region_estimate.py), plus the switch's hysteresis.

A window must hold every node the contact loads while the contact is up to (1/2 +
hysteresis) spacing from the window's centre (the body switches window beyond that:
integrate/moving_region.py). A point contact of Hertz radius a loads the nodes of the facets
its circle touches, at most a + h from its centre (h the facets' diameter), so

    half width >= (1/2 + hysteresis) spacing + h + a,

rounded up to a whole number of path stations (the distinct positions of the path's nodes
along its axis), so that every window holds whole stations. The spacing is one station: the
contact never leaves the station nearest the window's centre by more than the hysteresis.
A path whose nodes are not on stations (an unstructured mesh: fewer than two nodes a station
on average, or two stations less than a tenth of a facet apart) has no such lattice; its
spacing is the contact's reach h + a (a shift by it changes every node the contact loads),
and the half width is not rounded.

The Hertz radius is that of the contact pressed by the force its partner carries (Johnson,
*Contact Mechanics*, 1985, eq. 4.22: a = (3 F R / 4 E*)^(1/3)), F the largest component
along the contact normal of the partner's ``force`` loads (``force_n`` to give it), R the
equivalent curvature radius of the two surfaces at the expected contact point (step 3 of
studies/region_estimate.py). A sliding or rolling contact closes slowly: its radius is that of
the pressing force, not of an impact.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from flexmvm.errors import InputError, MeshError
from flexmvm.integrate.moving_region import HYSTERESIS
from flexmvm.reduction.kinds.mvm_moving import Path
from flexmvm.scenarios import Scenario
from flexmvm.studies.contact_point import facet_size
from flexmvm.studies.impact_estimate import e_star
from flexmvm.studies.region_estimate import contact_geometry

__all__ = ["MovingWindowEstimate", "estimate_moving_window"]


@dataclass(frozen=True)
class MovingWindowEstimate:
    """The windows of body ``body``'s moving region along node set ``path`` (module doc).
    Lengths [m], force [N]; ``nodes``: path nodes of a window in the path's middle (those on
    a support left out); ``windows``: the window count over the path."""

    body: str
    contact: int
    partner: str
    path: str
    force_n: float
    force_given: bool
    curvature_radius_m: float
    e_star_pa: float
    contact_radius_m: float
    facet_size_m: float
    station_m: float
    hysteresis: float
    spacing_m: float
    half_width_m: float
    nodes: int
    windows: int
    on_stations: bool = True  # False: an unstructured path, spacing h + a (module doc)

    @property
    def needed_m(self) -> float:
        """The half width before rounding: (1/2 + hysteresis) spacing + h + a [m]."""
        return (0.5 + self.hysteresis) * self.spacing_m + self.facet_size_m + self.contact_radius_m

    def key(self) -> str:
        """The scenario's ``moving`` line of this estimate."""
        return (
            f'moving = {{ path = "{self.path}", spacing_m = {self.spacing_m:.6g}, '
            f"half_width_m = {self.half_width_m:.6g} }}"
        )

    def as_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["needed_m"] = self.needed_m
        d["key"] = self.key()
        return d

    def lines(self) -> list[str]:
        """The console lines of the estimate."""
        mm = 1e3
        given = " (given)" if self.force_given else " (the partner's force loads)"
        return [
            (
                f"moving window of {self.body} along {self.path!r} (contacts[{self.contact}] "
                f"against {self.partner})"
            ),
            (
                f"Hertz contact: force {self.force_n:.4g} N{given}, curvature radius "
                f"{self.curvature_radius_m * mm:.4g} mm, E* {self.e_star_pa / 1e9:.4g} GPa: "
                f"contact radius a {self.contact_radius_m * mm:.4g} mm"
            ),
            (
                f"spacing {self.spacing_m * mm:.4g} mm ({self._spacing_reason()}); half width "
                f"(1/2 + {self.hysteresis:g}) spacing + h {self.facet_size_m * mm:.4g} mm + a = "
                f"{self.needed_m * mm:.4g} mm"
                + (
                    f", rounded up to whole stations: {self.half_width_m * mm:.4g} mm"
                    if self.on_stations
                    else ""
                )
            ),
            f"{self.windows} windows of {self.nodes} nodes ({3 * self.nodes} DOF + the modes)",
        ]

    def _spacing_reason(self) -> str:
        if self.on_stations:
            return "one path station"
        return "h + a: the path's nodes are not on stations (an unstructured mesh)"


def _pressing_force(sc: Scenario, partner: str, n: np.ndarray, where: str) -> float:
    """The largest force [N] the partner's ``force`` loads press along -n (module doc)."""
    f = 0.0
    for load in sc.loads:
        if load.body == partner and load.type.value == "force":
            f += float(np.max(load.history().values @ -n))
    if not f > 0:
        raise InputError(
            f"{where}: no force load on {partner} presses the contact (got {f:.4g} N along "
            "the normal); give the contact force (force_n, --force)"
        )
    return f


def _held_nodes(sc: Scenario, body: str, mesh) -> np.ndarray:
    """The nodes of ``body``'s supported node sets (left out of the windows)."""
    sets = [n for s in sc.supports if s.body == body for n in s.node_sets]
    if not sets:
        return np.zeros(0, dtype=np.int64)
    return np.unique(np.concatenate([mesh.node_set(n) for n in sets])).astype(np.int64)


def _stations(s: np.ndarray) -> np.ndarray:
    """The distinct positions (sorted) of path parameters s [m], merged within 1e-9 of the
    path's length."""
    s = np.sort(s)
    tol = 1e-9 * max(float(np.ptp(s)), 1e-12)
    return s[np.concatenate([[True], np.diff(s) > tol])]


def _positive(name: str, value: float | None) -> float | None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a number > 0, got {value!r}")
    return None if value is None else float(value)


def _path_of(sc: Scenario, body: str, path: str | None) -> str:
    if path is not None:
        return path
    mv = sc.body(body).model.moving
    if mv is None:
        raise InputError(
            f"bodies[{body}].model has no moving table; expected one, or the path's node set "
            "(path, --moving)"
        )
    return mv.path


def estimate_moving_window(
    sc: Scenario,
    body: str,
    *,
    path: str | None = None,
    force_n: float | None = None,
    radius_m: float | None = None,
    contact: int | None = None,
) -> MovingWindowEstimate:
    """The moving-region windows body ``body`` of scenario ``sc`` needs (module doc).

    Args:
        path: the node set the contact travels over (default: the body's ``moving.path``).
        force_n: the contact force [N] (default: the partner's force loads along the normal).
        radius_m: the equivalent curvature radius [m] instead of the fit.
        contact: index of the contact in ``sc.contacts`` (default: the body's first).

    Raises:
        InputError: no path, no pressing force, a flat contact without radius_m, an unknown
            node set.
    """
    force, radius_m = _positive("force_n", force_n), _positive("radius_m", radius_m)
    name = _path_of(sc, body, path)
    g = contact_geometry(sc, body, contact, radius_m)
    k, partner, fe, fs, x, point, n = g.contact, g.partner, g.fe, g.fs, g.x, g.point, g.normal
    R, where = g.radius_m, f"contacts[{g.contact}]"
    E = e_star(g.cfg, g.pcfg, f"{where}: {body} and {partner}")
    F = force if force is not None else _pressing_force(sc, partner, n, where)
    a = (3.0 * F * R / (4.0 * E)) ** (1.0 / 3.0)
    h = facet_size(x, fs, point, a)
    try:
        path_nodes = fe.mesh.node_set(name)
    except MeshError as exc:
        raise InputError(f"bodies[{body}].model.moving.path: {exc}") from None
    whole = Path.along(fe.mesh.nodes, path_nodes)
    stations = _stations(whole.s)
    if stations.size < 2:
        raise InputError(f"moving path {name!r}: its nodes are at one station; expected a line")
    pitch = float(np.min(np.diff(stations)))
    # a lattice of stations: nodes share them (two a station at least, as across a
    # structured face) and none is closer than a tenth of a facet to the next (module doc)
    on_stations = whole.s.size >= 2 * stations.size and pitch >= 0.1 * h
    spacing = pitch if on_stations else h + a
    needed = (0.5 + HYSTERESIS) * spacing + h + a
    half = pitch * math.ceil(needed / pitch - 1e-9) if on_stations else needed
    keep = ~np.isin(whole.nodes, _held_nodes(sc, body, fe.mesh))
    s = whole.s[keep]
    mid = stations[np.argmin(np.abs(stations - 0.5 * (s.min() + s.max())))]
    nodes = int(np.count_nonzero(np.abs(s - mid) <= half * (1 + 1e-9)))
    windows = max(int(np.ceil(np.ptp(s) / spacing - 1e-9)) + 1, 1)
    given = (F, force is not None, R, E, a, h, pitch, HYSTERESIS, spacing, half, nodes, windows)
    return MovingWindowEstimate(body, k, partner, name, *given, on_stations=on_stations)
