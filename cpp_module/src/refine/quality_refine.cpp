// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/refine/quality_refine.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <queue>
#include <string>
#include <tuple>
#include <vector>

#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/refine/tet10.h"
#include "bsptet/mesh/tet_shape.h"
#include "bsptet/refine/wall_thickness.h"

namespace bsptet {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// flat_collapse_pass works on the tets below this min dihedral angle (degrees).
constexpr double kFlatCollapseBelowDeg = 1.0;
// Edge removals (RefineMesh::remove_edge) look at shells of at most this many tets.
constexpr int kMaxEdgeRing = 7;
// Tets below this are polished once the curved elements have room (Refiner::polish_curved).
constexpr double kPolishCurvedBelowDeg = 15.0;
// polish_curved stops after this many rounds in a row that did not raise the mesh's worst tet,
// and after kPolishMaxRounds in all.
constexpr int kPolishPatienceRounds = 4;
constexpr int kPolishMaxRounds = 64;
// ODT smoothing (Refiner::odt_smooth_pass) never takes a tet below this or below the worst before.
constexpr double kOdtKeepDeg = 15.0;
// Delaunay refinement (Refiner::delaunay_refine_phase): tets with a circumradius above this times
// the target get a point; none lands closer than kRefineSpacing times the target to the points
// of its cavity. A regular tet of edge h has circumradius 0.61 h.
constexpr double kRefineCircumradius = 0.9;
constexpr double kRefineSpacing = 0.8;
// The flip and smoothing passes of the optimization rounds work on the tets below this (or below
// min_dihedral_deg when it is higher): above it a flip or a move rarely pays for its search
// (flips up to 70 degrees took 2 to 4 times the refinement's time for a median 0.2 degree
// better; the ODT smoothing evens out the typical tet instead).
constexpr double kFlipBelowDeg = 40.0;
using MoveAccept = std::function<bool(const std::vector<std::array<Vec3, 4>>&)>;

// Face (A, B, C) of a tet whose fourth corner is D, for placing points over it.
struct FaceFrame {
  Vec3 centroid;
  Vec3 normal;  ///< unit, towards D
  double mean_edge = 0;
  /// The point at `fraction` of a regular tet's height (sqrt(2/3) * mean edge) over the face.
  Vec3 apex(double fraction) const {
    const double h = fraction * std::sqrt(2.0 / 3.0) * mean_edge;
    return {centroid.x + normal.x * h, centroid.y + normal.y * h, centroid.z + normal.z * h};
  }
};

// False for a degenerate face.
bool face_frame(const Vec3& A, const Vec3& B, const Vec3& C, const Vec3& D, FaceFrame* f) {
  const Vec3 G{(A.x + B.x + C.x) / 3, (A.y + B.y + C.y) / 3, (A.z + B.z + C.z) / 3};
  const double ux = B.x - A.x, uy = B.y - A.y, uz = B.z - A.z, vx = C.x - A.x, vy = C.y - A.y, vz = C.z - A.z;
  double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(len > 0) || !std::isfinite(len)) return false;
  if ((D.x - G.x) * nx + (D.y - G.y) * ny + (D.z - G.z) * nz < 0) nx = -nx, ny = -ny, nz = -nz;
  f->centroid = G;
  f->normal = {nx / len, ny / len, nz / len};
  f->mean_edge = (std::sqrt(squared_distance(A, B)) + std::sqrt(squared_distance(B, C)) +
                  std::sqrt(squared_distance(C, A))) / 3;
  return true;
}

void check_options(const RefineOptions& o) {
  auto bad = [](const std::string& what) { throw InputError(ErrorCode::kBadArgument, "refine", -1, what); };
  if (!(o.size > 0)) bad("size must be a positive length (or infinity for none), got " + std::to_string(o.size));
  if (!(o.min_size >= 0) || !std::isfinite(o.min_size)) bad("min_size must be >= 0, got " + std::to_string(o.min_size));
  for (const auto& [tag, s] : o.size_by_tag)
    if (!(s > 0) || !std::isfinite(s))
      bad("the size of face tag " + std::to_string(tag) + " must be a positive length, got " + std::to_string(s));
  if (!(o.thickness_ratio >= 0) || !std::isfinite(o.thickness_ratio))
    bad("thickness_ratio must be 0 (off) or a positive number, got " + std::to_string(o.thickness_ratio));
  if (!(o.grading > 0)) bad("grading must be positive, got " + std::to_string(o.grading));
  if (!(o.collapse_ratio >= 0 && o.collapse_ratio < o.split_ratio))
    bad("collapse_ratio must be in [0, split_ratio), got " + std::to_string(o.collapse_ratio));
  if (!(o.collapse_min_dihedral_deg >= 0 && o.collapse_min_dihedral_deg <= 180))
    bad("collapse_min_dihedral_deg must be in [0, 180], got " + std::to_string(o.collapse_min_dihedral_deg));
  if (!(o.split_ratio >= 1) || !std::isfinite(o.split_ratio))
    bad("split_ratio must be at least 1, got " + std::to_string(o.split_ratio));
  if (!(o.radius_edge_bound == 0 || o.radius_edge_bound >= 0.7))
    bad("radius_edge_bound must be 0 (off) or at least 0.7 (a regular tet has 0.612), got " +
        std::to_string(o.radius_edge_bound));
  if (!(o.min_dihedral_deg >= 0 && o.min_dihedral_deg < 70.5))
    bad("min_dihedral_deg must be in [0, 70.5), got " + std::to_string(o.min_dihedral_deg));
  if (o.order != 1 && o.order != 2) bad("order must be 1 or 2, got " + std::to_string(o.order));
  if (o.max_passes < 0 || o.optimize_rounds < 0) bad("max_passes and optimize_rounds must be >= 0");
}

class Refiner {
 public:
  Refiner(RefineMesh& m, const RefineOptions& o, RefineStats& st) : m_(m), o_(o), st_(st) {}

  void run() {
    timed("targets", [&] { compute_targets(); return 0; });
    timed("size", [&] { delaunay_refine_phase(); return 0; });
    timed("size", [&] { size_phase(); return 0; });
    tets_after_size_ = m_.num_alive_tets();
    optimize_phase(o_.optimize_rounds);
    // Collapses and smoothing may have left some edges long again: one more short round, whose
    // splits never make a tet worse than the worst of the tets they replace (after the
    // optimization, a free split here could leave a sliver no later pass removes: the
    // Schoenhardt polyhedron went from 11 to 1.6 degrees).
    if (o_.max_passes > 0) {
      timed("size", [&] { size_phase(180.0); return 0; });
      optimize_phase(std::min(2, o_.optimize_rounds));
    }
    if (o_.separate_face_tags && !m_.surface().tag.empty()) {
      timed("separate_face_tags", [&] { separate_face_tags(); return 0; });
      // Its splits end where the optimization has stopped. Only moves of interior points follow
      // (a flip could join three points of one CAD face into an interior face again; a move
      // changes no connectivity), each raising the worst tet around the point.
      for (int round = 0; round < 3 && smooth_pass(30.0) > 0; ++round) {
      }
    }
    st_.worst_deg_optimized = worst_quality();
    timed("curving", [&] { lift_for_curved_elements(); return 0; });
    st_.worst_deg_curving_room = worst_quality();
    if (o_.projection && o_.order == 2)
      timed("curving", [&] { return polish_curved(kPolishCurvedBelowDeg); });
    st_.worst_deg = worst_quality();
    // Counted last (the smoothing after separate_face_tags and the lifts move points too) against
    // the asked sizes: the targets raised around edges that could not be split do not count.
    compute_targets(false);
    for (const auto& e : m_.edges())
      if (is_long(e[0], e[1])) ++st_.long_edges_left;
  }

 private:
  void poll(const std::string& stage, double fraction) {
    if (o_.cancelled && o_.cancelled())
      throw MeshingError(ErrorCode::kCancelled, "refine", -1, "cancelled during " + stage);
    if (o_.progress) o_.progress(stage, fraction);
  }

