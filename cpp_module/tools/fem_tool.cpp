// SPDX-License-Identifier: LGPL-2.1-or-later
// bsptet_fem: a CAD file to a tetrahedral FEM mesh (fem/fem_mesh.h), with its figures.
//
//   bsptet_fem PART.step [--size H] [--min-size HMIN] [--order 1|2] [--optimize-rounds N] [--workers N] [--vtu OUT.vtu] [--off OUT.off] [--distance]
//
// Prints the sizes, counts, dihedral angles (smallest, median of each tet's smallest, share of
// tets under 10 degrees; the refinement's worst at its stages, RefineStats::worst_deg_*) and
// seconds per stage. --optimize-rounds: FemOptions::optimize_rounds. --vtu writes the mesh (tets and CAD face triangles, fem_io.h); --off writes
// the CAD face triangles' corners as one surface; --distance also measures how far the nodes of
// the face triangles lie from their CAD faces (slow: one OpenCASCADE extrema search per node and
// face). --workers N: solids (pieces of a cut solid) meshed at the same time (FemOptions::workers; default every core).
// Exit status: 0, 2 for bad input, 1 otherwise.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bsptet/cad/cad_model.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/fem/fem_io.h"
#include "bsptet/fem/fem_mesh.h"
#include "bsptet/mesh/mesh_io.h"

int main(int argc, char** argv) {
  using namespace bsptet;
  const char* usage = "usage: bsptet_fem PART [--size H] [--min-size HMIN] [--order 1|2] [--optimize-rounds N] [--workers N] [--vtu OUT.vtu] [--off OUT.off] [--distance]\n";
  if (argc < 2) {
    std::fprintf(stderr, "%s", usage);
    return 2;
  }
  std::string path = argv[1], off, vtu;
  bool distance = false;
  fem::FemOptions options;
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--size") && i + 1 < argc) {
      options.size = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--min-size") && i + 1 < argc) {
      options.min_size = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--order") && i + 1 < argc) {
      options.order = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--optimize-rounds") && i + 1 < argc) {
      options.optimize_rounds = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--workers") && i + 1 < argc) {
      options.workers = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--off") && i + 1 < argc) {
      off = argv[++i];
    } else if (!std::strcmp(argv[i], "--vtu") && i + 1 < argc) {
      vtu = argv[++i];
    } else if (!std::strcmp(argv[i], "--distance")) {
      distance = true;
    } else {
      std::fprintf(stderr, "unknown argument '%s'\n%s", argv[i], usage);
      return 2;
    }
  }
  try {
    const cad::CadModel model = cad::read_cad_file(path);
    fem::FemStats st;
    const fem::FemMesh mesh = fem::mesh_cad_model(model, options, &st);
    std::printf("%s: %lld solids (meshed as %lld) %lld faces (%lld shared); h %.4g min %.4g; order %d\n", path.c_str(),
                (long long)st.solids, (long long)st.pieces, (long long)st.faces, (long long)st.shared_faces, st.size, st.min_size,
                options.order);
    std::printf("  surface: nodes %lld triangles %lld\n", (long long)st.surface_nodes, (long long)st.surface_triangles);
    std::printf("  core: points %lld tets %lld steiner %lld\n", (long long)st.core_points, (long long)st.core_tets,
                (long long)st.core_steiner_points);
    std::printf("  refine points: Delaunay refinement %lld, interior splits %lld, collapses %lld\n",
                (long long)st.refinement_points, (long long)st.interior_splits, (long long)st.collapses);
    std::printf("  refine: surface splits %lld, kept on shared faces %lld, projections refused %lld, mid-nodes "
                "projected %lld straightened %lld, curved conflicts left %lld; merge: mid-nodes reconciled %lld "
                "straightened %lld\n",
                (long long)st.surface_splits, (long long)st.splits_fixed_surface, (long long)st.projection_refused,
                (long long)st.midnodes_projected, (long long)st.midnodes_straightened,
                (long long)st.curving_conflicts_left, (long long)st.midnodes_reconciled,
                (long long)st.midnodes_straightened_at_merge);
    std::printf("  tet10 lift: tets mended by moving mid-nodes %lld (interior mid-nodes moved %lld, boundary "
                "mid-nodes moved along the CAD %lld), points inserted %lld\n",
                (long long)st.midnodes_relaxed_tets, (long long)st.midnodes_moved_interior,
                (long long)st.midnodes_moved_surface, (long long)st.lift_insertions);
    std::printf("  mesh: nodes %lld (corners %lld) tets %lld face triangles %lld\n", (long long)st.nodes,
                (long long)st.corner_nodes, (long long)st.tets, (long long)st.boundary_triangles);
    std::printf("  dihedral: min %.2f deg, median per-tet worst %.2f deg, tets under 10 deg %.2f%%\n",
                st.min_dihedral_deg, st.median_tet_min_dihedral_deg, 100.0 * st.tets_below_10_deg);
    std::printf("  worst dihedral in the refinement: optimized %.2f, end %.2f deg\n", st.refine_worst_deg_optimized,
                st.refine_worst_deg);
    std::printf("  projection: face %lld (outside trim %lld, fallbacks %lld) edge %lld (no common edge %lld)\n",
                (long long)st.projection.face_calls, (long long)st.projection.outside_trim,
                (long long)st.projection.face_fallbacks, (long long)st.projection.edge_calls,
                (long long)st.projection.no_common_edge);
    std::printf("  seconds: surface %.3f core %.3f refine %.3f merge %.3f total %.3f\n", st.seconds_surface,
                st.seconds_core, st.seconds_refine, st.seconds_merge, st.seconds_total);
    std::printf("  refine seconds by pass:");
    for (const auto& [pass, seconds] : st.refine_seconds_by_pass) std::printf(" %s %.3f", pass.c_str(), seconds);
    std::printf("\n");
    if (distance) {
      const fem::CadDistance d = fem::measure_cad_distance(model, mesh);
      std::printf("  distance to CAD: corners max %.3g, mid-nodes max %.3g (%.3g of the diagonal); %lld node-face "
                  "pairs; farthest: node %lld on Face%d\n",
                  d.max_corner, d.max_midnode, std::max(d.max_corner, d.max_midnode) / model.diagonal(),
                  (long long)d.pairs, (long long)d.worst_node, d.worst_face + 1);
    }
    if (!vtu.empty()) fem::write_vtu(vtu, mesh);
    if (!off.empty()) {
      SurfaceMesh s;
      s.xyz = mesh.mesh.xyz;
      for (Index t = 0; t < mesh.num_triangles(); ++t)
        for (int k = 0; k < 3; ++k) s.tri.push_back(mesh.tri[static_cast<std::size_t>(mesh.nodes_per_triangle * t + k)]);
      write_off(off, s);
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "INPUT ERROR: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ERROR: %s\n", e.what());
    return 1;
  }
  return 0;
}
