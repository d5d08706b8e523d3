# SPDX-License-Identifier: LGPL-2.1-or-later
"""What a mesh run reads: a surface file, or a CAD file tessellated through FreeCAD."""

from . import cad_tessellation
from .formats import CAD_EXTENSIONS, SURFACE_EXTENSIONS, extension
from .surface_io import read_surface
from ..kernel.errors import InputError


def load_input(path, size=None):
    """Reads a surface file or tessellates a CAD file through FreeCAD (its fins flipped away,
    :func:`FemBspTet.io.cad_tessellation.flip_out_fins_of`). Returns a list of Surfaces (one per
    solid). ``size``: the element size the CAD tessellation's deflection follows."""
    ext = extension(path)
    if ext in SURFACE_EXTENSIONS:
        return [read_surface(path)]
    if ext in CAD_EXTENSIONS:
        # OpenCASCADE's fins (near-collinear triangles) flipped inside their faces: every tet
        # on a fin is flat
        return cad_tessellation.flip_out_fins_of(
            cad_tessellation.tessellate_file(path, size=size))[0]
    raise InputError(
        f"unknown input format '{ext or '(no extension)'}'; supported: "
        + ", ".join(SURFACE_EXTENSIONS + CAD_EXTENSIONS),
        where=path,
    )
