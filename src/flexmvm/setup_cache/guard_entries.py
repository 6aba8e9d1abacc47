"""The guards' entries of the setup cache: what a warm run would otherwise load M and K for.

- ``truncation-``: reduction.truncation.modal_residual of a Craig-Bampton basis (it factors
  K_ii), keyed by the basis's inputs (entries.basis_inputs) and what else the guard depends
  on (its FE model, a mode floor);
- ``factorcounts-``: the nonzeros of a full-FE body's K and M and the stored entries of its
  iteration matrix's factor (the cost guard's, assembly.cost.full_factor: a symbolic
  analysis), keyed by the FE model's inputs.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from flexmvm.materials import Material
from flexmvm.reduction.kinds import ModelKind
from flexmvm.reduction.reference_condition import ReferenceCondition
from flexmvm.setup_cache.entries import basis_inputs
from flexmvm.setup_cache.store import decoded, make_key, save

#: The fields of a truncation guard (reduction.truncation.modal_residual) as stored.
_TRUNCATION_FIELDS = ("residual_time_s", "modal_residual")


def cached_truncation(
    source: Mapping | None,
    material: Material,
    kind: ModelKind,
    reference_set: str,
    reference: ReferenceCondition,
    retained: np.ndarray,
    n_modes: int,
    build: Callable[[], dict],
    extra: Mapping | None = None,
) -> dict:
    """The truncation guard of a basis (modal_residual's dict) from the cache, else
    ``build()`` stored: it factors K_ii of the body's interior (0.46 s on sphere_block's
    11,748 DOF), so a warm run reads it beside its basis. Its key is the basis's inputs
    (basis_key; ``extra`` there holds what else the guard depends on) under the entry kind
    ``truncation``; source None: build, no caching."""
    if source is None:
        return build()
    inputs = basis_inputs(
        source, material, kind, reference_set, reference, retained, n_modes, extra
    )
    key = make_key("truncation", inputs)

    def decode(arrays) -> dict:
        freqs = np.asarray(arrays["highest_mode_hz"], float)
        if freqs.shape not in ((0,), (1,)) or (freqs.size == 0) != (n_modes == 0):
            raise ValueError("stored highest mode is malformed")
        out: dict[str, float | int | None] = {n: float(arrays[n]) for n in _TRUNCATION_FIELDS}
        out["n_modes"] = int(n_modes)
        out["highest_mode_hz"] = float(freqs[0]) if freqs.size else None
        return out

    hit = decoded(key, decode)
    if hit is not None:
        return hit
    guard = build()
    top = guard.get("highest_mode_hz")
    arrays = {name: np.array(float(guard[name])) for name in _TRUNCATION_FIELDS}
    save(key, arrays | {"highest_mode_hz": np.array([] if top is None else [top], float)})
    return guard


#: The counts of a factorcounts- entry.
_FACTOR_COUNTS = ("k_nnz", "m_nnz", "l_nnz", "factor_entries", "front_entries")


def cached_factor_counts(source: Mapping | None, build: Callable[[], dict]) -> dict:
    """{k_nnz, m_nnz, l_nnz, factor_entries, front_entries} (assembly.cost.FullFactor) of the
    FE model of key inputs ``source`` (assembly.cache_keys mesh_source) from the cache, else
    ``build()`` stored; source None: build, no caching."""
    if source is None:
        return build()
    key = make_key("factorcounts", {"fe_model": dict(source)})

    def decode(arrays) -> dict:
        counts = np.asarray(arrays["counts"], np.int64)
        if counts.shape != (len(_FACTOR_COUNTS),) or counts.min() < 0:
            raise ValueError("stored counts are malformed")
        return {name: int(c) for name, c in zip(_FACTOR_COUNTS, counts, strict=True)}

    hit = decoded(key, decode)
    if hit is not None:
        return hit
    counts = build()
    save(key, {"counts": np.array([counts[name] for name in _FACTOR_COUNTS], np.int64)})
    return counts
