// SPDX-License-Identifier: LGPL-2.1-or-later
// bsptet_mesh: the core from the command line, for debugging and benchmarks (users run `fembsptet`).
// Meshes one OFF surface, checks the result exactly and prints one line of figures.
//
//   bsptet_mesh SURFACE.off [--allow-boundary-steiner] [--debug-checks] [--cone-cells] [--seed auto|delaunay|box] [--along-lines] [--reorient]
//               [--progress] [--write STEM]
//
// --bsp-shift K: score the BSP's sampled candidate planes shifted by K (another partition; what the
//   core retries with, after --along-lines, when its Steiner removal gets stuck).
// --steiner-effort N: work (exact orientation tests, cavity growth) the core may spend on removing
//   one interior Steiner point (0: no limit).
// --along-lines: refine the faces on input planes along whole input edge lines (the fallback
//   tetrahedralize() uses by itself when the Steiner removal gets stuck).
// --progress: print each stage and its percentage to stderr as it goes.
// --cone-cells: fill the cells by cones (the filler before the per-cell Delaunay), for comparison.
// --seed: what the BSP starts from (MeshOptions::seed; default auto).
// --no-check: skip the exact check of the output (timing the core alone, as a benchmark beside
//   TetGen does; the benchmark then checks the written mesh itself). Prints UNCHECKED, exit 0.
//
// --pieces N / --max-piece-triangles K / --max-memory SIZE (e.g. 2G, 512M): the out-of-core mode
//   (out_of_core.h): the solid is cut into pieces of at most ceil(#T / N), K, or as many triangles
//   as SIZE allows by the program's estimate, meshed one after the other and streamed to --write
//   STEM (needed). Without --no-check each piece's mesh is checked exactly against its own surface
//   (which checks the whole mesh in one piece's memory) instead of the whole mesh at the end.
//
// The input is checked (surface_check.h: also self-intersections, non-manifold vertices and
// shells facing the wrong way; the self-intersection search runs beside the core, or beside the
// cut and the pieces, and stops them when it finds a crossing); --reorient flips triangles as that
// check allows.
//
// Exit: 0 valid mesh, 1 meshing error or invalid mesh, 2 bad input.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <thread>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/mesh/mesh_io.h"
#include "bsptet/core/mesher.h"
#include "bsptet/pieces/out_of_core.h"
#include "bsptet/input/surface_check.h"

using namespace bsptet;

