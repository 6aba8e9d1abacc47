"""Option objects instead of twenty-parameter signatures (issue 50 item 5): the study entry
points take a frozen StudyOptions (where the cases run) and BasisSpec (the candidates), the
study commands pass their shared options as one StudyOptions, and TimeGrid is built from a
scenario's [time] table by name (TimeGrid.from_config). Calls written with the old keyword
arguments keep working. Exact checks (signatures, equal objects): no tolerance to choose."""

from __future__ import annotations

import dataclasses
import inspect
from pathlib import Path

import click
import pytest

from flexmvm.cli.main import main as cli_main
from flexmvm.integrate.run_result import TimeGrid
from flexmvm.scenarios import load_scenario
from flexmvm.studies import api, materials, selection
from flexmvm.studies.options import BasisSpec, StudyOptions

ROOT = Path(__file__).resolve().parents[1]
TINY = Path(__file__).parent / "data" / "tiny_impact.toml"

#: Parameters of the largest study entry point, measured: 22 before (run_selection_study;
#: select_cmd.command 23, select_models and api.select 19); now at most 9 (api.select).
MAX_PARAMETERS = 9


def test_study_entry_points_take_option_objects():
    """Each entry point has at most MAX_PARAMETERS parameters, an ``options`` StudyOptions and
    (the selection study's) a ``basis`` BasisSpec; both are frozen."""
    entry = {
        "api.select": api.select,
        "api.material_study": api.material_study,
        "selection.select_models": selection.select_models,
        "selection.run_selection_study": selection.run_selection_study,
        "materials.material_study": materials.material_study,
        "materials.run_materials_study": materials.run_materials_study,
    }
    sizes = {name: len(inspect.signature(f).parameters) for name, f in entry.items()}
    assert max(sizes.values()) <= MAX_PARAMETERS, sizes
    for name, f in entry.items():
        assert "options" in inspect.signature(f).parameters, name
    assert "basis" in inspect.signature(selection.run_selection_study).parameters
    with pytest.raises(dataclasses.FrozenInstanceError):
        StudyOptions().serial = True  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        BasisSpec().modes = (7,)  # type: ignore[misc]


def test_old_keyword_arguments_fill_the_objects(tmp_path, monkeypatch):
    """run_selection_study(..., layers=, modes=, serial=, t_end_s=, echo=) as written before the
    objects: select_models receives the equal BasisSpec and StudyOptions; a name of neither is
    Python's own TypeError, before anything runs."""
    seen = {}

    def fake(sc, body, out, basis, target, search, options):
        seen.update(basis=basis, options=options, search=search)
        raise RuntimeError("stop")  # nothing else of the study needed here

    monkeypatch.setattr(selection, "select_models", fake)
    lines: list[str] = []
    with pytest.raises(RuntimeError, match="stop"):
        selection.run_selection_study(
            TINY,
            "b2",
            tmp_path,
            layers=[1],
            laps=[1, 2],
            modes=[7],
            serial=True,
            progress=False,
            t_end_s=1e-4,
            echo=lines.append,
        )
    assert seen["basis"] == BasisSpec(layers=[1], laps=[1, 2], modes=[7])
    assert seen["options"] == StudyOptions(
        serial=True, progress=False, t_end_s=1e-4, echo=lines.append
    )
    with pytest.raises(TypeError, match="unexpected keyword argument 'workerz'"):
        selection.run_selection_study(TINY, "b2", tmp_path, workerz=2)


def test_select_command_passes_one_options_object(tmp_path, monkeypatch):
    """`flexmvm select` with every shared option: run_selection_study gets one StudyOptions
    holding them (echo: click.echo) and one BasisSpec of the grid options."""
    seen = {}

    def fake(scenario, body, out_dir, basis, target, search, options):
        seen.update(basis=basis, options=options, search=search)

    monkeypatch.setattr(selection, "run_selection_study", fake)
    argv = [
        "select", str(TINY), "--body", "b2", "--layers", "1..2", "--laps", "1", "--modes",
        "7:13:6", "--serial", "--workers", "3", "--t-end", "1e-4", "--dt", "1e-6", "--other",
        "full", "--no-progress", "--out", str(tmp_path / "s"),
    ]  # fmt: skip
    try:
        cli_main(argv)
    except SystemExit as exc:
        assert exc.code in (0, None), exc
    assert seen["options"] == StudyOptions(
        n_workers=3,
        serial=True,
        progress=False,
        t_end_s=1e-4,
        dt_s=1e-6,
        other="full",
        echo=click.echo,
    )
    assert list(seen["basis"].layers) == [1, 2] and list(seen["basis"].modes) == [7, 13]
    assert seen["search"] is False


def test_time_grid_from_config_is_the_positional_grid():
    """TimeGrid.from_config(sc.time) equals the grid built field by field in position, as
    assembly/build.py did, for the seed scenario (hf damping, contact outputs) and a tiny one."""
    for path in (ROOT / "scenarios" / "rod_impact.toml", TINY):
        t = load_scenario(path).time
        positional = TimeGrid(
            t.t_end_s,
            t.dt_s,
            t.dt_max_s,
            t.output_dt_s,
            t.theta,
            t.output_contact_dt_s,
            t.hf_damping_time_s,
            field_output_dt_s=t.field_output_dt_s,
            field_precision=t.field_precision,
        )
        assert TimeGrid.from_config(t) == positional
