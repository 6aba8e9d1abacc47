"""The moving region's tools (issue 53): `flexmvm region` sizing its windows
(studies/moving_window.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from flexmvm.cli.app import _register, cli
from flexmvm.cli.main import main
from flexmvm.scenarios import load_scenario

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
MOVING_LOAD = SCENARIOS / "moving_load.toml"


def _region(*args: str):
    _register()
    return CliRunner().invoke(cli, ["region", str(MOVING_LOAD), "--body", "beam", *args])


def test_region_sizes_the_moving_window():
    """On the moving-load beam (40 x 1 x 1 HEX27: top stations every 12.5 mm, linear
    sub-facets 12.5 x 10 mm): spacing one station, 12.5 mm as hand-sized in
    docs/notes/2026-11-29-moving-region.md; the Hertz radius of the 2 N press of the
    R 10 mm rigid sphere on aluminium (E* 78.55 GPa) a = (3 F R / 4 E*)^(1/3) = 0.0576 mm;
    the half width (1/2 + 0.2) 12.5 + h 16.0 (the sub-facet's diagonal) + a = 24.8 mm,
    rounded up to 2 stations: 25 mm, 5 stations x 3 nodes. The note's hand sizing took the
    HEX27 face (25 mm) for h: the same rule gives its 37.5 mm. Tolerances: round-off of the
    mesh coordinates (1e-9 relative) and 1e-3 on a (the curvature fit)."""
    res = _region("--json")
    assert res.exit_code == 0, res.output
    est = json.loads(res.output)
    a, pitch = est["contact_radius_m"], est["spacing_m"]
    assert pitch == pytest.approx(0.0125, rel=1e-9)
    assert a == pytest.approx((3 * 2.0 * 0.010 / (4 * 78.55e9)) ** (1 / 3), rel=1e-3)
    assert est["facet_size_m"] == pytest.approx(math.hypot(0.0125, 0.010), rel=1e-9)
    assert est["needed_m"] == pytest.approx(0.7 * pitch + est["facet_size_m"] + a, rel=1e-12)
    assert est["half_width_m"] == pytest.approx(0.025, rel=1e-9)
    assert (est["nodes"], est["windows"]) == (15, 79)
    hand = pitch * math.ceil((0.7 * pitch + 0.025 + a) / pitch)
    assert hand == pytest.approx(0.0375, rel=1e-9)
    text = _region()
    assert text.exit_code == 0, text.output
    assert 'moving = { path = "top", spacing_m = 0.0125, half_width_m = 0.025 }' in text.output
    assert "79 windows of 15 nodes" in text.output


def test_region_moving_options_and_errors(capsys):
    """--force scales a as F^(1/3) (8x the force: 2x the radius, to 1e-9); an unknown path
    and a body with no moving table and no --moving are one-line errors, exit status 2."""
    from flexmvm.studies.moving_window import estimate_moving_window

    sc = load_scenario(MOVING_LOAD)
    a1 = estimate_moving_window(sc, "beam").contact_radius_m
    a8 = estimate_moving_window(sc, "beam", force_n=16.0).contact_radius_m
    assert a8 == pytest.approx(2 * a1, rel=1e-9)
    with pytest.raises(SystemExit) as exit_:
        main(["region", str(MOVING_LOAD), "--body", "beam", "--moving", "nope"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2
    assert err.startswith("flexmvm: error:") and "unknown node set 'nope'" in err
    assert "Traceback" not in err
    with pytest.raises(Exception, match="no moving table"):
        estimate_moving_window(sc, "slider")


def _moving_load(**moving):
    """The shipped moving-load scenario, kind mvm-moving, its windows changed by ``moving``."""
    import tomllib

    import flexmvm as fm

    with open(MOVING_LOAD, "rb") as f:
        d = tomllib.load(f)
    for b in d["bodies"]:
        b["mesh_file"] = str(SCENARIOS / b["mesh_file"])
    d["time"].update(t_end_s=1e-3)
    d["bodies"][0]["model"]["kind"] = "mvm-moving"
    d["bodies"][0]["model"]["moving"].update(moving)
    return fm.scenario_from_dict(d)


def test_moving_windows_in_the_setup_cache(tmp_path, monkeypatch):
    """A moving region's setup is kept in the setup cache (a ``moving-`` entry): a second
    setup of the same windows neither factors K_ff, nor computes modes, nor computes inertia
    invariants (all three made to fail here), and its windows' bases and parts are those of
    the first bit for bit (exact: the same columns and the same operations). Windows of 25 mm
    (the estimate's) to keep it fast: ~1 s cold, ~0.5 s warm."""
    import numpy as np

    import flexmvm.integrate.moving_region as run_time
    from flexmvm.assembly.build_cache import default_setup
    from flexmvm.assembly.moving_region import moving_body
    from flexmvm.reduction.kinds.mvm_moving import GlobalFactor

    monkeypatch.setenv("FLEXMVM_CACHE_DIR", str(tmp_path))
    sc, setup = _moving_load(half_width_m=0.025), default_setup()
    cold = moving_body(sc.bodies[0], sc.supports, setup, 0)[1]
    assert len(list(tmp_path.glob("moving-*.npz"))) == 1

    def fails(*args, **kwargs):
        raise AssertionError("a warm setup made this again")

    monkeypatch.setattr(GlobalFactor, "of", classmethod(fails))
    monkeypatch.setattr(run_time, "inertia_invariants", fails)
    monkeypatch.setattr("flexmvm.reduction.kinds.mvm_moving.spd_solver", fails)
    warm = moving_body(sc.bodies[0], sc.supports, setup, 0)[1]
    assert len(warm.windows.centres) == len(cold.windows.centres) == 79
    for k in range(79):
        assert np.array_equal(warm.windows.basis(k).psi, cold.windows.basis(k).psi)
        a, b = warm.parts[k], cold.parts[k]
        assert np.array_equal(a.k_hat, b.k_hat) and np.array_equal(a.inv.M_qq, b.inv.M_qq)
        assert np.array_equal(a.inv.G2[0][2], b.inv.G2[0][2])
