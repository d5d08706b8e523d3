# SPDX-License-Identifier: LGPL-2.1-or-later
"""The native options classes are bound from the C++ schema tables: ``MeshOptions`` from
core/mesher.h ``for_each_mesh_option``, ``RefineOptions`` from refine/quality_refine.h
``for_each_refine_option`` (``FemOptions``: tests/test_fem_pipeline_binding.py). The Python
options of ``FemBspTet.kernel.core`` map onto their fields and nothing else; the core refuses a bad
value, naming the option; ``MeshOptions`` travels to a cluster's workers by pickle."""

import os
import pickle

import numpy as np
import pytest

from FemBspTet.kernel import core
from FemBspTet.kernel.errors import InputError
from FemBspTet.io.surface_io import read_surface

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")
PRISM = os.path.join(DATA, "paper", "dented_prism.off")


def test_mesh_options_class_from_the_schema():
    lib = core.native()
    names = list(lib.MeshOptions.names)
    assert names == ["allow_boundary_steiner", "cone_cells", "covered_faces_along_lines", "seed",
                     "bsp_candidate_shift", "steiner_effort", "debug_checks"]
    o = lib.MeshOptions()
    assert (o.allow_boundary_steiner, o.seed, o.steiner_effort) == (False, lib.BspSeed.auto, 1000000)
    with pytest.raises(AttributeError):
        o.no_such_option = 1
    # the Python options the core takes name its fields
    python = core.native_core_options({"allow_boundary_steiner": True, "steiner_effort": 5,
                                       "bsp_seed": "box"})
    assert (python.allow_boundary_steiner, python.steiner_effort, python.seed) == (True, 5, lib.BspSeed.box)
    with pytest.raises(InputError, match="bsp_seed"):
        core.native_core_options({"bsp_seed": "sphere"})
    # pickled with every field (a cluster's workers get it with each piece)
    back = pickle.loads(pickle.dumps(python))
    assert all(getattr(back, n) == getattr(python, n) for n in names)
    # a bad value is refused by the binding, naming the option
    surface = read_surface(PRISM)
    o.steiner_effort = -1
    with pytest.raises(ValueError, match="steiner_effort"):
        lib.tetrahedralize(surface.points, surface.triangles, options=o)


def test_mesh_options_change_the_mesh_as_asked():
    """The seed option reaches the core: stats name the seed the mesh came from."""
    lib = core.native()
    surface = read_surface(PRISM)
    for seed in ("delaunay", "box"):
        o = lib.MeshOptions()
        o.seed = getattr(lib.BspSeed, seed)
        points, tets, stats = lib.tetrahedralize(surface.points, surface.triangles, options=o)
        assert stats["bsp_seed"] == seed
        assert len(tets) > 0 and np.isfinite(points).all()


def test_refine_options_class_from_the_schema():
    lib = core.native()
    names = list(lib.RefineOptions.names)
    assert names[:3] == ["size", "min_size", "size_by_tag"] and len(names) == len(set(names))
    o = lib.RefineOptions()
    assert o.size == float("inf") and o.order == 1 and o.max_passes == 40
    assert o.surface_points == lib.SurfacePoints.exact
    with pytest.raises(AttributeError):
        o.no_such_option = 1
    o.size_by_tag = {3: 0.5}
    assert o.size_by_tag == {3: 0.5}
    # every Python option of the quality stage but the projection callback names a field
    python_names = set(core.REFINE_OPTIONS) - {"projection"}
    assert {core.REFINE_OPTION_OF.get(k, k) for k in python_names} <= set(names)
    assert set(core.REFINE_OPTION_OF) <= python_names
    # a bad value is refused by the core, naming the option
    surface = read_surface(PRISM)
    mesh, _ = core.tetrahedralize(surface)
    o.order = 3
    with pytest.raises(ValueError, match="order"):
        lib.refine(surface.points, surface.triangles, None, mesh.points, mesh.tets, options=o)


def test_every_python_option_maps_onto_a_schema_or_is_python_only():
    """core.OPTION_NAMES (the options of tetrahedralize, which the CLI's flags fill): each is a
    MeshOptions field, a RefineOptions field or one of the few handled in Python."""
    lib = core.native()
    mesh_names, refine_names = set(lib.MeshOptions.names), set(lib.RefineOptions.names)
    assert set(core.MESH_OPTION_OF.values()) <= mesh_names
    for name in core.OPTION_NAMES:
        assert (name in core.MESH_OPTION_OF or core.REFINE_OPTION_OF.get(name, name) in refine_names
                or name in core.PYTHON_OPTIONS), name

