"""Members added to a string enum after its class was made: the registries of model kinds
(reduction/kinds/registry.py) and contact laws (constraints/contact_laws/registry.py) make
one for a name registered by a user, and remove it again (a test's toy entry)."""

from __future__ import annotations

from collections.abc import MutableMapping
from enum import Enum
from typing import Any, TypeVar

from flexmvm.errors import InputError

E = TypeVar("E", bound=Enum)


def add_member(enum_cls: type[E], name: str, value: str) -> E:
    """A new member ``name`` = ``value`` of the str enum ``enum_cls``, made the way Enum's own
    class creation makes one."""
    member: Any = str.__new__(enum_cls, value)  # type: ignore[type-var]  # a str enum
    member._name_, member._value_ = name, value
    member.__objclass__ = enum_cls
    member.__init__(value)
    enum_cls._member_names_.append(name)
    enum_cls._member_map_[name] = member
    enum_cls._value2member_map_[value] = member
    type.__setattr__(enum_cls, name, member)
    return member


def member_of(enum_cls: type[E], value: Any) -> E | None:
    """The member of ``enum_cls`` whose value is ``value`` (a member is its own value), or
    None."""
    try:
        return enum_cls._value2member_map_.get(value)  # type: ignore[return-value]
    except TypeError:  # an unhashable value
        return None


def remove_member(enum_cls: type[Enum], member: Enum) -> None:
    """Remove ``member`` (one made by add_member) from ``enum_cls``."""
    del enum_cls._value2member_map_[member.value]
    del enum_cls._member_map_[member.name]
    enum_cls._member_names_.remove(member.name)
    type.__delattr__(enum_cls, member.name)


def register(enum_cls: type[E], table: MutableMapping[E, Any], spec: Any, what: str) -> E:
    """Register ``spec`` in ``table`` under its name (``spec.name``) and return its member of
    ``enum_cls``, made for a name not in it yet (member name: the name in upper case, dashes
    as underscores). ``what`` names the thing in errors ("model kind"). InputError for a
    name that is not a lower-case string or is registered already."""
    name = spec.name
    if not isinstance(name, str) or not name or name != name.strip().lower():
        raise InputError(f"{what} name {name!r}; expected a lower-case string")
    member = member_of(enum_cls, name)
    if member is not None and member in table:
        raise InputError(f"{what} {name!r} is registered already")
    if member is None:
        member = add_member(enum_cls, name.upper().replace("-", "_"), name)
    table[member] = spec
    return member


def unregister(
    enum_cls: type[E], table: MutableMapping[E, Any], name: str, built_in: frozenset, what: str
) -> None:
    """Remove what register added under ``name`` (not one of the ``built_in`` names): its
    entry in ``table`` and its member of ``enum_cls``."""
    member = member_of(enum_cls, name)
    if member is None or name in built_in:
        raise InputError(f"{what} {name!r}: not a registered added {what.split()[-1]}")
    table.pop(member, None)
    remove_member(enum_cls, member)
