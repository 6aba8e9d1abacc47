"""summary.json's renamed keys, and the one mapping that reads a summary written before a
rename under the current names (results.read.read_run, runs.stored_run).

A key says what it means: ``energy_conserving_scheme`` was true when every contact used the
position law (constraints/contact_laws: ``conserves_energy``), not that the scheme kept the
energy (at theta > 1/2 it damps: a plate impact lost 10 % with it true, issue 51); it is
``contact_laws_add_no_energy`` now, beside ``numerical_dissipation_J`` and
``numerical_dissipation_share`` (the energy the scheme's theta > 1/2 took, runs.run).
"""

from __future__ import annotations

#: old key -> current key, for summaries written before the rename
RENAMED_KEYS = {"energy_conserving_scheme": "contact_laws_add_no_energy"}


def with_current_keys(summary: dict) -> dict:
    """``summary`` with every old key of RENAMED_KEYS under its current name (a key already
    under its current name wins); the same dict when nothing is renamed."""
    if not any(old in summary for old in RENAMED_KEYS):
        return summary
    out = {}
    for key, value in summary.items():
        new = RENAMED_KEYS.get(key)
        if new is None:
            out[key] = value
        elif new not in summary:
            out[new] = value
    return out


__all__ = ["RENAMED_KEYS", "with_current_keys"]
