// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet FEM pipeline: CAD surface, core, refinement and merge of the solids (see fem_mesh.h).
#include "bsptet/fem/fem_mesh.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <system_error>
#include <thread>

#include "bsptet/cad/cad_projection.h"
#include "bsptet/cad/cad_split.h"
#include "bsptet/cad/cad_surface.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/core/mesher.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/tet10.h"
#include "bsptet/mesh/tet_shape.h"

namespace bsptet::fem {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Tet edges in the mid-node order of types.h: m12 m23 m31 m14 m24 m34.
constexpr int kTetEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

/// Rethrows a stage's error with the solid named first (same type, code and index).
[[noreturn]] void rethrow_for_solid(const Error& e, const cad::CadModel& model, int solid) {
  const std::string what = model.source + ": Solid" + std::to_string(solid + 1) + ": " + e.what();
  if (dynamic_cast<const InputError*>(&e)) throw InputError(e.code(), e.stage(), e.index(), what);
  throw MeshingError(e.code(), e.stage(), e.index(), what);
}

Vec3 midpoint(const Vec3& a, const Vec3& b) { return {0.5 * (a.x + b.x), 0.5 * (a.y + b.y), 0.5 * (a.z + b.z)}; }
bool same(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// The faces of solid s that bound another solid too: their surface stays as meshed.
std::vector<std::int32_t> fixed_tags_of(const std::vector<std::vector<std::int32_t>>& faces_of_solid,
                                        const std::vector<int>& solids_of_face, int s) {
  std::vector<std::int32_t> fixed;
  for (std::int32_t f : faces_of_solid[static_cast<std::size_t>(s)])
    if (solids_of_face[static_cast<std::size_t>(f)] > 1) fixed.push_back(f);
  return fixed;
}

// The result figures of `out` in `st`: nodes, tets, boundary triangles and the linear tets'
// dihedral angles (corner_nodes is the caller's).
void set_figures(const FemMesh& out, FemStats* st) {
  const int npt = out.mesh.nodes_per_tet;
  st->nodes = out.mesh.num_points();
  st->tets = out.mesh.num_tets();
  st->boundary_triangles = out.num_triangles();
  std::vector<double> worst(static_cast<std::size_t>(st->tets));
  for (Index k = 0; k < out.mesh.num_tets(); ++k) {
    const Index* q = &out.mesh.tet[static_cast<std::size_t>(npt * k)];
    worst[static_cast<std::size_t>(k)] =
        tet_min_dihedral_deg(out.mesh.point(q[0]), out.mesh.point(q[1]), out.mesh.point(q[2]), out.mesh.point(q[3]));
  }
  if (!worst.empty()) {
    st->min_dihedral_deg = *std::min_element(worst.begin(), worst.end());
    std::int64_t below = 0;
    for (double w : worst) below += w < 10 ? 1 : 0;
    st->tets_below_10_deg = static_cast<double>(below) / static_cast<double>(worst.size());
    std::nth_element(worst.begin(), worst.begin() + static_cast<std::ptrdiff_t>(worst.size() / 2), worst.end());
    st->median_tet_min_dihedral_deg = worst[worst.size() / 2];
  }
}

// One solid's core and refinement (stages 2 and 3), before the merge.
struct SolidMesh {
  std::vector<Index> node_of;  // the solid surface's nodes -> CAD surface nodes
  SurfaceMesh solid;           // the solid's closed CAD surface
  TetMesh refined;             // its refined mesh (the surface nodes first, in order)
  SurfaceMesh boundary;        // its boundary triangles with their CAD face tags
  MeshStats mst;
  RefineStats rst;
  cad::ProjectionStats projection;
  double seconds_core = 0, seconds_refine = 0;
};

using Report = std::function<void(const std::string&, double)>;

// Stages 2 and 3 for solid s. `cancelled` as MeshOptions::cancelled; `report(stage, f)` with f
// the fraction of this solid's work done.
SolidMesh mesh_solid(const cad::CadModel& model, const cad::CadSurface& surface, const cad::CadSurfaceStats& sst,
                     const std::vector<std::int32_t>& fixed_tags, const FemOptions& options, int s,
                     const std::function<bool()>& cancelled, const Report& report) {
  SolidMesh out;
  const std::string name = "Solid" + std::to_string(s + 1);
  out.solid = surface.solid_surface(s, &out.node_of);
  // Its own projector: CadProjector is not thread-safe, and its answers then depend on this
  // solid's calls only.
  std::shared_ptr<cad::CadProjector> projector;
  const ProjectionHook hook = cad::make_projection_hook(model, &projector);

  MeshOptions mo;
  mo.progress = [&](const std::string& stage, double f) { report(name + ": " + stage, 0.3 * f); };
  mo.cancelled = cancelled;
  auto t = Clock::now();
  try {
    out.refined = check_and_tetrahedralize(out.solid, SurfaceCheckOptions{}, mo, &out.mst);
  } catch (const Error& e) {
    if (e.code() == ErrorCode::kCancelled) throw;
    rethrow_for_solid(e, model, s);
  }
  out.seconds_core = seconds_since(t);

  RefineOptions ro;
  ro.size = sst.size;
  ro.min_size = sst.min_size;
  for (const auto& [face, size] : options.size_by_face) ro.size_by_tag[face] = size;
  ro.size_from_surface = true;
  ro.grading = options.grading;
  ro.order = options.order;
  ro.optimize_rounds = options.optimize_rounds;
  ro.projection = hook;
  ro.fixed_tags = fixed_tags;
  // Nodes inside a CAD face slide along it during smoothing (those of a shared face stay: the
  // refinement keeps fixed tags' nodes).
  ro.sliding_points.assign(out.node_of.size(), 0);
  for (std::size_t i = 0; i < out.node_of.size(); ++i)
    ro.sliding_points[i] = surface.node_dim[static_cast<std::size_t>(out.node_of[i])] == 2;
  ro.progress = [&](const std::string& stage, double f) { report(name + ": " + stage, 0.3 + 0.7 * f); };
  ro.cancelled = cancelled;
  t = Clock::now();
  try {
    const TetMesh core = std::move(out.refined);
    out.refined = refine_quality(out.solid, core, ro, &out.rst, &out.boundary);
  } catch (const Error& e) {
    if (e.code() == ErrorCode::kCancelled) throw;
    rethrow_for_solid(e, model, s);
  }
  out.seconds_refine = seconds_since(t);
  out.projection = projector->stats();
  return out;
}

// Stages 2 and 3 for every solid, at most options.workers (0: the machine's cores) at a time;
// the results do not depend on how many. Progress goes to `report` as the whole run's fraction
// (0.1 to 1: the surface took the first tenth), serialized and never going back. The first
// error in solid order is rethrown once all threads have stopped; an error stops the others.
std::vector<SolidMesh> mesh_solids(const cad::CadModel& model, const cad::CadSurface& surface,
                                   const cad::CadSurfaceStats& sst,
                                   const std::vector<std::vector<std::int32_t>>& faces_of_solid,
                                   const std::vector<int>& solids_of_face, const FemOptions& options,
                                   const Report& report) {
  const int n = model.num_solids();
  std::vector<SolidMesh> meshed(static_cast<std::size_t>(n));
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(n));
  std::vector<double> done(static_cast<std::size_t>(n), 0.0);
  std::mutex mutex;  // guards next, stop, done, shown and the caller's callbacks
  int next = 0;
  bool stop = false;
  double shown = 0.1;
  const auto cancelled = [&]() {
    std::lock_guard<std::mutex> lock(mutex);
    return stop || (options.cancelled && options.cancelled());
  };
  auto work = [&]() {
    for (;;) {
      int s;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (stop || next == n) return;
        s = next++;
      }
      try {
        if (cancelled()) throw MeshingError(ErrorCode::kCancelled, "fem", -1, "cancelled");
        const Report solid_report = [&](const std::string& stage, double f) {
          std::lock_guard<std::mutex> lock(mutex);
          done[static_cast<std::size_t>(s)] = std::clamp(f, 0.0, 1.0);
          double sum = 0;
          for (double d : done) sum += d;
          shown = std::max(shown, 0.1 + 0.9 * sum / n);
          report(stage, shown);
        };
        meshed[static_cast<std::size_t>(s)] = mesh_solid(model, surface, sst, fixed_tags_of(faces_of_solid, solids_of_face, s),
                                                         options, s, cancelled, solid_report);
        std::lock_guard<std::mutex> lock(mutex);
        done[static_cast<std::size_t>(s)] = 1.0;
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        errors[static_cast<std::size_t>(s)] = std::current_exception();
        stop = true;
      }
    }
  };
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const int workers = std::min(n, options.workers > 0 ? options.workers : static_cast<int>(cores));
  std::vector<std::thread> threads;
  try {
    for (int w = 1; w < workers; ++w) threads.emplace_back(work);
  } catch (const std::system_error&) {
    // no more threads to be had: the ones started and this one share the solids
  }
  work();
  for (auto& thread : threads) thread.join();
  // A solid stopped because another failed reports kCancelled: the other's error comes first.
  std::exception_ptr first_cancel;
  for (const auto& e : errors) {
    if (!e) continue;
    try {
      std::rethrow_exception(e);
    } catch (const Error& error) {
      if (error.code() != ErrorCode::kCancelled) throw;
      if (!first_cancel) first_cancel = e;
    }
  }
  if (first_cancel) std::rethrow_exception(first_cancel);
  return meshed;
}

}  // namespace

