"""The scenario's ``[[contacts]]`` and ``[[probes]]`` tables (pydantic v2): a contact's surfaces,
law and options, a probe's body point; scenarios/schema.py checks their cross-references
(bodies, surfaces) and docs/scenario_format.md lists the keys."""

from __future__ import annotations

from typing import Annotated, Literal

from annotated_types import Ge, Le
from pydantic import (
    Strict,
    StringConstraints,
    model_serializer,
    model_validator,
)

from flexmvm.constraints.contact import ContactKind, ContactLaw
from flexmvm.scenarios.fields import (
    Frozen,
    Name,
    Positive,
    SetName,
    Vec3,
)
from flexmvm.scenarios.problems import problem


class ContactConfig(Frozen):
    """Slave nodes of ``slave`` ('body.surface') against the master facets of ``master``."""

    slave: Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+\.[A-Za-z0-9_]+$")]
    master: Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_]+\.[A-Za-z0-9_]+$")]
    kind: ContactKind = ContactKind.FRICTIONLESS
    search_radius_m: Positive | None = None
    # Coulomb friction coefficient [-] of the pair; 0: frictionless rows, the exact LCP
    friction_coefficient: Annotated[float, Strict(), Ge(0.0)] = 0.0
    # the contact nodes of both surfaces carry no mass (fe/mass_redistribution.py)
    redistribute_mass: bool = False
    # the normal rows' law (constraints.contact.ContactLaw): velocity (Moreau, beta recovery)
    # or position (the gap at the end of the step, with the scenario's time.theta)
    law: ContactLaw = ContactLaw.VELOCITY
    # the velocity law's penetration recovery beta [-]: u_N+ >= beta max(0, -g) / h
    # (None: contact.pairs.PENETRATION_RECOVERY); docs/studies.md "Material study" for when 0
    penetration_recovery: Annotated[float, Strict(), Ge(0.0), Le(1.0)] | None = None
    # two-pass: also the reverse pair (the master's surface nodes against the slave's facets,
    # the same law and options), so that each surface is checked against the other: a master
    # edge or corner can otherwise go through the slave surface (docs/contact_law.md,
    # "When one pair is not enough"); the builder adds it (assembly.build)
    two_pass: bool = False

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        # options at their defaults dump as before the keys existed: study case keys and cache
        # identities hash these dumps
        data = handler(self)
        if isinstance(data, dict):
            for key, default in (
                ("friction_coefficient", 0.0),
                ("redistribute_mass", False),
                ("law", ContactLaw.VELOCITY),
                ("penetration_recovery", None),
                ("two_pass", False),
            ):
                if key in data and data[key] == default:
                    data.pop(key)
        return data

    @model_validator(mode="after")
    def _check_friction(self) -> ContactConfig:
        if self.friction_coefficient > 0.0 and self.kind is ContactKind.BONDED:
            raise problem(
                "a bonded contact locks all three components: friction_coefficient "
                f"must be 0, got {self.friction_coefficient!r}",
                "friction_coefficient",
            )
        # the law's own checks (constraints/contact_laws: the position law takes no bonded
        # contact and no penetration_recovery)
        refused = self.law.spec.scenario_problem(
            self.kind is ContactKind.BONDED, self.penetration_recovery
        )
        if refused is not None:
            raise problem(*refused)
        return self

    @property
    def pairs(self) -> tuple[tuple[str, str], ...]:
        """(slave, master) of the pairs this table builds: itself, and its reverse if two_pass."""
        one = ((self.slave, self.master),)
        return one + ((self.master, self.slave),) if self.two_pass else one

    @property
    def slave_body(self) -> str:
        return self.slave.split(".")[0]

    @property
    def slave_surface(self) -> str:
        return self.slave.split(".")[1]

    @property
    def master_body(self) -> str:
        return self.master.split(".")[0]

    @property
    def master_surface(self) -> str:
        return self.master.split(".")[1]


class ProbeConfig(Frozen):
    """A probe: a node set's first node, or any point of the body (its node when one is
    within reach, else interpolated in the element that holds it); ``axis`` the velocity
    component its comparisons use (the history holds all three and the speed)."""

    name: Name
    body: Name
    node_set: SetName | None = None
    point_m: Vec3 | None = None
    axis: Literal["x", "y", "z", "norm"] = "x"

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        data = handler(self)  # axis left out at its default: study and cache keys unchanged
        if isinstance(data, dict) and data.get("axis") == "x":
            data.pop("axis", None)
        return data

    @model_validator(mode="after")
    def _check(self) -> ProbeConfig:
        if (self.node_set is None) == (self.point_m is None):
            raise problem("needs exactly one of node_set or point_m", "node_set")
        return self
