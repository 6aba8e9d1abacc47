"""Volume cell types, one module each holding its CellSpec (cells/spec.py); registered here,
one line each. A new cell type: a CellType member (spec.py), its module, its line here and
its scikit-fem entry (fe/assembly.py ``_SKFEM``)."""

from flexmvm.mesh.cells import hex8, hex27, tet4, tet10, wedge6
from flexmvm.mesh.cells.spec import CELLS, CellSpec, CellType, register_cell, spec_named

register_cell(hex8.SPEC)
register_cell(wedge6.SPEC)
register_cell(tet4.SPEC)
register_cell(tet10.SPEC)
register_cell(hex27.SPEC)

__all__ = ["CELLS", "CellSpec", "CellType", "register_cell", "spec_named"]
