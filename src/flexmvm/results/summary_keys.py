"""summary.json's renamed keys, and the one mapping that reads a summary written before a
rename under the current names (results.read.read_run, runs.stored_run).

A key says what it means: ``energy_conserving_scheme`` was true when every contact used the
position law (constraints/contact_laws: ``conserves_energy``), not that the scheme kept the
energy (at theta > 1/2 it damps: a plate impact lost 10 % with it true, issue 51); it is
``contact_laws_add_no_energy`` now, beside ``numerical_dissipation_J`` and
``numerical_dissipation_share`` (the energy the scheme's theta > 1/2 took, runs.run).
The same round renamed four more:

- ``energy_rel_error`` -> ``energy_rel_change`` (and its ``_max``): (E(t_end) - E(0)) / E(0),
  a change, not an error, when loads, drives or plasticity act (their terms are in
  ``energy_balance_*``);
- ``steps_not_converged`` -> ``steps_on_roundoff_floor``: the steps accepted on the Newton
  iteration's round-off floor above its rtol (integrate.driver), not steps that failed;
- ``max_contact_force_N`` / ``min_contact_force_N`` -> ``max_contact_force_interval_mean_N`` /
  ``min_contact_force_interval_mean_N``: the total normal contact impulse of an output interval
  over its length (``output_contact_dt_s`` while in contact), the largest / smallest such mean,
  not the largest force of a step;
- ``smallest_step_s`` was ``dt_min_taken_s`` written twice: only ``dt_min_taken_s`` is left.
"""

from __future__ import annotations

#: old key -> current key, for summaries written before the rename
RENAMED_KEYS = {
    "energy_conserving_scheme": "contact_laws_add_no_energy",
    "energy_rel_error": "energy_rel_change",
    "energy_rel_error_max": "energy_rel_change_max",
    "steps_not_converged": "steps_on_roundoff_floor",
    "max_contact_force_N": "max_contact_force_interval_mean_N",
    "min_contact_force_N": "min_contact_force_interval_mean_N",
    "smallest_step_s": "dt_min_taken_s",
}


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