  // ---- Sizing ---------------------------------------------------------------------------------
  // Target size per point: `size`, lowered near tagged faces, graded along mesh edges (Dijkstra).
  void compute_targets(bool raise_stuck = true) {
    const Index np = m_.num_points();
    target_.assign(static_cast<std::size_t>(np), o_.size);
    if (!o_.size_by_tag.empty())
      for (const auto& [face, parent] : m_.boundary_faces()) {
        auto it = o_.size_by_tag.find(m_.tag_of(parent));
        if (it == o_.size_by_tag.end()) continue;
        for (Index v : face) target_[static_cast<std::size_t>(v)] = std::min(target_[static_cast<std::size_t>(v)], it->second);
      }
    if (o_.size_from_surface) {
      const SurfaceMesh& in = m_.surface();
      for (const auto& [face, parent] : m_.boundary_faces()) {
        const Index* t = &in.tri[static_cast<std::size_t>(3 * parent)];
        double mean = 0;
        for (int k = 0; k < 3; ++k) {
          const std::size_t a = static_cast<std::size_t>(3 * t[k]), b = static_cast<std::size_t>(3 * t[(k + 1) % 3]);
          const double dx = in.xyz[a] - in.xyz[b], dy = in.xyz[a + 1] - in.xyz[b + 1], dz = in.xyz[a + 2] - in.xyz[b + 2];
          mean += std::sqrt(dx * dx + dy * dy + dz * dz) / 3;
        }
        for (Index v : face) target_[static_cast<std::size_t>(v)] = std::min(target_[static_cast<std::size_t>(v)], mean);
      }
    }
    if (floor_ == 0) compute_floor();
    if (o_.thickness_ratio > 0) apply_wall_thickness();
    // Grading: t(v) <= t(u) + grading * |uv|.
    std::vector<std::vector<Index>> nbr(static_cast<std::size_t>(np));
    for (const auto& e : m_.edges()) {
      nbr[static_cast<std::size_t>(e[0])].push_back(e[1]);
      nbr[static_cast<std::size_t>(e[1])].push_back(e[0]);
    }
    using Item = std::pair<double, Index>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    for (Index v = 0; v < np; ++v)
      if (std::isfinite(target_[static_cast<std::size_t>(v)]) && !nbr[static_cast<std::size_t>(v)].empty())
        q.push({target_[static_cast<std::size_t>(v)], v});
    while (!q.empty()) {
      const auto [t, v] = q.top();
      q.pop();
      if (t > target_[static_cast<std::size_t>(v)]) continue;
      for (Index w : nbr[static_cast<std::size_t>(v)]) {
        const double c = t + o_.grading * std::sqrt(squared_distance(m_.point(v), m_.point(w)));
        if (c < target_[static_cast<std::size_t>(w)]) {
          target_[static_cast<std::size_t>(w)] = c;
          q.push({c, w});
        }
      }
    }
    // Where an edge could not be split (no exact point on the surface, or every candidate
    // inverted a tet) the target is raised to that edge's length / split_ratio on the edge,
    // decreasing by one unit per unit of distance from it: refinement then does not chase the edge
    // with ever closer points (degrading gracefully near facets without exact points).
    for (Index v = 0; v < np && raise_stuck; ++v) {
      const Vec3& p = m_.point(v);
      double& t = target_[static_cast<std::size_t>(v)];
      for (const Stuck& e : stuck_) {
        if (p.x < e.lo[0] - e.reach || p.x > e.hi[0] + e.reach || p.y < e.lo[1] - e.reach ||
            p.y > e.hi[1] + e.reach || p.z < e.lo[2] - e.reach || p.z > e.hi[2] + e.reach)
          continue;
        t = std::max(t, e.reach - segment_distance(p, e.a, e.b));
      }
    }
  }

