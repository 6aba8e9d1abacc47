"""The contact laws, one module each, and their registry (registry.py: ContactLaw, LAWS,
register_law, law_spec; what a law declares: spec.py ContactLawSpec).

A new law is one new module here holding its spec object ``SPEC`` (a LawSpec subclass: its
name, properties, row window and lower bound) and one line below registering it; nothing else
names it (docs/architecture.md, "Where a change goes")."""

from flexmvm.constraints.contact_laws import position, velocity
from flexmvm.constraints.contact_laws.registry import (
    LAWS,
    ContactLaw,
    law_spec,
    massless_laws,
    register_law,
    unregister_law,
)
from flexmvm.constraints.contact_laws.spec import ContactLawSpec, LawSpec

register_law(velocity.SPEC)
register_law(position.SPEC)

__all__ = [
    "LAWS",
    "ContactLaw",
    "ContactLawSpec",
    "LawSpec",
    "law_spec",
    "massless_laws",
    "register_law",
    "unregister_law",
]
