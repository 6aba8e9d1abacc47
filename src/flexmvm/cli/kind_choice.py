"""The model kinds an option of a command takes, read from the kind registry
(reduction/kinds/) when click first needs them (the command's --help, its parsing): a kind
registered there is a choice of every command without an edit here, and registering the
commands (`flexmvm --help`) imports no numerical stage."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import click


class KindChoice(click.Choice):
    """click.Choice over the registered model kinds that ``which`` accepts (a predicate on the
    ModelKind member; None: every kind), in the registry's order, read at each use (a kind
    registered later is a choice from then on)."""

    def __init__(self, which: Callable[[Any], bool] | None = None) -> None:
        self._which = which
        self.case_sensitive = True

    @property
    def choices(self) -> Sequence[str]:  # type: ignore[override]  # click: an attribute
        import flexmvm.reduction.kinds  # noqa: F401  (registers the built-in kinds)
        from flexmvm.reduction.kinds.registry import ModelKind

        which = self._which
        return tuple(k.value for k in ModelKind if which is None or which(k))


def every_kind() -> KindChoice:
    """Every model kind (`flexmvm run --model`)."""
    return KindChoice()


def retaining_kinds() -> KindChoice:
    """The kinds that keep a node selection beside modes (the MVM kinds)."""
    return KindChoice(lambda k: k.retains_nodes)


def selectable_kinds() -> KindChoice:
    """The kinds `flexmvm select` builds candidates of (ModelKindSpec.selectable)."""
    return KindChoice(lambda k: k.spec.selectable)
