"""`flexmvm region`'s moving-window sizing on a path whose nodes are not on stations (issue
53; studies/moving_window.py): on the cam follower's unstructured tet10 strip the station rule
gave a spacing of 5.8e-9 mm and 1.9 million windows; the spacing is now the contact's reach
h + a, and the windows it gives carry the run as the hand-sized ones do."""

from __future__ import annotations

import re

import numpy as np
import pytest
from test_cam_follower import OMEGA, _variant

import flexmvm as fm
from flexmvm.mesh.cam import cam_part, follower_part
from flexmvm.metrics.ncc import ncc
from flexmvm.studies.moving_window import estimate_moving_window


def test_unstructured_path_windows_from_the_contact_reach(tmp_path):
    """A coarse cam variant whose strip is unstructured (the follower 10 mm with 0.5 mm along
    its path, 10,140 DOF: 229 path nodes on 97 stations, the closest two 0.01 mm apart, a
    tenth of a facet 0.05 mm; the shipped mesh: 541 nodes on 541 stations): spacing h + a,
    half width 1.7 (h + a) not rounded, a few tens of windows (the station rule: 1.9 million
    on the shipped mesh); the moving region on those windows against full FE over half a
    revolution: force NCC >= 0.9999 and peak within 1e-4, the bounds the hand-sized windows
    meet (tests/test_cam_follower.py). Measured: spacing 0.43 mm, half width 0.73 mm, 27
    windows of 27 nodes, 35 switches, NCC 0.9999997."""
    pytest.importorskip("gmsh")
    meshes = {
        "cam": cam_part(tmp_path / "cam.msh", size_m=5e-3, fine_m=0.8e-3),
        "follower": follower_part(tmp_path / "follower.msh", size_m=10e-3, fine_m=0.5e-3),
    }
    path = _variant(meshes, tmp_path, OMEGA, 0.05, dt=0.5e-3)
    sc = fm.load_scenario(path)
    est = estimate_moving_window(sc, "follower", force_n=90.0)
    assert not est.on_stations
    reach = est.facet_size_m + est.contact_radius_m
    assert est.spacing_m == reach
    assert (
        est.half_width_m == est.needed_m == (1.7 * reach)
        or abs(est.half_width_m - 1.7 * reach) <= 1e-12 * reach
    )
    assert 5 <= est.windows <= 100
    text = re.sub(
        r"spacing_m = [0-9.e-]+, half_width_m = [0-9.e-]+",
        f"spacing_m = {est.spacing_m!r}, half_width_m = {est.half_width_m!r}",
        path.read_text(),
    )
    path.write_text(text)
    sc = fm.load_scenario(path)
    full = fm.run(sc).result
    mv = fm.run(sc.with_kind("mvm-moving"))
    assert len(mv.built.switches.switches) >= 4
    rho = ncc(full.t, full.contact_force, mv.result.t, mv.result.contact_force)
    assert rho >= 0.9999
    pf, pm = full.contact_force.max(), mv.result.contact_force.max()
    assert abs(pm - pf) <= 1e-4 * pf
    assert np.isfinite(pm)
