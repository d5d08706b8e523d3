// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage's optimization passes (mesh_optimizer.h).
#include "bsptet/refine/mesh_optimizer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "bsptet/mesh/tet_shape.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// flat_collapse_pass works on the tets below this min dihedral angle (degrees).
constexpr double kFlatCollapseBelowDeg = 1.0;
// A surface point slides (MeshOptimizer::odt_move) only when the mean angle around it rises by
// at least this many degrees: each slide costs a search on the CAD surface.
constexpr double kSlideGainDeg = 0.1;
// ... and only when a tet around it is below this many degrees.
constexpr double kSlideBelowDeg = 40.0;
// ODT smoothing (MeshOptimizer::odt_smooth_pass) never takes a tet below this or below the worst
// before.
constexpr double kOdtKeepDeg = 15.0;
// Sweeps of ODT smoothing per optimization round: a sweep moves each point once, in index order,
// so the second one (over the neighbours of the points that moved) finds them moved. One sweep
// gave a median per-tet worst angle about 0.3 degree lower over the CAD corpus; three or four
// changed it by less than the spread between runs at other sizes, for 5 to 10% more time.
constexpr int kOdtSweeps = 2;
// The flip and smoothing passes of the optimization rounds work on the tets below this (or below
// min_dihedral_deg when it is higher): above it a flip or a move rarely pays for its search
// (flips up to 70 degrees took 2 to 4 times the refinement's time for a median 0.2 degree
// better; the ODT smoothing evens out the typical tet instead).
constexpr double kFlipBelowDeg = 40.0;

}  // namespace

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

void poll_refine(const RefineOptions& o, const std::string& stage, double fraction) {
  if (o.cancelled && o.cancelled())
    throw MeshingError(ErrorCode::kCancelled, "refine", -1, "cancelled during " + stage);
  if (o.progress) o.progress(stage, fraction);
}

std::vector<Index> MeshOptimizer::tets_below(double q) const {
  std::vector<std::pair<double, Index>> bad;
  for (Index t = 0; t < m_.num_tet_slots(); ++t)
    if (m_.tet_alive(t) && m_.tet_quality(t) < q) bad.emplace_back(m_.tet_quality(t), t);
  std::sort(bad.begin(), bad.end());
  std::vector<Index> out;
  for (const auto& b : bad) out.push_back(b.second);
  return out;
}

std::size_t MeshOptimizer::count_below(double q) const {
  std::size_t n = 0;
  for (Index t = 0; t < m_.num_tet_slots(); ++t) n += m_.tet_alive(t) && m_.tet_quality(t) < q;
  return n;
}

