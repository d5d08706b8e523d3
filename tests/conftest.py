# SPDX-License-Identifier: LGPL-2.1-or-later
"""Shared pytest set-up: the checkout on sys.path, test data locations, TetGen meshes."""

import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

DATA = os.path.join(ROOT, "tests", "data")
PAPER = os.path.join(DATA, "paper")
CORPUS = os.path.join(DATA, "corpus")
PAPER_MODELS = ("dented_box", "schoenhardt", "box_with_hole", "dented_prism")


def paper_path(name):
    return os.path.join(PAPER, name + ".off")


def corpus_path(name):
    return os.path.join(CORPUS, name + ".off")


@pytest.fixture(scope="session")
def cli():
    """Path of the bin/fembsptet launcher."""
    return os.path.join(ROOT, "bin", "fembsptet")


@pytest.fixture(scope="session")
def tetgen_meshes():
    """TetGen -pY meshes of the paper polyhedra: {name: (surface, mesh)}. TetGen is a declared
    dependency (scripts/setup.sh installs it), so its absence is a failure, not a skip."""
    from FemBspTet.peers.tetgen import run_tetgen, tetgen_available
    from FemBspTet.io.surface_io import read_surface

    assert tetgen_available(), "tetgen is missing: run scripts/setup.sh"
    out = {}
    for name in PAPER_MODELS:
        surface = read_surface(paper_path(name))
        out[name] = (surface, run_tetgen(surface, "pY").mesh)
    return out


@pytest.fixture(scope="module")
def fc():
    """(FreeCAD, Part, Fem), FreeCAD bootstrapped headless (freecad_env). Test modules that need
    FreeCAD skip themselves first when it is missing; test_cad_tessellation has its own (FreeCAD,
    Part) variant."""
    from FemBspTet.kernel.freecad_env import import_freecad

    freecad = import_freecad()
    import Fem
    import Part

    return freecad, Part, Fem
