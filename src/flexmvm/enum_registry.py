"""Members added to a string enum after its class was made: the registries of model kinds
(reduction/kinds/registry.py) and contact laws (constraints/contact_laws/registry.py) make
one for a name registered by a user, and remove it again (a test's toy entry)."""

from __future__ import annotations

from enum import Enum
from typing import Any, TypeVar

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
