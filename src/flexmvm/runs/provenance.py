"""What a stored run was made from: the one key of every stored result that is reused instead
of recomputed (validation cases, study cases and references, benchmark rows).

A run's numbers depend on the package source, the numerical libraries, the resolved scenario
(every body, mesh parameter, model, contact, joint, probe and time setting) and the content of
its mesh files. :func:`run_inputs` collects them, :func:`run_key` hashes them (SHA-256 of the
canonical JSON, 32 hex digits) and :func:`stamp` is the compact record a stored result keeps
beside its key, so that :func:`stamp_mismatch` can say *which* of them changed. A record made by
a script that builds its own scenarios (a benchmark study) keeps :func:`script_stamp` instead:
the same code and libraries, the script's SHA-256 and its settings in place of the scenario;
:func:`script_stamp_mismatch` checks it.

The package source is :func:`run_code_version`: a hash of every source file of flexmvm (the
validation, which runs cases but changes none, is a repository tool: tools/validation/). The
libraries are
numpy, scipy and numba (LIBRARIES: a new BLAS kernel or a new compiled kernel can change the
last bits of a history), scikit-fem (it assembles the mass and stiffness matrices) and gmsh
(it writes the meshes of the parts made at run time: flexmvm.mesh.parts).
"""

from __future__ import annotations

import hashlib
import importlib.metadata
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import flexmvm
from flexmvm.results.atomic import canonical_json
from flexmvm.scenarios.schema import Scenario
from flexmvm.setup_cache import code_version

__all__ = [
    "FORMAT",
    "LIBRARIES",
    "library_versions",
    "run_code_version",
    "run_inputs",
    "run_key",
    "script_stamp",
    "script_stamp_mismatch",
    "stamp",
    "stamp_mismatch",
]

#: Format of a key; bump when what goes into it changes (every stored result goes stale).
#: 3: a mesh file enters by its name and content, not its absolute path (a fresh clone or
#: another checkout reuses what this one stored).
#: 4: scikit-fem and gmsh among the libraries.
FORMAT = 4

#: The libraries (distribution names) whose versions are part of the key: the linear algebra,
#: the compiled kernels, the matrices' assembly (scikit-fem) and the meshes made at run time
#: (gmsh).
LIBRARIES = ("numpy", "scipy", "numba", "scikit-fem", "gmsh")

#: Package entries that are not source
_NOT_RUN_CODE = ("__pycache__",)


def run_code_version() -> str:
    """Hash (16 hex) of every package source file: what a run's numbers depend on."""
    root = Path(flexmvm.__file__).parent
    names = tuple(
        sorted(
            p.name
            for p in root.iterdir()
            if p.name not in _NOT_RUN_CODE and (p.is_dir() or p.suffix == ".py")
        )
    )
    return code_version(names)


def library_versions() -> dict[str, str]:
    """{name: installed version} of LIBRARIES ("absent" for one not installed)."""
    out = {}
    for name in LIBRARIES:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = "absent"
    return out


def _mesh_files(sc: Scenario) -> dict[str, str]:
    """{body: SHA-256 of its mesh file} of the bodies read from a file."""
    return {
        b.name: hashlib.sha256(Path(b.mesh_file).read_bytes()).hexdigest()
        for b in sc.bodies
        if b.mesh_file is not None
    }


def _scenario_form(sc: Scenario) -> dict[str, Any]:
    """The resolved scenario's JSON form with each mesh_file reduced to its file name: where
    the checkout lies changes no run, the file's content (mesh_files) does."""
    form = sc.model_dump(mode="json")
    for body in form["bodies"]:
        if body.get("mesh_file") is not None:
            body["mesh_file"] = Path(body["mesh_file"]).name
    return form


def run_inputs(sc: Scenario) -> dict[str, Any]:
    """Everything a run of ``sc`` depends on: {format, code, libraries, scenario (the resolved
    scenario's JSON form, mesh files by name), mesh_files ({body: SHA-256})}."""
    return {
        "format": FORMAT,
        "code": run_code_version(),
        "libraries": library_versions(),
        "scenario": _scenario_form(sc),
        "mesh_files": _mesh_files(sc),
    }


