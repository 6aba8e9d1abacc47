"""Comparisons of runs: NCC of the contact force and of every probe, with peak, impulse and
contact-duration errors (seed section 3.1; NCC alone is blind to scale and offset)."""

from __future__ import annotations

import numpy as np

from flexmvm.errors import InputError
from flexmvm.metrics.ncc import compare, compare_force


def compare_runs(t_ref, f_ref, probes_ref: dict, t, f, probes: dict) -> dict:
    """Candidate (t, f, probes) against a reference: ncc_force, peak_err, impulse_err,
    duration_err and ncc_<probe> for every probe both have."""
    out: dict = {}
    try:
        c = compare_force(t_ref, f_ref, t, f)
        out.update(ncc_force=c.ncc, peak_err=c.peak_err, impulse_err=c.impulse_err,
                   duration_err=c.duration_err)
    except InputError as exc:
        out["force_comparison_error"] = str(exc)
    for name, y_ref in probes_ref.items():
        if name in probes:
            try:
                out[f"ncc_{name}"] = compare(t_ref, y_ref, t, probes[name])
            except InputError as exc:
                out[f"ncc_{name}_error"] = str(exc)
    return {k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in out.items()}


def run_curves(res) -> tuple[np.ndarray, np.ndarray, dict]:
    """(t, contact force, {probe: axial velocity}) of a RunResult."""
    return res.t, res.contact_force, {n: res.probe_v[:, i, 0] for i, n in enumerate(res.probe_names)}
