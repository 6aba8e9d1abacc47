"""One place per contact law (constraints/contact_laws/): a law is one object registered once,
and nothing else compares laws or probes a provider or an integrator for a capability.

A toy law registered from outside the package sets the rows of a contact by itself (its row
window and lower bound reach contact.pairs unchanged); the source names no law member in a
comparison and calls no getattr/hasattr in the driver, the energy ledger, the run's summary
and the massless check; the protocols declare what those ask for."""

from __future__ import annotations

import ast
import types
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from flexmvm.bodies.body import FlexibleBody
from flexmvm.constraints.contact import ContactProvider
from flexmvm.constraints.contact_laws import (
    LAWS,
    ContactLaw,
    LawSpec,
    register_law,
    unregister_law,
)
from flexmvm.contact.geometry import MasterSurface
from flexmvm.contact.pairs import PointToSurfaceContact
from flexmvm.integrate.step import Integrator
from flexmvm.scenarios.contact_schema import ContactConfig

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "flexmvm"


@dataclass(frozen=True)
class _EndGapLaw(LawSpec):
    """A toy law: every pair within 1 mm is a row, bound to close its gap over the step,
    u_N+ >= -g / h (the end gap at theta = 1)."""

    def row_window(self, h, gap_tol, speed):
        return 0.0, 1e-3

    def lower(self, gaps, u_n, h, beta, theta):
        return -gaps / h


def _plate_and_nodes():
    """Master: one unit quad at z = 0 (rigid, nq 0 plus one dummy coordinate); slave: four
    nodes above it at gaps 0.1, 0.2, 0.3 mm and one at 5 mm (out of the toy law's window)."""
    Xm = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    gaps = np.array([1e-4, 2e-4, 3e-4, 5e-3])
    Xs = np.column_stack([[0.2, 0.4, 0.6, 0.8], [0.5] * 4, gaps])
    mk = lambda name, X: FlexibleBody(
        name, X, sp.csr_matrix((3 * len(X), 1)), types.SimpleNamespace(nq=1), None
    )
    state = lambda v: types.SimpleNamespace(r=np.zeros(3), A=np.eye(3), q=np.zeros(1), v=v)
    bodies = [mk("plate", Xm), mk("nodes", Xs)]
    v_s = np.zeros(7)
    v_s[2] = -1.0  # the nodes approach at 1 m/s
    return (
        bodies,
        [state(np.zeros(7)), state(v_s)],
        MasterSurface(quads=np.array([[0, 1, 2, 3]]), tris=np.zeros((0, 3), np.int64)),
        gaps,
    )


def test_a_law_registered_from_outside_sets_the_rows():
    """register_law(spec) makes ContactLaw member END_GAP, which a scenario's contact table
    takes as its ``law``; a contact under it takes its rows
    from the law alone: the three nodes within its 1 mm window (the velocity law, from the
    same states, takes none: g + h u_N- > 0 for all four at h = 1e-5 s), with lower bounds
    -g / h equal to the law's to round-off (1e-12 relative: the gaps are computed from the
    projection, not copied)."""
    law = register_law(_EndGapLaw("end-gap"))
    try:
        assert law is ContactLaw.END_GAP and ContactLaw("end-gap").spec is LAWS[law]
        assert ContactConfig(slave="a.s", master="b.m", law="end-gap").law is law
        bodies, states, surf, gaps = _plate_and_nodes()
        h = 1e-5
        rows = {}
        for name in (ContactLaw.VELOCITY, law):
            prov = PointToSurfaceContact(
                bodies, 1, np.arange(4), 0, surf, search_radius_m=0.01, law=name
            )
            rows[name] = prov.candidate_rows(bodies, states, h)
        assert rows[ContactLaw.VELOCITY].rows.m == 0
        toy = rows[law]
        assert [k[1] for k in toy.keys] == [0, 1, 2]
        np.testing.assert_allclose(toy.lower, -gaps[:3] / h, rtol=1e-12, atol=0)
    finally:
        unregister_law("end-gap")
    assert "end-gap" not in {x.value for x in ContactLaw} and len(LAWS) == 2


def _law_comparisons(tree: ast.AST) -> int:
    """Comparisons with a member of the (constraints) ContactLaw, and getattr(x, "law", ...)."""
    members = {"VELOCITY", "POSITION"}
    n = 0
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            for side in [node.left, *node.comparators]:
                n += (
                    isinstance(side, ast.Attribute)
                    and side.attr in members
                    and isinstance(side.value, ast.Name)
                    and side.value.id == "ContactLaw"
                )
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "getattr":
            arg = node.args[1] if len(node.args) > 1 else None
            n += isinstance(arg, ast.Constant) and arg.value == "law"
    return n


def test_no_law_is_compared_outside_its_module():
    """Every question about a law goes to its spec (law.spec): the package compares no
    ContactLaw member and asks getattr for no provider's law (9 comparisons and 2 getattr
    in 6 files before the registry)."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        n = _law_comparisons(ast.parse(path.read_text(encoding="utf-8")))
        if n:
            found[str(path.relative_to(PACKAGE))] = n
    assert found == {}


def test_the_step_and_its_report_probe_no_capability():
    """The driver, the energy ledger, the run's summary and the massless check read declared
    attributes: no getattr/hasattr in them (11 calls before), and the protocols declare
    what they read (the integrator's theta_rule, plastic and carried_state; a contact's law,
    slave and master)."""
    probes = {}
    for name in (
        "integrate/driver.py",
        "integrate/energy_ledger.py",
        "integrate/moreau_jean/massless.py",
        "runs/run.py",
    ):
        tree = ast.parse((PACKAGE / name).read_text(encoding="utf-8"))
        calls = [
            n.lineno
            for n in ast.walk(tree)
            if isinstance(n, ast.Call) and getattr(n.func, "id", None) in ("getattr", "hasattr")
        ]
        if calls:
            probes[name] = calls
    assert probes == {}
    # declared as annotations or as read-only properties (integrate.step)
    declared = set(Integrator.__annotations__) | set(vars(Integrator))
    assert {"theta_rule", "plastic", "carried_state"} <= declared
    assert {"law", "slave", "master", "mu"} <= set(ContactProvider.__annotations__)
