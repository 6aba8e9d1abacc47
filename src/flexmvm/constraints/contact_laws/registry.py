"""The contact laws: the one ContactLaw enum and the registry LAWS of their specs.

Each law is one object (a ContactLawSpec, contact_laws/spec.py) that holds everything about
it: which pairs become rows and the rows' lower bound, its options and scenario checks, and
what it allows (massless contact nodes, bonded contact, held pairs). Code that needs a
property of a law asks ``law.spec`` (or ``law_spec(law)``) instead of comparing laws. The
built-in laws are registered by constraints/contact_laws/__init__.py, one line each;
``register_law(spec)`` adds another (a new member of ContactLaw is made for a new name).
"""

from __future__ import annotations

from enum import StrEnum
from typing import TYPE_CHECKING

from flexmvm.enum_registry import member_of, register, unregister
from flexmvm.errors import InputError

if TYPE_CHECKING:
    from flexmvm.constraints.contact_laws.spec import ContactLawSpec


class ContactLaw(StrEnum):
    """The lower bound of a frictionless normal row (values: the scenario file's ``law``);
    each member's spec (``law.spec``, contact_laws/velocity.py, position.py) states it."""

    VELOCITY = "velocity"  # Moreau's impact law with a capped penetration recovery (default)
    POSITION = "position"  # the gap at the end of the step (massless contact nodes)

    @property
    def spec(self) -> ContactLawSpec:
        """This law's registered spec (LAWS)."""
        return LAWS[self]


#: The registered laws, in registration order (built-in: constraints/contact_laws/__init__.py).
LAWS: dict[ContactLaw, ContactLawSpec] = {}


def register_law(spec: ContactLawSpec) -> ContactLaw:
    """Register ``spec`` under its name (``spec.name``, the scenario file's contact ``law``)
    and return its ContactLaw, made for a name not in ContactLaw yet (member name: the name
    in upper case, dashes as underscores). InputError for a name already registered."""
    return register(ContactLaw, LAWS, spec, "contact law")


def unregister_law(name: str) -> None:
    """Remove a law registered by register_law that is not built in (a test's toy law): its
    spec and its ContactLaw member."""
    unregister(ContactLaw, LAWS, name, _BUILT_IN, "contact law")


_BUILT_IN = frozenset(law.value for law in ContactLaw)


def law_spec(law: ContactLaw | str) -> ContactLawSpec:
    """The spec of ``law`` (a ContactLaw or its name); InputError naming the laws for an
    unknown one."""
    spec = LAWS.get(member_of(ContactLaw, law))  # type: ignore[arg-type]
    if spec is None:
        known = ", ".join(k.value for k in LAWS)
        raise InputError(f"contact law {law!r}: expected one of {known}")
    return spec


def massless_laws() -> list[ContactLaw]:
    """The registered laws that may carry massless (mass-redistributed) contact nodes."""
    return [law for law, spec in LAWS.items() if spec.massless_nodes]
