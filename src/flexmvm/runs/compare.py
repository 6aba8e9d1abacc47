"""Comparisons of runs: NCC of the contact force and of every probe, with peak, impulse and
contact-duration errors (seed section 3.1; NCC alone is blind to scale and offset)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from flexmvm.errors import InputError
from flexmvm.metrics.ncc import compare_force, ncc


def compare_runs(t_ref, f_ref, probes_ref: dict, t, f, probes: dict) -> dict:
    """Candidate (t, f, probes) against a reference: ncc_force (over the contact window:
    metrics.ncc.compare_force), ncc_force_whole (over the whole window), peak_err,
    impulse_err, duration_err and ncc_<probe> (whole window) for every probe both have."""
    out: dict = {}
    try:
        c = compare_force(t_ref, f_ref, t, f)
        out.update(
            ncc_force=c.ncc,
            ncc_force_whole=c.ncc_whole,
            peak_err=c.peak_err,
            impulse_err=c.impulse_err,
            duration_err=c.duration_err,
        )
    except InputError as exc:
        out["force_comparison_error"] = str(exc)
    for name, y_ref in probes_ref.items():
        if name in probes:
            try:
                out[f"ncc_{name}"] = ncc(t_ref, y_ref, t, probes[name])
            except InputError as exc:
                out[f"ncc_{name}_error"] = str(exc)
    return {k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in out.items()}


@dataclass(frozen=True)
class RunComparison:
    """A run against a reference: force NCC over the contact window (ncc_force; over the whole
    window: ncc_force_whole) and relative errors of peak, impulse and contact duration
    (candidate - reference) / reference, NCC of every probe both runs have, and the
    comparisons that could not be made (name -> reason)."""

    ncc_force: float | None
    peak_err: float | None
    impulse_err: float | None
    duration_err: float | None
    ncc_probes: dict[str, float] = field(default_factory=dict)
    not_compared: dict[str, str] = field(default_factory=dict)
    ncc_force_whole: float | None = None

    def as_dict(self) -> dict:
        """The flat form summary.json uses (ncc_force, ..., ncc_<probe>, <item>_error)."""
        out = {
            k: getattr(self, k)
            for k in ("ncc_force", "ncc_force_whole", "peak_err", "impulse_err", "duration_err")
            if getattr(self, k) is not None
        }
        out.update({f"ncc_{k}": v for k, v in self.ncc_probes.items()})
        out.update({f"{k}_error": v for k, v in self.not_compared.items()})
        return out


@runtime_checkable
class CurveSource(Protocol):
    """What compare reads of a run (flexmvm.run's Run, a RunResult, a stored result): its
    (t, contact force, {probe: velocity}) curves along an axis."""

    def curves(self, axis=0) -> tuple: ...


def _curves(run, axis: int | str | None = None) -> tuple:
    if isinstance(run, tuple) and len(run) == 3:
        if axis not in (None, 0, "x"):
            raise InputError(
                f"compare: a (t, force, {{probe: v}}) tuple holds one velocity component; "
                f"expected axis 0 with it, got {axis!r}"
            )
        return run
    if isinstance(run, CurveSource):
        return run.curves(axis)
    raise InputError(
        f"compare: received {type(run).__name__}, expected a run (flexmvm.run), "
        "a RunResult or a (t, force, {probe: v}) tuple"
    )


def compare(candidate, reference, axis: int | str | None = None) -> RunComparison:
    """``candidate`` against ``reference``: each a run (flexmvm.run, flexmvm.read_run), a
    RunResult or a (t [s], force [N], {probe: axial velocity [m/s]}) tuple such as
    theory_histories gives. The probes' NCCs compare their global velocity component ``axis``:
    0, 1, 2 or "x", "y", "z", or "norm" (the speed); None (default) each probe's own, the
    scenario's probe ``axis`` (x when not given); a tuple holds x only."""
    flat = compare_runs(*_curves(reference, axis), *_curves(candidate, axis))
    probes = {
        k[4:]: v
        for k, v in flat.items()
        if k.startswith("ncc_")
        and k not in ("ncc_force", "ncc_force_whole")
        and not k.endswith("_error")
    }
    errors = {k[: -len("_error")]: v for k, v in flat.items() if k.endswith("_error")}
    return RunComparison(
        flat.get("ncc_force"),
        flat.get("peak_err"),
        flat.get("impulse_err"),
        flat.get("duration_err"),
        probes,
        errors,
        flat.get("ncc_force_whole"),
    )
