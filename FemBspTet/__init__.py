"""FemBspTet: BSP-assisted constrained tetrahedralization for FreeCAD FEM.

The compiled core is the private extension ``FemBspTet._bsptet`` (built by ``scripts/setup.sh``).
Importing this package never imports FreeCAD; the FreeCAD layer is imported on demand.
"""

__version__ = "0.1.0"

from .errors import BspTetError, InputError, InternalError, NotImplementedYetError  # noqa: F401
from .mesh_types import Surface, TetMesh  # noqa: F401