void check_fem_options(const FemOptions& o) {
  auto bad = [](const std::string& what) { throw InputError(ErrorCode::kBadArgument, "fem", -1, what); };
  auto non_negative = [&](double value, const char* name) {
    if (!std::isfinite(value) || value < 0) {
      std::ostringstream what;
      what << "option " << name << " must be a finite number >= 0, got " << value;
      bad(what.str());
    }
  };
  non_negative(o.size, "size");
  non_negative(o.min_size, "min_size");
  non_negative(o.points_per_circle, "points_per_circle");
  non_negative(o.grading, "grading");
  if (o.order != 1 && o.order != 2) bad("option order must be 1 or 2, got " + std::to_string(o.order));
  if (o.optimize_rounds < 0) bad("option optimize_rounds must be >= 0");
  if (o.face_rounds < 0) bad("option face_rounds must be >= 0");
  if (o.workers < 0) bad("option workers must be >= 0 (0: every core)");
  for (const auto& [face, size] : o.size_by_face) {
    if (!std::isfinite(size) || size <= 0) {
      std::ostringstream what;
      what << "option size_by_face: the size of Face" << face + 1 << " must be a finite number > 0, got " << size;
      bad(what.str());
    }
  }
}

cad::CadSurfaceOptions cad_surface_options(const FemOptions& options) {
  cad::CadSurfaceOptions so;
  so.size.size = options.size;
  so.size.min_size = options.min_size;
  so.size.points_per_circle = options.points_per_circle;
  so.size.grading = options.grading;
  so.size.size_by_face = options.size_by_face;
  so.face_rounds = options.face_rounds;
  so.cancelled = options.cancelled;
  return so;
}

