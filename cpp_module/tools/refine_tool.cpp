// SPDX-License-Identifier: LGPL-2.1-or-later
// bsptet_refine: the core then the quality stage, from the command line (debugging, benchmarks;
// users run `fembsptet mesh --size H`). Meshes one OFF surface, refines it, checks the result
// exactly and prints one line of figures.
//
//   bsptet_refine SURFACE.off [--size H | --size-diag N] [--min-size L] [--radius-edge B]
//                 [--min-dihedral D] [--split-ratio R] [--thickness-ratio K] [--collapse-ratio C] [--optimize-rounds N]
//                 [--max-passes N] [--rounded] [--write STEM] [--core-cache STEM]
//
// --size-diag N sets H to the bounding-box diagonal / N. --core-cache STEM reads the core's mesh
// from STEM.node/.ele when they exist (else meshes and writes them there): the quality stage
// alone, again and again, on a model whose core takes minutes. Exit: 0 valid, 1 error or invalid, 2 bad input.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/mesh/mesh_io.h"
#include "bsptet/core/mesher.h"
#include "bsptet/refine/quality_refine.h"

using namespace bsptet;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s SURFACE.off [--size H | --size-diag N] [--min-size L] [--radius-edge B] "
                 "[--min-dihedral D] [--split-ratio R] [--write STEM]\n",
                 argv[0]);
    return 2;
  }
  RefineOptions o;
  double size_diag = 0;
  std::string stem, core_cache;
  for (int i = 2; i < argc; ++i) {
    auto value = [&]() {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", argv[i]);
        std::exit(2);
      }
      return std::atof(argv[++i]);
    };
    if (!std::strcmp(argv[i], "--size")) o.size = value();
    else if (!std::strcmp(argv[i], "--size-diag")) size_diag = value();
    else if (!std::strcmp(argv[i], "--min-size")) o.min_size = value();
    else if (!std::strcmp(argv[i], "--radius-edge")) o.radius_edge_bound = value();
    else if (!std::strcmp(argv[i], "--min-dihedral")) o.min_dihedral_deg = value();
    else if (!std::strcmp(argv[i], "--split-ratio")) o.split_ratio = value();
    else if (!std::strcmp(argv[i], "--thickness-ratio")) o.thickness_ratio = value();
    else if (!std::strcmp(argv[i], "--collapse-ratio")) o.collapse_ratio = value();
    else if (!std::strcmp(argv[i], "--optimize-rounds")) o.optimize_rounds = static_cast<int>(value());
    else if (!std::strcmp(argv[i], "--max-passes")) o.max_passes = static_cast<int>(value());
    else if (!std::strcmp(argv[i], "--rounded")) o.surface_points = SurfacePoints::kRounded;
    else if (!std::strcmp(argv[i], "--write") && i + 1 < argc) stem = argv[++i];
    else if (!std::strcmp(argv[i], "--core-cache") && i + 1 < argc) core_cache = argv[++i];
    else {
      std::fprintf(stderr, "unknown argument %s\n", argv[i]);
      return 2;
    }
  }
  try {
    const SurfaceMesh s = read_off(argv[1]);
    if (size_diag > 0) {
      double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
      for (Index i = 0; i < s.num_points(); ++i)
        for (int c = 0; c < 3; ++c) {
          lo[c] = std::fmin(lo[c], s.point(i)[c]);
          hi[c] = std::fmax(hi[c], s.point(i)[c]);
        }
      o.size = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                         (hi[2] - lo[2]) * (hi[2] - lo[2])) / size_diag;
    }
    MeshStats cst;
    TetMesh core;
    std::FILE* cached = core_cache.empty() ? nullptr : std::fopen((core_cache + ".node").c_str(), "r");
    if (cached) {
      std::fclose(cached);
      core = read_tetgen(core_cache);
    } else {
      core = tetrahedralize(s, MeshOptions{}, &cst);
      if (!core_cache.empty()) write_tetgen(core_cache, core);
    }
    const MeshCheckReport before = check_mesh(s, core);
    RefineStats st;
    const TetMesh m = refine_quality(s, core, o, &st);
    // Rounded mode: the boundary is checked against itself (see refine_mesh.h).
    const SurfaceMesh reference = o.surface_points == SurfacePoints::kRounded ? boundary_surface(m) : s;
    const MeshCheckReport r = check_mesh(reference, m);
    std::printf("%s: %s h %.6g core tets %d min_dihedral %.2f -> tets %d points %d min_dihedral %.2f p1 %.2f "
                "median %.2f max_radius_edge %.3g splits %lld (surface %lld, no exact point %lld, rejected %lld) "
                "collapses %lld flips %lld/%lld/%lld moves %lld inserted %lld long_left %lld core_s %.3f refine_s %.3f\n",
                argv[1], r.valid ? "VALID" : "INVALID", o.size, core.num_tets(), before.quality.min_dihedral_deg,
                m.num_tets(), m.num_points(), r.quality.min_dihedral_deg, r.quality.p1_dihedral_deg,
                r.quality.median_dihedral_deg, r.quality.max_radius_edge_ratio, static_cast<long long>(st.splits),
                static_cast<long long>(st.surface_splits), static_cast<long long>(st.splits_no_exact_point),
                static_cast<long long>(st.splits_rejected), static_cast<long long>(st.collapses),
                static_cast<long long>(st.flips23), static_cast<long long>(st.flips32),
                static_cast<long long>(st.edge_removals),
                static_cast<long long>(st.relocations), static_cast<long long>(st.insertions),
                static_cast<long long>(st.long_edges_left),
                cst.seconds_total, st.seconds);
    std::printf("  passes:");
    for (const auto& [pass, seconds] : st.seconds_by_pass) std::printf("  %s %.3f", pass.c_str(), seconds);
    std::printf("\n");
    for (const auto& msg : r.messages) std::printf("  %s\n", msg.c_str());
    if (!stem.empty()) write_tetgen(stem, m);
    return r.valid ? 0 : 1;
  } catch (const InputError& e) {
    std::printf("%s: INPUT ERROR %s\n", argv[1], e.what());
    return 2;
  } catch (const std::exception& e) {
    std::printf("%s: ERROR %s\n", argv[1], e.what());
    return 1;
  }
}
