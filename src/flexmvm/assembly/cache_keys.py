"""Keys of what setup builds for a scenario's body: the mesh key of a body (a RodSpec or a mesh
file path, wrapped in a ContactMass when its contact nodes carry no mass) and the disk-cache
key inputs derived from it (flexmvm.setup_cache: rod spec fields or the mesh file's content
hash, with the massless nodes; an interface basis's further parameters)."""

from __future__ import annotations

from dataclasses import dataclass

from flexmvm import setup_cache
from flexmvm.mesh.rod import RodSpec
from flexmvm.reduction.interface import InterfaceSpec


@dataclass(frozen=True)
class MergedFile:
    """The mesh key of a mesh file read with its coincident nodes merged (a body's
    ``merge_nodes = true``; mesh/connectivity.py): another mesh than the file read as it is."""

    path: str


@dataclass(frozen=True)
class ContactMass:
    """The mesh key (a RodSpec or a mesh file path, either on spring beds) of a body whose
    contact nodes ``nodes`` carry no mass (fe/mass_redistribution.py): a key of its own for
    every cache."""

    key: RodSpec | str | MergedFile | SpringBeds
    nodes: tuple[int, ...]


@dataclass(frozen=True)
class SpringBeds:
    """The mesh key of a body on spring beds (fe/spring_bed.py; a ``[[supports]]`` spring_bed):
    its K has the beds' stiffness added, so every cache gets a key of its own. beds: (facet
    set, stiffness [N/m^3], direction: a body axis or "normal"), sorted."""

    key: RodSpec | str | MergedFile
    beds: tuple[tuple[str, float, str], ...]


#: What names a body's mesh in every cache: its rod spec, its mesh file path, either on spring
#: beds, or any of these with massless contact nodes.
MeshKey = RodSpec | str | MergedFile | SpringBeds | ContactMass


def mesh_key(cfg) -> RodSpec | str | MergedFile:
    """The mesh key of a scenario's body ``cfg``: its rod spec, else its mesh file path (a
    MergedFile when its nodes are merged)."""
    if cfg.rod is not None:
        return cfg.rod.spec()
    return MergedFile(str(cfg.mesh_file)) if cfg.merge_nodes else str(cfg.mesh_file)


def plain_key(key: MeshKey) -> RodSpec | str | MergedFile:
    """The mesh key without its massless contact nodes and spring beds (same mesh)."""
    while isinstance(key, (ContactMass, SpringBeds)):
        key = key.key
    return key


def mesh_source(key: MeshKey) -> dict | None:
    """Disk-cache key inputs of a rod spec or a mesh file (None: file unreadable, no caching),
    with the massless contact nodes of a ContactMass key."""
    if isinstance(key, ContactMass):
        inner = mesh_source(key.key)
        return None if inner is None else inner | {"massless_nodes": list(key.nodes)}
    if isinstance(key, SpringBeds):
        inner = mesh_source(key.key)
        return None if inner is None else inner | {"spring_beds": [list(b) for b in key.beds]}
    if isinstance(key, RodSpec):
        return setup_cache.rod_source(key)
    if isinstance(key, MergedFile):
        inner = setup_cache.file_source(key.path)
        return None if inner is None else inner | {"merge_nodes": True}
    return setup_cache.file_source(key)


def interface_inputs(interface: InterfaceSpec | None) -> dict | None:
    """Further key inputs of an interface basis (None for the other kinds, whose keys then
    stay those they had before the interface kind existed)."""
    return None if interface is None else interface.key()