namespace {

// Stages 1 to 4 on `model` (the file comment of fem_mesh.h); `given` (with `given_stats`): stage
// 1's surface when it is already made. Progress goes to `report` (fractions of this run).
FemMesh mesh_model(const cad::CadModel& model, const FemOptions& options, const cad::CadSurface* given,
                   const cad::CadSurfaceStats* given_stats, Clock::time_point start, const Report& report,
                   FemStats* stats,
                   const std::map<int, std::vector<std::pair<Vec3, double>>>& size_sources = {}) {
  FemStats st;
  st.solids = model.num_solids();
  st.faces = model.num_faces();
  st.pieces = model.num_solids();
  const int n_solids = model.num_solids();
  // ---- 1. Surface. ----
  cad::CadSurfaceOptions so = cad_surface_options(options);
  so.size_sources = size_sources;
  so.progress = [&](const std::string& stage, double f) { report("surface: " + stage, 0.1 * f); };
  cad::CadSurfaceStats sst;
  auto t = Clock::now();
  cad::CadSurface made;
  if (given)
    sst = *given_stats;
  else
    made = cad::mesh_cad_surface(model, so, &sst);
  const cad::CadSurface& surface = given ? *given : made;
  st.seconds_surface = given ? sst.seconds : seconds_since(t);
  st.size = sst.size;
  st.min_size = sst.min_size;
  st.surface_nodes = sst.nodes;
  st.surface_triangles = sst.triangles;

  // Faces that bound two solids: kept as meshed in both (fem_mesh.h).
  std::vector<int> solids_of_face(static_cast<std::size_t>(model.num_faces()), 0);
  std::vector<std::vector<std::int32_t>> faces_of_solid(static_cast<std::size_t>(n_solids));
  for (int s = 0; s < n_solids; ++s) {
    auto& faces = faces_of_solid[static_cast<std::size_t>(s)];
    faces = surface.solid_tag[static_cast<std::size_t>(s)];
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    for (std::int32_t f : faces) ++solids_of_face[static_cast<std::size_t>(f)];
  }
  for (int n : solids_of_face) st.shared_faces += n > 1 ? 1 : 0;

  // Merged numbering: corner nodes (the CAD surface nodes first), mid-nodes apart until the end.
  std::vector<double> corner_xyz = surface.xyz;
  std::vector<Vec3> mid_xyz;
  std::vector<std::array<Index, 2>> mid_edge;          // merged corner ids of each mid-node's edge
  std::vector<char> mid_conflict;                      // two solids placed it differently
  std::map<std::array<Index, 2>, Index> mid_of_edge;   // sorted corner pair -> mid-node
  std::vector<Index> tets;                             // merged ids; mid-nodes as -(1 + mid index)
  FemMesh out;
  out.solid_names = model.solid_names;
  out.face_names = model.face_names;
  // Triangles, deduplicated by their sorted corners (a shared face's triangles come twice).
  std::set<std::array<Index, 3>> seen_triangles;
  std::vector<std::array<Index, 3>> tri_corners;
  const int npt = options.order == 2 ? 10 : 4;

  // ---- 2 and 3. Core and refinement of every solid, options.workers at a time (fem_mesh.h). ----
  const std::vector<SolidMesh> meshed = mesh_solids(model, surface, sst, faces_of_solid, solids_of_face, options, report);
  for (const SolidMesh& m : meshed) {
    st.seconds_core += m.seconds_core;
    st.core_points += m.mst.points;
    st.core_tets += m.mst.tets;
    st.core_steiner_points += m.mst.steiner_points;
    const RefineStats& rst = m.rst;
    st.seconds_refine += m.seconds_refine;
    st.surface_splits += rst.surface_splits;
    st.refinement_points += rst.refinement_points;
    st.interior_splits += rst.splits - rst.surface_splits;
    st.collapses += rst.collapses;
    st.splits_fixed_surface += rst.splits_fixed_surface;
    st.projection_refused += rst.projection_rejected;
    st.midnodes_projected += rst.midnodes_projected;
    st.midnodes_straightened += rst.midnodes_straightened;
    st.curving_conflicts_left += rst.curving_conflicts_left;
    st.refine_worst_deg_optimized = std::min(st.refine_worst_deg_optimized, rst.worst_deg_optimized);
    st.refine_worst_deg = std::min(st.refine_worst_deg, rst.worst_deg);
    st.midnodes_relaxed_tets += rst.midnodes_relaxed_tets;
    st.midnodes_moved_interior += rst.midnodes_moved_interior;
    st.midnodes_moved_surface += rst.midnodes_moved_surface;
    st.lift_insertions += rst.lift_insertions;
    for (const auto& [pass, seconds] : rst.seconds_by_pass) st.refine_seconds_by_pass[pass] += seconds;
    st.projection.face_calls += m.projection.face_calls;
    st.projection.edge_calls += m.projection.edge_calls;
    st.projection.outside_trim += m.projection.outside_trim;
    st.projection.face_fallbacks += m.projection.face_fallbacks;
    st.projection.no_common_edge += m.projection.no_common_edge;
  }

  for (int s = 0; s < n_solids; ++s) {
    const std::string name = "Solid" + std::to_string(s + 1);
    const SolidMesh& sm = meshed[static_cast<std::size_t>(s)];
    const SurfaceMesh& solid = sm.solid;
    const std::vector<Index>& node_of = sm.node_of;
    const TetMesh& refined = sm.refined;
    const SurfaceMesh& boundary = sm.boundary;

    // ---- 4. Merge this solid. ----
    t = Clock::now();
    // The core and the refinement keep the input points first, in order (mesher.h,
    // quality_refine.h): the solid's surface nodes are the CAD nodes node_of[i].
    // A node inside a CAD face that only this solid has may have slid along the face.
    const Index n_surface = solid.num_points();
    for (Index i = 0; i < n_surface; ++i) {
      const std::size_t cad_node = static_cast<std::size_t>(node_of[static_cast<std::size_t>(i)]);
      if (i < refined.num_points() && same(refined.point(i), solid.point(i))) continue;
      if (i >= refined.num_points() || surface.node_dim[cad_node] != 2 ||
          solids_of_face[static_cast<std::size_t>(surface.node_entity[cad_node])] != 1)
        throw MeshingError(ErrorCode::kInternal, "fem", i,
                           model.source + ": " + name + ": surface node " + std::to_string(i) +
                               " is not at its place in the refined mesh");
      const Vec3 p = refined.point(i);
      corner_xyz[3 * cad_node] = p.x, corner_xyz[3 * cad_node + 1] = p.y, corner_xyz[3 * cad_node + 2] = p.z;
    }
    std::vector<Index> corner_of(static_cast<std::size_t>(refined.num_points()), -1);
    for (Index i = 0; i < n_surface; ++i) corner_of[static_cast<std::size_t>(i)] = node_of[static_cast<std::size_t>(i)];
    const Index nk = refined.num_tets();
    for (Index k = 0; k < nk; ++k)
      for (int c = 0; c < 4; ++c) {
        const Index v = refined.tet[static_cast<std::size_t>(npt * k + c)];
        Index& id = corner_of[static_cast<std::size_t>(v)];
        if (id >= 0) continue;
        id = static_cast<Index>(corner_xyz.size() / 3);
        const Vec3 p = refined.point(v);
        corner_xyz.insert(corner_xyz.end(), {p.x, p.y, p.z});
      }
    auto mid_id = [&](Index a, Index b, const Vec3& p) {
      const std::array<Index, 2> key{std::min(a, b), std::max(a, b)};
      auto [it, fresh] = mid_of_edge.emplace(key, static_cast<Index>(mid_xyz.size()));
      if (fresh) {
        mid_xyz.push_back(p);
        mid_edge.push_back(key);
        mid_conflict.push_back(0);
      } else if (!same(mid_xyz[static_cast<std::size_t>(it->second)], p)) {
        mid_conflict[static_cast<std::size_t>(it->second)] = 1;
      }
      return it->second;
    };
    for (Index k = 0; k < nk; ++k) {
      const Index* q = &refined.tet[static_cast<std::size_t>(npt * k)];
      std::array<Index, 4> c{};
      for (int i = 0; i < 4; ++i) c[i] = corner_of[static_cast<std::size_t>(q[i])];
      tets.insert(tets.end(), c.begin(), c.end());
      if (npt == 10)
        for (int e = 0; e < 6; ++e)
          tets.push_back(-1 - mid_id(c[kTetEdge[e][0]], c[kTetEdge[e][1]], refined.point(q[4 + e])));
      out.tet_solid.push_back(s);
    }
    for (Index f = 0; f < boundary.num_triangles(); ++f) {
      std::array<Index, 3> c{};
      for (int i = 0; i < 3; ++i) c[i] = corner_of[static_cast<std::size_t>(boundary.tri[static_cast<std::size_t>(3 * f + i)])];
      std::array<Index, 3> key = c;
      std::sort(key.begin(), key.end());
      if (!seen_triangles.insert(key).second) continue;
      tri_corners.push_back(c);
      out.tri_face.push_back(boundary.tag[static_cast<std::size_t>(f)]);
    }
    st.seconds_merge += seconds_since(t);
  }

  t = Clock::now();
  const Index n_mid = static_cast<Index>(mid_xyz.size());
  auto corner = [&](Index v) {
    return Vec3{corner_xyz[3 * static_cast<std::size_t>(v)], corner_xyz[3 * static_cast<std::size_t>(v) + 1],
                corner_xyz[3 * static_cast<std::size_t>(v) + 2]};
  };
  auto chord = [&](Index m) {
    const auto& e = mid_edge[static_cast<std::size_t>(m)];
    return midpoint(corner(e[0]), corner(e[1]));
  };
  if (npt == 10) {
    // Shared mid-nodes two solids placed differently go on their chord; then every curved tet that
    // is not valid gets its mid-nodes on their chords, until all pass (a straight tet passes when
    // its corners are positive).
    std::vector<char> dirty(static_cast<std::size_t>(n_mid), 0);
    for (Index m = 0; m < n_mid; ++m)
      if (mid_conflict[static_cast<std::size_t>(m)]) {
        ++st.midnodes_reconciled;
        mid_xyz[static_cast<std::size_t>(m)] = chord(m);
        dirty[static_cast<std::size_t>(m)] = 1;
      }
    const Index nk = static_cast<Index>(out.tet_solid.size());
    for (bool changed = st.midnodes_reconciled > 0; changed;) {
      changed = false;
      for (Index k = 0; k < nk; ++k) {
        const Index* q = &tets[static_cast<std::size_t>(10 * k)];
        bool touched = false;
        for (int e = 0; e < 6; ++e) touched = touched || dirty[static_cast<std::size_t>(-1 - q[4 + e])];
        if (!touched) continue;
        double x[30];
        for (int i = 0; i < 10; ++i) {
          const Vec3 p = i < 4 ? corner(q[i]) : mid_xyz[static_cast<std::size_t>(-1 - q[i])];
          x[3 * i] = p.x, x[3 * i + 1] = p.y, x[3 * i + 2] = p.z;
        }
        if (certify_tet10(x) == Tet10Validity::kCertified) continue;
        for (int e = 0; e < 6; ++e) {
          const Index m = -1 - q[4 + e];
          const Vec3 c = chord(m);
          if (same(mid_xyz[static_cast<std::size_t>(m)], c)) continue;
          mid_xyz[static_cast<std::size_t>(m)] = c;
          dirty[static_cast<std::size_t>(m)] = 1;
          ++st.midnodes_straightened_at_merge;
          changed = true;
        }
      }
    }
  }

  // Final numbering: used corner nodes in order, then the mid-nodes.
  const Index n_corner_all = static_cast<Index>(corner_xyz.size() / 3);
  std::vector<Index> renum(static_cast<std::size_t>(n_corner_all), -1);
  for (std::size_t i = 0; i < tets.size(); ++i)
    if (npt == 4 || i % 10 < 4) renum[static_cast<std::size_t>(tets[i])] = 0;
  Index n_corner = 0;
  for (Index v = 0; v < n_corner_all; ++v)
    if (renum[static_cast<std::size_t>(v)] == 0) {
      renum[static_cast<std::size_t>(v)] = n_corner++;
      const Vec3 p = corner(v);
      out.mesh.xyz.insert(out.mesh.xyz.end(), {p.x, p.y, p.z});
    }
  for (const Vec3& p : mid_xyz) out.mesh.xyz.insert(out.mesh.xyz.end(), {p.x, p.y, p.z});
  auto final_id = [&](Index v) { return v >= 0 ? renum[static_cast<std::size_t>(v)] : n_corner + (-1 - v); };
  out.mesh.nodes_per_tet = npt;
  out.mesh.tet.reserve(tets.size());
  for (Index v : tets) out.mesh.tet.push_back(final_id(v));
  out.nodes_per_triangle = npt == 10 ? 6 : 3;
  for (const auto& c : tri_corners) {
    for (Index v : c) out.tri.push_back(renum[static_cast<std::size_t>(v)]);
    if (npt == 10)
      for (int e = 0; e < 3; ++e) {
        const Index a = c[e], b = c[(e + 1) % 3];
        auto it = mid_of_edge.find({std::min(a, b), std::max(a, b)});
        if (it == mid_of_edge.end())
          throw MeshingError(ErrorCode::kInternal, "fem", -1,
                             model.source + ": a face triangle's edge has no mid-node in the tets");
        out.tri.push_back(n_corner + it->second);
      }
  }
  st.seconds_merge += seconds_since(t);

  st.corner_nodes = n_corner;
  set_figures(out, &st);
  st.seconds_total = seconds_since(start);
  report("done", 1.0);
  if (stats) *stats = st;
  return out;
}

// Smooths the nodes that lie exactly on the plane x_axis = position inside the merged mesh of a
// cut model (the cut faces' nodes, fixed while the halves were meshed apart; see cad_split.h),
// `sweeps` times in node order: each moves towards the centroid of its tets' other corners (all
// the way, half, a quarter) when its tets stay positive (exact), certified as tet10 with the
// mid-nodes of its edges at their new midpoints, none gets a worst dihedral below the lower of
// its old worst and 30 degrees, and their mean worst angle rises. Returns the moves made.
std::int64_t smooth_cut_nodes(FemMesh& out, int axis, double position, int sweeps) {
  TetMesh& m = out.mesh;
  const int npt = m.nodes_per_tet;
  const Index np = m.num_points(), nk = m.num_tets();
  std::vector<char> movable(static_cast<std::size_t>(np), 0);
  for (Index k = 0; k < nk; ++k)
    for (int c = 0; c < 4; ++c) {
      const Index v = m.tet[static_cast<std::size_t>(npt * k + c)];
      const Vec3 p = m.point(v);
      movable[static_cast<std::size_t>(v)] = (axis == 0 ? p.x : axis == 1 ? p.y : p.z) == position;
    }
  for (Index v : out.tri) movable[static_cast<std::size_t>(v)] = 0;  // the boundary stays
  std::vector<std::vector<Index>> ball(static_cast<std::size_t>(np));
  for (Index k = 0; k < nk; ++k)
    for (int c = 0; c < 4; ++c) {
      const Index v = m.tet[static_cast<std::size_t>(npt * k + c)];
      if (movable[static_cast<std::size_t>(v)]) ball[static_cast<std::size_t>(v)].push_back(k);
    }
  const auto corner = [&](Index k, int c) { return m.point(m.tet[static_cast<std::size_t>(npt * k + c)]); };
  const auto set_point = [&](Index v, const Vec3& p) {
    m.xyz[3 * static_cast<std::size_t>(v)] = p.x, m.xyz[3 * static_cast<std::size_t>(v) + 1] = p.y;
    m.xyz[3 * static_cast<std::size_t>(v) + 2] = p.z;
  };
  std::int64_t moves = 0;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    std::int64_t moved = 0;
    for (Index v = 0; v < np; ++v) {
      const std::vector<Index>& b = ball[static_cast<std::size_t>(v)];
      if (b.empty()) continue;
      const Vec3 old = m.point(v);
      std::vector<Sign> sign(b.size());
      double worst_before = 180, mean_before = 0;
      Vec3 centroid{0, 0, 0};
      int others = 0;
      for (std::size_t i = 0; i < b.size(); ++i) {
        sign[i] = orient3d(corner(b[i], 0), corner(b[i], 1), corner(b[i], 2), corner(b[i], 3));
        const double q = tet_min_dihedral_deg(corner(b[i], 0), corner(b[i], 1), corner(b[i], 2), corner(b[i], 3));
        worst_before = std::min(worst_before, q);
        mean_before += q / static_cast<double>(b.size());
        for (int c = 0; c < 4; ++c) {
          const Vec3 p = corner(b[i], c);
          if (m.tet[static_cast<std::size_t>(npt * b[i] + c)] == v) continue;
          centroid.x += p.x, centroid.y += p.y, centroid.z += p.z;
          ++others;
        }
      }
      if (others == 0) continue;
      centroid = {centroid.x / others, centroid.y / others, centroid.z / others};
      // The mid-nodes of v's edges, to put back when a move is refused.
      std::vector<std::pair<Index, Vec3>> mids;
      if (npt == 10)
        for (Index k : b)
          for (int e = 0; e < 6; ++e) {
            const Index a = m.tet[static_cast<std::size_t>(10 * k + kTetEdge[e][0])];
            const Index c = m.tet[static_cast<std::size_t>(10 * k + kTetEdge[e][1])];
            if (a == v || c == v) mids.emplace_back(m.tet[static_cast<std::size_t>(10 * k + 4 + e)], Vec3{});
          }
      for (auto& [mid, p] : mids) p = m.point(mid);
      bool accepted = false;
      for (double f : {1.0, 0.5, 0.25}) {
        const Vec3 p{old.x + f * (centroid.x - old.x), old.y + f * (centroid.y - old.y), old.z + f * (centroid.z - old.z)};
        set_point(v, p);
        bool ok = true;
        double mean = 0;
        for (std::size_t i = 0; i < b.size() && ok; ++i) {
          ok = orient3d(corner(b[i], 0), corner(b[i], 1), corner(b[i], 2), corner(b[i], 3)) == sign[i] &&
               sign[i] != Sign::kZero;
          const double q = tet_min_dihedral_deg(corner(b[i], 0), corner(b[i], 1), corner(b[i], 2), corner(b[i], 3));
          ok = ok && q >= std::min(worst_before, 30.0);
          mean += q / static_cast<double>(b.size());
        }
        ok = ok && mean > mean_before;
        if (ok && npt == 10) {
          for (Index k : b)
            for (int e = 0; e < 6; ++e) {
              const Index a = m.tet[static_cast<std::size_t>(10 * k + kTetEdge[e][0])];
              const Index c = m.tet[static_cast<std::size_t>(10 * k + kTetEdge[e][1])];
              if (a == v || c == v) set_point(m.tet[static_cast<std::size_t>(10 * k + 4 + e)], midpoint(m.point(a), m.point(c)));
            }
          for (std::size_t i = 0; i < b.size() && ok; ++i) {
            double x[30];
            for (int j = 0; j < 10; ++j) {
              const Vec3 q = m.point(m.tet[static_cast<std::size_t>(10 * b[i] + j)]);
              x[3 * j] = q.x, x[3 * j + 1] = q.y, x[3 * j + 2] = q.z;
            }
            ok = certify_tet10(x) == Tet10Validity::kCertified;
          }
          if (!ok)
            for (const auto& [mid, q] : mids) set_point(mid, q);
        }
        if (ok) {
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        set_point(v, old);
        continue;
      }
      ++moved;
    }
    moves += moved;
    if (moved == 0) break;
  }
  return moves;
}

// A solid's tets estimated from its surface triangles and its volume at the size h, as the cut's
// plane balances them (cad_split.h): kTetsPerTriangle per triangle (graded meshes of parts with
// small features: about 4 over the CAD corpus) plus the tets of edge h, h^3 / (6 sqrt 2) each,
// that fill the volume.
double estimated_tets(std::size_t triangles, double volume, double h) {
  return cad::kTetsPerTriangle * static_cast<double>(triangles) + volume / (h * h * h / (6 * std::sqrt(2.0)));
}

}  // namespace

