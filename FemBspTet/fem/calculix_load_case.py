# SPDX-License-Identifier: LGPL-2.1-or-later
"""A linear static CalculiX analysis of a CAD FEM mesh, with no FreeCAD: the solver's own verdict
on the elements (it refuses a tet10 whose Jacobian is not positive at its integration points).

    from FemBspTet.fem.cad_mesh import mesh_cad_file
    from FemBspTet.fem.calculix_load_case import solve_face_load

    result = mesh_cad_file("part.step", order=2)
    figures = solve_face_load(result, "work/")   # InternalError if CalculiX refuses the mesh

The mesh is written with its named sets (``Face<n>`` node sets and element-face surfaces,
``Solid<n>`` element sets, as ``fembsptet mesh`` writes them) and the load case refers to them by
name only. Per group of connected solids (solids that share nodes; solids that only touch have
separate nodes and are separate groups): the group's lowest-numbered CAD face fixed
(``*BOUNDARY``, all its nodes, mid-nodes included), and a pressure (``*DSLOAD``) of 1000 N over
the face's area on the other face whose pressure has the largest resultant (the first such),
among the faces that share no node with the fixed one when there are such. A group with a single CAD face (a sphere) is
fixed on it and carries its own weight instead. The solver's reaction on the fixed faces must
balance the pressure's resultant (integrated exactly over the mesh's faces, curved tet10 faces
included), which also checks that each element face of the surfaces is the right one. Steel:
E = 210000 MPa, nu = 0.3, density 7.9e-9 t/mm^3. Model units are taken as mm.
"""

import math
import os
import re
import shutil
import subprocess

import numpy as np
import time

from ..kernel.errors import InternalError
from ..io.volume_io import write_tet_mesh

TOTAL_FORCE_N = 1000.0


def _groups_of_solids(tets, tet_solid):
    """Lists of solid ids that share nodes (connected through shared faces), sorted."""
    solids = sorted(set(np.unique(tet_solid).tolist()))
    parent = {s: s for s in solids}

    def find(s):
        while parent[s] != s:
            parent[s] = parent[parent[s]]
            s = parent[s]
        return s

    corners = tets[:, :4]
    node_solid = np.full(int(corners.max()) + 1, -1, dtype=np.int64)
    for s in solids:
        nodes = np.unique(corners[tet_solid == s])
        other = node_solid[nodes]
        for t in np.unique(other[other >= 0]).tolist():
            parent[find(t)] = find(s)
        node_solid[nodes] = s
    groups = {}
    for s in solids:
        groups.setdefault(find(s), []).append(s)
    return sorted(groups.values())


def _face_nodes(result, face):
    """Node ids (0-based) of CAD face `face`: corners and, for tet10, mid-nodes of its triangles."""
    rows = result.boundary.face_tags == face
    nodes = [result.boundary.triangles[rows].ravel()]
    if len(result.boundary_midnodes):
        nodes.append(result.boundary_midnodes[rows].ravel())
    return np.unique(np.concatenate(nodes))


def _face_triangles(result, face):
    """The CAD face's triangles (corners, then tet10 mid-nodes m_ab, m_bc, m_ca)."""
    groups = result.groups
    return groups.face_triangles[groups.face_tags == face]


def _area_vector(points, tri):
    """Sum over the triangles of the integral of the (unnormalized, right-hand) normal: exact for
    flat (3-node) and quadratic (6-node) triangles. The quadratic map's tangents are linear, so
    their cross product is quadratic, integrated exactly by the edge-midpoint rule."""
    p = points[tri]
    if tri.shape[1] == 3:
        return 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]).sum(axis=0)
    a, b, c, ab, bc, ca = (p[:, k] for k in range(6))
    total = np.zeros(3)
    for xi, eta in ((0.5, 0.0), (0.5, 0.5), (0.0, 0.5)):
        # x(xi, eta), xi toward b, eta toward c (quadratic Lagrange shape functions)
        l0 = 1.0 - xi - eta
        dxi = (a * (1 - 4 * l0) + b * (4 * xi - 1) + ab * (4 * (l0 - xi))
               + bc * (4 * eta) - ca * (4 * eta))
        deta = (a * (1 - 4 * l0) + c * (4 * eta - 1) - ab * (4 * xi)
                + bc * (4 * xi) + ca * (4 * (l0 - eta)))
        total += np.cross(dxi, deta).sum(axis=0) / 6.0
    return total