  // The smallest length refinement works at (RefineOptions::min_size), from the asked targets
  // (size, size_by_tag, size_from_surface), once.
  void compute_floor() {
    const Index np = m_.num_points();
    double smallest = kInf;
    for (Index v = 0; v < np; ++v)
      smallest = std::min(smallest, target_[static_cast<std::size_t>(v)]);
    if (o_.min_size > 0) {
      floor_ = o_.min_size;
    } else if (std::isfinite(smallest)) {
      floor_ = smallest / 8;
    } else {
      double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
      for (Index v = 0; v < np; ++v) {
        const Vec3& p = m_.point(v);
        for (int c = 0; c < 3; ++c) {
          lo[c] = std::min(lo[c], p[c]);
          hi[c] = std::max(hi[c], p[c]);
        }
      }
      floor_ = 1e-3 * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                (hi[2] - lo[2]) * (hi[2] - lo[2]));
    }
  }

  // RefineOptions::thickness_ratio: the target at a boundary point is at most thickness_ratio times
  // the wall's thickness there (wall_thickness.h), measured against the input triangles with the
  // point's normal the mean of its boundary faces' parents' normals; never below floor_. Walls
  // are looked for only up to min(target, twice the longest edge of the point's input triangles)
  // / thickness_ratio away: a wall thicker than the input's own triangles around the point is
  // crossed by tets no longer than those triangles, not flat ones (and the search stays local on
  // a fine tessellation meshed at a coarse size). Points without a finite target are left.
  void apply_wall_thickness() {
    if (!walls_) walls_ = std::make_unique<WallThickness>(m_.surface());
    const SurfaceMesh& in = m_.surface();
    const Index np = m_.num_points();
    std::vector<std::vector<Index>> own(static_cast<std::size_t>(np));
    for (const auto& [face, parent] : m_.boundary_faces())
      for (Index v : face) {
        auto& list = own[static_cast<std::size_t>(v)];
        if (std::find(list.begin(), list.end(), parent) == list.end()) list.push_back(parent);
      }
    for (Index v = 0; v < np; ++v) {
      const auto& list = own[static_cast<std::size_t>(v)];
      double& t = target_[static_cast<std::size_t>(v)];
      if (list.empty() || !std::isfinite(t)) continue;
      Vec3 n;
      double longest = 0;
      for (Index tri : list) {
        const Vec3& m = walls_->normal(tri);
        n = {n.x + m.x, n.y + m.y, n.z + m.z};
        for (int k = 0; k < 3; ++k)
          longest = std::max(longest, squared_distance(in.point(in.tri[3 * tri + k]), in.point(in.tri[3 * tri + (k + 1) % 3])));
      }
      const double len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
      if (!(len > 0)) continue;
      n = {n.x / len, n.y / len, n.z / len};
      const double reach = std::min(t, 2 * std::sqrt(longest)) / o_.thickness_ratio;
      const double thickness = walls_->at(m_.point(v), n, list, reach);
      if (std::isfinite(thickness)) t = std::min(t, std::max(o_.thickness_ratio * thickness, floor_));
    }
  }

  double target(Index v) const {
    return static_cast<std::size_t>(v) < target_.size() ? target_[static_cast<std::size_t>(v)] : o_.size;
  }
  double edge_target(Index u, Index v) const { return std::min(target(u), target(v)); }
  double length(Index u, Index v) const { return std::sqrt(squared_distance(m_.point(u), m_.point(v))); }
  bool is_long(Index u, Index v) const {
    const double l = length(u, v);
    return l > o_.split_ratio * edge_target(u, v) && l > 2 * floor_;
  }
  // The grading rule at a new point x from the corners of the tet it was made in: the least of
  // target(corner) + grading * |x - corner|, at most `size`. (The corners' mean instead gave a
  // circumcentre deep inside a large tet its corners' small surface sizes: on a crankshaft the
  // refinement made 89,000 points and the optimization collapsed 66,000 of them again.)
  double graded_target(const Vec3& x, const std::array<Index, 4>& corners) const {
    double t = o_.size;
    for (Index k : corners) t = std::min(t, target(k) + o_.grading * std::sqrt(squared_distance(x, m_.point(k))));
    return t;
  }
  void set_target(Index n, double t) {
    if (static_cast<std::size_t>(n) >= target_.size()) target_.resize(static_cast<std::size_t>(n) + 1, o_.size);
    target_[static_cast<std::size_t>(n)] = t;
  }

  static double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
    const double wx = p.x - a.x, wy = p.y - a.y, wz = p.z - a.z;
    const double uu = ux * ux + uy * uy + uz * uz;
    double t = uu > 0 ? (ux * wx + uy * wy + uz * wz) / uu : 0;
    t = std::max(0.0, std::min(1.0, t));
    const double dx = wx - t * ux, dy = wy - t * uy, dz = wz - t * uz;
    return std::sqrt(dx * dx + dy * dy + dz * dz);
  }

  void raise_lower(Index u, Index v) {
    Stuck e;
    e.a = m_.point(u);
    e.b = m_.point(v);
    e.reach = length(u, v) / o_.split_ratio * 1.0001;
    for (int c = 0; c < 3; ++c) {
      e.lo[c] = std::min(e.a[c], e.b[c]);
      e.hi[c] = std::max(e.a[c], e.b[c]);
    }
    stuck_.push_back(e);
    for (Index w : {u, v}) set_target(w, std::max(target(w), e.reach));
  }

  bool split(Index u, Index v, double min_quality) {
    Index n = -1;
    const SplitOutcome r = m_.split_edge(u, v, min_quality, &n);
    if (r != SplitOutcome::kSplit && r != SplitOutcome::kNoEdge) raise_lower(u, v);
    switch (r) {
      case SplitOutcome::kSplit:
        ++st_.splits;
        if (m_.support(n).kind != Support::kInterior) ++st_.surface_splits;
        set_target(n, 0.5 * (target(u) + target(v)));
        return true;
      case SplitOutcome::kNoExactPoint:
        ++st_.splits_no_exact_point;
        return false;
      case SplitOutcome::kInverted:
        ++st_.splits_rejected;
        return false;
      case SplitOutcome::kBadProjection:
        ++st_.projection_rejected;
        return false;
      case SplitOutcome::kFixedSurface:
        ++st_.splits_fixed_surface;
        return false;
      case SplitOutcome::kNoEdge:
        return false;
    }
    return false;
  }

  // ---- Phase 1: size --------------------------------------------------------------------------
  // A bound on the points the size phase may create: four times what regular tets of the smallest
  // target would need to fill the volume, plus the input's. It only stops a runaway.
  void set_budget() {
    double volume = 0, smallest = kInf;
    for (Index t = 0; t < m_.num_tet_slots(); ++t) {
      if (!m_.tet_alive(t)) continue;
      const auto& q = m_.tet(t);
      const Vec3 a = m_.point(q[0]), b = m_.point(q[1]), c = m_.point(q[2]), d = m_.point(q[3]);
      const double bx = b.x - a.x, by = b.y - a.y, bz = b.z - a.z, cx = c.x - a.x, cy = c.y - a.y, cz = c.z - a.z,
                   dx = d.x - a.x, dy = d.y - a.y, dz = d.z - a.z;
      volume += (bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx)) / 6;
    }
    for (double t : target_) smallest = std::min(smallest, t);
    smallest = std::max(smallest, floor_);
    const double regular = smallest * smallest * smallest / (6 * std::sqrt(2.0));
    const double estimate = std::isfinite(regular) && regular > 0 ? 4 * volume / regular : 0;
    budget_ = m_.num_points() + static_cast<Index>(std::min(estimate + 1000.0, 5e8));
  }

  // ---- Phase 1a: interior points by Delaunay refinement ---------------------------------------
  // Tets whose circumradius exceeds kRefineCircumradius * their target (the mean of their
  // corners') get a point at their circumcentre, inserted Bowyer-Watson (RefineMesh::insert_point:
  // the cavity is shaped by the circumspheres, made star-shaped exactly), largest relative radius
  // first, in rounds until none is left. The spacing rule: the insertion is refused when a vertex
  // of its cavity is closer than kRefineSpacing * the target there, so every new point keeps that
  // distance from the points it connects to and the refinement ends. A circumcentre outside the
  // solid (or on its boundary) is skipped: the surface is already at size (the CAD surface
  // mesher), and the edge-split phase after this one splits what is still long. Points spread
  // this way are far more regular than midpoints of split edges, so the optimization that
  // follows has less to mend. Only with a finite size.
  void delaunay_refine_phase() {
    if (!std::isfinite(o_.size)) return;
    set_budget();
    std::vector<std::uint64_t> refused_at;  // failure memory as the flip pass's
    for (int round = 0; round < o_.max_passes; ++round) {
      poll("refining to size", std::min(0.4, 0.04 * round));
      std::vector<std::tuple<double, Index>> todo;
      for (Index t = 0; t < m_.num_tet_slots(); ++t) {
        if (!m_.tet_alive(t) || failed_before(refused_at, t)) continue;
        const auto& q = m_.tet(t);
        Vec3 c;
        double r2 = 0;
        if (!tet_circumsphere(m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3]), &c, &r2)) continue;
        const double tg = 0.25 * (target(q[0]) + target(q[1]) + target(q[2]) + target(q[3]));
        const double ratio = std::sqrt(r2) / tg;
        if (ratio > kRefineCircumradius) todo.emplace_back(-ratio, t);
      }
      if (todo.empty()) break;
      std::sort(todo.begin(), todo.end());
      std::int64_t done = 0;
      for (const auto& [key, t] : todo) {
        if (m_.num_points() >= budget_) return;
        if (!m_.tet_alive(t)) continue;
        const auto q = m_.tet(t);
        Vec3 c;
        double r2 = 0;
        if (!tet_circumsphere(m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3]), &c, &r2)) continue;
        const double tg = 0.25 * (target(q[0]) + target(q[1]) + target(q[2]) + target(q[3]));
        Index p = -1;
        if (m_.insert_point(t, c, kRefineSpacing * tg, &p, 256) == InsertOutcome::kInserted) {
          ++st_.refinement_points;
          set_target(p, graded_target(c, q));
          ++done;
        } else {
          record_failure(refused_at, t);
        }
      }
      if (done == 0) break;
    }
  }

  // `min_quality`: as RefineMesh::split_edge's (0: any valid split).
  void size_phase(double min_quality = 0) {
    set_budget();
    for (int pass = 0; pass < o_.max_passes; ++pass) {
      poll("refining to size", std::min(0.5, 0.05 * pass));
      if (pass > 0) compute_targets();
      std::vector<std::tuple<double, Index, Index>> todo;
      for (const auto& e : m_.edges())
        if (is_long(e[0], e[1])) todo.emplace_back(-length(e[0], e[1]) / edge_target(e[0], e[1]), e[0], e[1]);
      if (todo.empty()) break;
      std::sort(todo.begin(), todo.end());
      std::int64_t done = 0;
      for (const auto& [key, u, v] : todo) {
        if (m_.num_points() >= budget_) break;
        done += split(u, v, min_quality) ? 1 : 0;
      }
      ++st_.size_passes;
      flip_pass(30.0);
      if (done == 0) break;
    }
  }

  // ---- separate_face_tags (see the option) ---------------------------------------------------
  // The offending tets (see the option), each with the edges whose split would mend it, best
  // first: interior edges (their midpoint is off every face), then edges of other tags' faces;
  // longer first.
  std::vector<std::pair<Index, std::vector<std::array<Index, 2>>>> tag_conflicts() {
    using Key3 = std::array<Index, 3>;
    std::map<Key3, std::int32_t> face_tag;                                // sorted boundary face -> tag
    std::map<std::array<Index, 2>, std::vector<std::int32_t>> edge_tags;  // boundary edge -> tags
    std::vector<std::vector<std::int32_t>> point_tags(static_cast<std::size_t>(m_.num_points()));
    for (const auto& [face, parent] : m_.boundary_faces()) {
      const std::int32_t tag = m_.tag_of(parent);
      Key3 key = face;
      std::sort(key.begin(), key.end());
      face_tag[key] = tag;
      for (int i = 0; i < 3; ++i) {
        auto& pt = point_tags[static_cast<std::size_t>(face[i])];
        if (std::find(pt.begin(), pt.end(), tag) == pt.end()) pt.push_back(tag);
        std::array<Index, 2> e{std::min(face[i], face[(i + 1) % 3]), std::max(face[i], face[(i + 1) % 3])};
        auto& et = edge_tags[e];
        if (std::find(et.begin(), et.end(), tag) == et.end()) et.push_back(tag);
      }
    }
    auto on_tag = [&](Index v, std::int32_t tag) {
      const auto& pt = point_tags[static_cast<std::size_t>(v)];
      return std::find(pt.begin(), pt.end(), tag) != pt.end();
    };
    std::vector<std::pair<Index, std::vector<std::array<Index, 2>>>> out;
    for (Index t = 0; t < m_.num_tet_slots(); ++t) {
      if (!m_.tet_alive(t)) continue;
      const auto q = m_.tet(t);
      std::vector<std::int32_t> tags;
      for (Index v : q)
        for (std::int32_t tag : point_tags[static_cast<std::size_t>(v)])
          if (std::find(tags.begin(), tags.end(), tag) == tags.end()) tags.push_back(tag);
      std::sort(tags.begin(), tags.end());
      for (std::int32_t tag : tags) {
        std::vector<Index> on;
        for (Index v : q)
          if (on_tag(v, tag)) on.push_back(v);
        if (on.size() < 3) continue;
        if (on.size() == 3) {
          Key3 key{on[0], on[1], on[2]};
          std::sort(key.begin(), key.end());
          const auto it = face_tag.find(key);
          if (it != face_tag.end() && it->second == tag) continue;
        }
        std::vector<std::tuple<bool, double, Index, Index>> ranked;
        for (std::size_t i = 0; i < on.size(); ++i)
          for (std::size_t j = i + 1; j < on.size(); ++j) {
            const Index a = std::min(on[i], on[j]), b = std::max(on[i], on[j]);
            const auto it = edge_tags.find({a, b});
            const bool boundary = it != edge_tags.end();
            if (boundary && std::find(it->second.begin(), it->second.end(), tag) != it->second.end()) continue;
            ranked.emplace_back(boundary, -length(a, b), a, b);
          }
        std::sort(ranked.begin(), ranked.end());
        std::vector<std::array<Index, 2>> edges;
        for (const auto& r : ranked) edges.push_back({std::get<2>(r), std::get<3>(r)});
        out.emplace_back(t, std::move(edges));
        break;
      }
    }
    return out;
  }

  static constexpr double kTagSplitMinDihedral = 1.0;  // degrees

  void separate_face_tags() {
    for (int pass = 0; pass < 16; ++pass) {
      poll("separating CAD faces", 0.9);
      std::int64_t done = 0;
      // A split may not make a tet flatter than kTagSplitMinDihedral: where the face is flat
      // (a plane, a nearly flat strip) the midpoint of an interior edge between two of its
      // points lies on it, and splitting there made flat tets on the face instead of mending
      // one (part.step: 0.0025 degrees). Then a new interior point above the tet (insert_for).
      for (const auto& [t, edges] : tag_conflicts()) {
        bool mended = false;
        // split_edge bounds new tets by min(this, the worst old tet): a flat conflict tet gets
        // no split (it would only make more flat tets), only insert_for below
        const bool flat = m_.tet_alive(t) && m_.tet_quality(t) < kTagSplitMinDihedral;
        for (const auto& e : edges)
          if (!flat && m_.point_alive(e[0]) && m_.point_alive(e[1]) && split(e[0], e[1], kTagSplitMinDihedral)) {
            ++st_.tag_splits;
            mended = true;
            break;
          }
        if (!mended && m_.tet_alive(t) && insert_for(t)) {
          ++st_.tag_splits;
          mended = true;
        }
        if (mended) ++done;
      }
      if (done == 0) break;
    }
    st_.tag_conflicts_left = static_cast<std::int64_t>(tag_conflicts().size());
  }

  // ---- Phase 4: room for curved tet10 elements -----------------------------------------------
  // With a projection hook and order 2, each boundary mid-node goes onto the true surface, off its
  // chord by the chord's sag. A tet whose interior apex stands lower over its boundary face than
  // that sag becomes an invalid curved element with straight interior mid-nodes (make_second_order
  // then has to move mid-nodes or insert a point, tet10.h). Such apexes (interior Steiner points only) are lifted towards
  // the height of a regular tet over the face, when every tet around stays positive (exact), the
  // number of invalid curved elements around goes down, and no tet around drops below
  // min(1 degree, the worst before): a valid curved mesh is worth a worse linear angle there.
  // Failing that, a new interior point above one of the tet's faces (Bowyer-Watson), accepted when
  // all its new tets are valid curved elements of at least 1 degree. Splitting the sagging edges
  // instead was tried and made more invalid elements (docs/design/quality-stage.md). Sets
  // curving_conflicts_left.
  void lift_for_curved_elements() {
    if (!o_.projection || o_.order != 2) return;
    constexpr auto& kFace = kTetOppositeFace;  // types.h
    prepare_curved_check();
    auto curved_ok = [&](const std::array<Index, 4>& q, const std::array<Vec3, 4>& P) {
      return curved_element_ok(q, P);
    };
    auto corners = [&](const std::array<Index, 4>& q) {
      return std::array<Vec3, 4>{m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3])};
    };
    for (int round = 0; round < 6; ++round) {
      poll("making room for curved tet10 elements", 0.95);
      std::vector<Index> bad;
      for (Index t = 0; t < m_.num_tet_slots(); ++t)
        if (m_.tet_alive(t) && !curved_ok(m_.tet(t), corners(m_.tet(t)))) bad.push_back(t);
      st_.curving_conflicts_left = static_cast<std::int64_t>(bad.size());
      if (bad.empty()) return;
      std::int64_t lifted = 0;
      for (Index t : bad) {
        if (!m_.tet_alive(t) || curved_ok(m_.tet(t), corners(m_.tet(t)))) continue;
        const auto q = m_.tet(t);
        bool done = reconnect_for_curving(t, curved_ok, corners);
        if (done) ++lifted;
        for (int k = 0; k < 4 && !done; ++k) {
          const Index d = q[k];
          if (m_.support(d).kind != Support::kInterior) continue;
          const Vec3& D = m_.point(d);
          FaceFrame fr;
          if (!face_frame(m_.point(q[kFace[k][0]]), m_.point(q[kFace[k][1]]), m_.point(q[kFace[k][2]]), D, &fr))
            continue;
          const std::vector<Index> ball = m_.tets_around_point(d);
          int bad_before = 0;
          double worst_before = 180;
          for (Index s2 : ball) {
            bad_before += !curved_ok(m_.tet(s2), corners(m_.tet(s2)));
            worst_before = std::min(worst_before, m_.tet_quality(s2));
          }
          const double floor_deg = std::min(1.0, worst_before);
          // Targets in order: towards the apex of a regular tet over the face at 1, 0.75, 0.5,
          // 0.35 and 0.25 of its height, all the way or half way; then small lifts straight up
          // from the face's plane by 1, 3 or 7 times the apex's own height (over a long needle
          // face even a quarter of a regular tet's height moves the apex too far for the tets
          // around it).
          std::vector<Vec3> targets;
          for (double f : {1.0, 0.75, 0.5, 0.35, 0.25}) {
            const Vec3 full = fr.apex(f);
            for (double lambda : {1.0, 0.5})
              targets.push_back({D.x + lambda * (full.x - D.x), D.y + lambda * (full.y - D.y), D.z + lambda * (full.z - D.z)});
          }
          const double height = (D.x - fr.centroid.x) * fr.normal.x + (D.y - fr.centroid.y) * fr.normal.y +
                                (D.z - fr.centroid.z) * fr.normal.z;
          if (height > 0)
            for (double times : {1.0, 3.0, 7.0})
              targets.push_back({D.x + times * height * fr.normal.x, D.y + times * height * fr.normal.y,
                                 D.z + times * height * fr.normal.z});
          auto accept = [&](const std::vector<std::array<Vec3, 4>>& moved) {
            int bad_after = 0;
            double w = 180;
            for (std::size_t i = 0; i < moved.size(); ++i) {
              const auto& c4 = moved[i];
              w = std::min(w, tet_min_dihedral_deg(c4[0], c4[1], c4[2], c4[3]));
              bad_after += !curved_ok(m_.tet(ball[i]), c4);
            }
            return w >= floor_deg && bad_after < bad_before;
          };
          for (const Vec3& target : targets) {
            if (m_.relocate_point_if(d, target, accept)) {
              ++st_.curving_lifts;
              ++lifted;
              done = true;
              break;
            }
          }
        }
        // Else a new interior point above each face of the tet, Bowyer-Watson, accepted when its
        // new tets are all valid curved elements of at least 1 degree.
        for (int k = 0; k < 4 && !done; ++k) {
          const Vec3& D = m_.point(q[k]);
          FaceFrame fr;
          if (!face_frame(m_.point(q[kFace[k][0]]), m_.point(q[kFace[k][1]]), m_.point(q[kFace[k][2]]), D, &fr))
            continue;
          const Vec3& G = fr.centroid;
          auto accept = [&](const std::vector<std::array<Index, 4>>& cone, const Vec3& p) {
            for (const auto& c4 : cone) {
              const std::array<Vec3, 4> P{m_.point(c4[0]), m_.point(c4[1]), m_.point(c4[2]), p};
              if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) < 1.0 || !curved_ok(c4, P)) return false;
            }
            return true;
          };
          // Over the face at the height of a regular tet (or less), then on the segment from the
          // face's centroid to the opposite corner (thin walls, where the first points fall out).
          std::vector<Vec3> cand;
          for (double f : {1.0, 0.5, 0.25}) cand.push_back(fr.apex(f));
          for (double lambda : {0.5, 0.33, 0.67})
            cand.push_back({G.x + lambda * (D.x - G.x), G.y + lambda * (D.y - G.y), G.z + lambda * (D.z - G.z)});
          for (const Vec3& x : cand) {
            Index np = -1;
            if (m_.insert_point(t, x, 0.05 * fr.mean_edge, &np, 256, false, accept) == InsertOutcome::kInserted) {
              ++st_.insertions;
              ++st_.curving_lifts;
              ++lifted;
              done = true;
              break;
            }
          }
        }
      }
      if (lifted == 0) return;
    }
  }

  // ---- Curved tet10 validity -------------------------------------------------------------------
  // Once the surface is final: the tags of each boundary edge's faces, for the projection hook.
  void prepare_curved_check() {
    edge_tags_.clear();
    projected_.clear();
    for (const auto& [face, parent] : m_.boundary_faces())
      for (int k = 0; k < 3; ++k) {
        const Index a = face[k], b = face[(k + 1) % 3];
        const std::array<Index, 2> key{std::min(a, b), std::max(a, b)};
        const std::int32_t tag = m_.tag_of(parent);
        auto it = edge_tags_.find(key);
        if (it == edge_tags_.end())
          edge_tags_.emplace(key, std::array<std::int32_t, 2>{tag, tag});
        else
          it->second[1] = tag;
      }
  }

  // True when the tet10 of corners q at positions P, its boundary edges' mid-nodes on the true
  // surface (projection hook) and the others straight, has a Jacobian determinant certified
  // positive (certify_tet10); straight elements are true at once (their corner tet is positive).
  bool curved_element_ok(const std::array<Index, 4>& q, const std::array<Vec3, 4>& P) {
    static const int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
    double x[30];
    bool curved = false;
    for (int k = 0; k < 4; ++k) x[3 * k] = P[k].x, x[3 * k + 1] = P[k].y, x[3 * k + 2] = P[k].z;
    for (int e = 0; e < 6; ++e) {
      const int i = kEdge[e][0], j = kEdge[e][1];
      Vec3 mid{0.5 * (P[i].x + P[j].x), 0.5 * (P[i].y + P[j].y), 0.5 * (P[i].z + P[j].z)};
      const std::array<Index, 2> key{std::min(q[i], q[j]), std::max(q[i], q[j])};
      auto tg = edge_tags_.find(key);
      if (tg != edge_tags_.end()) {
        auto pr = projected_.find(key);  // boundary points never move: a safe cache
        if (pr == projected_.end()) {
          const auto tt = tg->second;
          Vec3 y = o_.projection(mid, tt[0], tt[1] != tt[0] ? tt[1] : -1);
          if (!std::isfinite(y.x) || !std::isfinite(y.y) || !std::isfinite(y.z)) y = mid;
          pr = projected_.emplace(key, y).first;
        }
        curved = curved || squared_distance(pr->second, mid) > 0;
        mid = pr->second;
      }
      x[3 * (4 + e)] = mid.x, x[3 * (4 + e) + 1] = mid.y, x[3 * (4 + e) + 2] = mid.z;
    }
    return !curved || certify_tet10(x) == Tet10Validity::kCertified;
  }

  std::array<Vec3, 4> corner_points(const std::array<Index, 4>& q) const {
    return {m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3])};
  }

  // After the lifts (curved tet10 through a hook): the tets below `below` degrees, worst first,
  // get 3-2 and 2-3 flips, edge removals, moves of their interior corners (towards their
  // neighbours' centroid, then steepest ascent), collapses of their interior Steiner corners and
  // new interior points (insert_keeping_curved).
  // A change is applied when the worst tet it makes is better than the worst it replaces and the
  // curved elements it makes invalid are not more than those it removes (the lifts and insertions
  // for curved elements accept down to 1 degree; this takes the worst back up). Input points and
  // the surface never move. Rounds while something changes and the mesh's worst tet rose in one of
  // the last kPolishPatienceRounds rounds (at most kPolishMaxRounds); returns the changes made. No
  // change lowers the worst tet it replaces, so the mesh's worst never drops here. (At most 4
  // rounds left t20_data at 6.3 degrees where its worst was still rising: 8.1 after 16.)
  std::int64_t polish_curved(double below) {
    const TetsAccept accept = [&](const std::vector<std::array<Index, 4>>& removed,
                                  const std::vector<std::array<Index, 4>>& created) {
      double worst_before = 180;
      int bad_before = 0;
      for (const auto& r : removed) {
        const auto P = corner_points(r);
        worst_before = std::min(worst_before, tet_min_dihedral_deg(P[0], P[1], P[2], P[3]));
        bad_before += !curved_element_ok(r, P);
      }
      std::vector<std::array<Vec3, 4>> made;
      made.reserve(created.size());
      for (const auto& c : created) {
        made.push_back(corner_points(c));
        const auto& P = made.back();
        if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) <= worst_before) return false;
      }
      int bad_after = 0;
      for (std::size_t i = 0; i < created.size(); ++i)
        if (!curved_element_ok(created[i], made[i]) && ++bad_after > bad_before) return false;
      return true;
    };
    std::int64_t changes = 0;
    double worst = worst_quality();
    for (int round = 0, idle = 0; round < kPolishMaxRounds && idle < kPolishPatienceRounds; ++round) {
      poll("optimizing curved elements", 0.97);
      std::int64_t now = 0;
      for (Index t : tets_below(below)) {
        if (!m_.tet_alive(t) || m_.tet_quality(t) >= below) continue;
        const auto q = m_.tet(t);
        bool done = false;
        for (int i = 0; i < 4 && !done; ++i)
          for (int j = i + 1; j < 4 && !done; ++j)
            if (m_.flip32(q[i], q[j], accept)) {
              ++st_.flips32;
              done = true;
            }
        for (int k = 0; k < 4 && !done; ++k)
          if (m_.flip23(t, k, accept)) {
            ++st_.flips23;
            done = true;
          }
        for (int i = 0; i < 4 && !done; ++i)
          for (int j = i + 1; j < 4 && !done; ++j)
            if (m_.remove_edge(q[i], q[j], kMaxEdgeRing, accept, 4)) {
              ++st_.edge_removals;
              done = true;
            }
        for (int k = 0; k < 4 && !done; ++k)
          if (move_keeping_curved(q[k])) {
            ++st_.relocations;
            done = true;
          }
        for (int k = 0; k < 4 && !done; ++k) {
          const Index from = q[k];
          if (m_.support(from).kind != Support::kInterior) continue;
          std::vector<std::pair<double, Index>> near;
          for (Index s2 : m_.tets_around_point(from))
            for (Index w : m_.tet(s2))
              if (w != from) near.emplace_back(length(from, w), w);
          std::sort(near.begin(), near.end());
          near.erase(std::unique(near.begin(), near.end()), near.end());
          for (const auto& [l, to] : near) {
            const double lim = o_.split_ratio * target(to);
            if (m_.collapse_edge(from, to, 0.0, std::isfinite(lim) ? lim * lim : kInf, accept)) {
              ++st_.collapses;
              done = true;
              break;
            }
          }
        }
        if (!done && insert_keeping_curved(t)) {
          ++st_.insertions;
          done = true;
        }
        now += done;
      }
      changes += now;
      if (now == 0) break;
      const double now_worst = worst_quality();
      idle = now_worst > worst ? 0 : idle + 1;
      worst = now_worst;
    }
    return changes;
  }

  // A new interior point for tet t (Bowyer-Watson, t forced into the cavity, the smallest angle
  // of the new tets above the replaced ones', every new curved element valid): above each face
  // of t at 1, 1/2 and 1/4 of a regular tet's height, then its circumcentre and centroid; no
  // point closer than a quarter of t's mean edge to a corner of its cavity. What lifts a flat
  // tet whose four corners lie on the surface, which no flip mends. True when one went in.
  bool insert_keeping_curved(Index t) {
    constexpr auto& kFace = kTetOppositeFace;  // types.h
    const auto q = m_.tet(t);
    const auto P = corner_points(q);
    double mean = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) mean += length(q[i], q[j]) / 6;
    std::vector<Vec3> cand;
    for (int k = 0; k < 4; ++k) {
      FaceFrame fr;
      if (face_frame(P[kFace[k][0]], P[kFace[k][1]], P[kFace[k][2]], P[k], &fr))
        for (double f : {1.0, 0.5, 0.25}) cand.push_back(fr.apex(f));
    }
    Vec3 cc;
    double r2 = 0;
    if (tet_circumsphere(P[0], P[1], P[2], P[3], &cc, &r2)) cand.push_back(cc);
    cand.push_back({(P[0].x + P[1].x + P[2].x + P[3].x) / 4, (P[0].y + P[1].y + P[2].y + P[3].y) / 4,
                    (P[0].z + P[1].z + P[2].z + P[3].z) / 4});
    auto accept = [&](const std::vector<std::array<Index, 4>>& cone, const Vec3& p) {
      for (const auto& c4 : cone) {
        const std::array<Vec3, 4> C{m_.point(c4[0]), m_.point(c4[1]), m_.point(c4[2]), p};
        if (!curved_element_ok(c4, C)) return false;
      }
      return true;
    };
    for (const Vec3& x : cand) {
      if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) continue;
      Index np = -1;
      if (m_.insert_point(t, x, 0.25 * mean, &np, 256, true, accept, t) == InsertOutcome::kInserted) {
        set_target(np, 0.25 * (target(q[0]) + target(q[1]) + target(q[2]) + target(q[3])));
        return true;
      }
    }
    return false;
  }

  // Moves interior point v where the worst tet around it gets better and no curved element
  // around it becomes invalid that was valid: towards its neighbours' centroid (all, half, a
  // quarter, a tenth of the way), then steepest ascent (ascend_point). True when v moved.
  bool move_keeping_curved(Index v) {
    if (!m_.point_alive(v) || m_.support(v).kind != Support::kInterior) return false;
    const std::vector<Index> ball = m_.tets_around_point(v);
    double worst_before = 180;
    int bad_before = 0;
    Vec3 c{0, 0, 0};
    int k = 0;
    double mean_edge = 0;
    for (Index t : ball) {
      worst_before = std::min(worst_before, m_.tet_quality(t));
      bad_before += !curved_element_ok(m_.tet(t), corner_points(m_.tet(t)));
      for (Index w : m_.tet(t))
        if (w != v) {
          c.x += m_.point(w).x, c.y += m_.point(w).y, c.z += m_.point(w).z;
          mean_edge += length(v, w);
          ++k;
        }
    }
    if (k == 0) return false;
    c = {c.x / k, c.y / k, c.z / k};
    mean_edge /= k;
    const MoveAccept accept = [&](const std::vector<std::array<Vec3, 4>>& moved) {
      for (const auto& P : moved)
        if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) <= worst_before) return false;
      int bad_after = 0;
      for (std::size_t i = 0; i < moved.size(); ++i)
        if (!curved_element_ok(m_.tet(ball[i]), moved[i]) && ++bad_after > bad_before) return false;
      return true;
    };
    const Vec3 p = m_.point(v);
    for (double f : {1.0, 0.5, 0.25, 0.1})
      if (m_.relocate_point_if(v, {p.x + f * (c.x - p.x), p.y + f * (c.y - p.y), p.z + f * (c.z - p.z)}, accept))
        return true;
    return ascend_point(v, mean_edge, &accept);
  }

  // Tries to make the invalid curved element t valid by changing the connectivity around it: 2-3
  // flips of its interior faces, 3-2 flips and removals of its interior edges, then collapses of
  // its interior Steiner corners onto a neighbour. A change is applied when it lowers the number of invalid
  // curved elements among the tets it replaces and none of its new tets is below min(1 degree,
  // the worst old tet's) (as the lifts below). The surface never changes. True when one was made.
  template <class CurvedOk, class Corners>
  bool reconnect_for_curving(Index t, const CurvedOk& curved_ok, const Corners& corners) {
    static const int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
    const TetsAccept accept = [&](const std::vector<std::array<Index, 4>>& removed,
                                  const std::vector<std::array<Index, 4>>& created) {
      int bad_before = 0;
      double worst_before = 180;
      for (const auto& r : removed) {
        const auto P = corners(r);
        bad_before += !curved_ok(r, P);
        worst_before = std::min(worst_before, tet_min_dihedral_deg(P[0], P[1], P[2], P[3]));
      }
      const double floor_deg = std::min(1.0, worst_before);
      int bad_after = 0;
      for (const auto& c : created) {
        const auto P = corners(c);
        if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) < floor_deg) return false;
        bad_after += !curved_ok(c, P);
        if (bad_after >= bad_before) return false;
      }
      return bad_after < bad_before;
    };
    const auto q = m_.tet(t);
    for (int k = 0; k < 4; ++k)
      if (m_.flip23(t, k, accept)) {
        ++st_.flips23;
        return true;
      }
    for (const auto& e : kEdge)
      if (m_.flip32(q[e[0]], q[e[1]], accept)) {
        ++st_.flips32;
        return true;
      }
    for (const auto& e : kEdge)
      if (m_.remove_edge(q[e[0]], q[e[1]], kMaxEdgeRing, accept, 4)) {
        ++st_.edge_removals;
        return true;
      }
    for (int k = 0; k < 4; ++k) {
      const Index d = q[k];
      if (m_.support(d).kind != Support::kInterior) continue;
      std::vector<Index> nbrs;
      for (Index s : m_.tets_around_point(d))
        for (Index w : m_.tet(s))
          if (w != d) nbrs.push_back(w);
      std::sort(nbrs.begin(), nbrs.end());
      nbrs.erase(std::unique(nbrs.begin(), nbrs.end()), nbrs.end());
      for (Index w : nbrs)
        if (m_.collapse_edge(d, w, 0.0, kInf, accept)) {
          ++st_.collapses;
          return true;
        }
    }
    return false;
  }

  // ---- Phase 2: optimization ------------------------------------------------------------------
  double worst_quality() const {
    double w = 180;
    for (Index t = 0; t < m_.num_tet_slots(); ++t)
      if (m_.tet_alive(t)) w = std::min(w, m_.tet_quality(t));
    return w;
  }

  std::vector<Index> tets_below(double q) const {
    std::vector<std::pair<double, Index>> bad;
    for (Index t = 0; t < m_.num_tet_slots(); ++t)
      if (m_.tet_alive(t) && m_.tet_quality(t) < q) bad.emplace_back(m_.tet_quality(t), t);
    std::sort(bad.begin(), bad.end());
    std::vector<Index> out;
    for (const auto& b : bad) out.push_back(b.second);
    return out;
  }

  std::size_t count_below(double q) const {
    std::size_t n = 0;
    for (Index t = 0; t < m_.num_tet_slots(); ++t) n += m_.tet_alive(t) && m_.tet_quality(t) < q;
    return n;
  }

  // Flips around the tets below `below` degrees, worst first: 3-2 flips of their edges, 2-3 flips
  // of their faces, edge removals (rings of 4 to kMaxEdgeRing), the first that raises the worst
  // tet involved. Up to 4 sweeps while something changes; returns the flips made.
  std::int64_t flip_pass(double below) {
    std::int64_t flips = 0;
    std::vector<char> tried(static_cast<std::size_t>(m_.num_tet_slots()), 0);
    for (int round = 0; round < 4; ++round) {
      std::int64_t now = 0;
      for (Index t : tets_below(below)) {
        if (!m_.tet_alive(t) || (static_cast<std::size_t>(t) < tried.size() && tried[static_cast<std::size_t>(t)]))
          continue;
        if (static_cast<std::size_t>(t) < tried.size()) tried[static_cast<std::size_t>(t)] = 1;
        if (failed_before(flip_failed_at_, t)) continue;
        bool done = false;
        const auto q = m_.tet(t);
        for (int i = 0; i < 4 && !done; ++i)
          for (int j = i + 1; j < 4 && !done; ++j)
            if (m_.flip32(q[i], q[j])) {
              ++st_.flips32;
              done = true;
            }
        for (int k = 0; k < 4 && !done; ++k)
          if (m_.flip23(t, k)) {
            ++st_.flips23;
            done = true;
          }
        for (int i = 0; i < 4 && !done; ++i)
          for (int j = i + 1; j < 4 && !done; ++j)
            if (m_.remove_edge(q[i], q[j], kMaxEdgeRing, {}, 4)) {
              ++st_.edge_removals;
              done = true;
            }
        if (!done) record_failure(flip_failed_at_, t);
        now += done;
      }
      flips += now;
      if (now == 0) break;
    }
    return flips;
  }

  // Collapses short edges (one end a Steiner point), never worsening the worst tet around.
  std::int64_t collapse_pass() {
    std::vector<std::tuple<double, Index, Index>> todo;
    for (const auto& e : m_.edges()) {
      const double l = length(e[0], e[1]);
      const double t = edge_target(e[0], e[1]);
      if (std::isfinite(t) ? l < o_.collapse_ratio * t : false) todo.emplace_back(l / t, e[0], e[1]);
    }
    std::sort(todo.begin(), todo.end());
    // New tets stay at or above min(max(collapse_min_dihedral_deg, the mesh's worst tet), the
    // worst tet around the point): the mesh's worst dihedral angle never drops.
    const double floor = std::max(o_.collapse_min_dihedral_deg, worst_quality());
    std::int64_t n = 0;
    for (const auto& [r, u, v] : todo) {
      if (!m_.point_alive(u) || !m_.point_alive(v)) continue;
      for (const auto& [from, to] : {std::pair<Index, Index>{u, v}, std::pair<Index, Index>{v, u}}) {
        if (m_.support(from).kind == Support::kInputVertex) continue;
        const double lim = o_.split_ratio * target(to);
        if (m_.collapse_edge(from, to, floor, std::isfinite(lim) ? lim * lim : kInf)) {
          ++n;
          break;
        }
      }
    }
    st_.collapses += n;
    return n;
  }

  // Removes Steiner corners of the tets below `below` degrees whatever their edge lengths: each
  // such corner (not an input point) is collapsed onto one of its neighbours, nearest first,
  // when every new tet is positive (exact), none is worse than the worst tet around the corner
  // was, and either the worst gets better or fewer tets are below `below` there. Meant for flat
  // tets that moving one point never mends: three nearly collinear Steiner points make a flat tet
  // wherever its fourth corner goes, and a layer of Steiner points a few ulps inside a plane (the
  // core's relocated surface points) traps each of them between the plane and the others. Each
  // collapse removes a point, so the pass ends.
  std::int64_t flat_collapse_pass(double below) {
    std::int64_t n = 0;
    std::vector<std::pair<double, Index>> near;
    for (Index t : tets_below(below)) {
      if (!m_.tet_alive(t) || m_.tet_quality(t) >= below) continue;
      const auto q = m_.tet(t);
      bool done = false;
      for (int i = 0; i < 4 && !done; ++i) {
        const Index from = q[i];
        if (!m_.point_alive(from) || m_.support(from).kind == Support::kInputVertex) continue;
        near.clear();
        double old_min = 180;
        std::size_t old_below = 0;
        for (Index s : m_.tets_around_point(from)) {
          old_min = std::min(old_min, m_.tet_quality(s));
          old_below += m_.tet_quality(s) < below;
          for (Index w : m_.tet(s))
            if (w != from && std::find_if(near.begin(), near.end(), [&](const auto& p) { return p.second == w; }) == near.end())
              near.emplace_back(length(from, w), w);
        }
        std::sort(near.begin(), near.end());
        auto better = [&](const std::vector<std::array<Index, 4>>&, const std::vector<std::array<Index, 4>>& created) {
          double worst = 180;
          std::size_t now_below = 0;
          for (const auto& c : created) {
            const double a = tet_min_dihedral_deg(m_.point(c[0]), m_.point(c[1]), m_.point(c[2]), m_.point(c[3]));
            worst = std::min(worst, a);
            now_below += a < below;
          }
          return worst > old_min || now_below < old_below;  // (collapse_edge: worst >= old_min)
        };
        for (const auto& [l, to] : near) {
          const double lim = o_.split_ratio * target(to);  // no edge longer than a split allows
          if (m_.collapse_edge(from, to, 180.0, std::isfinite(lim) ? lim * lim : kInf, better)) {
            ++n;
            done = true;
            break;
          }
        }
      }
    }
    st_.flat_collapses += n;
    st_.collapses += n;
    return n;
  }

  // ODT smoothing (optimal Delaunay triangulation, Chen and Holst; CGAL's odt_optimize_mesh_3):
  // every interior point moves to the volume-weighted mean of its tets' circumcentres, the
  // minimizer of the interpolation error of |x|^2 over its ball, which evens out the whole mesh
  // rather than its worst tets only. A move is applied when every tet around stays positive
  // (exact), the mean of their smallest dihedral angles rises, and their worst stays at least
  // min(the worst before, kOdtKeepDeg). Points are visited in index order. Returns the moves.
  std::int64_t odt_smooth_pass() {
    std::int64_t n = 0;
    for (Index v = 0; v < m_.num_points(); ++v) {
      if (!m_.point_alive(v) || m_.support(v).kind != Support::kInterior) continue;
      const std::vector<Index> ball = m_.tets_around_point(v);
      if (ball.empty()) continue;
      double wsum = 0, mean_before = 0, worst_before = 180;
      Vec3 x{0, 0, 0};
      bool ok = true;
      for (Index t : ball) {
        const auto P = corner_points(m_.tet(t));
        Vec3 c;
        double r2 = 0;
        if (!tet_circumsphere(P[0], P[1], P[2], P[3], &c, &r2)) {
          ok = false;
          break;
        }
        const double ux = P[1].x - P[0].x, uy = P[1].y - P[0].y, uz = P[1].z - P[0].z;
        const double wx = P[2].x - P[0].x, wy = P[2].y - P[0].y, wz = P[2].z - P[0].z;
        const double dx = P[3].x - P[0].x, dy = P[3].y - P[0].y, dz = P[3].z - P[0].z;
        const double vol = std::abs(dx * (uy * wz - uz * wy) + dy * (uz * wx - ux * wz) + dz * (ux * wy - uy * wx));
        x.x += vol * c.x, x.y += vol * c.y, x.z += vol * c.z;
        wsum += vol;
        mean_before += m_.tet_quality(t);
        worst_before = std::min(worst_before, m_.tet_quality(t));
      }
      if (!ok || !(wsum > 0)) continue;
      x = {x.x / wsum, x.y / wsum, x.z / wsum};
      mean_before /= static_cast<double>(ball.size());
      const double keep = std::min(worst_before, kOdtKeepDeg);
      const MoveAccept accept = [&](const std::vector<std::array<Vec3, 4>>& moved) {
        double mean = 0;
        for (const auto& P : moved) {
          const double q = tet_min_dihedral_deg(P[0], P[1], P[2], P[3]);
          if (q < keep) return false;
          mean += q;
        }
        return mean / static_cast<double>(moved.size()) > mean_before + 1e-9;
      };
      const Vec3 p = m_.point(v);
      for (double f : {1.0, 0.5})
        if (m_.relocate_point_if(v, {p.x + f * (x.x - p.x), p.y + f * (x.y - p.y), p.z + f * (x.z - p.z)}, accept)) {
          ++n;
          break;
        }
    }
    st_.relocations += n;
    return n;
  }

  // Moves interior points towards the centroid of their neighbours when it helps the worst tet.
  std::int64_t smooth_pass(double below) {
    std::vector<Index> pts;
    std::vector<char> seen(static_cast<std::size_t>(m_.num_points()), 0);
    for (Index t : tets_below(below))
      for (Index v : m_.tet(t))
        if (!seen[static_cast<std::size_t>(v)] && m_.support(v).kind == Support::kInterior) {
          seen[static_cast<std::size_t>(v)] = 1;
          pts.push_back(v);
        }
    std::int64_t n = 0;
    for (Index v : pts) n += smooth_point(v) ? 1 : 0;
    st_.relocations += n;
    return n;
  }

  // Tries a few positions for interior point v and keeps the first that raises the worst tet
  // around it: towards the centroid of its neighbours, then away from the face opposite v in its
  // worst tet (lifting a flat tet).
  bool smooth_point(Index v) {
    if (!m_.point_alive(v) || m_.support(v).kind != Support::kInterior) return false;
    const std::vector<Index> ball = m_.tets_around_point(v);
    Vec3 c{0, 0, 0};
    int k = 0;
    double mean_edge = 0, worst = 180;
    Index worst_tet = -1;
    for (Index t : ball) {
      if (m_.tet_quality(t) < worst) {
        worst = m_.tet_quality(t);
        worst_tet = t;
      }
      for (Index w : m_.tet(t))
        if (w != v) {
          c.x += m_.point(w).x;
          c.y += m_.point(w).y;
          c.z += m_.point(w).z;
          mean_edge += std::sqrt(squared_distance(m_.point(v), m_.point(w)));
          ++k;
        }
    }
    if (k == 0) return false;
    c = {c.x / k, c.y / k, c.z / k};
    mean_edge /= k;
    const Vec3 p = m_.point(v);
    for (double f : {1.0, 0.5, 0.25, 0.1}) {
      const Vec3 q{p.x + f * (c.x - p.x), p.y + f * (c.y - p.y), p.z + f * (c.z - p.z)};
      if (m_.relocate_point(v, q)) return true;
    }
    // Normal of the face opposite v in its worst tet, pointing to the side of the neighbours'
    // centroid (v itself may lie almost on that face's plane).
    const auto& q = m_.tet(worst_tet);
    Vec3 f[3];
    int j = 0;
    for (Index w : q)
      if (w != v) f[j++] = m_.point(w);
    const double ux = f[1].x - f[0].x, uy = f[1].y - f[0].y, uz = f[1].z - f[0].z;
    const double wx = f[2].x - f[0].x, wy = f[2].y - f[0].y, wz = f[2].z - f[0].z;
    double nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (!(len > 0)) return false;
    const double side = nx * (c.x - f[0].x) + ny * (c.y - f[0].y) + nz * (c.z - f[0].z);
    const double sgn = side >= 0 ? 1.0 : -1.0;
    nx *= sgn / len;
    ny *= sgn / len;
    nz *= sgn / len;
    for (double a : {0.3, 0.15, 0.07, 0.03, 0.01}) {
      const Vec3 r{p.x + a * mean_edge * nx, p.y + a * mean_edge * ny, p.z + a * mean_edge * nz};
      if (m_.relocate_point(v, r)) return true;
    }
    return ascend_point(v, mean_edge);
  }

  // Steepest ascent of the worst min dihedral angle of the tets around interior point v. The angle
  // is not smooth: central differences (step 1e-4 of the mean edge) give the ascent direction of
  // the worst tets, a halving line search from 0.1 of the mean edge the step; a step is taken
  // only through relocate_point (exact positivity, a strictly better worst angle). At most 8
  // steps; true when v moved. The doubles here only choose candidates.
  bool ascend_point(Index v, double mean_edge, const MoveAccept* keep = nullptr) {
    if (!(mean_edge > 0)) return false;
    bool moved = false;
    for (int step = 0; step < 8; ++step) {
      const std::vector<Index> ball = m_.tets_around_point(v);
      auto worst_at = [&](const Vec3& p) {
        double w = 180;
        for (Index t : ball) {
          const auto& q = m_.tet(t);
          Vec3 c[4];
          for (int k = 0; k < 4; ++k) c[k] = q[k] == v ? p : m_.point(q[k]);
          if (orient3d(c[0], c[1], c[2], c[3]) != Sign::kPositive) return -1.0;
          w = std::min(w, tet_min_dihedral_deg(c[0], c[1], c[2], c[3]));
        }
        return w;
      };
      const Vec3 p = m_.point(v);
      const double f0 = worst_at(p), d = 1e-4 * mean_edge;
      double g[3];
      for (int c = 0; c < 3; ++c) {
        Vec3 a = p, b = p;
        (c == 0 ? a.x : c == 1 ? a.y : a.z) += d;
        (c == 0 ? b.x : c == 1 ? b.y : b.z) -= d;
        g[c] = (worst_at(a) - worst_at(b)) / (2 * d);
      }
      const double norm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
      if (!(norm > 0) || !std::isfinite(norm)) break;
      bool ok = false;
      for (double a = 0.1 * mean_edge; a > 1e-3 * mean_edge && !ok; a *= 0.5) {
        const Vec3 q{p.x + a * g[0] / norm, p.y + a * g[1] / norm, p.z + a * g[2] / norm};
        ok = worst_at(q) > f0 + 1e-9 && (keep ? m_.relocate_point_if(v, q, *keep) : m_.relocate_point(v, q));
      }
      if (!ok) break;
      moved = true;
    }
    return moved;
  }

  // Tets below `below` degrees: a new interior point where it makes them better (Bowyer-Watson
  // cavity, RefineMesh::insert_point with must_improve, the tet itself forced into the cavity).
  // Candidates, in order: above each face of the tet, at 1, 1/2 and 1/4 of the height of a
  // regular tet on that face, on the side of the tet (the apex that face would want: this is what
  // lifts flat tets whose four corners lie on the surface, which no flip or interior split can
  // mend), then the circumcentre and the centroid. A cap on two nearly coplanar boundary faces
  // has a huge circumsphere that often lies beyond the surface: without forcing it into the
  // cavity the point went in beside it and the cap stayed (triceratops: 17 caps at 0.00
  // degrees).
  std::int64_t insert_pass(double below) {
    std::int64_t n = 0;
    for (Index t : tets_below(below)) {
      if (!m_.tet_alive(t) || failed_before(insert_failed_at_, t)) continue;
      if (insert_for(t))
        ++n;
      else
        record_failure(insert_failed_at_, t);
    }
    return n;
  }

  // Failure memory of the flip and insertion passes: a tet on which every operation failed is not
  // tried again until a tet around one of its corners changes (RefineMesh::tet_stamp). Exact for
  // the 3-2 and 2-3 flips and edge removals up to their checks that a new edge does not exist yet;
  // for insertions the cavity can reach further, so a retry that would now succeed can be skipped
  // (adis16480 at h = diagonal / 20: 2.3 million attempts for 3,600 insertions before this).
  bool failed_before(const std::vector<std::uint64_t>& at, Index t) const {
    const auto i = static_cast<std::size_t>(t);
    return i < at.size() && at[i] != 0 && m_.tet_stamp(t) <= at[i];
  }
  void record_failure(std::vector<std::uint64_t>& at, Index t) {
    const auto i = static_cast<std::size_t>(t);
    if (at.size() <= i) at.resize(std::max<std::size_t>(i + 1, 2 * at.size()), 0);
    at[i] = std::max<std::uint64_t>(m_.clock(), 1);
  }

  // One interior point that improves tet t (see insert_pass); false when no candidate does.
  bool insert_for(Index t) {
    constexpr auto& kFace = kTetOppositeFace;  // types.h
    const bool curved = curved_tet10();       // the pre-session-16 pass there (see curved_tet10)
    {
      const auto q = m_.tet(t);
      Vec3 P[4];
      double mean = 0;
      for (int i = 0; i < 4; ++i) P[i] = m_.point(q[i]);
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) mean += length(q[i], q[j]) / 6;
      std::vector<Vec3> cand;
      for (int k = 0; k < 4; ++k) {
        FaceFrame fr;
        if (face_frame(P[kFace[k][0]], P[kFace[k][1]], P[kFace[k][2]], P[k], &fr))
          for (double f : {1.0, 0.5, 0.25})
            if (f == 1.0 || !curved) cand.push_back(fr.apex(f));
      }
      Vec3 cc;
      double r2 = 0;
      if (tet_circumsphere(P[0], P[1], P[2], P[3], &cc, &r2)) cand.push_back(cc);
      cand.push_back({(P[0].x + P[1].x + P[2].x + P[3].x) / 4, (P[0].y + P[1].y + P[2].y + P[3].y) / 4,
                      (P[0].z + P[1].z + P[2].z + P[3].z) / 4});
      // Local: a global floor (h / 8) kept points away from input surfaces finer than it
      // (triceratops: surface edges 0.1 h, every cap's candidate refused).
      const double clearance = curved ? std::max(floor_, 0.25 * mean) : 0.25 * mean;
      for (const Vec3& x : cand) {
        if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) continue;
        Index p = -1;
        // The cavity is capped at 64 tets: larger ones hardly ever improved a tet, and the failed
        // attempts were most of the pass's time (anchor: the same mesh as with 256, 15% faster).
        if (m_.insert_point(t, x, clearance, &p, curved ? 256 : 64, true, {}, curved ? -1 : t) != InsertOutcome::kInserted)
          continue;
        ++st_.insertions;
        double tg = 0;
        for (Index v : q) tg += target(v) / 4;
        set_target(p, tg);
        for (int k = 0; k < 3 && smooth_point(p); ++k) ++st_.relocations;
        return true;
      }
    }
    return false;
  }

  // Tets still worse than `below` after flips and smoothing: split their longest interior edge and
  // smooth the new point. Only with a size: without one, this made the mesh grow round after round
  // while the worst angle stayed (Pump_Nut: 2307 -> 16030 tets in 3 rounds, still 0 degrees).
  std::int64_t sliver_pass(double below) {
    std::int64_t n = 0;
    // No split may make a tet worse than the mesh's worst: unchecked splits here made slivers
    // that no later pass removed (hinge at h = diagonal / 20: the last optimization's sliver
    // splits took the worst angle from 4.4 to 1.3 degrees, and it ended at 2.3).
    const double keep = curved_tet10() ? 0.0 : worst_quality();
    for (Index t : tets_below(below)) {
      if (!m_.tet_alive(t)) continue;
      const auto q = m_.tet(t);
      std::vector<std::tuple<double, Index, Index>> e;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
          if (m_.edge_kind(q[i], q[j]) == EdgeKind::kInterior) e.emplace_back(-length(q[i], q[j]), q[i], q[j]);
      std::sort(e.begin(), e.end());
      for (const auto& [l, a, b] : e) {
        if (-l <= 2 * floor_) break;
        Index p = -1;
        if (m_.split_edge(a, b, keep, &p) != SplitOutcome::kSplit) continue;
        ++st_.splits;
        set_target(p, 0.5 * (target(a) + target(b)));
        for (int k = 0; k < 3 && smooth_point(p); ++k) ++st_.relocations;
        ++n;
        break;
      }
    }
    return n;
  }

  // Tets worse than the bound: their shortest edge collapsed (if it helps), else their longest
  // edge split (if it is long enough).
  std::int64_t radius_edge_pass() {
    if (o_.radius_edge_bound <= 0) return 0;
    std::vector<std::pair<double, Index>> bad;
    for (Index t = 0; t < m_.num_tet_slots(); ++t) {
      if (!m_.tet_alive(t)) continue;
      const auto& q = m_.tet(t);
      const double r = tet_radius_edge_ratio(m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3]));
      if (r > o_.radius_edge_bound) bad.emplace_back(-r, t);
    }
    std::sort(bad.begin(), bad.end());
    std::int64_t n = 0;
    for (const auto& [r, t] : bad) {
      if (!m_.tet_alive(t)) continue;
      const auto q = m_.tet(t);
      std::vector<std::tuple<double, Index, Index>> e;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) e.emplace_back(length(q[i], q[j]), q[i], q[j]);
      std::sort(e.begin(), e.end());
      const auto [ls, a, b] = e.front();
      bool done = false;
      for (const auto& [from, to] : {std::pair<Index, Index>{a, b}, std::pair<Index, Index>{b, a}}) {
        if (m_.support(from).kind == Support::kInputVertex) continue;
        const double lim = o_.split_ratio * target(to);
        if (m_.collapse_edge(from, to, 180.0, std::isfinite(lim) ? lim * lim : kInf)) {
          ++st_.collapses;
          done = true;
          break;
        }
      }
      const auto [ll, c, d] = e.back();
      if (!done && ll > 2 * floor_) done = split(c, d, 0);
      n += done;
    }
    return n;
  }

  void optimize_phase(int rounds) {
    const double goal = o_.min_dihedral_deg > 0 ? o_.min_dihedral_deg : 70.0;
    const double goal_below = o_.min_dihedral_deg;  // 0 when not asked
    // The sliver pass runs while the number of tets below its bound falls from round to round. On
    // inputs whose small angles make every split near them another sliver it rose round after
    // round instead (adis16480 at h = diagonal / 20: 14,000 -> 62,000 such tets, 21,000 -> 157,000
    // tets in all, the worst angle still 0.1 degree), so it stops at the first rise.
    std::size_t slivers_before = std::numeric_limits<std::size_t>::max();
    for (int round = 0; round < rounds; ++round) {
      poll("optimizing", 0.5 + 0.5 * round / std::max(1, rounds));
      std::int64_t changes = 0;
      changes += timed("collapse", [&] { return collapse_pass(); });
      changes += timed("collapse", [&] { return flat_collapse_pass(kFlatCollapseBelowDeg); });
      changes += timed("smooth", [&] { return odt_smooth_pass(); });
      changes += timed("flip", [&] { return flip_pass(std::max(goal_below, kFlipBelowDeg)); });
      changes += timed("smooth", [&] { return smooth_pass(std::max(goal_below, kFlipBelowDeg)); });
      changes += timed("radius_edge", [&] { return radius_edge_pass(); });
      changes += timed("flip", [&] { return flip_pass(std::max(goal_below, kFlipBelowDeg)); });
      changes += timed("insert", [&] { return insert_pass(std::min(goal, 15.0)); });
      if (round + 1 < rounds && std::isfinite(o_.size)) {
        const std::size_t slivers = count_below(std::min(goal, 15.0));
        // Curved tet10 elements need room over the curved faces, which these splits give:
        // there the pass goes on while the mesh stays within three times its size after the
        // first size phase (featuretype.STEP meshes at tet10 with it, not without).
        const bool curved = curved_tet10();
        if (slivers < slivers_before || (curved && m_.num_alive_tets() <= 3 * tets_after_size_))
          changes += timed("sliver", [&] { return sliver_pass(std::min(goal, 15.0)); });
        slivers_before = slivers < slivers_before ? slivers : 0;
      }
      ++st_.optimize_rounds;
      if (changes == 0 || (o_.min_dihedral_deg > 0 && worst_quality() >= o_.min_dihedral_deg)) break;
    }
  }

  // Curved tet10 through a projection hook (FreeCAD's tet10). Its insertion and sliver passes
  // stay in their earlier form (no forced tet, one height, the h / 8 clearance floor,
  // sliver splits not held to the worst angle; only insert_point's walk is the new one): the
  // curving stage after them needs the room those left over curved faces. With the newer
  // passes 9 of the 13 CAD corpus files meshed at tet10 instead of 10 (featuretype.STEP and
  // bottle.brep stopped with inverted curved elements, SampleCrankshaft4A meshed).
  bool curved_tet10() const { return o_.order == 2 && static_cast<bool>(o_.projection); }

  // Runs f, adding its wall time to st_.seconds_by_pass[pass]; returns f's result.
  template <class F>
  std::int64_t timed(const char* pass, F&& f) {
    const auto start = std::chrono::steady_clock::now();
    const std::int64_t result = f();
    st_.seconds_by_pass[pass] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

  RefineMesh& m_;
  const RefineOptions& o_;
  RefineStats& st_;
  std::vector<double> target_;
  std::map<std::array<Index, 2>, std::array<std::int32_t, 2>> edge_tags_;  // prepare_curved_check
  std::map<std::array<Index, 2>, Vec3> projected_;  // hook results at boundary edge midpoints
  struct Stuck {  ///< an edge that could not be split
    Vec3 a, b;
    double lo[3], hi[3];
    double reach;  ///< length / split_ratio
  };
  std::vector<Stuck> stuck_;
  double floor_ = 0;
  std::unique_ptr<WallThickness> walls_;  ///< thickness_ratio: the input's walls, built once
  Index budget_ = 0;
  std::vector<std::uint64_t> flip_failed_at_, insert_failed_at_;  ///< see failed_before
  Index tets_after_size_ = 0;  ///< live tets after the first size phase (optimize_phase)
};

}  // namespace

