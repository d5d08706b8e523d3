# SPDX-License-Identifier: LGPL-2.1-or-later
"""The FEM path: a CAD part to a sized tet4/tet10 mesh with its CAD faces and solids
(:func:`FemBspTet.fem.cad_mesh.mesh_cad_file`)."""
