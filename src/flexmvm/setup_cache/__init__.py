"""Disk cache of what setup builds (the store: store.py; its entries: entries.py): FE models (M, K, M_scalar), reduction bases (psi), the
parts of bodies with dense bases (inertia invariants and k_hat, flexmvm.bodies.build.BodyParts)
and the two expensive parts of an interface basis that do not depend on its mode count: the
free-free mode pool (``freemodes-``: frequencies and M-normalised modes of the lowest k free-free
modes, keyed by mesh, material and k; 36 MB for the seed rod's 178) and the patch vectors'
static responses (``patchstatic-``: keyed by mesh, material, reference, surface, patch node and
radii), so bases that differ only in ``modes`` (and share a ``mode_pool``) share them; and the
elimination orders of large iteration matrices (``order-``: keyed by their sparsity pattern);
and a Craig-Bampton basis's truncation guard (``truncation-``: keyed by its basis's inputs and
its FE model's; it factors K_ii, which a warm run then does not) and the cost guard's counts of
a full-FE body's factor (``factorcounts-``: keyed by its FE model's inputs; a symbolic
analysis, setup_cache/guard_entries.py); and a moving region's global modes, static columns and
windows' parts (``moving-``: setup_cache/moving_entries.py).

An entry is one ``.npz`` file (``np.savez``, no pickles; sparse matrices as their CSR
arrays) named ``<kind>-<key>.npz``. The key is a SHA-256 of the canonical JSON of every input
the entry depends on (mesh: rod spec or mesh-file content hash; material E, nu, rho; basis
kind, retained nodes, modes, reference set and DOFs) and of the code version, a hash of the
source files that produce it (CODE_SOURCES; body parts: BODY_SOURCES, which adds the body
modules, so editing them rebuilds only body entries). Entries are written atomically, with the
SHA-256 of their arrays (names, dtypes, shapes, bytes) as one more array (CHECKSUM). An entry
is used only if it passes its check: readable, that checksum matches, every float array finite
(nothing setup stores holds NaN or inf) and its decoder accepts its shapes. One that fails is
evicted (deleted), announced in one line (``setup cache basis-....npz: holds NaN or inf in
psi: evicted and rebuilt``) and rebuilt; an unwritable cache directory is ignored.

Location: ``$FLEXMVM_CACHE_DIR`` if set, else the platform user cache directory
(``~/.cache/flexmvm`` on Linux). ``FLEXMVM_NO_CACHE=1`` bypasses the cache (no read, no
write). Rod meshes are not stored: generating one takes ~10 ms, no more than reading it back.
"""

from flexmvm.setup_cache.entries import (
    basis_key,
    body_key,
    cached_basis,
    cached_body,
    cached_elimination_order,
    cached_fe,
    cached_free_modes,
    cached_patch_statics,
    fe_key,
    free_modes_key,
    patch_statics_key,
)
from flexmvm.setup_cache.guard_entries import cached_factor_counts, cached_truncation
from flexmvm.setup_cache.store import (
    BODY_SOURCES,
    CHECKSUM,
    CODE_SOURCES,
    ENV_DIR,
    ENV_OFF,
    CacheInfo,
    cache_dir,
    checksum,
    clear,
    code_version,
    enabled,
    entry_problem,
    file_source,
    info,
    load,
    make_key,
    material_inputs,
    rod_source,
    save,
)

__all__ = [
    "BODY_SOURCES",
    "CHECKSUM",
    "CODE_SOURCES",
    "ENV_DIR",
    "ENV_OFF",
    "CacheInfo",
    "basis_key",
    "body_key",
    "cache_dir",
    "cached_basis",
    "cached_body",
    "cached_elimination_order",
    "cached_factor_counts",
    "cached_fe",
    "cached_free_modes",
    "cached_patch_statics",
    "cached_truncation",
    "checksum",
    "clear",
    "code_version",
    "enabled",
    "entry_problem",
    "fe_key",
    "file_source",
    "free_modes_key",
    "info",
    "load",
    "make_key",
    "material_inputs",
    "patch_statics_key",
    "rod_source",
    "save",
]
