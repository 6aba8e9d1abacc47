"""Run a scenario with one body as a moving region (issue 53 item 1; bodies/moving_region.py,
reduction/kinds/mvm_moving.py): the scenario built as it is (the body's own model then
replaced), the body's FE model and reference condition (its supports, or its reference)
taken from the setup cache, the windows made along the node set ``path`` and the run made
with the MovingRegion as the driver's ``switches``.

Not wired into the scenario file or ``flexmvm run --model`` yet: the window options (path,
spacing, half width, modes, outside) are this function's arguments.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from flexmvm.bodies.moving_region import MovingOutside, MovingRegion, rebind_contacts
from flexmvm.errors import InputError
from flexmvm.integrate.driver import simulate
from flexmvm.integrate.run_result import RunResult
from flexmvm.integrate.state import BodyState
from flexmvm.reduction.kinds.mvm_moving import MovingWindows, moving_windows
from flexmvm.scenarios.body_reference import reference_label
from flexmvm.scenarios.build import BuiltScenario, build_scenario
from flexmvm.scenarios.cache_keys import mesh_key
from flexmvm.scenarios.setup import default_setup
from flexmvm.scenarios.supports import bedded_key, clamp_label


@dataclass
class MovingRun:
    """A moving-region run: the result, the region (its switches, contact centres, guard),
    the built scenario (with the region's first body) and CPU seconds [s] of the windows'
    setup (global factor and modes, every window's basis and parts) and of the run."""

    result: RunResult
    region: MovingRegion
    built: BuiltScenario
    setup_cpu_s: float
    run_cpu_s: float


def moving_setup(
    sc,
    body: str,
    path: str,
    modes: int,
    spacing_m: float,
    half_width_m: float,
    s_range=None,
    setup=None,
) -> MovingWindows:
    """The windows of body ``body`` of scenario ``sc`` along its node set ``path``
    (reduction.kinds.mvm_moving.moving_windows)."""
    setup = default_setup() if setup is None else setup
    names = [b.name for b in sc.bodies]
    if body not in names:
        raise InputError(f"moving region: body {body!r}; expected one of {', '.join(names)}")
    cfg = sc.bodies[names.index(body)]
    mesh = setup.mesh(mesh_key(cfg))
    fe_key = bedded_key(mesh_key(cfg), cfg, sc.supports)
    fe = setup.fe_model(fe_key, cfg.material_obj())
    label = clamp_label(cfg, mesh, sc.supports) or reference_label(
        cfg.model.reference, mesh, (), f"bodies[{body}].model.reference"
    )
    reference = setup.reference_condition(fe_key, mesh, label)
    return moving_windows(
        fe, reference, mesh.node_set(path), modes, spacing_m, half_width_m, s_range
    )


def run_moving(
    sc,
    body: str,
    path: str,
    modes: int,
    spacing_m: float,
    half_width_m: float,
    outside: MovingOutside = MovingOutside.WARN,
    s_range=None,
    start_s: float | None = None,
    setup=None,
) -> MovingRun:
    """Scenario ``sc`` with body ``body`` a moving region (module doc); its first window the
    one nearest ``start_s`` (default: the path's first). SimulationFailed (its partial the
    RunResult up to the stop) when the guard stops the run (outside = STOP)."""
    c0 = time.process_time()
    windows = moving_setup(sc, body, path, modes, spacing_m, half_width_m, s_range, setup)
    index = [b.name for b in sc.bodies].index(body)
    start = 0 if start_s is None else windows.nearest(start_s)
    region = MovingRegion(index, windows, body, start, outside)
    for k in range(len(windows.centres)):
        region.body(k)
    c1 = time.process_time()
    built = build_scenario(sc, setup)
    first = region.body(start)
    bodies = list(built.system.bodies)
    bodies[index] = first
    system = dataclasses.replace(built.system, bodies=tuple(bodies))
    rebind_contacts(system, index, first)
    states = list(built.states)
    st = states[index]
    v = np.zeros(first.nv)
    v[:6] = st.v[:6]
    states[index] = BodyState(st.r, st.A, np.zeros(first.nq), v)
    built = BuiltScenario(system, states, built.probes, built.grid, built.info)
    c2 = time.process_time()
    res = simulate(system, states, built.grid, built.probes, switches=region)
    return MovingRun(res, region, built, c1 - c0, time.process_time() - c2)
