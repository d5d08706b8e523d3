# SPDX-License-Identifier: LGPL-2.1-or-later
"""FemBspTet: BSP-assisted constrained tetrahedralization for FreeCAD FEM.

The compiled code is two private extensions (built by ``scripts/setup.sh``): ``FemBspTet._bsptet``,
the core, and ``FemBspTet._bsptet_cad``, the FEM pipeline from CAD (it loads OpenCASCADE).
Importing this package never imports FreeCAD; the FreeCAD layer is imported on demand:
``make_mesher``, ``run_mesher``, ``mesh_shape`` and ``export_mesh`` (see
:mod:`FemBspTet.freecad.mesher_tools`) import it when called.
"""

__version__ = "0.1.0"

from .kernel.errors import BspTetError, InputError, InternalError, NotImplementedYetError  # noqa: F401
from .kernel.mesh_types import Surface, TetMesh  # noqa: F401


# --- FreeCAD scripting API; each imports FreeCAD only when called -------------------

def make_mesher(doc, part=None, name="MeshBspTet", **properties):
    """Create a BspTet mesher object (not meshed yet); see mesher_object.make_mesher."""
    from .freecad.mesher_object import make_mesher as _make

    return _make(doc, part, name, **properties)


def run_mesher(obj, progress=None, cancel=None):
    """Mesh the mesher object now (synchronously); see mesher_tools.run_mesher."""
    from .freecad.mesher_tools import run_mesher as _run

    return _run(obj, progress=progress, cancel=cancel)


def mesh_shape(shape, **options):
    """Mesh a Part.Shape into a Fem.FemMesh; see mesher_tools.mesh_shape."""
    from .freecad.mesher_tools import mesh_shape as _mesh

    return _mesh(shape, **options)


def export_mesh(obj, path):
    """Write a FEM mesh object's mesh (.inp .unv .vtk .vtu .med .z88); see mesher_tools."""
    from .freecad.mesher_tools import export_mesh as _export

    return _export(obj, path)
