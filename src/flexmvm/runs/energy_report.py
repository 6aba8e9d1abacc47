"""summary.json's energy ledger and momentum report of a run (runs/run.py summarize).

Energy: the ledger's works and dissipations (integrate.energy_ledger) at the run's end, and the
balance E(t) - E(0) - works + dissipations (its residual), relative to the input work (the
largest |work of the loads and joints| over the run) or, when nothing does work, to E(0).

Momentum: the total linear momentum is conserved only when nothing outside the bodies pushes
them. Where it is not, the report says why (gravity, a joint or spring to the ground, an
external load) and gives the momentum error of each free subsystem instead: the bodies linked
by joints, springs, revolute torques and contacts, none of them held by the ground or loaded
from outside. A joint exchanges momentum with the ground when the translational parts of one
of its rows do not cancel over the bodies (a row on one body: a point held in space);
generic over every Joint, the drives included.
"""

from __future__ import annotations

import numpy as np

from flexmvm.integrate.energy_ledger import load_label
from flexmvm.integrate.system import StoringLoad

#: relative size below which the sum of a joint row's translational parts is zero (round-off)
CANCEL_TOL = 1e-12

ENERGY_LEDGER_NOTE = (
    "energy_ledger: works and dissipations summed over the steps [J] (integrate.energy_ledger): "
    "loads h F . v_m, joints and contacts lambda . (Phi v_m), damping h v_m^T C v_m, numerical "
    "(theta - 1/2)(dv^T M dv + dq^T K dq); balance_residual = E(t) - E(0) - works + "
    "dissipations, relative to balance_reference_J (the input work, else E(0))."
)


def report_entries(res, built, why_not: str | None, subsystems: dict) -> dict:
    """summary.json's entries of this module: why momentum_rel_error is None (gravity, a
    joint or load to the ground: momentum_report's reason) and the error of each free
    subsystem instead, then the energy ledger."""
    return {
        "momentum_error_undefined_because": why_not,
        "subsystem_momentum_rel_error": subsystems,
        **energy_ledger_summary(res, built),
    }


def energy_ledger_summary(res, built) -> dict:
    """The ``energy_ledger`` entry of summary.json ({} without a ledger)."""
    led = res.energy_ledger
    if led is None or not len(led.contact):
        return {}
    E = res.total_energy[: len(led.contact)]
    resid = led.residual(E)
    inputs = led.loads.sum(axis=1) + led.joints.sum(axis=1)
    w_in = float(np.abs(inputs).max()) if inputs.size else 0.0
    scale_e = float(np.abs(E).max()) if E.size else 0.0
    if w_in > 1e-9 * scale_e and w_in > 0.0:
        ref, ref_j = "input work", w_in
    else:
        ref, ref_j = "initial energy", abs(float(E[0])) or scale_e
    springs = {
        n: float(led.load_energy[-1, k])
        for k, n in enumerate(led.load_names)
        if isinstance(built.system.loads[k], StoringLoad)
    }
    return {
        "energy_ledger": {
            "kinetic_J": float(res.kinetic[-1]),
            "strain_J": float(res.strain[-1]),
            "potential_J": float(res.potential[-1]),
            "total_start_J": float(E[0]),
            "total_end_J": float(E[-1]),
            "work_loads_J": {n: float(led.loads[-1, k]) for k, n in enumerate(led.load_names)},
            "load_damper_dissipation_J": {
                n: float(led.load_damping[-1, k]) for k, n in enumerate(led.load_names)
            },
            "spring_energy_J": springs,
            "work_joints_J": {n: float(led.joints[-1, k]) for k, n in enumerate(led.joint_names)},
            "work_contact_J": float(led.contact[-1]),
            "dissipation_damping_J": float(led.damping[-1]),
            "dissipation_numerical_J": float(led.numerical[-1]),
            # spinning bodies only (bodies.stiffening): the work of -s K_G q
            "work_stiffening_J": None if led.stiffening is None else float(led.stiffening[-1]),
            # plastic bodies only (integrate.plastic_bodies): their plastic work
            **({} if led.plastic is None else {"plastic_work_J": float(led.plastic[-1])}),
            "balance_residual_J": float(resid[-1]),
            "balance_residual_rel_max": float(np.abs(resid).max() / ref_j) if ref_j else None,
            "balance_reference": ref,
            "balance_reference_J": ref_j,
            "note": ENERGY_LEDGER_NOTE,
        }
    }


def _grounded_joints(system, states) -> list[tuple[int, set[int]]]:
    """[(joint index, its bodies)] of the joints one of whose rows has a resultant force."""
    out = []
    for k, joint in enumerate(system.joints):
        _, rows = joint.evaluate(system.bodies, states, 0.0)
        total = sum((bf[:, :3] for bf, _ in rows.blocks.values()), np.zeros((rows.m, 3)))
        size = max((float(np.abs(bf[:, :3]).max()) for bf, _ in rows.blocks.values()), default=0)
        if rows.m and np.abs(total).max() > CANCEL_TOL * max(size, 1e-300):
            out.append((k, set(rows.blocks)))
    return out


def _links(system, states) -> list[set[int]]:
    """Sets of bodies that exchange momentum among themselves (joints, loads, contacts)."""
    links = []
    for joint in system.joints:
        links.append(set(joint.evaluate(system.bodies, states, 0.0)[1].blocks))
    for load in system.loads:
        links.append(_load_bodies(load))
    for c in system.contacts:
        links.append({c.slave, c.master})
    return links


def _load_bodies(load) -> set[int]:
    """The bodies a load acts on (its declared acted_on, whatever its value at t = 0)."""
    return set(load.acted_on)


def _components(n: int, links: list[set[int]]) -> list[set[int]]:
    parent = list(range(n))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for link in links:
        members = sorted(link)
        for b in members[1:]:
            parent[root(b)] = root(members[0])
    groups: dict[int, set[int]] = {}
    for b in range(n):
        groups.setdefault(root(b), set()).add(b)
    return list(groups.values())


def momentum_report(res, built) -> tuple[str | None, dict]:
    """(why the total momentum error is not defined, or None; {subsystem: its momentum
    error}) of a run (module doc). A subsystem's error is max_t |p(t) - p(0)| over the
    largest momentum one of its bodies carries over the run."""
    system, states = built.system, built.states
    names = [b.name for b in system.bodies]
    reasons, held = [], set()
    if np.any(system.gravity):
        reasons.append("gravity pushes every body from outside")
        held = set(range(len(names)))
    for k, bodies in _grounded_joints(system, states):
        who = ", ".join(repr(names[b]) for b in sorted(bodies))
        kind = type(system.joints[k]).__name__
        reasons.append(f"joints[{k}] ({kind}) holds {who} to the ground, which exchanges momentum")
        held |= bodies
    for k, load in enumerate(system.loads):
        if load.external:
            who = ", ".join(repr(names[b]) for b in sorted(_load_bodies(load)))
            reasons.append(f"{load_label(k, load)} pushes {who} from outside")
            held |= _load_bodies(load)
    if not reasons:
        return None, {}
    errors = {}
    if res.body_momentum is not None:
        for group in _components(len(names), _links(system, states)):
            if group & held:
                continue
            idx = sorted(group)
            p = res.body_momentum[:, idx, :]
            total = p.sum(axis=1)
            scale = float(np.linalg.norm(p, axis=2).max())
            err = float(np.linalg.norm(total - total[0], axis=1).max())
            errors["+".join(names[b] for b in idx)] = err / scale if scale > 0 else err
    return "; ".join(reasons), errors
