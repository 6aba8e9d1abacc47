"""What a model kind declares (ModelKindSpec) and what its basis builder is given
(BasisRequest); the Basis it returns. KindSpec is a frozen base with the common answers, so a
kind's module states only where it differs."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Any, Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp

from flexmvm.fe.assembly import FEModel
from flexmvm.reduction.interface import InterfaceSources, InterfaceSpec
from flexmvm.reduction.kinds.registry import ModelKind, kind_spec
from flexmvm.reduction.reference_condition import ReferenceCondition


class MasslessStatics(Enum):
    """The static columns of the massless retained nodes of a Craig-Bampton basis."""

    ALL = "all"  # every massless DOF's interior static field: span contains Craig-Bampton's
    PATCH = "patch"  # the static fields of massless_patterns: a few columns per body


@dataclass(frozen=True)
class Basis:
    """A reduction basis of one body.

    psi: (3n, nq) ndarray (csr for FULL); u = psi @ q [m]; reference DOF rows are zero.
    retained_nodes: (nb,) region-II node ids, in column order (FULL: every node not in the
    reference condition; MODAL: empty). n_modes: number of modal columns.
    mode_freqs_hz: (n_modes,) frequencies [Hz] of the modes in the modal columns.
    """

    kind: ModelKind
    psi: np.ndarray | sp.csr_matrix
    retained_nodes: np.ndarray
    n_modes: int
    reference: ReferenceCondition
    mode_freqs_hz: np.ndarray

    @property
    def nq(self) -> int:
        """Number of generalised elastic coordinates."""
        return int(self.psi.shape[1])

    @property
    def n_static(self) -> int:
        """Static columns of the massless retained nodes (CRAIG_BAMPTON: between the retained
        nodes' columns and the modal ones; 0 for the other kinds)."""
        return kind_spec(self.kind).n_static(self)

    def retained_columns(self) -> np.ndarray:
        """Columns of psi holding the x, y, z displacement of each retained node, (nb, 3).

        For FULL, a reference node's clamped components have no column and do not appear
        (such nodes are not retained). CRAIG_BAMPTON: 0..3nb-1; SEED_BLOCK and
        SEED_FIXED: after the modes.
        """
        return kind_spec(self.kind).retained_columns(self)


@dataclass(frozen=True)
class BasisRequest:
    """What build_basis hands a kind's builder: the FE model, the reference condition, the
    validated retained node ids (nb,), the mode count and the kind's further inputs."""

    fe: FEModel
    reference: ReferenceCondition
    nodes: np.ndarray
    n_modes: int
    interface: InterfaceSpec | None = None
    sources: InterfaceSources | None = None
    massless_statics: MasslessStatics = MasslessStatics.PATCH


@runtime_checkable
class ModelKindSpec(Protocol):
    """Everything about one model kind. Properties: has_basis (False: a rigid body, no
    elastic coordinates), retains_nodes (a node selection beside its modes), uses_modes (a
    mode count >= 1), reads_modes (takes model.modes at all, >= 0 allowed when not
    uses_modes), nodal (every free node a coordinate: a sparse basis and sparse body parts,
    not kept in the setup cache), uses_patches (model.patch_* keys: the interface kind),
    cuts_modes (a basis of fewer modes is the leading columns of one of more: a study's mode
    floor), clampable (its basis is built under a reference condition, which a clamp
    replaces: scenarios/support_schema.py), selectable (`flexmvm select` builds candidates
    of it: a node selection and a mode count). Hooks: build_basis, n_static and retained_columns and modal_columns (the damping
    hook: where its modal coordinates are) of a basis, cost_columns (the dense columns to
    cost, None: not costed), study_fields (the model of a study's 'kind:args' text),
    body_builder (None: bodies.build.body_from_parts on the cached parts; else called as
    body_builder(name, fe, basis, damping=..., parts_cache=...), parts_cache(fe, basis, build)
    the setup cache's entry for what it builds: assembly/build.py)."""

    # read-only properties, so that a frozen dataclass satisfies them
    @property
    def name(self) -> str: ...
    @property
    def has_basis(self) -> bool: ...
    @property
    def retains_nodes(self) -> bool: ...
    @property
    def uses_modes(self) -> bool: ...
    @property
    def reads_modes(self) -> bool: ...
    @property
    def nodal(self) -> bool: ...
    @property
    def uses_patches(self) -> bool: ...
    @property
    def cuts_modes(self) -> bool: ...
    @property
    def clampable(self) -> bool: ...
    @property
    def selectable(self) -> bool: ...
    @property
    def body_builder(self) -> Callable[..., Any] | None: ...

    def build_basis(self, request: BasisRequest) -> Basis: ...

    def n_static(self, basis: Basis) -> int: ...

    def retained_columns(self, basis: Basis) -> np.ndarray: ...

    def modal_columns(self, basis: Basis) -> np.ndarray: ...

    def cost_columns(self, n_retained: int, n_modes: int) -> int | None: ...

    def study_fields(self, args: tuple[str, ...]) -> Mapping[str, Any] | None: ...


@dataclass(frozen=True)
class KindSpec:
    """The common answers of a ModelKindSpec: an elastic reduced kind with modes last, no
    retained nodes, no static columns, not costed, not parsed from a study's text, its body
    built the default way. A kind module subclasses it and states where it differs."""

    name: str
    has_basis: bool = True
    retains_nodes: bool = False
    uses_modes: bool = False
    reads_modes: bool = False
    nodal: bool = False
    uses_patches: bool = False
    cuts_modes: bool = False
    clampable: bool = True
    # `flexmvm select` builds its candidates (a node selection and a mode count) of this kind
    selectable: bool = False
    body_builder: Callable[..., Any] | None = None

    def build_basis(self, request: BasisRequest) -> Basis:
        raise NotImplementedError(f"model kind {self.name!r} builds no basis")

    def n_static(self, basis: Basis) -> int:
        return 0

    def retained_columns(self, basis: Basis) -> np.ndarray:
        """Retained nodes' x, y, z columns first (nb, 3)."""
        nb = len(basis.retained_nodes)
        return np.arange(3 * nb).reshape(nb, 3)

    def modal_columns(self, basis: Basis) -> np.ndarray:
        """The modal coordinates are the last n_modes columns."""
        return np.arange(basis.nq - basis.n_modes, basis.nq)

    def cost_columns(self, n_retained: int, n_modes: int) -> int | None:
        return None

    def study_fields(self, args: tuple[str, ...]) -> Mapping[str, Any] | None:
        return None


@dataclass(frozen=True)
class NodesAndModes(KindSpec):
    """A kind that retains nodes beside a mode count >= 1 (the MVM kinds): costed by its
    3 nb + modes dense columns; a study's text 'kind:I-J:M' is selection I-J with M modes."""

    retains_nodes: bool = True
    uses_modes: bool = True
    reads_modes: bool = True
    selectable: bool = True

    def cost_columns(self, n_retained: int, n_modes: int) -> int | None:
        return 3 * n_retained + n_modes

    def study_fields(self, args: tuple[str, ...]) -> Mapping[str, Any] | None:
        if len(args) != 2 or not args[1].isdigit():
            return None
        return {"kind": self.name, "selection": args[0], "modes": int(args[1])}


@dataclass(frozen=True)
class ModesFirst(NodesAndModes):
    """Seed eq. (4)'s column order: the modes, then the retained nodes' x, y, z."""

    def retained_columns(self, basis: Basis) -> np.ndarray:
        nb = len(basis.retained_nodes)
        return basis.n_modes + np.arange(3 * nb).reshape(nb, 3)

    def modal_columns(self, basis: Basis) -> np.ndarray:
        return np.arange(basis.n_modes)
