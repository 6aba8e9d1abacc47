"""`flexmvm run` prints the plastic guard's warning at its end (issue 51, item 2;
docs/scenario_format.md, `plastic_outside = "warn"`): a reduced plastic body whose cells
outside its retained region reach the yield stress goes on, and the command says so, as it
says the contact guard's and the energy gain's warnings (runs/main_job.py)."""

from __future__ import annotations

import json
import warnings

from click.testing import CliRunner
from test_plastic_dynamics import Y, _block, _hertz, _impact, _yield_speed

from flexmvm.assembly.cost import ReducedCostWarning


def _toml(value) -> str:
    """One TOML value, inline (tables as inline tables; strings as JSON writes them, which
    TOML's basic strings read alike for these paths and names)."""
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    return repr(value)


def test_run_prints_the_plastic_guard_warning(tmp_path):
    """The block of tests/test_plastic_dynamics.py reduced (the nodes within 0.6 mm of the
    contact kept, 4 modes) and struck at 1.5 v_y: its plastic zone grows past the region's
    whole cells (the same run stops there with plastic_outside = "stop"); with the default
    "warn" it runs to its end, exit status 0, and the command prints one warning line naming
    the body and the count of cells. About 10 s."""
    from flexmvm.cli.main import _register, cli

    mesh = _block(tmp_path, 0.3e-3, 0.8e-3)
    region = {"ball": {"centre_m": [0, 0, 0], "radius_m": 0.6e-3}}
    model = {"kind": "mvm", "region": region, "modes": 4}
    v = 1.5 * _yield_speed(mesh)
    t_end = 1.25 * _hertz(mesh, v).duration_s
    data = _impact(mesh, v, {"yield_pa": Y}, t_end, 0.5e-6, model=model, run=False)
    path = tmp_path / "plastic_block.toml"
    path.write_text("".join(f"{k} = {_toml(v)}\n" for k, v in data.items()))
    _register()
    args = ["run", str(path), "--no-fields", "--no-progress", "--jobs", "1"]
    with warnings.catch_warnings():  # the cost guard's verdict on this block is not this test's
        warnings.simplefilter("ignore", ReducedCostWarning)
        res = CliRunner().invoke(cli, [*args, "--out", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    lines = [x for x in res.output.splitlines() if x.startswith("warning: body 'block'")]
    assert len(lines) == 1, res.output
    assert "cells outside the retained region reached the yield stress" in lines[0], lines