TetMesh refine_quality(const SurfaceMesh& surface, const TetMesh& mesh, const RefineOptions& options,
                       RefineStats* stats, SurfaceMesh* boundary) {
  const auto start = std::chrono::steady_clock::now();
  check_options(options);
  RefineStats st;
  RefineMesh m(surface, mesh, options.projection, options.surface_points);
  m.set_fixed_tags(options.fixed_tags);
  Refiner(m, options, st).run();
  if (boundary) {
    std::vector<Index> old_to_new;
    m.to_tet_mesh(&old_to_new);  // the numbering of the result (make_second_order's corners too)
    *boundary = SurfaceMesh{};
    for (const auto& [face, parent] : m.boundary_faces()) {
      for (Index v : face) boundary->tri.push_back(old_to_new[static_cast<std::size_t>(v)]);
      boundary->tag.push_back(m.tag_of(parent));
    }
  }
  TetMesh out;
  if (options.order == 2) {
    SecondOrderStats so;
    const auto lift_start = std::chrono::steady_clock::now();
    out = make_second_order(m, options.projection, &so);
    st.seconds_by_pass["tet10"] += std::chrono::duration<double>(std::chrono::steady_clock::now() - lift_start).count();
    st.midnodes_projected = so.projected;
    st.midnodes_straightened = so.straightened;
    st.midnodes_relaxed_tets = so.relaxed;
    st.midnodes_moved_interior = so.interior_moved;
    st.midnodes_moved_surface = so.surface_moved;
    st.lift_insertions = so.points_inserted;
  } else {
    out = m.to_tet_mesh();
  }
  st.tets = out.num_tets();
  st.nodes = out.num_points();
  st.points = m.to_tet_mesh().num_points();
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = st;
  return out;
}

}  // namespace bsptet
