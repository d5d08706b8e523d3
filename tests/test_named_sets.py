# SPDX-License-Identifier: LGPL-2.1-or-later
"""Named sets per CAD face and per solid, in every format `fembsptet mesh` writes, read back by
readers that are not ours (meshio, the gmsh binary, FreeCAD's Fem.read) and by ours.

The part has two solids (a cube and a cylinder, named "red_cube" and "blue_cylinder" by the STEP
file) and nine CAD faces (unnamed: FreeCAD's Face1..Face9); the CLI's mesh is compared
with the FEM path's own groups (the meshing is deterministic: same nodes, same numbering)."""

import os
import shutil
import subprocess

import meshio
import numpy as np
import pytest

from FemBspTet.cli.main import main
from FemBspTet.fem.cad_mesh import mesh_cad_file
from FemBspTet.kernel.freecad_env import freecad_available
from FemBspTet.io.volume_io import read_tet_mesh

PART = os.path.join(os.path.dirname(__file__), "data", "cad", "red_cube_blue_cylinder.step")
SOLIDS = ["blue_cylinder", "red_cube"]  # Solid1, Solid2 in FreeCAD's order
FORMATS = ["m.vtu", "m.msh", "m.inp", "m.mesh", "m.node"]


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    out = tmp_path_factory.mktemp("sets")
    files = FORMATS + (["m.unv", "m.med"] if freecad_available() else [])
    argv = ["mesh", PART, "--order", "2", "--quiet"]
    for name in files:
        argv += ["-o", str(out / name)]
    assert main(argv, supervise=False) == 0
    result = mesh_cad_file(PART, order=2)
    return out, result


def rows_set(rows):
    return {tuple(r) for r in np.asarray(rows).tolist()}


def face_nodes(groups, tag):
    return set(np.unique(groups.face_triangles[groups.face_tags == tag]).tolist())


def test_the_part_has_two_solids_and_nine_faces(written):
    _, result = written
    groups = result.groups
    assert groups.solid_names == SOLIDS
    assert set(np.unique(groups.tet_solid).tolist()) == {0, 1}
    assert groups.face_names == [f"Face{i}" for i in range(1, 10)]
    assert set(np.unique(groups.face_tags).tolist()) == set(range(9))
    assert groups.face_triangles.shape[1] == 6


def test_vtu_cell_data_through_meshio(written):
    out, result = written
    groups = result.groups
    m = meshio.read(out / "m.vtu")
    assert np.array_equal(m.points, result.mesh.points)
    types = [c.type for c in m.cells]
    assert types == ["tetra10", "triangle6"]
    assert np.array_equal(m.cells[0].data, result.mesh.tets)
    assert np.array_equal(m.cells[1].data, groups.face_triangles)
    assert np.array_equal(m.cell_data["solid_id"][0], groups.tet_solid + 1)
    assert np.array_equal(m.cell_data["face_id"][1], groups.face_tags + 1)
    assert not m.cell_data["solid_id"][1].any() and not m.cell_data["face_id"][0].any()
    ours = read_tet_mesh(out / "m.vtu")
    assert np.array_equal(ours.extra["region"], groups.tet_solid + 1)
    assert np.array_equal(ours.extra["triangle_tags"], groups.face_tags)


def test_msh_physical_names_through_meshio(written):
    out, result = written
    groups = result.groups
    m = meshio.read(out / "m.msh")
    names = {k: (int(v[0]), int(v[1])) for k, v in m.field_data.items()}
    assert names == {**{f"Face{i}": (i, 2) for i in range(1, 10)}, SOLIDS[0]: (1, 3),
                     SOLIDS[1]: (2, 3)}
    by_type = {c.type: k for k, c in enumerate(m.cells)}
    tet_tags = m.cell_data["gmsh:physical"][by_type["tetra10"]]
    assert np.array_equal(tet_tags, groups.tet_solid + 1)
    tri = m.cells[by_type["triangle6"]].data
    tri_tags = m.cell_data["gmsh:physical"][by_type["triangle6"]]
    assert rows_set(np.column_stack([tri, tri_tags])) == \
        rows_set(np.column_stack([groups.face_triangles, groups.face_tags + 1]))