// Flips around the tets below `below` degrees, worst first: 3-2 flips of their edges, 2-3 flips
// of their faces, edge removals (rings of 4 to kMaxEdgeRing), the first that raises the worst
// tet involved. Up to 4 sweeps while something changes; returns the flips made.
std::int64_t MeshOptimizer::flip_pass(double below) {
  std::int64_t flips = 0;
  std::vector<char> tried(static_cast<std::size_t>(m_.num_tet_slots()), 0);
  for (int round = 0; round < 4; ++round) {
    std::int64_t now = 0;
    for (Index t : tets_below(below)) {
      if (!m_.tet_alive(t) || (static_cast<std::size_t>(t) < tried.size() && tried[static_cast<std::size_t>(t)]))
        continue;
      if (static_cast<std::size_t>(t) < tried.size()) tried[static_cast<std::size_t>(t)] = 1;
      if (flip_failed_.failed_before(m_, t)) continue;
      bool done = false;
      const auto q = m_.tet(t);
      // The shell sizes of the six edges, looked up once: nothing changes until an operation
      // succeeds, and a 3-2 flip needs a shell of 3, an edge removal one of 4 to kMaxEdgeRing.
      // One scan of each corner's ball counts the shells of its edges to the later corners.
      int shell[4][4] = {};
      for (int i = 0; i < 3; ++i)
        for (Index s : m_.tets_around_point(q[i])) {
          const auto& r = m_.tet(s);
          for (int j = i + 1; j < 4; ++j)
            shell[i][j] += r[0] == q[j] || r[1] == q[j] || r[2] == q[j] || r[3] == q[j];
        }
      for (int i = 0; i < 4 && !done; ++i)
        for (int j = i + 1; j < 4 && !done; ++j)
          if (shell[i][j] == 3 && m_.flip32(q[i], q[j])) {
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
          if (shell[i][j] >= 4 && shell[i][j] <= kMaxEdgeRing && m_.remove_edge(q[i], q[j], kMaxEdgeRing, {}, 4)) {
            ++st_.edge_removals;
            done = true;
          }
      if (!done) flip_failed_.record(m_, t);
      now += done;
    }
    flips += now;
    if (now == 0) break;
  }
  return flips;
}

// Collapses short edges (one end a Steiner point), never worsening the worst tet around.
std::int64_t MeshOptimizer::collapse_pass() {
  std::vector<std::tuple<double, Index, Index>> todo;
  for (const auto& e : m_.edges()) {
    const double l = size_.length(e[0], e[1]);
    const double t = size_.edge_target(e[0], e[1]);
    if (std::isfinite(t) ? l < o_.collapse_ratio * t : false) todo.emplace_back(l / t, e[0], e[1]);
  }
  std::sort(todo.begin(), todo.end());
  // New tets stay at or above min(max(collapse_min_dihedral_deg, the mesh's worst tet), the
  // worst tet around the point): the mesh's worst dihedral angle never drops.
  const double floor = std::max(o_.collapse_min_dihedral_deg, m_.worst_tet_quality());
  std::int64_t n = 0;
  for (const auto& [r, u, v] : todo) {
    if (!m_.point_alive(u) || !m_.point_alive(v)) continue;
    for (const auto& [from, to] : {std::pair<Index, Index>{u, v}, std::pair<Index, Index>{v, u}}) {
      if (m_.support(from).kind == Support::kInputVertex) continue;
      const double lim = o_.split_ratio * size_.target(to);
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
std::int64_t MeshOptimizer::flat_collapse_pass(double below) {
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
            near.emplace_back(size_.length(from, w), w);
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
        const double lim = o_.split_ratio * size_.target(to);  // no edge longer than a split allows
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
// rather than its worst tets only; failing that, to the centroid of its neighbours. A move (all the
// way, else half way) is applied when every tet around stays positive
// (exact), the mean of their smallest dihedral angles rises, and their worst stays at least
// min(the worst before, kOdtKeepDeg). Points are visited in index order: first all, then, in
// each further sweep, those next to a point the sweep before moved. Returns the moves.
std::int64_t MeshOptimizer::odt_smooth_pass(int sweeps) {
  std::int64_t n = 0;
  const std::size_t np = static_cast<std::size_t>(m_.num_points());
  std::vector<char> active(np, 1), next(np, 0);
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    std::int64_t moved = 0;
    for (Index v = 0; v < m_.num_points(); ++v)
      if (active[static_cast<std::size_t>(v)] && odt_move(v, &next)) ++moved;
    n += moved;
    if (moved == 0) break;
    active.swap(next);
    std::fill(next.begin(), next.end(), 0);
  }
  st_.relocations += n;
  return n;
}

// One point's move of odt_smooth_pass; marks the corners of its tets in moved_near when it moves.
bool MeshOptimizer::odt_move(Index v, std::vector<char>* moved_near) {
  if (!m_.point_alive(v)) return false;
  const bool slides = m_.slides(v);
  if (!slides && m_.support(v).kind != Support::kInterior) return false;
  // The ODT point, the centroids and every check depend on the tets around v only.
  if (odt_failed_.skip(m_, v)) return false;
  const std::vector<Index> ball = m_.tets_around_point(v);
  if (ball.empty()) return false;
  double wsum = 0, mean_before = 0, worst_before = 180;
  Vec3 x{0, 0, 0};
  bool ok = true;
  for (Index t : ball) {
    const auto P = corner_points(m_, m_.tet(t));
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
  if (!ok || !(wsum > 0)) return false;
  if (slides && worst_before >= kSlideBelowDeg) return false;
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
    return mean / static_cast<double>(moved.size()) > mean_before + (slides ? kSlideGainDeg : 1e-9);
  };
  const Vec3 p = m_.point(v);
  // All the way, else half way, towards y (a sliding point: then back onto its face); marks v's
  // neighbours when v moved.
  const auto move_towards = [&](const Vec3& y) {
    for (double f : {1.0, 0.5}) {
      const Vec3 q{p.x + f * (y.x - p.x), p.y + f * (y.y - p.y), p.z + f * (y.z - p.z)};
      if (slides ? m_.slide_point_if(v, q, accept) : m_.relocate_point_if(v, q, accept)) {
        for (Index t : ball)
          for (Index w : m_.tet(t)) (*moved_near)[static_cast<std::size_t>(w)] = 1;
        return true;
      }
    }
    return false;
  };
  if (slides) {
    // A surface point: towards the centroid of its boundary neighbours (the surface mesh evened
    // out along the face), else the ODT point, each put back on its face. Over the CAD corpus at
    // h = diagonal / 20, tet10, the median per-tet worst angle rose by 0.06 degree with the
    // centroid alone, 0.33 with the ODT point alone, 0.43 with both.
    const std::vector<Index> around = m_.boundary_neighbours(v);
    if (!around.empty()) {
      Vec3 c{0, 0, 0};
      for (Index w : around) c.x += m_.point(w).x, c.y += m_.point(w).y, c.z += m_.point(w).z;
      const double k = static_cast<double>(around.size());
      if (move_towards({c.x / k, c.y / k, c.z / k})) return true;
    }
    return move_towards(x);
  }
  if (move_towards(x)) return true;
  // Then the centroid of its neighbours (Laplacian smoothing), where the ODT point is refused:
  // next to the surface the ODT point is pulled by the large circumspheres of the boundary
  // tets, while the centroid still evens the ball out (on the CAD corpus the median per-tet
  // worst angle rose by about 0.3 degree with it).
  Vec3 centroid{0, 0, 0};
  int k = 0;
  for (Index t : ball)
    for (Index w : m_.tet(t))
      if (w != v) centroid.x += m_.point(w).x, centroid.y += m_.point(w).y, centroid.z += m_.point(w).z, ++k;
  return move_towards({centroid.x / k, centroid.y / k, centroid.z / k});
}

// Moves interior points towards the centroid of their neighbours when it helps the worst tet.
std::int64_t MeshOptimizer::smooth_pass(double below) {
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
bool MeshOptimizer::smooth_point(Index v) {
  if (!m_.point_alive(v) || m_.support(v).kind != Support::kInterior) return false;
  if (smooth_failed_.skip(m_, v)) return false;  // its candidates depend on the tets around v only
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
bool MeshOptimizer::ascend_point(Index v, double mean_edge, const MoveAccept* keep) {
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
std::int64_t MeshOptimizer::insert_pass(double below) {
  std::int64_t n = 0;
  for (Index t : tets_below(below)) {
    if (!m_.tet_alive(t) || insert_failed_.failed_before(m_, t)) continue;
    if (insert_for(t))
      ++n;
    else
      insert_failed_.record(m_, t);
  }
  return n;
}

// One interior point that improves tet t (see insert_pass); false when no candidate does.
bool MeshOptimizer::insert_for(Index t) {
  constexpr auto& kFace = kTetOppositeFace;  // types.h
  const bool curved = curved_tet10();       // the earlier form of the pass there (see curved_tet10)
  {
    const auto q = m_.tet(t);
    Vec3 P[4];
    double mean = 0;
    for (int i = 0; i < 4; ++i) P[i] = m_.point(q[i]);
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) mean += size_.length(q[i], q[j]) / 6;
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
    const double clearance = curved ? std::max(size_.floor(), 0.25 * mean) : 0.25 * mean;
    for (const Vec3& x : cand) {
      if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) continue;
      Index p = -1;
      // The cavity is capped at 64 tets: larger ones hardly ever improved a tet, and the failed
      // attempts were most of the pass's time (anchor: the same mesh as with 256, 15% faster).
      if (m_.insert_point(t, x, clearance, &p, curved ? 256 : 64, true, {}, curved ? -1 : t) != InsertOutcome::kInserted)
        continue;
      ++st_.insertions;
      double tg = 0;
      for (Index v : q) tg += size_.target(v) / 4;
      size_.set_target(p, tg);
      for (int k = 0; k < 3 && smooth_point(p); ++k) ++st_.relocations;
      return true;
    }
  }
  return false;
}

// Tets still worse than `below` after flips and smoothing: split their longest interior edge and
// smooth the new point. Only with a size: without one, this made the mesh grow round after round
// while the worst angle stayed (Pump_Nut: 2307 -> 16030 tets in 3 rounds, still 0 degrees).
std::int64_t MeshOptimizer::sliver_pass(double below) {
  std::int64_t n = 0;
  // No split may make a tet worse than the mesh's worst: unchecked splits here made slivers
  // that no later pass removed (hinge at h = diagonal / 20: the last optimization's sliver
  // splits took the worst angle from 4.4 to 1.3 degrees, and it ended at 2.3).
  const double keep = curved_tet10() ? 0.0 : m_.worst_tet_quality();
  for (Index t : tets_below(below)) {
    if (!m_.tet_alive(t)) continue;
    const auto q = m_.tet(t);
    std::vector<std::tuple<double, Index, Index>> e;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (m_.edge_kind(q[i], q[j]) == EdgeKind::kInterior) e.emplace_back(-size_.length(q[i], q[j]), q[i], q[j]);
    std::sort(e.begin(), e.end());
    for (const auto& [l, a, b] : e) {
      if (-l <= 2 * size_.floor()) break;
      Index p = -1;
      if (m_.split_edge(a, b, keep, &p) != SplitOutcome::kSplit) continue;
      ++st_.splits;
      size_.set_target(p, 0.5 * (size_.target(a) + size_.target(b)));
      for (int k = 0; k < 3 && smooth_point(p); ++k) ++st_.relocations;
      ++n;
      break;
    }
  }
  return n;
}

// Tets worse than the bound: their shortest edge collapsed (if it helps), else their longest
// edge split (if it is long enough).
std::int64_t MeshOptimizer::radius_edge_pass() {
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
      for (int j = i + 1; j < 4; ++j) e.emplace_back(size_.length(q[i], q[j]), q[i], q[j]);
    std::sort(e.begin(), e.end());
    const auto [ls, a, b] = e.front();
    bool done = false;
    for (const auto& [from, to] : {std::pair<Index, Index>{a, b}, std::pair<Index, Index>{b, a}}) {
      if (m_.support(from).kind == Support::kInputVertex) continue;
      const double lim = o_.split_ratio * size_.target(to);
      if (m_.collapse_edge(from, to, 180.0, std::isfinite(lim) ? lim * lim : kInf)) {
        ++st_.collapses;
        done = true;
        break;
      }
    }
    const auto [ll, c, d] = e.back();
    if (!done && ll > 2 * size_.floor()) done = size_.split(c, d, 0, st_);
    n += done;
  }
  return n;
}

void MeshOptimizer::optimize(int rounds, Index tets_after_size) {
  const double goal = o_.min_dihedral_deg > 0 ? o_.min_dihedral_deg : 70.0;
  const double goal_below = o_.min_dihedral_deg;  // 0 when not asked
  // The sliver pass runs while the number of tets below its bound falls from round to round. On
  // inputs whose small angles make every split near them another sliver it rose round after
  // round instead (adis16480 at h = diagonal / 20: 14,000 -> 62,000 such tets, 21,000 -> 157,000
  // tets in all, the worst angle still 0.1 degree), so it stops at the first rise.
  std::size_t slivers_before = std::numeric_limits<std::size_t>::max();
  for (int round = 0; round < rounds; ++round) {
    poll_refine(o_, "optimizing", 0.5 + 0.5 * round / std::max(1, rounds));
    std::int64_t changes = 0;
    changes += timed_pass(st_, "collapse", [&] { return collapse_pass(); });
    changes += timed_pass(st_, "collapse", [&] { return flat_collapse_pass(kFlatCollapseBelowDeg); });
    changes += timed_pass(st_, "smooth", [&] { return odt_smooth_pass(kOdtSweeps); });
    changes += timed_pass(st_, "flip", [&] { return flip_pass(std::max(goal_below, kFlipBelowDeg)); });
    changes += timed_pass(st_, "smooth", [&] { return smooth_pass(std::max(goal_below, kFlipBelowDeg)); });
    changes += timed_pass(st_, "radius_edge", [&] { return radius_edge_pass(); });
    changes += timed_pass(st_, "flip", [&] { return flip_pass(std::max(goal_below, kFlipBelowDeg)); });
    changes += timed_pass(st_, "insert", [&] { return insert_pass(std::min(goal, 15.0)); });
    if (round + 1 < rounds && std::isfinite(o_.size)) {
      const std::size_t slivers = count_below(std::min(goal, 15.0));
      // Curved tet10 elements need room over the curved faces, which these splits give:
      // there the pass goes on while the mesh stays within three times its size after the
      // first size phase (featuretype.STEP meshes at tet10 with it, not without).
      const bool curved = curved_tet10();
      if (slivers < slivers_before || (curved && m_.num_alive_tets() <= 3 * tets_after_size))
        changes += timed_pass(st_, "sliver", [&] { return sliver_pass(std::min(goal, 15.0)); });
      slivers_before = slivers < slivers_before ? slivers : 0;
    }
    ++st_.optimize_rounds;
    if (changes == 0 || (o_.min_dihedral_deg > 0 && m_.worst_tet_quality() >= o_.min_dihedral_deg)) break;
  }
}

}  // namespace bsptet
