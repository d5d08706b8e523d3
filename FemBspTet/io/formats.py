# SPDX-License-Identifier: LGPL-2.1-or-later
"""The one table of file formats: which extensions are read and written, and by whom.

    SURFACE_EXTENSIONS          triangle surfaces we read and write (io.surface_io)
    CAD_EXTENSIONS              CAD files: meshed by the FEM path (C++ CAD layer), tessellated
                                through FreeCAD for ``--tessellation`` (io.cad_tessellation)
    VOLUME_EXTENSIONS           tet meshes we read and write ourselves (io.volume_io)
    FREECAD_VOLUME_EXTENSIONS   tet meshes written and read through FreeCAD's FemMesh
                                (freecad.femmesh), which FreeCAD also writes as .inp .vtk .vtu
Extensions compare in lower case.
"""

import os

SURFACE_EXTENSIONS = (".off", ".stl", ".obj", ".ply")
CAD_EXTENSIONS = (".step", ".stp", ".brep", ".brp", ".iges", ".igs")
VOLUME_EXTENSIONS = (".vtu", ".msh", ".inp", ".node", ".ele", ".mesh")
FREECAD_VOLUME_EXTENSIONS = (".unv", ".med", ".z88")


def extension(path):
    """The lower-case extension of ``path`` (with its dot; "" when there is none)."""
    return os.path.splitext(os.fspath(path))[1].lower()