// "2G", "512M", "1.5GiB", "1000000" -> bytes (binary units); -1 when it is not a size.
static long long parse_size(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  std::string unit(end);
  for (char& c : unit) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  double scale = 0;
  if (unit.empty() || unit == "b") scale = 1;
  else if (unit == "k" || unit == "kb" || unit == "kib") scale = 1024.0;
  else if (unit == "m" || unit == "mb" || unit == "mib") scale = 1024.0 * 1024;
  else if (unit == "g" || unit == "gb" || unit == "gib") scale = 1024.0 * 1024 * 1024;
  return end == text.c_str() || scale == 0 || !(v * scale >= 1) ? -1 : static_cast<long long>(v * scale);
}

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s SURFACE.off [--allow-boundary-steiner] [--debug-checks] [--cone-cells] [--seed auto|delaunay|box] [--along-lines] [--bsp-shift K] [--steiner-effort N] [--reorient] "
                 "[--progress] [--no-check] [--write STEM] [--pieces N | --max-piece-triangles K | --max-memory SIZE] [--workers W]\n",
                 argv[0]);
    return 2;
  }
  MeshOptions o;
  SurfaceCheckOptions check;
  std::string stem;
  bool no_check = false;
  long long pieces = 0, piece_triangles = 0, max_memory = 0;  // the out-of-core mode when any is set
  int workers = 1;                                             // pieces meshed at once
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--allow-boundary-steiner")) o.allow_boundary_steiner = true;
    else if (!std::strcmp(argv[i], "--debug-checks")) o.debug_checks = true;
    else if (!std::strcmp(argv[i], "--cone-cells")) o.cone_cells = true;
    else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) {
      const std::string m = argv[++i];
      if (m == "auto") o.seed = MeshOptions::Seed::kAuto;
      else if (m == "delaunay") o.seed = MeshOptions::Seed::kDelaunay;
      else if (m == "box") o.seed = MeshOptions::Seed::kBox;
      else {
        std::fprintf(stderr, "--seed: auto, delaunay or box, got %s\n", m.c_str());
        return 2;
      }
    }
    else if (!std::strcmp(argv[i], "--along-lines")) o.covered_faces_along_lines = true;
    else if (!std::strcmp(argv[i], "--bsp-shift") && i + 1 < argc) o.bsp_candidate_shift = std::strtoul(argv[++i], nullptr, 10);
    else if (!std::strcmp(argv[i], "--steiner-effort") && i + 1 < argc) o.steiner_effort = std::strtoll(argv[++i], nullptr, 10);
    else if (!std::strcmp(argv[i], "--reorient")) check.reorient = true;
    else if (!std::strcmp(argv[i], "--no-check")) no_check = true;
    else if (!std::strcmp(argv[i], "--progress"))
      o.progress = [last = std::string(), last_pct = -1](const std::string& stage, double f) mutable {
        const int pct = static_cast<int>(f * 100);
        if (stage != last) {
          // The resident memory now and its peak so far (Linux), at each new stage: where the
          // peak is reached.
          long hwm_kib = -1, rss_kib = -1;
          if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
            char line[256];
            while (std::fgets(line, sizeof line, f))
              if (std::sscanf(line, "VmHWM: %ld", &hwm_kib) != 1) std::sscanf(line, "VmRSS: %ld", &rss_kib);
            std::fclose(f);
          }
          if (hwm_kib >= 0)
            std::fprintf(stderr, "[memory %.1f MB, peak so far %.1f MB]\n", rss_kib / 1024.0, hwm_kib / 1024.0);
        }
        if (stage != last || pct != last_pct) std::fprintf(stderr, "[%s %d%%]\n", stage.c_str(), pct);
        last = stage;
        last_pct = pct;
      };
    else if (!std::strcmp(argv[i], "--write") && i + 1 < argc) stem = argv[++i];
    else if (!std::strcmp(argv[i], "--pieces") && i + 1 < argc) pieces = std::strtoll(argv[++i], nullptr, 10);
    else if (!std::strcmp(argv[i], "--workers") && i + 1 < argc) workers = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--max-piece-triangles") && i + 1 < argc) piece_triangles = std::strtoll(argv[++i], nullptr, 10);
    else if (!std::strcmp(argv[i], "--max-memory") && i + 1 < argc) {
      max_memory = parse_size(argv[++i]);
      if (max_memory < 0) {
        std::fprintf(stderr, "--max-memory: cannot read %s as a size (write e.g. 2G or 512M)\n", argv[i]);
        return 2;
      }
    }
    else {
      std::fprintf(stderr, "unknown argument %s\n", argv[i]);
      return 2;
    }
  }
  try {
    using Clock = std::chrono::steady_clock;
    auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    auto t0 = Clock::now();
    SurfaceMesh s = read_off(argv[1]);
    const double read_s = since(t0);
    // The surface check's self-intersection search runs beside the core (check_and_tetrahedralize);
    // "check beyond the core" below: the rest of the check, done first, and any wait for the search.
    if (pieces > 0 || piece_triangles > 0 || max_memory > 0 || workers > 1) {
      if (stem.empty()) {
        std::fprintf(stderr, "--pieces, --max-piece-triangles, --max-memory and --workers write the mesh as they go: give --write STEM\n");
        return 2;
      }
      // The check but its self-intersection search first; the search runs beside the cut and
      // the pieces (as check_and_tetrahedralize runs it beside the core) and stops them when it
      // finds a crossing.
      t0 = Clock::now();
      SurfaceCheckOptions first = check;
      first.self_intersections = false;
      s.tri = check_surface(s, first).tri;
      const double check_s = since(t0);
      std::atomic<bool> crossed{false};
      std::exception_ptr search_error;
      std::thread searcher([&] {
        try {
          check_self_intersections(s, check);
        } catch (...) {
          search_error = std::current_exception();
          crossed = true;
        }
      });
      o.cancelled = [&] { return crossed.load(); };
      // Rethrows the search's error (the pieces' files removed) once it is done.
      auto join_search = [&] {
        searcher.join();
        if (search_error) {
          std::remove((stem + ".node").c_str());
          std::remove((stem + ".ele").c_str());
          std::rethrow_exception(search_error);
        }
      };
      PieceOptions po;
      po.check_pieces = !no_check;
      po.workers = workers;
      po.max_piece_triangles = piece_triangles > 0 ? piece_triangles
                               : pieces > 0       ? (s.num_triangles() + pieces - 1) / pieces
                               : max_memory > 0   ? piece_triangles_for_budget(max_memory)
                                                  : piece_triangles_for_workers(s.num_triangles(), workers);
      if (o.progress) po.log = [](const std::string& line) { std::fprintf(stderr, "[%s]\n", line.c_str()); };
      PieceStats ps;
      try {
        tetrahedralize_in_pieces(s, o, po, stem, &ps);
      } catch (...) {
        join_search();
        throw;
      }
      join_search();
      for (const auto& line : ps.uncut) std::fprintf(stderr, "warning: %s\n", line.c_str());
      std::printf("%s: %s tets %lld points %lld steiner %lld pieces %lld (largest %lld triangles, at most %lld) cuts %lld "
                  "(refused %lld) cap_triangles %lld cap_points %lld\n  program: read %.3f s  check (its search beside) %.3f s  cutting %.3f s  meshing "
                  "%.3f s  writing %.3f s\n",
                  argv[1], no_check ? "UNCHECKED" : "VALID (each piece checked exactly)", static_cast<long long>(ps.tets),
                  static_cast<long long>(ps.points), static_cast<long long>(ps.steiner_points),
                  static_cast<long long>(ps.pieces), static_cast<long long>(ps.largest_piece_triangles),
                  static_cast<long long>(po.max_piece_triangles), static_cast<long long>(ps.cuts),
                  static_cast<long long>(ps.cuts_refused), static_cast<long long>(ps.cap_triangles),
                  static_cast<long long>(ps.cap_points), read_s, check_s,
                  ps.seconds_cutting, ps.seconds_meshing, ps.seconds_writing);
      return 0;
    }
    MeshStats st;
    t0 = Clock::now();
    SurfaceCheckResult checked;
    const TetMesh m = check_and_tetrahedralize(s, check, o, &st, &checked);
    s.tri = checked.tri;
    const double check_s = since(t0) - st.seconds_total;
    MeshCheckReport r;
    if (no_check) {
      r.valid = true;
      r.quality.min_dihedral_deg = std::nan("");
    } else {
      r = check_mesh(s, m);
    }
    std::printf("%s: %s tets %d points %d steiner %lld (before removal %lld, on surface %lld) collapsed %lld "
                "relocated %lld pushed %lld cells %lld inside %lld pulled %lld apex %lld delaunay %lld (recovered %lld) fallback %lld bsp_points %lld seconds %.3f "
                "min_dihedral %.2f%s%s\n",
                argv[1], no_check ? "UNCHECKED" : r.valid ? "VALID" : "INVALID", m.num_tets(), m.num_points(),
                static_cast<long long>(st.steiner_points), static_cast<long long>(st.steiner_before_removal),
                static_cast<long long>(st.boundary_steiner_before_removal), static_cast<long long>(st.collapsed),
                static_cast<long long>(st.relocated), static_cast<long long>(st.pushed), static_cast<long long>(st.convex_cells),
                static_cast<long long>(st.inside_cells), static_cast<long long>(st.pulled_cells),
                static_cast<long long>(st.apex_cells), static_cast<long long>(st.delaunay_cells),
                static_cast<long long>(st.delaunay_recovered_cells),
                static_cast<long long>(st.delaunay_fallback_cells),
                static_cast<long long>(st.bsp_points), st.seconds_total, r.quality.min_dihedral_deg,
                st.retried_along_lines ? " (retried along lines)" : "",
                st.bsp_candidate_shift ? (" (retried with BSP candidate shift " + std::to_string(st.bsp_candidate_shift) + ")").c_str() : "");
    if (st.seed_tets > 0 || st.seed_fell_back)
      std::printf("  seed: tets %lld (untouched %lld) missing edges %lld recovered %lld missing faces %lld recovered %lld flips %lld conflicts %lld relabelled faces %lld used %lld fell_back %lld\n",
                  static_cast<long long>(st.seed_tets), static_cast<long long>(st.seed_untouched_tets),
                  static_cast<long long>(st.seed_missing_edges),
                  static_cast<long long>(st.seed_recovered_edges), static_cast<long long>(st.seed_missing_faces),
                  static_cast<long long>(st.seed_recovered_faces), static_cast<long long>(st.seed_flips),
                  static_cast<long long>(st.seed_conflicts),
                  static_cast<long long>(st.seed_faces_relabelled), static_cast<long long>(st.delaunay_seeded),
                  static_cast<long long>(st.seed_fell_back));
    for (const auto& [stage, sec] : st.seconds_by_stage) std::printf("  %s %.3f", stage.c_str(), sec);
    std::printf("\n  steiner removal:");
    for (const auto& [phase, sec] : st.steiner_seconds_by_phase)
      std::printf("  %s %.3f s -%lld", phase.c_str(), sec,
                  static_cast<long long>(st.steiner_removed_by_phase.at(phase)));
    std::printf("\n");
    for (const auto& msg : r.messages) std::printf("  %s\n", msg.c_str());
    t0 = Clock::now();
    if (!stem.empty()) write_tetgen(stem, m);
    std::printf("  program: read %.3f s  check beyond the core %.3f s  write %.3f s\n", read_s, check_s, since(t0));
    return r.valid ? 0 : 1;
  } catch (const InputError& e) {
    std::printf("%s: INPUT ERROR %s\n", argv[1], e.what());
    return 2;
  } catch (const std::exception& e) {
    std::printf("%s: ERROR %s\n", argv[1], e.what());
    return 1;
  }
}