def _hash(obj: Any, n: int = 32) -> str:
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:n]


def run_key(sc: Scenario) -> str:
    """The key (32 hex) of a run of ``sc``: a hash of :func:`run_inputs`."""
    return _hash(run_inputs(sc))


def stamp(sc: Scenario) -> dict[str, Any]:
    """The record a stored run keeps: {key, format, code, libraries, scenario_sha256 (16 hex
    of the resolved scenario), mesh_files}; equal stamps, equal keys."""
    inputs = run_inputs(sc)
    return {
        "key": _hash(inputs),
        "format": inputs["format"],
        "code": inputs["code"],
        "libraries": inputs["libraries"],
        "scenario_sha256": _hash(inputs["scenario"], 16),
        "mesh_files": inputs["mesh_files"],
    }


def stamp_mismatch(stored: Any, current: Mapping[str, Any]) -> str | None:
    """None if ``stored`` is the stamp ``current``; else what differs, in words (e.g. "run
    under code version 0123abcd.. (this code 4567ef01..)", "numpy 1.26.4 (now 2.0.1)")."""
    if not isinstance(stored, Mapping) or "key" not in stored:
        return "stored without a code version (made before results were keyed)"
    if stored.get("key") == current["key"]:
        return None
    what = []
    if stored.get("format") != current["format"]:
        what.append(f"key format {stored.get('format')} (now {current['format']})")
    if stored.get("code") != current["code"]:
        what.append(f"code version {stored.get('code')} (now {current['code']})")
    libs = stored.get("libraries")
    if not isinstance(libs, Mapping):
        libs = {}
    what += [
        f"{name} {libs.get(name)} (now {v})"
        for name, v in current["libraries"].items()
        if libs.get(name) != v
    ]
    if stored.get("scenario_sha256") != current["scenario_sha256"]:
        what.append("another resolved scenario")
    if stored.get("mesh_files") != current["mesh_files"]:
        what.append("other mesh files")
    return "run under " + ", ".join(what or ["another key"])


def script_stamp(scripts: Path | Sequence[Path], settings: Mapping[str, Any]) -> dict[str, Any]:
    """The stamp of a record made by a script (a benchmark that builds its scenarios from
    ``settings``, JSON-able; ``scripts``: it and the scripts it imports): :func:`stamp`'s
    fields, the scenario's hash taken over the scripts' names and SHA-256 and the settings
    (kept verbatim under "settings"); meshes the scripts make are covered by the scripts,
    gmsh's version and the settings."""
    paths = [Path(scripts)] if isinstance(scripts, (str, Path)) else [Path(p) for p in scripts]
    settings_kept = dict(settings)
    inputs: dict[str, Any] = {
        "format": FORMAT,
        "code": run_code_version(),
        "libraries": library_versions(),
        "scenario": {
            "scripts": {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in paths},
            "settings": settings_kept,
        },
        "mesh_files": {},
    }
    return {
        "key": _hash(inputs),
        "format": inputs["format"],
        "code": inputs["code"],
        "libraries": inputs["libraries"],
        "scenario_sha256": _hash(inputs["scenario"], 16),
        "mesh_files": {},
        "scripts": sorted(p.name for p in paths),
        "settings": settings_kept,
    }


def script_stamp_mismatch(stored: Any, scripts: Path | Sequence[Path]) -> str | None:
    """None if ``stored`` is the :func:`script_stamp` that ``scripts`` give its own stored
    settings now; else what differs, in words (:func:`stamp_mismatch`; "another resolved
    scenario" there means edited scripts)."""
    if not isinstance(stored, Mapping) or not isinstance(stored.get("settings"), Mapping):
        return stamp_mismatch(None, {})
    return stamp_mismatch(stored, script_stamp(scripts, stored["settings"]))
