"""The numpy API of FemBspTet: meshing and checking. Never imports FreeCAD.

    from FemBspTet import core
    report = core.check_mesh(surface, tetmesh)      # exact validity check, see below
    result = core.tetrahedralize(surface, options)  # the BSP-assisted mesher

``check_mesh`` returns a dict: ``valid`` (bool), defect counts (``inverted_tets``,
``flat_tets``, ``overshared_faces``, ``same_orientation_faces``, ``boundary_faces_off_surface``,
``boundary_faces_inward``, ``unpaired_boundary_edges``, ``miscovered_triangles``,
``duplicate_points``, ``unreferenced_points``, ``inconsistent_midnodes``, ...), ``volume_equal``,
``tet_volume``, ``surface_volume``, ``steiner_points``, ``boundary_steiner_points``, ``messages``
(the first problems, with indices) and ``quality`` (dihedral angles, radius-edge ratios). The
conditions are listed in ``cpp_module/include/bsptet/mesh_check.h``.
"""

import numpy as np

from .errors import InternalError, NotImplementedYetError
from .mesh_types import Surface, TetMesh


def _native():
    """The compiled core, with a message that says how to build it when it is missing."""
    try:
        from . import _bsptet
    except ImportError as exc:  # pragma: no cover - depends on the build
        raise InternalError(
            "the C++ core FemBspTet._bsptet is not built or does not load "
            f"({exc}); run scripts/setup.sh (it installs what is missing and builds the core)"
        ) from exc
    return _bsptet


def check_mesh(surface: Surface, mesh: TetMesh, max_messages: int = 20, compute_quality=True):
    """Checks ``mesh`` against the closed surface it should fill, exactly. Returns a dict."""
    return _native().check_mesh(
        surface.points,
        surface.triangles,
        mesh.points,
        mesh.tets,
        max_messages=max_messages,
        compute_quality=compute_quality,
    )


def tet_quality(mesh: TetMesh):
    """Dihedral angles (degrees) and radius-edge ratios of the linear tets of ``mesh``."""
    return _native().tet_quality(mesh.points, mesh.tets)


def orient3d(a, b, c, d) -> int:
    """Exact sign of det[b-a, c-a, d-a] (+1: d on the side of the right-hand normal of a, b, c)."""
    return _native().orient3d(tuple(map(float, a)), tuple(map(float, b)), tuple(map(float, c)),
                              tuple(map(float, d)))


def tetrahedralize(surface: Surface, options=None, progress=None):
    """Tetrahedralizes the solid bounded by ``surface`` (BSP-assisted, exact).

    Not built yet: raises :class:`NotImplementedYetError`. No placeholder mesher stands in.
    """
    raise NotImplementedYetError(
        "the BSP-assisted tetrahedralizer is not implemented yet (FemBspTet "
        f"{_version()}); `fembsptet check` and the file converters work"
    )


def _version():
    from . import __version__

    return __version__


def signed_volume(surface: Surface) -> float:
    """Volume enclosed by ``surface`` (positive for outward orientation), in double precision."""
    p = surface.points
    t = surface.triangles
    if len(t) == 0:
        return 0.0
    o = p[t[0, 0]]
    a, b, c = p[t[:, 0]] - o, p[t[:, 1]] - o, p[t[:, 2]] - o
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)
