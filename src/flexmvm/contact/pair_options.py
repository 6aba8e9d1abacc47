"""The options of a contact pair set (contact.pairs.PointToSurfaceContact), checked: the
friction coefficient, the penetration recovery beta and the contact law with its theta."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from flexmvm.constraints.contact import ContactKind, ContactLaw
from flexmvm.errors import InputError


def pair_options(
    name: str,
    kind: ContactKind,
    friction_coefficient: float,
    beta: float,
    law: ContactLaw | str,
    theta: float | Callable[[float], float] | None,
) -> tuple[float, float, ContactLaw, float | Callable[[float], float] | None]:
    """(mu, beta, law, theta) of the contact ``name`` of kind ``kind``, checked: mu finite and
    >= 0 (none for bonded contact), beta in [0, 1] (the fraction of a penetration pushed back
    per step), and the law's own checks (ContactLawSpec.options_problem: the position law
    takes the scheme's theta in [0.5, 1], a number or a rule of the step size, and no bonded
    contact). Raises InputError naming the contact."""
    mu = float(friction_coefficient)
    if not (np.isfinite(mu) and mu >= 0.0):
        raise InputError(
            f"{name}: friction coefficient must be a finite number >= 0, "
            f"got {friction_coefficient!r}"
        )
    if mu > 0.0 and kind is ContactKind.BONDED:
        raise InputError(
            f"{name}: bonded contact locks all three components and takes "
            f"no friction coefficient, got {mu!r}"
        )
    if not 0.0 <= beta <= 1.0:
        raise InputError(f"{name}: penetration recovery beta must be in [0, 1], got {beta!r}")
    # the law's own checks (constraints/contact_laws: e.g. the position law's theta, a number
    # or the integrator's theta of the step size h, integrate.theta.ThetaRule; not bonded)
    law = ContactLaw(law)
    problem = law.spec.options_problem(kind is ContactKind.BONDED, theta)
    if problem is not None:
        raise InputError(f"{name}: {problem}")
    theta = None if theta is None else (theta if callable(theta) else float(theta))
    return mu, float(beta), law, theta
