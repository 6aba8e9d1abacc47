"""Mesh stage: plain mesh data, the O-grid rod generator, meshio I/O and quality checks."""

from flexmvm.mesh.io import MeshWarning, read_mesh, write_mesh
from flexmvm.mesh.mesh import CellBlock, CellType, FacetSet, Mesh
from flexmvm.mesh.quality import cell_volumes, check_quality, mesh_volume
from flexmvm.mesh.rod import EndShape, RodMesh, RodSpec, graded_lengths, rod_mesh

__all__ = [
    "CellBlock",
    "CellType",
    "EndShape",
    "FacetSet",
    "Mesh",
    "MeshWarning",
    "RodMesh",
    "RodSpec",
    "cell_volumes",
    "check_quality",
    "graded_lengths",
    "mesh_volume",
    "read_mesh",
    "rod_mesh",
    "write_mesh",
]
