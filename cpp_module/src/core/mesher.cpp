// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/mesher.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <system_error>
#include <thread>
#include <tuple>
#include <unordered_map>

#include "bsptet/core/bsp_complex.h"
#include "bsptet/core/cell_classify.h"
#include "bsptet/core/cell_tetrahedralize.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/implicit_geometry.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/core/snap_round.h"
#include "bsptet/core/steiner_removal.h"
#include "bsptet/input/surface_check.h"

namespace bsptet {

namespace {

using Clock = std::chrono::steady_clock;

std::string tri_str(const SurfaceMesh& s, Index t) {
  return "triangle " + std::to_string(t) + " (vertices " + std::to_string(s.tri[3 * t]) + " " +
         std::to_string(s.tri[3 * t + 1]) + " " + std::to_string(s.tri[3 * t + 2]) + ")";
}

// Groups the triangles by exact plane: a canonical rational key (the plane equation divided by
// its first non-zero normal component, each entry truncated to a double: a function of the exact
// values alone) finds candidates, an exact orientation test confirms. A triangle sharing an edge
// with one of the plane's triangles and exactly coplanar with it joins that plane without a key
// (a planar CAD face is one key, not one per triangle).
std::vector<Index> group_planes(ImplicitGeometry& geo, const SurfaceMesh& s) {
  const Index nt = s.num_triangles();
  std::vector<Index> tri_plane(nt, -1);
  // The triangles across each edge: slot 3t + e (edge e of t) -> the run of edge_tri holding
  // every slot on the same undirected edge (two on a closed manifold surface).
  std::vector<std::pair<std::uint64_t, Index>> edge_tri;  // (edge key, slot)
  edge_tri.reserve(3 * static_cast<std::size_t>(nt));
  for (Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      Index u = s.tri[3 * t + k], w = s.tri[3 * t + (k + 1) % 3];
      if (u > w) std::swap(u, w);
      edge_tri.push_back({(static_cast<std::uint64_t>(static_cast<std::uint32_t>(u)) << 32) | static_cast<std::uint32_t>(w),
                          3 * t + k});
    }
  std::sort(edge_tri.begin(), edge_tri.end());
  std::vector<std::pair<Index, Index>> run_of(3 * static_cast<std::size_t>(nt));  // [begin, end) in edge_tri
  for (std::size_t i = 0; i < edge_tri.size();) {
    std::size_t j = i;
    while (j < edge_tri.size() && edge_tri[j].first == edge_tri[i].first) ++j;
    for (std::size_t k = i; k < j; ++k) run_of[edge_tri[k].second] = {static_cast<Index>(i), static_cast<Index>(j)};
    i = j;
  }
  struct KeyHash {
    std::size_t operator()(const std::array<double, 4>& k) const {
      std::uint64_t h = 0x9E3779B97F4A7C15ULL;
      for (double d : k) {
        std::uint64_t bits;
        const double z = d + 0.0;  // -0.0 hashes as 0.0
        std::memcpy(&bits, &z, sizeof bits);
        h = (h ^ bits) * 0x100000001B3ULL;
        h ^= h >> 29;
      }
      return static_cast<std::size_t>(h);
    }
  };
  // key -> first entry of its chain in `reps` (plane, representative triangle, next entry or -1).
  std::unordered_map<std::array<double, 4>, Index, KeyHash> buckets;
  buckets.reserve(static_cast<std::size_t>(nt));
  struct Rep {
    Index plane, tri, next;
  };
  std::vector<Rep> reps;
  std::vector<Index> patch;
  for (Index t0 = 0; t0 < nt; ++t0) {
    if (tri_plane[t0] >= 0) continue;
    const Index a = s.tri[3 * t0], b = s.tri[3 * t0 + 1], c = s.tri[3 * t0 + 2];
    const Vec3 pa = s.point(a), pb = s.point(b), pc = s.point(c);
    const ExactFloat ax(pa.x), ay(pa.y), az(pa.z);
    const ExactFloat ux = ExactFloat(pb.x) - ax, uy = ExactFloat(pb.y) - ay, uz = ExactFloat(pb.z) - az;
    const ExactFloat vx = ExactFloat(pc.x) - ax, vy = ExactFloat(pc.y) - ay, vz = ExactFloat(pc.z) - az;
    const ExactFloat n[3] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
    const ExactFloat d = n[0] * ax + n[1] * ay + n[2] * az;
    int k = 0;
    while (k < 3 && n[k].sign() == 0) ++k;
    std::array<double, 4> key;
    for (int i = 0; i < 3; ++i) key[i] = n[i].truncated_quotient(n[k]);
    key[3] = d.truncated_quotient(n[k]);
    const auto slot = buckets.try_emplace(key, -1).first;
    Index plane = -1;
    for (Index r = slot->second; r >= 0 && plane < 0; r = reps[r].next) {
      const Index rep = reps[r].tri;
      const Vec3 ra = s.point(s.tri[3 * rep]), rb = s.point(s.tri[3 * rep + 1]), rc = s.point(s.tri[3 * rep + 2]);
      if (orient3d(ra, rb, rc, pa) == Sign::kZero && orient3d(ra, rb, rc, pb) == Sign::kZero &&
          orient3d(ra, rb, rc, pc) == Sign::kZero)
        plane = reps[r].plane;
    }
    if (plane < 0) {
      plane = geo.add_plane(a, b, c);
      // At the chain's head (distinct planes are not coplanar: at most one entry can match).
      reps.push_back({plane, t0, slot->second});
      slot->second = static_cast<Index>(reps.size() - 1);
    }
    // The edge-connected triangles exactly on t0's plane.
    tri_plane[t0] = plane;
    patch.assign(1, t0);
    for (std::size_t h = 0; h < patch.size(); ++h) {
      const Index t = patch[h];
      for (int e = 0; e < 3; ++e) {
        const Index u = s.tri[3 * t + e], w = s.tri[3 * t + (e + 1) % 3];
        const auto [rb, re] = run_of[3 * t + e];
        for (Index r = rb; r < re; ++r) {
          const Index o = edge_tri[r].second / 3;
          if (tri_plane[o] >= 0) continue;
          bool on = true;
          for (int j = 0; j < 3 && on; ++j) {
            const Index x = s.tri[3 * o + j];
            on = x == u || x == w || orient3d(pa, pb, pc, s.point(x)) == Sign::kZero;
          }
          if (!on) continue;
          tri_plane[o] = plane;
          patch.push_back(o);
        }
      }
    }
  }
  return tri_plane;
}

}  // namespace

namespace {

// validate_surface, returning the surface with coincident points merged (so callers need not
// merge again).
SurfaceMesh validated_surface(const SurfaceMesh& s) {
  const Index np = s.num_points(), nt = s.num_triangles();
  if (s.tri.size() % 3 != 0 || s.xyz.size() % 3 != 0)
    throw InputError(ErrorCode::kBadArgument, "input", -1, "arrays must have 3 columns");
  if (nt == 0) throw InputError(ErrorCode::kBadArgument, "input", -1, "the surface has no triangles");
  for (Index i = 0; i < np; ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(s.xyz[3 * i + k]))
        throw InputError(ErrorCode::kNonFiniteCoordinate, "input", i,
                         "vertex " + std::to_string(i) + " has a non-finite coordinate");
  for (Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      if (s.tri[3 * t + k] < 0 || s.tri[3 * t + k] >= np)
        throw InputError(ErrorCode::kBadArgument, "input", t,
                         "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(s.tri[3 * t + k]) +
                             ", out of range [0, " + std::to_string(np) + ")");
  const SurfaceMesh m = merge_coincident_points(s);
  // The first triangle (in input order) on the same three vertices as an earlier one.
  Index dup = -1, of = -1;
  {
    std::vector<std::pair<std::array<Index, 3>, Index>> keys(static_cast<std::size_t>(nt));
    for (Index t = 0; t < nt; ++t) {
      std::array<Index, 3> k = {m.tri[3 * t], m.tri[3 * t + 1], m.tri[3 * t + 2]};
      std::sort(k.begin(), k.end());
      keys[t] = {k, t};
    }
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 1; i < keys.size(); ++i)
      if (keys[i].first == keys[i - 1].first && (i < 2 || keys[i - 2].first != keys[i].first) &&
          (dup < 0 || keys[i].second < dup)) {
        dup = keys[i].second;
        of = keys[i - 1].second;
      }
  }
  for (Index t = 0; t < nt; ++t) {
    const Index a = m.tri[3 * t], b = m.tri[3 * t + 1], c = m.tri[3 * t + 2];
    const Vec3 pa = m.point(a), pb = m.point(b), pc = m.point(c);
    if (a == b || b == c || a == c ||
        (orient2d_projected(pa, pb, pc, 0) == Sign::kZero && orient2d_projected(pa, pb, pc, 1) == Sign::kZero &&
         orient2d_projected(pa, pb, pc, 2) == Sign::kZero))
      throw InputError(ErrorCode::kDegenerateTriangle, "input", t,
                       tri_str(s, t) + " is degenerate (zero area); remove it or repair the surface");
    if (t == dup)
      throw InputError(ErrorCode::kDuplicateTriangle, "input", dup,
                       tri_str(s, dup) + " duplicates triangle " + std::to_string(of));
  }
  // Directed edges (u << 32 | v) with their triangles, sorted: each must be matched by as many
  // uses of (v, u). The first failing edge in key order is reported.
  std::vector<std::pair<std::uint64_t, Index>> directed;
  directed.reserve(3 * static_cast<std::size_t>(nt));
  for (Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      directed.push_back({(static_cast<std::uint64_t>(m.tri[3 * t + k]) << 32) |
                              static_cast<std::uint32_t>(m.tri[3 * t + (k + 1) % 3]),
                          t});
  std::sort(directed.begin(), directed.end());
  auto uses = [&](std::uint64_t e) {
    const auto lo = std::lower_bound(directed.begin(), directed.end(), std::pair<std::uint64_t, Index>{e, -1});
    std::size_t n = 0;
    for (auto it = lo; it != directed.end() && it->first == e; ++it) ++n;
    return n;
  };
  for (std::size_t i = 0; i < directed.size();) {
    std::size_t j = i;
    while (j < directed.size() && directed[j].first == directed[i].first) ++j;
    const std::uint64_t e = directed[i].first;
    const std::size_t count = j - i;
    const Index t = directed[j - 1].second;  // the last triangle using it
    const std::size_t back = uses((e << 32) | (e >> 32));
    i = j;
    if (back == count) continue;
    const std::string edge = "(" + std::to_string(e >> 32) + " " + std::to_string(e & 0xffffffffu) + ")";
    if (back == 0 && count == 1)
      throw InputError(ErrorCode::kOpenBoundary, "input", t,
                       "edge " + edge + " of " + tri_str(s, t) +
                           " is used by only one triangle: the surface is open there (fill the hole)");
    if (back != count)
      throw InputError(ErrorCode::kInconsistentOrientation, "input", t,
                       "edge " + edge + " of " + tri_str(s, t) + " is used " + std::to_string(count) +
                           " times in one direction and " + std::to_string(back) +
                           " in the other: the triangles around it are inconsistently oriented or non-manifold");
  }
  return m;
}

}  // namespace

void validate_surface(const SurfaceMesh& s) { validated_surface(s); }

// Gives the pages of freed heap memory back to the system (glibc: malloc_trim also releases free
// pages inside the heap, not only at its top). Called once, after the seed: its temporaries (the
// points' Delaunay, face records, walks) are freed then, and without it they stayed resident under
// the splits' growth, whose end is the peak on inputs with many splits (the cube-sphere at 10^5
// triangles: 218 -> 208 MB). Not after the later stages: their freed memory does not raise a later
// peak, and pages given back are faulted in again when reused (5 to 10 % of the 10^5 CAD bottle's run
// on this machine).
static void return_free_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

// The implicit geometry of a checked surface: its points and the corners of the box around it
// (explicit vertices), the input triangles' planes grouped (`tri_plane`: each triangle's plane)
// and each input vertex noted on its triangles' planes. What the BSP is built on.
static std::unique_ptr<ImplicitGeometry> input_geometry(const SurfaceMesh& surface, std::vector<Index>* tri_plane) {
  std::vector<Vec3> pts;
  pts.reserve(surface.num_points() + 8);
  for (Index i = 0; i < surface.num_points(); ++i) pts.push_back(surface.point(i));
  for (const Vec3& c : BspComplex::box_corners(surface)) pts.push_back(c);
  auto geo = std::make_unique<ImplicitGeometry>(std::move(pts));
  for (Index i = 0; i < geo->num_explicit(); ++i) geo->add_explicit_vertex(i);
  *tri_plane = group_planes(*geo, surface);
  for (Index t = 0; t < surface.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) geo->note_on_plane(surface.tri[3 * t + k], (*tri_plane)[t]);
  return geo;
}

// `seeded` (may be null) is set as soon as the complex exists: did this attempt use the Delaunay
// seed (so that tetrahedralize knows what a failure means)? `surface_checked`: check_surface
// passed on `input` (check_and_tetrahedralize), so validate_surface's weaker checks are skipped.
static TetMesh tetrahedralize_once(const SurfaceMesh& input, const MeshOptions& options, MeshStats* stats,
                                   bool surface_checked, bool* seeded) {
  const auto t_start = Clock::now();
  MeshStats st;
  // Between stages too (the BSP and the Steiner removal also poll inside theirs).
  auto check_cancel = [&](const char* stage) {
    if (options.cancelled && options.cancelled()) throw MeshingError(ErrorCode::kCancelled, stage, -1, "cancelled");
  };
  auto stage_time = [&](const char* name, Clock::time_point since) {
    st.seconds_by_stage[name] += std::chrono::duration<double>(Clock::now() - since).count();
  };
  auto progress = [&](const std::string& stage, double f) {
    if (options.progress) options.progress(stage, f);
  };
  st.input_points = input.num_points();
  st.input_triangles = input.num_triangles();

  auto t0 = Clock::now();
  progress("checking the input", 0);
  const SurfaceMesh surface = surface_checked ? merge_coincident_points(input) : validated_surface(input);
  stage_time("input_check", t0);

  t0 = Clock::now();
  std::vector<Index> tri_plane;
  const std::unique_ptr<ImplicitGeometry> geometry = input_geometry(surface, &tri_plane);
  ImplicitGeometry& geo = *geometry;
  st.input_planes = geo.num_planes();
  stage_time("planes", t0);
  check_cancel("planes");

  t0 = Clock::now();
  using Seed = MeshOptions::Seed;
  // kAuto: the walks stop as soon as the conflicts pass the bound (then the box is cheaper).
  const std::int64_t max_seed_conflicts =
      options.seed == Seed::kAuto
          ? static_cast<std::int64_t>(MeshOptions::kSeedConflictsPerTriangle * static_cast<double>(surface.num_triangles()))
          : -1;
  auto complex = std::make_unique<BspComplex>(geo, surface, tri_plane,
                                              options.seed == Seed::kBox ? BspSeed::kBox : BspSeed::kDelaunay,
                                              max_seed_conflicts);
  st.seed_tets = complex->stats().seed_tets;
  st.seed_conflicts = complex->stats().seed_conflicts;
  st.seed_missing_edges = complex->stats().seed_missing_edges;
  st.seed_recovered_edges = complex->stats().seed_recovered_edges;
  st.seed_flips = complex->stats().seed_flips;
  st.seed_missing_faces = complex->stats().seed_missing_faces;
  st.seed_recovered_faces = complex->stats().seed_recovered_faces;
  for (const auto& [step, sec] : complex->stats().seed_seconds) st.seconds_by_stage[step] += sec;
  if (complex->stats().seed_abandoned) {
    complex.reset();
    complex = std::make_unique<BspComplex>(geo, surface, tri_plane, BspSeed::kBox);
  }
  return_free_memory();
  st.delaunay_seeded = complex->stats().seed_tets > 0 ? 1 : 0;
  st.seed_untouched_tets = complex->stats().untouched_tets;
  st.seed_faces_relabelled = complex->stats().seed_faces_relabelled;
  if (seeded) *seeded = st.delaunay_seeded != 0;
  check_cancel("bsp");
  BspComplex& bsp = *complex;
  bsp.set_candidate_shift(options.bsp_candidate_shift);
  bsp.set_debug_checks(options.debug_checks);
  if (options.debug_checks) bsp.check_consistency();
  bsp.build(options.cancelled, [&](double f) { progress("BSP tree", f); });
  bsp.identify_input_vertices();
  const Index before_refinement = geo.num_vertices();
  if (options.covered_faces_along_lines)
    bsp.refine_covered_faces_along_lines();
  else
    bsp.refine_covered_faces();
  bsp.identify_input_vertices(before_refinement);
  bsp.release_split_data();
  stage_time("bsp", t0);

  CellTets cell_tets;
  {
    t0 = Clock::now();
    progress("inside / outside", 0);
    const CellLabels labels = classify_cells(bsp);
    stage_time("classify", t0);
    check_cancel("classify");

    t0 = Clock::now();
    progress("tetrahedralizing cells", 0);
    cell_tets = tetrahedralize_cells(bsp, labels, options.cone_cells ? CellFill::kCone : CellFill::kDelaunay);
  }
  // The complex is not needed any more: free it before the Steiner removal builds its own mesh
  // (the two together made the peak memory). Its figures and the triangles' planes are kept.
  const BspStats bsp_stats = bsp.stats();
  const std::vector<Index> triangle_planes = bsp.triangle_planes();
  complex.reset();
  stage_time("cell_tets", t0);
  check_cancel("cell_tets");

  t0 = Clock::now();
  SteinerRemovalOptions so;
  so.allow_boundary_steiner = options.allow_boundary_steiner;
  so.interior_work_per_point = options.steiner_effort;
  so.cancelled = options.cancelled;
  so.progress = [&](double f) { progress("removing Steiner points", f); };
  SteinerRemovalStats ss;
  const std::vector<std::array<Index, 4>> tets =
      remove_steiner_points(geo, surface, triangle_planes, cell_tets, so, &ss);
  stage_time("steiner_removal", t0);

  t0 = Clock::now();
  progress("rounding", 0);
  std::int64_t steiner = 0;
  TetMesh mesh = snap_round(geo, tets, surface.num_points(), &steiner);
  stage_time("snap_round", t0);

  st.points = mesh.num_points();
  st.tets = mesh.num_tets();
  st.steiner_points = steiner;
  st.boundary_steiner_points = ss.boundary_steiner_after;
  st.steiner_before_removal = ss.steiner_before;
  st.boundary_steiner_before_removal = ss.boundary_steiner_before;
  st.collapsed = ss.collapsed;
  st.relocated = ss.relocated;
  st.steiner_seconds_by_phase = ss.seconds_by_phase;
  st.steiner_removed_by_phase = ss.removed_by_phase;
  st.pushed = ss.pushed;
  st.apex_cells = cell_tets.apex_cells;
  st.pulled_cells = cell_tets.pulled_cells;
  st.delaunay_cells = cell_tets.delaunay_cells;
  st.delaunay_recovered_cells = cell_tets.recovered_cells;
  st.delaunay_fallback_cells = cell_tets.delaunay_fallback_cells;
  st.bsp_nodes = 2 * bsp_stats.splits + (st.delaunay_seeded ? bsp_stats.seed_tets : 1);
  st.convex_cells = bsp_stats.leaves;
  st.inside_cells = cell_tets.inside_cells;
  st.bsp_points = bsp_stats.bsp_points;
  st.exact_fallbacks = geo.exact_fallbacks();
  st.seconds_total = std::chrono::duration<double>(Clock::now() - t_start).count();
  if (stats) *stats = st;
  return mesh;
}

// tetrahedralize (header), its retries; `surface_checked` as in tetrahedralize_once.
static TetMesh tetrahedralize_attempts(const SurfaceMesh& input, const MeshOptions& options, MeshStats* stats,
                                       bool surface_checked) {
  const auto t_start = Clock::now();
  // The Steiner removal can get stuck on a surface point it cannot move inside (a fan of slivers
  // from planes that pass within rounding of each other, docs/design/bsp-cells.md). Another complex has
  // other points and usually goes through: first the other refinement of the covered faces, then
  // other partitions (BspComplex::set_candidate_shift 1, 2), each as valid as the first. Anything
  // else (bad input, cancelled, other stages) is reported as it is, and so is the last attempt's
  // failure.
  // With the Delaunay seed, any internal failure or a contradiction in the inside/outside
  // labels (which a face of the seed on an input plane that the seed did not recognise as such
  // could cause, bsp_seed.cpp) is retried from the box, the paper's partition, with its own
  // retries: an input the box meshes is never refused because of the seed.
  // A seeded attempt stuck in the Steiner removal is first retried from the seed with another
  // partition (candidate shift 1): the seed's complex is far cheaper than the box's where many
  // nearly coplanar triangles cross (a rotated CAD tessellation: 5 s against 53 s on
  // no_print_feeder_body under bench/rotated_core.py's rotation 2).
  using Seed = MeshOptions::Seed;
  std::vector<MeshOptions> attempts{options};
  MeshOptions box = options;
  box.seed = Seed::kBox;
  std::size_t seeded_shift = attempts.size() + 99;  // the index of that attempt, if any
  if (options.seed != Seed::kBox) {
    MeshOptions other = options;
    other.bsp_candidate_shift = options.bsp_candidate_shift + 1;
    seeded_shift = attempts.size();
    attempts.push_back(other);
    attempts.push_back(box);
  }
  if (!options.covered_faces_along_lines) {
    MeshOptions lines = box;
    lines.covered_faces_along_lines = true;
    attempts.push_back(lines);
  }
  for (std::size_t shift : {1, 2}) {
    MeshOptions other = box;
    other.bsp_candidate_shift = options.bsp_candidate_shift + shift;
    attempts.push_back(other);
  }
  bool first_seeded = false, stuck_in_steiner = false, shift_skipped = false;
  for (std::size_t k = 0; k < attempts.size(); ++k) {
    if (k == seeded_shift && !(first_seeded && stuck_in_steiner)) {
      shift_skipped = true;  // not an attempt: not counted in `retries`
      continue;
    }
    bool seeded = false;
    try {
      MeshStats st;
      TetMesh mesh = tetrahedralize_once(input, attempts[k], &st, surface_checked, &seeded);
      if (k == 0) first_seeded = seeded;
      if (k > 0) {
        st.retries = static_cast<std::int64_t>(k) - (shift_skipped && k > seeded_shift ? 1 : 0);
        st.seed_fell_back = first_seeded && !seeded ? 1 : 0;
        st.retried_along_lines = attempts[k].covered_faces_along_lines && !options.covered_faces_along_lines;
        st.bsp_candidate_shift = static_cast<std::int64_t>(attempts[k].bsp_candidate_shift);
        const double total = std::chrono::duration<double>(Clock::now() - t_start).count();
        st.seconds_by_stage["first_run"] = total - st.seconds_total;  // every failed attempt
        st.seconds_total = total;
      }
      if (stats) *stats = st;
      return mesh;
    } catch (const InputError& e) {
      if (k == 0) first_seeded = seeded;
      if (k + 1 == attempts.size() || !seeded || e.stage() != "classify") throw;
      if (options.progress) options.progress("retrying from the box: " + std::string(e.what()), 0);
    } catch (const MeshingError& e) {
      if (k == 0) first_seeded = seeded;
      stuck_in_steiner = e.code() == ErrorCode::kInternal && e.stage() == "steiner";
      const bool retry = seeded ? e.code() == ErrorCode::kInternal
                                : e.code() == ErrorCode::kInternal && e.stage() == "steiner";
      if (k + 1 == attempts.size() || !retry) throw;
      if (options.progress) options.progress("retrying: " + std::string(e.what()), 0);
    }
    // A first attempt that took the box by itself (kAuto) has just been the box attempt.
    if (k == 0 && !seeded && options.seed != Seed::kBox) {
      k += 2;
      shift_skipped = true;
    }
  }
  throw MeshingError(ErrorCode::kInternal, "mesher", -1, "no attempt left");  // not reached
}

TetMesh tetrahedralize(const SurfaceMesh& input, const MeshOptions& options, MeshStats* stats) {
  return tetrahedralize_attempts(input, options, stats, false);
}

TetMesh check_and_tetrahedralize(const SurfaceMesh& input, const SurfaceCheckOptions& check,
                                 const MeshOptions& options, MeshStats* stats, SurfaceCheckResult* checked) {
  SurfaceCheckOptions quick = check;
  quick.self_intersections = false;
  SurfaceCheckResult result;
  try {
    result = check_surface(input, quick);
  } catch (const Error& e) {
    // Step 10 (shells facing the right way, and their nesting) comes after step 9: its errors stand
    // only when the surface does not cross itself.
    if (check.self_intersections && (e.code() == ErrorCode::kInwardFacing || e.code() == ErrorCode::kInternal))
      check_self_intersections(input, check);
    throw;
  }
  SurfaceMesh surface = input;
  surface.tri = result.tri;
  if (!check.self_intersections) {
    TetMesh mesh = tetrahedralize_attempts(surface, options, stats, true);
    if (checked) *checked = std::move(result);
    return mesh;
  }
  std::atomic<bool> crossed{false};
  std::exception_ptr check_error;
  auto search = [&] {
    try {
      check_self_intersections(input, check);
    } catch (...) {
      check_error = std::current_exception();
      crossed.store(true);
    }
  };
  // A small surface is searched first, on this thread: its search takes less than starting a
  // thread costs (about 1 ms with the second thread's memory arena; the search of 1,300 triangles
  // takes 2.5 ms, of 13,000 about 30 ms).
  constexpr Index kThreadedFrom = 4096;  // triangles
  std::thread searcher;
  try {
    if (input.num_triangles() >= kThreadedFrom) searcher = std::thread(search);
  } catch (const std::system_error&) {
    // no second thread to be had: searched first below
  }
  if (!searcher.joinable()) {
    search();
    if (check_error) std::rethrow_exception(check_error);
  }
  MeshOptions o = options;
  o.cancelled = [&] { return crossed.load(std::memory_order_relaxed) || (options.cancelled && options.cancelled()); };
  TetMesh mesh;
  std::exception_ptr mesh_error;
  try {
    mesh = tetrahedralize_attempts(surface, o, stats, true);
  } catch (...) {
    mesh_error = std::current_exception();
  }
  if (searcher.joinable()) searcher.join();
  if (check_error) std::rethrow_exception(check_error);
  if (mesh_error) std::rethrow_exception(mesh_error);
  if (checked) *checked = std::move(result);
  return mesh;
}

BspCellsView bsp_cells_view(const SurfaceMesh& input) {
  const SurfaceMesh surface = validated_surface(input);
  std::vector<Index> tri_plane;
  const std::unique_ptr<ImplicitGeometry> geometry = input_geometry(surface, &tri_plane);
  ImplicitGeometry& geo = *geometry;
  BspComplex bsp(geo, surface, tri_plane, BspSeed::kBox);
  bsp.build(nullptr, nullptr);
  bsp.identify_input_vertices();
  const CellLabels labels = classify_cells(bsp);

  BspCellsView view;
  view.points.reserve(static_cast<std::size_t>(geo.num_vertices()));
  for (Index v = 0; v < geo.num_vertices(); ++v) view.points.push_back(geo.rounded(v));
  const auto& faces = bsp.faces();
  for (Index c = 0; c < static_cast<Index>(bsp.cells().size()); ++c) {
    const BspCell& cell = bsp.cells()[c];
    if (!cell.alive) continue;
    std::vector<std::vector<Index>> cycles;
    for (const Index f : cell.faces) {
      const BspFace& face = faces[f];
      std::vector<Index> cycle = face.verts;
      // CCW around the plane normal, which points into cell[0]: seen from outside cell[0] the
      // cycle is clockwise, so reverse it there
      if (face.cell[0] == c) std::reverse(cycle.begin(), cycle.end());
      cycles.push_back(std::move(cycle));
    }
    view.cells.push_back(std::move(cycles));
    view.inside.push_back(labels.winding[static_cast<std::size_t>(c)] != 0 ? 1 : 0);
  }
  return view;
}

}  // namespace bsptet
