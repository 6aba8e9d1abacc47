"""The sum of a system's applied loads (point forces, body torques, spring-dampers, revolute
torques: every object with ``forces(bodies, states, t)``) at the step's midpoint.

The Moreau-Jean step (integrate.moreau_jean) evaluates them at x_m = x(t) (+) theta h v_m
with velocity v_m = theta v+ + (1 - theta) v- and time t + theta h; they enter the residual
only (its iteration matrix is the bodies' own: loads.spring says for which stiffness that
converges).
"""

from __future__ import annotations

import numpy as np


def applied_forces(loads, bodies, states, t: float) -> dict[int, np.ndarray]:
    """{body: sum of the loads' generalized forces (6 + nq,)} at states (with velocities) and
    time t [s]; bodies without a load are absent."""
    out: dict[int, np.ndarray] = {}
    for load in loads:
        for b, f in load.forces(bodies, states, t).items():
            out[b] = out[b] + f if b in out else f.copy()
    return out


def start_run(loads) -> None:
    """Reset what a load keeps between its evaluations (the unwrapped angle of a revolute
    torque, loads.revolute) at the start of a run."""
    for load in loads:
        load.reset()


def midpoint_states(states, v_plus, h: float, theta: float) -> list:
    """The step's midpoint states x(t) (+) theta h v_m with velocity v_m (module doc)."""
    return [
        st.advanced(theta * vp + (1.0 - theta) * st.v, theta * h) for st, vp in zip(states, v_plus)
    ]


def midpoint_forces(loads, bodies, states, v_plus, h: float, theta: float, t: float) -> dict:
    """applied_forces at the step's midpoint states and time t + theta h ({} without loads)."""
    if not loads:
        return {}
    return applied_forces(loads, bodies, midpoint_states(states, v_plus, h, theta), t + theta * h)
