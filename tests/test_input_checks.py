"""Input checks of issue 48: mesh errors number elements as the file does, an empty contact
surface is blamed on the contact that names it, a nearly incompressible material is refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from flexmvm.assembly.build import build_scenario
from flexmvm.assembly.build_cache import SetupCache
from flexmvm.errors import InputError, MeshError
from flexmvm.materials import MAX_NU, Material
from flexmvm.mesh.io import read_mesh
from flexmvm.scenarios.load import scenario_from_dict
from flexmvm.scenarios.problems import ScenarioError

gmsh = pytest.importorskip("gmsh")

ROOT = Path(__file__).resolve().parents[1]
BALL = ROOT / "scenarios" / "meshes" / "sphere_r10_cap.msh"


def _box(path: Path, size: float = 0.01) -> tuple[Path, list[int]]:
    """A 40 x 40 x 20 mm tet4 box (top face at z = 0), MSH 4.1 ASCII; groups ``top``,
    ``solid`` and ``pad``, an empty surface group. Returns the path and the tets' gmsh tags."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.model.add("box")
        v = gmsh.model.occ.addBox(-0.02, -0.02, -0.02, 0.04, 0.04, 0.02)
        gmsh.model.occ.synchronize()
        top = [
            t
            for _, t in gmsh.model.getEntities(2)
            if abs(gmsh.model.occ.getCenterOfMass(2, t)[2]) < 1e-12
        ]
        gmsh.model.addPhysicalGroup(3, [v], name="solid")
        gmsh.model.addPhysicalGroup(2, top, name="top")
        gmsh.model.addPhysicalGroup(2, [], name="pad")
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.mesh.generate(3)
        tags = [int(t) for t in gmsh.model.mesh.getElementsByType(4)[0]]
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path, tags


def _invert(path: Path, tag: int) -> None:
    """Swap the first two nodes of element ``tag`` in an MSH 4.1 ASCII file (inverts a tet)."""
    lines = path.read_text().splitlines()
    start = lines.index("$Elements")
    for k in range(start + 2, lines.index("$EndElements")):
        f = lines[k].split()
        if len(f) == 5 and int(f[0]) == tag:
            lines[k] = " ".join([f[0], f[2], f[1], f[3], f[4]])
            break
    else:
        raise AssertionError(f"no tet {tag}")
    path.write_text("\n".join(lines) + "\n")


def test_inverted_element_named_by_its_file_number(tmp_path):
    """An inverted tet is named by gmsh's element tag (the file's number, which counts the
    surface and line elements before the tets), not its index among the tets."""
    path, tets = _box(tmp_path / "box.msh")
    tag = tets[len(tets) // 2]
    index = len(tets) // 2
    assert tag != index and tag != index + 1  # the old numbering would differ
    _invert(path, tag)
    with pytest.raises(MeshError, match=rf"tetra element {tag} \(numbered as in the file") as err:
        read_mesh(path)
    assert "\n" not in str(err.value)


def _scenario(block: Path, slave: str, material="aluminium") -> dict:
    return {
        "name": "ball_on_box",
        "time": {"t_end_s": 1e-5, "dt_s": 1e-6, "output_dt_s": 1e-6},
        "bodies": [
            {
                "name": "ball",
                "material": "aluminium",
                "mesh_file": str(BALL),
                "model": {"kind": "rigid"},
                "placement": {"position_m": [0.0, 0.0, 0.010], "velocity_mps": [0, 0, -0.1]},
            },
            {"name": "block", "material": material, "mesh_file": str(block)},
        ],
        "contacts": [{"slave": f"block.{slave}", "master": "ball.front"}],
    }


def test_empty_contact_surface_blamed_on_the_contact(tmp_path):
    """A contact whose slave surface is an empty physical group: the one-line error names the
    contact key and the group, not the body's automatic reference (which met it first)."""
    path, _ = _box(tmp_path / "box.msh", size=0.02)
    sc = scenario_from_dict(_scenario(path, "pad"))
    with pytest.raises(InputError) as err:
        build_scenario(sc, SetupCache())
    msg = str(err.value)
    assert msg.startswith("contacts[0].slave = 'block.pad': ")
    assert "surface 'pad' is empty" in msg
    assert "reference" not in msg and "\n" not in msg


@pytest.mark.parametrize("nu", [0.4999, 0.495, 0.4901])
def test_nearly_incompressible_material_refused(nu):
    """nu in (0.49, 0.5): refused with the reason (locking, the bulk/shear ratio), by the
    Material and by a scenario's inline material; 0.49 and a negative nu are accepted, 0.5
    is refused as before, a boolean is no number."""
    with pytest.raises(InputError, match=r"nearly incompressible .*expected nu <= 0.49"):
        Material(E=1e9, nu=nu, rho=1000.0)
    with pytest.raises(ScenarioError, match=r"nu.*nearly incompressible"):
        scenario_from_dict(
            _scenario(
                ROOT / "scenarios" / "meshes" / "block_60x60x30.msh",
                "top",
                material={"E_pa": 1e9, "nu": nu, "rho_kg_m3": 1000.0},
            )
        )
    assert Material(E=1e9, nu=MAX_NU, rho=1000.0).nu == 0.49
    assert Material(E=1e9, nu=-0.5, rho=1000.0).nu == -0.5
    for bad in (0.5, True):
        with pytest.raises(InputError):
            Material(E=1e9, nu=bad, rho=1000.0)
