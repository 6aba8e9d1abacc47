"""The cantilever of tests/test_supports.py and tests/test_damping.py: an aluminium rod
(L = 0.6 m, r = 0.01 m, hex27 O-grid with 0.05 m axial elements) clamped at end B."""

from __future__ import annotations

from flexmvm.scenarios.load import scenario_from_dict

L, R = 0.6, 0.01
ROD = {
    "length_m": L,
    "radius_m": R,
    "core_elements": 1,
    "core_half_width_m": 0.003,
    "n_rings": 1,
    "first_element_m": 0.05,
    "growth": 1.0,
    "max_element_m": 0.05,
}
CLAMP = {"type": "clamp", "body": "beam", "node_set": "end_b"}


def scenario(model, supports=(CLAMP,), joints=(), damping=None):
    """A rod along +x clamped at end B (x = L) by default: a cantilever, its free end A."""
    body = {"name": "beam", "material": "aluminium", "rod": ROD, "model": model}
    if damping is not None:
        body["damping"] = damping
    data = {
        "name": "cantilever",
        "time": {"t_end_s": 1e-3, "dt_s": 1e-4, "output_dt_s": 1e-4, "theta": 0.5},
        "bodies": [body],
        "supports": list(supports),
        "joints": list(joints),
    }
    return scenario_from_dict(data)