@pytest.mark.skipif(shutil.which("gmsh") is None, reason="gmsh not installed")
def test_msh_physical_groups_through_gmsh(written, tmp_path):
    out, result = written
    subprocess.run(["gmsh", str(out / "m.msh"), "-0", "-format", "msh41", "-o", "g.msh"],
                   cwd=tmp_path, check=True, capture_output=True, timeout=300)
    text = (tmp_path / "g.msh").read_text()
    block = text[text.index("$PhysicalNames"):text.index("$EndPhysicalNames")]
    for i in range(1, 10):
        assert f'2 {i} "Face{i}"' in block
    assert f'3 1 "{SOLIDS[0]}"' in block and f'3 2 "{SOLIDS[1]}"' in block
    back = read_tet_mesh(tmp_path / "g.msh")
    assert sorted(np.bincount(back.extra["region"]).tolist()) == \
        sorted([0] + np.bincount(result.groups.tet_solid).tolist())
    assert np.array_equal(np.bincount(back.extra["triangle_tags"]),
                          np.bincount(result.groups.face_tags))


def test_inp_sets_through_meshio(written):
    out, result = written
    groups = result.groups
    m = meshio.read(out / "m.inp")
    for tag in range(9):
        assert set(m.point_sets[f"Face{tag + 1}"].tolist()) == face_nodes(groups, tag)
    for solid in (0, 1):
        ids = np.concatenate([c for c in m.cell_sets[SOLIDS[solid]] if c is not None])
        assert set(ids.tolist()) == set(np.flatnonzero(groups.tet_solid == solid).tolist())
    text = (out / "m.inp").read_text()
    assert text.count("*SURFACE, NAME=Face") == 9
    # each surface lists one element face per face triangle
    surface = text[text.index("*SURFACE, NAME=Face3,"):].split("\n", 1)[1]
    surface = surface[:surface.index("*")] if "*" in surface else surface
    assert len(surface.strip().splitlines()) == int((groups.face_tags == 2).sum())


def test_medit_and_tetgen_regions(written):
    out, result = written
    groups = result.groups
    medit = read_tet_mesh(out / "m.mesh")
    assert np.array_equal(medit.extra["region"], groups.tet_solid + 1)
    assert np.array_equal(medit.extra["triangle_tags"], groups.face_tags)
    assert np.array_equal(medit.extra["triangles"], groups.face_triangles)
    tetgen = read_tet_mesh(out / "m.ele")
    assert np.array_equal(tetgen.extra["region"], groups.tet_solid + 1)


@pytest.mark.skipif(not freecad_available(), reason="FreeCAD not installed")
@pytest.mark.parametrize("name", ["m.unv", "m.med"])
def test_freecad_reads_the_groups(written, name):
    out, result = written
    groups = result.groups
    from FemBspTet.kernel.freecad_env import import_freecad

    import_freecad()
    import Fem

    fem = Fem.read(str(out / name))
    assert fem.VolumeCount == len(result.mesh.tets)
    assert fem.FaceCount == len(groups.face_triangles)
    found = {(fem.getGroupName(g), fem.getGroupElementType(g)): g for g in fem.Groups}
    for tag in range(9):
        nodes = fem.getGroupElements(found[(f"Face{tag + 1}", "Node")])
        assert len(nodes) == len(face_nodes(groups, tag))
        faces = fem.getGroupElements(found[(f"Face{tag + 1}", "Face")])
        assert len(faces) == int((groups.face_tags == tag).sum())
    for solid in (0, 1):
        volumes = fem.getGroupElements(found[(SOLIDS[solid], "Volume")])
        assert len(volumes) == int((groups.tet_solid == solid).sum())


@pytest.mark.skipif(shutil.which("gmsh") is None, reason="gmsh not installed")
def test_msh41_groups_through_meshio_and_gmsh(tmp_path):
    out = tmp_path / "m41.msh"
    assert main(["mesh", PART, "--order", "2", "--quiet", "--msh-version", "4.1", "-o", str(out)],
                supervise=False) == 0
    assert out.read_text().startswith("$MeshFormat\n4.1 0 8\n")
    result = mesh_cad_file(PART, order=2)
    groups = result.groups
    m = meshio.read(out)
    names = {k: (int(v[0]), int(v[1])) for k, v in m.field_data.items()}
    assert names["Face9"] == (9, 2) and names[SOLIDS[1]] == (2, 3)
    tets = np.concatenate([c.data for c in m.cells if c.type == "tetra10"])
    assert len(tets) == len(result.mesh.tets)
    subprocess.run(["gmsh", str(out), "-0", "-format", "msh22", "-o", "g.msh"], cwd=tmp_path,
                   check=True, capture_output=True, timeout=300)
    back = read_tet_mesh(tmp_path / "g.msh")
    assert np.array_equal(np.bincount(back.extra["region"])[1:], np.bincount(groups.tet_solid))
    assert np.array_equal(np.bincount(back.extra["triangle_tags"]), np.bincount(groups.face_tags))