FemMesh mesh_cad_model(const cad::CadModel& model, const FemOptions& options, FemStats* stats) {
  const auto start = Clock::now();
  check_fem_options(options);
  const auto report = [&](const std::string& stage, double f) {
    if (options.progress) options.progress(stage, std::clamp(f, 0.0, 1.0));
  };
  if (model.num_solids() != 1) return mesh_model(model, options, nullptr, nullptr, start, report, stats);

  // One solid: its surface first; a solid big enough is cut in two (cad_split.h) and the halves
  // are meshed as two solids sharing the cut, at the same time (fem_mesh.h).
  cad::CadSurfaceOptions so = cad_surface_options(options);
  so.progress = [&](const std::string& stage, double f) { report("surface: " + stage, 0.05 * f); };
  cad::CadSurfaceStats sst;
  const cad::CadSurface surface = cad::mesh_cad_surface(model, so, &sst);
  const double volume = cad::enclosed_volume(surface, 0);
  if (estimated_tets(surface.solid_tag[0].size(), volume, sst.size) >= kCutFromTets) {
    const auto t = Clock::now();
    const cad::CutPlane plane = cad::choose_cut_plane(model, surface, sst.size);
    cad::CadSplit split = cad::split_by_plane(model, plane);
    if (split.cut) {
      FemOptions o = options;
      o.size_by_face.clear();
      for (const auto& [face, size] : options.size_by_face)
        for (std::size_t g = 0; g < split.face_origin.size(); ++g)
          if (split.face_origin[g] == face) o.size_by_face[static_cast<int>(g)] = size;
      // The cut faces are meshed at the sizes the volume will have there.
      std::map<int, std::vector<std::pair<Vec3, double>>> sources;
      const auto cut_sources = cad::cut_size_sources(surface, plane, sst.size, options.grading);
      for (std::size_t g = 0; g < split.face_origin.size(); ++g)
        if (split.face_origin[g] < 0) sources[static_cast<int>(g)] = cut_sources;
      FemStats st;
      FemMesh out;
      const double seconds_before = sst.seconds + seconds_since(t);
      try {
        out = mesh_model(split.model, o, nullptr, nullptr, start,
                         [&](const std::string& stage, double f) { report(stage, 0.05 + 0.95 * f); }, &st, sources);
      } catch (const Error& e) {
        // The halves could not be meshed (a seam OpenCASCADE made badly): the whole solid is.
        if (e.code() == ErrorCode::kCancelled) throw;
        return mesh_model(model, options, &surface, &sst, start, report, stats);
      }
      // The halves' tags as the model's: tets to the solid, triangles to their original face,
      // the cut's triangles (inside the solid) dropped.
      for (auto& s : out.tet_solid) s = split.solid_origin[static_cast<std::size_t>(s)];
      const int npf = out.nodes_per_triangle;
      std::vector<Index> tri;
      std::vector<std::int32_t> tri_face;
      for (Index f = 0; f < out.num_triangles(); ++f) {
        const int origin = split.face_origin[static_cast<std::size_t>(out.tri_face[static_cast<std::size_t>(f)])];
        if (origin < 0) continue;
        tri.insert(tri.end(), out.tri.begin() + npf * f, out.tri.begin() + npf * (f + 1));
        tri_face.push_back(origin);
      }
      out.tri = std::move(tri);
      out.tri_face = std::move(tri_face);
      out.solid_names = model.solid_names;
      out.face_names = model.face_names;
      // The cut's nodes were fixed while the pieces were meshed apart; inside the merged mesh
      // they are free.
      const auto ts = Clock::now();
      st.cut_nodes_smoothed = smooth_cut_nodes(out, plane.axis, plane.position, 3);
      set_figures(out, &st);
      st.seconds_merge += seconds_since(ts);
      st.seconds_total = seconds_since(start);
      st.solids = model.num_solids();
      st.faces = model.num_faces();
      st.shared_faces = 0;
      st.boundary_triangles = out.num_triangles();
      st.seconds_surface += seconds_before;
      if (stats) *stats = st;
      return out;
    }
  }
  return mesh_model(model, options, &surface, &sst, start,
                    [&](const std::string& stage, double f) { report(stage, std::max(0.05, f)); }, stats);
}

