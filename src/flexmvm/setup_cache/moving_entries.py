"""The moving region's entry of the setup cache (``moving-``, issue 53): what a moving
region's setup makes (reduction/kinds/mvm_moving.py, integrate/moving_region.py), kept so that
a second run of the same scenario skips it.

Stored: the global modes Phi (n_dof, m) and their frequencies [Hz], every path node's three
static columns K_ff^-1 e_d (n_dof, 3 per node: the windows' attachment modes, the costly part
of a window's basis) and every window's body parts (inertia invariants and k_hat: the other
costly part) with the signature of the basis they came from. A warm run then makes a window's
basis again from the stored columns when the contact reaches it (the nodal form: small dense
products under one BLAS thread, the same bits) and neither factors K_ff nor computes the
invariants (unless the basis made again differs from the signature: its parts made again). Not stored: the bases themselves (n_dof x nq each, 79 of them on the coarse
moving-load beam: 100 MB, more than the columns they are made from).

Keyed by the FE model's inputs, material, reference condition (set and held DOFs), path nodes,
mode count, spacing, half width and span, under the body modules' code version (BODY_SOURCES).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from flexmvm.bodies.build import BodyParts
from flexmvm.materials import Material
from flexmvm.setup_cache.entries import parts_arrays, parts_from
from flexmvm.setup_cache.store import (
    BODY_SOURCES,
    code_version,
    decoded,
    make_key,
    material_inputs,
    save,
)

__all__ = ["StoredWindows", "load_moving", "moving_key", "save_moving"]


@dataclass(frozen=True)
class StoredWindows:
    """A ``moving-`` entry: Phi (n_dof, m), its frequencies [Hz] (m,), the static columns by
    node ({node: (n_dof, 3)}), the windows' parts ({window: BodyParts}) and the signatures of
    the bases they came from."""

    phi: np.ndarray
    freqs_hz: np.ndarray
    columns: dict[int, np.ndarray]
    parts: dict[int, BodyParts]
    signatures: dict[int, np.ndarray]  # {window: basis_signature of its basis}


def moving_key(
    source: Mapping,
    material: Material,
    reference_set: str,
    fixed_dofs: np.ndarray,
    path_nodes: np.ndarray,
    n_modes: int,
    windows: Mapping,
) -> str:
    """Entry name of a moving region's setup (module doc); ``windows``: spacing_m,
    half_width_m and s_range_m as given."""
    inputs = {
        "mesh": dict(source),
        "material": material_inputs(material),
        "reference": {"set": reference_set, "fixed_dofs": [int(d) for d in fixed_dofs]},
        "path": [int(k) for k in path_nodes],
        "n_modes": int(n_modes),
        "windows": dict(windows),
    }
    return make_key("moving", inputs, code_version(BODY_SOURCES))


def save_moving(
    key: str, phi, freqs_hz, columns: Mapping[int, np.ndarray], parts, signatures
) -> None:
    """Store entry ``key`` (module doc): parts ``{window: BodyParts}``, signatures ``{window:
    basis_signature}``."""
    nodes = np.array(sorted(columns), dtype=np.int64)
    arrays = {
        "phi": np.ascontiguousarray(phi),
        "freqs_hz": np.asarray(freqs_hz, float),
        "column_nodes": nodes,
        # transposed: read back as a Fortran-order (n_dof, 3 P) view, each node's columns
        # contiguous as the solve made them
        "columns_t": np.vstack([columns[int(k)].T for k in nodes]),
        "windows": np.array(sorted(parts), dtype=np.int64),
        "nq": np.array([parts[k].k_hat.shape[0] for k in sorted(parts)], dtype=np.int64),
    }
    for k in sorted(parts):
        arrays |= {f"w{k}_{name}": a for name, a in parts_arrays(parts[k]).items()}
        arrays[f"w{k}_signature"] = np.asarray(signatures[k], float)
    save(key, arrays)


def load_moving(key: str, n_dof: int, n_modes: int) -> StoredWindows | None:
    """Entry ``key`` decoded, or None (absent, or malformed: evicted)."""

    def decode(a) -> StoredWindows:
        phi, nodes, cols = a["phi"], a["column_nodes"], a["columns_t"].T
        if phi.shape != (n_dof, n_modes) or cols.shape != (n_dof, 3 * nodes.size):
            raise ValueError("stored moving windows are malformed")
        columns = {int(k): cols[:, 3 * j : 3 * j + 3] for j, k in enumerate(nodes)}
        parts = {
            int(k): parts_from({n: a[f"w{k}_{n}"] for n in _PARTS}, int(nq))
            for k, nq in zip(a["windows"], a["nq"], strict=True)
        }
        signatures = {int(k): a[f"w{k}_signature"] for k in a["windows"]}
        return StoredWindows(phi, a["freqs_hz"], columns, parts, signatures)

    return decoded(key, decode)


#: The arrays of a window's parts (entries.parts_arrays)
_PARTS = ("mass", "S0", "S1", "G0", "G1", "G2", "M_qq", "k_hat")