def _read_displacements(dat_path):
    """{node id: (ux, uy, uz)} from CalculiX's .dat (*NODE PRINT, U)."""
    u = {}
    reading = False
    with open(dat_path, errors="replace") as f:
        for line in f:
            if line.strip().startswith("displacements"):
                reading = True
                continue
            if not reading:
                continue
            parts = line.split()
            if len(parts) == 4 and re.fullmatch(r"\d+", parts[0]):
                u[int(parts[0])] = tuple(float(x.replace("D", "E")) for x in parts[1:])
            elif parts and u:
                reading = False
    return u


def _read_totals(dat_path):
    """{set name (upper case): (fx, fy, fz)} from CalculiX's .dat (*NODE PRINT, TOTALS=ONLY, RF)."""
    totals, name = {}, None
    with open(dat_path, errors="replace") as f:
        for line in f:
            m = re.match(r"\s*total force \(fx,fy,fz\) for set (\S+)", line)
            if m:
                name = m.group(1)
                continue
            parts = line.split()
            if name and len(parts) == 3:
                totals[name] = tuple(float(x.replace("D", "E")) for x in parts)
                name = None
    return totals


def solve_face_load(result, workdir, ccx=None, timeout=1800):
    """Writes the mesh and the load case (module doc) into `workdir`, runs CalculiX and returns
    {"groups", "fixed_faces", "loaded_faces", "nodes", "elements", "max_displacement",
    "seconds", "applied_force" (the pressures' resultant), "reaction_force" (on the fixed
    faces; it balances the applied force when "loads_touching_fixed_faces" is 0)}. Raises InternalError with CalculiX's message when it refuses or fails, or when a
    displacement is not finite or a fixed node moved."""

    ccx = ccx or shutil.which("ccx")
    if ccx is None:
        raise InternalError("CalculiX (ccx) is not installed: apt install calculix-ccx")
    os.makedirs(workdir, exist_ok=True)
    mesh = result.mesh
    order = 2 if mesh.tets.shape[1] == 10 else 1
    groups = result.groups
    write_tet_mesh(os.path.join(workdir, "mesh.inp"), mesh, groups)
    lines = ["*INCLUDE, INPUT=mesh.inp\n"]
    fixed, loaded, gravity = [], [], []
    touching_fixed = 0
    applied = np.zeros(3)
    node_solid = np.full(len(mesh.points), -1, dtype=np.int64)
    for s in np.unique(result.tet_solid).tolist():
        node_solid[np.unique(mesh.tets[result.tet_solid == s])] = s
    for group in _groups_of_solids(mesh.tets, result.tet_solid):
        in_group = np.isin(node_solid[result.boundary.triangles[:, 0]], group)
        faces = sorted(set(result.boundary.face_tags[in_group].tolist()))
        if not faces:
            raise InternalError(f"solids {group} have no boundary face")
        fixed.append(faces[0])
        if len(faces) > 1:
            # the face whose pressure has the largest resultant (a large flat face), among those
            # with no node on the fixed face if there are any: the load on a fixed node goes
            # into the support without showing in the reaction
            fixed_nodes = _face_nodes(result, faces[0])
            apart = [f for f in faces[1:]
                     if not np.isin(_face_nodes(result, f), fixed_nodes).any()]
            touching_fixed += 0 if apart else 1
            candidates = apart or faces[1:]
            resultant = [np.linalg.norm(_area_vector(mesh.points, _face_triangles(result, f)))
                         for f in candidates]
            loaded.append(candidates[int(np.argmax(resultant))])
        else:
            gravity += group
    lines += ["*MATERIAL, NAME=STEEL\n", "*ELASTIC\n", "210000, 0.3\n", "*DENSITY\n", "7.9e-9\n",
              "*SOLID SECTION, ELSET=Eall, MATERIAL=STEEL\n", "*STEP\n", "*STATIC\n", "*BOUNDARY\n"]
    lines += [f"{groups.face_names[f]}, 1, 3\n" for f in fixed]
    if loaded:
        lines.append("*DSLOAD\n")
        for f in loaded:
            tri = _face_triangles(result, f)
            p = mesh.points[tri[:, :3]]
            area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]),
                                        axis=1).sum()
            pressure = TOTAL_FORCE_N / area
            lines.append(f"{groups.face_names[f]}, P, {pressure:.12e}\n")
            applied -= pressure * _area_vector(mesh.points, tri)  # a pressure pushes inward
    if gravity:
        lines.append("*DLOAD\n")
        lines += [f"{groups.solid_names[s]}, GRAV, 9810., 0., 0., -1.\n" for s in gravity]
    lines += ["*NODE PRINT, NSET=Nall\n", "U\n"]
    lines += [f"*NODE PRINT, NSET={groups.face_names[f]}, TOTALS=ONLY\nRF\n" for f in fixed]
    lines.append("*END STEP\n")
    with open(os.path.join(workdir, "job.inp"), "w") as f:
        f.writelines(lines)
    t0 = time.perf_counter()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    try:
        run = subprocess.run([ccx, "job"], cwd=workdir, capture_output=True, text=True,
                             timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        raise InternalError(f"CalculiX did not finish within {timeout} s (see {workdir})") from None
    seconds = time.perf_counter() - t0
    log = run.stdout + run.stderr
    with open(os.path.join(workdir, "ccx.log"), "w") as f:
        f.write(log)
    refused = [ln.strip() for ln in log.splitlines()
               if "*ERROR" in ln or "nonpositive jacobian" in ln.lower()]
    if run.returncode != 0 or refused:
        raise InternalError("CalculiX refused the mesh: "
                            + ("; ".join(refused[:5]) or f"exit {run.returncode}")
                            + f" (see {workdir}/ccx.log)")
    u = _read_displacements(os.path.join(workdir, "job.dat"))
    if len(u) != len(mesh.points):
        raise InternalError(f"CalculiX printed {len(u)} displacements for {len(mesh.points)} "
                            f"nodes (see {workdir}/job.dat)")
    disp = np.array([u[i + 1] for i in range(len(mesh.points))])
    if not np.isfinite(disp).all():
        raise InternalError(f"CalculiX gave non-finite displacements (see {workdir}/job.dat)")
    fixed_nodes = np.concatenate([_face_nodes(result, f) for f in fixed])
    if np.abs(disp[fixed_nodes]).max() != 0.0:
        raise InternalError("a fixed node moved in the CalculiX result")
    totals = _read_totals(os.path.join(workdir, "job.dat"))
    missing = [groups.face_names[f] for f in fixed if groups.face_names[f].upper() not in totals]
    if missing:
        raise InternalError(f"CalculiX printed no reaction total for {', '.join(missing)} "
                            f"(see {workdir}/job.dat)")
    reaction = np.sum([totals[groups.face_names[f].upper()] for f in fixed], axis=0)
    lengths = np.linalg.norm(disp, axis=1)
    return {"groups": len(fixed), "fixed_faces": [f + 1 for f in fixed],
            "loaded_faces": [f + 1 for f in loaded], "gravity_solids": len(gravity),
            "nodes": int(len(mesh.points)), "elements": int(len(mesh.tets)), "order": order,
            "max_displacement": float(lengths.max()), "seconds": seconds,
            "applied_force": applied.tolist(), "reaction_force": reaction.tolist(),
            "loads_touching_fixed_faces": touching_fixed,
            "finite": bool(math.isfinite(float(lengths.max())))}