CadDistance measure_cad_distance(const cad::CadModel& model, const FemMesh& mesh) {
  std::set<std::pair<Index, std::int32_t>> pairs;  // (node, face), each measured once
  const int npf = mesh.nodes_per_triangle;
  for (Index t = 0; t < mesh.num_triangles(); ++t)
    for (int i = 0; i < npf; ++i)
      pairs.insert({mesh.tri[static_cast<std::size_t>(npf * t + i)], mesh.tri_face[static_cast<std::size_t>(t)]});
  // Corner nodes are the tets' first four nodes.
  std::vector<char> is_corner(static_cast<std::size_t>(mesh.mesh.num_points()), 0);
  const int npt = mesh.mesh.nodes_per_tet;
  for (std::size_t i = 0; i < mesh.mesh.tet.size(); ++i)
    if (static_cast<int>(i % static_cast<std::size_t>(npt)) < 4) is_corner[static_cast<std::size_t>(mesh.mesh.tet[i])] = 1;
  CadDistance d;
  double worst = -1;
  cad::CadProjector projector(model);
  for (const auto& [node, face] : pairs) {
    const Vec3 p = mesh.mesh.point(node), q = projector.to_face(p, face);
    const double dist = std::min(cad::distance_to_face(model, face, p), std::sqrt(squared_distance(p, q)));
    double& max = is_corner[static_cast<std::size_t>(node)] ? d.max_corner : d.max_midnode;
    max = std::max(max, dist);
    if (dist > worst) {
      worst = dist;
      d.worst_node = node;
      d.worst_face = face;
    }
    ++d.pairs;
  }
  return d;
}

}  // namespace bsptet::fem
