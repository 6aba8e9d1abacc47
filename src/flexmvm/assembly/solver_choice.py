"""Solver choices made at setup: a large full-FE body gets the elimination order of its
iteration matrices (fe.ordering), looked for once and kept in the setup cache."""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from flexmvm.assembly.build_cache import SetupCache
from flexmvm.bodies.body import FlexibleBody
from flexmvm.fe.solvers import ldl
from flexmvm.fe.solvers.ordering import elimination_order, iteration_pattern


def with_elimination_order(body: FlexibleBody, setup: SetupCache) -> FlexibleBody:
    """A full-FE body with the elimination order of its iteration matrices (fe.ordering,
    ~1.7 s for a 25,000-DOF rod), kept in the setup cache under their sparsity pattern; any
    other body unchanged."""
    if not (body.nq >= ldl.SPLIT_MIN_N and body.is_sparse and sp.issparse(body.k_hat)):
        return body
    pattern = iteration_pattern(
        body.inv.M_qq, body.k_hat, body.c_hat if sp.issparse(body.c_hat) else None
    )
    order = setup.elimination_order(pattern, elimination_order)
    # an empty order: made, none found (the solver then takes SuperLU's minimum degree
    # without looking again)
    return dataclasses.replace(
        body, elimination_order=(order if order is not None else np.zeros(0, np.int64))
    )
