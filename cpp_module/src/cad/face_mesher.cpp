// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: face meshing by local operations in the parameter plane (see face_mesher.h).
#include "bsptet/cad/face_mesher.h"

#include "bsptet/cad/size_field.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <utility>

#include <BRepAdaptor_Surface.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

namespace bsptet::cad {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kSplitRatio = 1.4;     // split edges longer than this times the size
constexpr double kCollapseRatio = 0.7;  // collapse edges shorter than this times the size
constexpr double kSmoothKeep = 0.7;     // smoothing for the mean never takes a triangle below this

Vec3 sub(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 cross(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
double dist(const Vec3& a, const Vec3& b) { return std::sqrt(dot(sub(a, b), sub(a, b))); }
Uv mid(const Uv& a, const Uv& b) { return {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])}; }

class FaceMesher {
 public:
  FaceMesher(const TopoDS_Face& face, const FaceMeshOptions& options) : surface_(face), options_(options) {}

  FaceMesh run(const std::vector<std::vector<BoundaryNode>>& loops, Index first_new_node);

 private:
  struct Vertex {
    Uv uv;
    Vec3 xyz;
    Index node;      // global id (boundary) or -1 (interior, numbered at the end)
    bool boundary;
    bool pole;       // a node of a degenerated edge (several (u, v) copies, one 3D point)
    double size;
    Vec3 normal;     // unit surface normal S_u x S_v there (zero where it is undefined, at a pole)
  };
  using Tri = std::array<int, 3>;

  Vec3 eval(const Uv& uv) const {
    const gp_Pnt p = surface_.Value(uv[0], uv[1]);
    return {p.X(), p.Y(), p.Z()};
  }
  /// Unit normal S_u x S_v at uv; zero where the surface is degenerate (a pole).
  Vec3 normal(const Uv& uv) const {
    gp_Pnt p;
    gp_Vec du, dv;
    surface_.D1(uv[0], uv[1], p, du, dv);
    const gp_Vec n = du.Crossed(dv);
    const double length = n.Magnitude();
    const double scale = du.Magnitude() * dv.Magnitude();
    if (!(length > 1e-12 * scale) || length == 0) return {0, 0, 0};
    return {n.X() / length, n.Y() / length, n.Z() / length};
  }
  bool same_node(int a, int b) const {
    return verts_[a].node >= 0 && verts_[a].node == verts_[b].node;
  }
  /// Two copies of one node: at a pole (a degenerated edge) such an edge is zero-length by design;
  /// across a seam it spans the whole face and must go.
  bool pole_pair(int a, int b) const { return same_node(a, b) && verts_[a].pole; }
  bool seam_pair(int a, int b) const { return same_node(a, b) && !verts_[a].pole; }
  /// Signed shape quality of (a, b, c) (see face_mesher.h): 1 for triangles that are zero-area
  /// by design (two corners on one pole node; dropped at the end), -1 for a triangle with two
  /// copies of a seam node (it spans the face in (u, v) and has no area in 3D).
  double quality(int a, int b, int c) const {
    if (seam_pair(a, b) || seam_pair(b, c) || seam_pair(c, a)) return -1;
    if (pole_pair(a, b) || pole_pair(b, c) || pole_pair(c, a)) return 1;
    const Vec3 &pa = verts_[a].xyz, &pb = verts_[b].xyz, &pc = verts_[c].xyz;
    const Vec3 n = cross(sub(pb, pa), sub(pc, pa));
    const double area2 = std::sqrt(dot(n, n));
    const double l2 = dot(sub(pb, pa), sub(pb, pa)) + dot(sub(pc, pb), sub(pc, pb)) + dot(sub(pa, pc), sub(pa, pc));
    if (l2 <= 0 || area2 <= 0) return 0;
    const double shape = 2 * std::sqrt(3.0) * area2 / l2;
    // Times the worst cosine between the triangle's normal and the surface's at its corners: a
    // triangle that cuts across a curved surface (a chord of a wide arc) is poor however equilateral.
    double worst = 1;
    int defined = 0;
    for (int v : {a, b, c}) {
      const Vec3& sn = verts_[v].normal;
      if (sn.x == 0 && sn.y == 0 && sn.z == 0) continue;
      worst = std::min(worst, dot(sn, n) / area2);
      ++defined;
    }
    if (defined == 0) {
      const Uv centroid{(verts_[a].uv[0] + verts_[b].uv[0] + verts_[c].uv[0]) / 3,
                        (verts_[a].uv[1] + verts_[b].uv[1] + verts_[c].uv[1]) / 3};
      worst = dot(normal(centroid), n) / area2;
    }
    return shape * worst;
  }
  /// May (a, b, c) be made: counter-clockwise in (u, v) (exact), except at a pole, where the
  /// corner's u is arbitrary and the parameter plane's orientation says nothing about the 3D
  /// triangle: there the triangle must face the surface's way in 3D (quality > 0).
  bool valid(int a, int b, int c) const {
    if (verts_[a].pole || verts_[b].pole || verts_[c].pole) return quality(a, b, c) > 0;
    return uv_orient(verts_[a].uv, verts_[b].uv, verts_[c].uv) > 0;
  }
  double size_at(const Uv& uv, const Vec3& p) const {
    double s = options_.face_size;
    if (options_.local_curvature_points_per_circle > 0)
      s = std::min(s, local_curvature_size(surface_, uv[0], uv[1], options_.local_curvature_points_per_circle));
    s = std::max(s, options_.min_size);
    for (const auto& [b, sb] : boundary_sizes_) s = std::min(s, sb + options_.grading * dist(p, b));
    return std::max(s, floor_);
  }
  /// Edge length along the surface (two chords through the (u, v) midpoint), over the local size.
  double edge_ratio(int a, int b) const {
    if (seam_pair(a, b)) return kInf;  // two copies of one node across the face: must go
    if (pole_pair(a, b)) return 0;     // zero length in 3D; never split
    const Vec3 m = eval(mid(verts_[a].uv, verts_[b].uv));
    const double length = dist(verts_[a].xyz, m) + dist(m, verts_[b].xyz);
    return length / (0.5 * (verts_[a].size + verts_[b].size));
  }

  int add_tri(const Tri& t) {
    const int id = static_cast<int>(tris_.size());
    tris_.push_back(t);
    alive_.push_back(1);
    for (int v : t) vt_[static_cast<std::size_t>(v)].push_back(id);
    return id;
  }
  void kill_tri(int t) {
    alive_[static_cast<std::size_t>(t)] = 0;
    for (int v : tris_[static_cast<std::size_t>(t)]) {
      auto& list = vt_[static_cast<std::size_t>(v)];
      list.erase(std::find(list.begin(), list.end(), t));
    }
  }
  int add_vertex(const Uv& uv, const Vec3& xyz) {
    verts_.push_back({uv, xyz, -1, false, false, size_at(uv, xyz), normal(uv)});
    vt_.emplace_back();
    return static_cast<int>(verts_.size()) - 1;
  }
  /// Triangles holding the directed edge a -> b and b -> a (-1 when absent).
  std::pair<int, int> edge_tris(int a, int b) const {
    int ab = -1, ba = -1;
    for (int t : vt_[static_cast<std::size_t>(a)]) {
      const Tri& x = tris_[static_cast<std::size_t>(t)];
      for (int i = 0; i < 3; ++i) {
        if (x[i] == a && x[(i + 1) % 3] == b) ab = t;
        if (x[i] == b && x[(i + 1) % 3] == a) ba = t;
      }
    }
    return {ab, ba};
  }
  static int opposite(const Tri& t, int a, int b) {
    for (int v : t)
      if (v != a && v != b) return v;
    return -1;
  }
  std::vector<std::pair<int, int>> interior_edges() const {
    std::vector<std::pair<int, int>> edges;
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      if (!alive_[t]) continue;
      for (int i = 0; i < 3; ++i) {
        const int a = tris_[t][i], b = tris_[t][(i + 1) % 3];
        if (a < b) edges.emplace_back(a, b);
      }
    }
    return edges;
  }

  /// First fundamental form (E, F, G) of the surface at uv: |S_u|^2, S_u . S_v, |S_v|^2.
  std::array<double, 3> metric(const Uv& uv) const {
    gp_Pnt p;
    gp_Vec du, dv;
    surface_.D1(uv[0], uv[1], p, du, dv);
    return {du.Dot(du), du.Dot(dv), dv.Dot(dv)};
  }
  /// Shape quality of the (u, v) triangle (a, b, c) in the constant metric m (1 equilateral in
  /// that metric; its sign is the (u, v) orientation's).
  static double metric_shape(const Uv& a, const Uv& b, const Uv& c, const std::array<double, 3>& m) {
    auto len2 = [&](const Uv& p, const Uv& q) {
      const double du = q[0] - p[0], dv = q[1] - p[1];
      return m[0] * du * du + 2 * m[1] * du * dv + m[2] * dv * dv;
    };
    const double cross_uv = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    const double l2 = len2(a, b) + len2(b, c) + len2(c, a);
    const double det = std::max(0.0, m[0] * m[2] - m[1] * m[1]);
    return l2 > 0 ? 2 * std::sqrt(3.0) * cross_uv * std::sqrt(det) / l2 : 0;
  }
  int metric_flip_pass();
  bool split(int a, int b, bool untangle = false);
  bool flip(int a, int b, bool in_3d = false);
  int untangle_pass();
  bool collapse(int v, int w, bool untangle = false);
  bool smooth(int v);
  int split_pass();
  int collapse_pass();
  int flip_pass();
  int smooth_pass();

  BRepAdaptor_Surface surface_;
  FaceMeshOptions options_;
  std::vector<Vertex> verts_;
  std::vector<Tri> tris_;
  std::vector<char> alive_;
  std::vector<std::vector<int>> vt_;
  std::vector<std::pair<Vec3, double>> boundary_sizes_;
  double floor_ = 0;  // min(options_.min_size, the smallest boundary size)
};

bool FaceMesher::split(int a, int b, bool untangle) {
  const auto [t0, t1] = edge_tris(a, b);
  if (t0 < 0 || t1 < 0) return false;  // a boundary edge: never split
  const int c = opposite(tris_[static_cast<std::size_t>(t0)], a, b);
  const int d = opposite(tris_[static_cast<std::size_t>(t1)], a, b);
  const Uv uv = mid(verts_[a].uv, verts_[b].uv);
  const int m = add_vertex(uv, eval(uv));
  // Splits are judged in (u, v) even at a pole: they refine big start triangles whose 3D shape
  // is poor anyway, until (u, v) and 3D agree. Untangling splits must leave no folded triangle.
  auto uv_ok = [&](int x, int y, int z) { return uv_orient(verts_[x].uv, verts_[y].uv, verts_[z].uv) > 0; };
  bool ok = uv_ok(a, m, c) && uv_ok(m, b, c) && uv_ok(b, m, d) && uv_ok(m, a, d);
  if (ok && untangle) {
    const double before = std::min(quality(a, b, c), quality(b, a, d));
    const double after = std::min({quality(a, m, c), quality(m, b, c), quality(b, m, d), quality(m, a, d)});
    ok = after > 0 && after > before;  // no fold among the four, and better than the two
  }
  if (!ok) {
    verts_.pop_back();
    vt_.pop_back();
    return false;
  }
  kill_tri(t0);
  kill_tri(t1);
  add_tri({a, m, c});
  add_tri({m, b, c});
  add_tri({b, m, d});
  add_tri({m, a, d});
  return true;
}

bool FaceMesher::flip(int a, int b, bool in_3d) {
  const auto [t0, t1] = edge_tris(a, b);
  if (t0 < 0 || t1 < 0) return false;
  const int c = opposite(tris_[static_cast<std::size_t>(t0)], a, b);
  const int d = opposite(tris_[static_cast<std::size_t>(t1)], a, b);
  if (c == d || seam_pair(c, d)) return false;
  if (in_3d) {
    // The new edge must not exist already (in (u, v) it cannot; judged in 3D it could).
    for (int t : vt_[static_cast<std::size_t>(c)])
      for (int u : tris_[static_cast<std::size_t>(t)])
        if (u == d) return false;
    if (!(quality(a, d, c) > 0) || !(quality(d, b, c) > 0)) return false;
  } else if (!valid(a, d, c) || !valid(d, b, c)) {
    return false;
  }
  const double before = std::min(quality(a, b, c), quality(b, a, d));
  const double after = std::min(quality(a, d, c), quality(d, b, c));
  // An edge joining two copies of one node across the face (a seam's two sides) always goes.
  if (!seam_pair(a, b) && after <= before + 1e-9) return false;
  kill_tri(t0);
  kill_tri(t1);
  add_tri({a, d, c});
  add_tri({d, b, c});
  return true;
}

bool FaceMesher::collapse(int v, int w, bool untangle) {
  if (verts_[v].boundary) return false;
  const auto ring = vt_[static_cast<std::size_t>(v)];
  // Link condition: v and w may share only the two corners opposite their edge; another common
  // neighbour would make an edge twice (two triangles on the same three nodes).
  std::vector<int> around_v, around_w;
  for (int t : ring)
    for (int u : tris_[static_cast<std::size_t>(t)])
      if (u != v) around_v.push_back(u);
  for (int t : vt_[static_cast<std::size_t>(w)])
    for (int u : tris_[static_cast<std::size_t>(t)])
      if (u != w) around_w.push_back(u);
  std::sort(around_v.begin(), around_v.end());
  around_v.erase(std::unique(around_v.begin(), around_v.end()), around_v.end());
  std::sort(around_w.begin(), around_w.end());
  around_w.erase(std::unique(around_w.begin(), around_w.end()), around_w.end());
  std::vector<int> common;
  std::set_intersection(around_v.begin(), around_v.end(), around_w.begin(), around_w.end(), std::back_inserter(common));
  if (common.size() != 2) return false;
  double before = kInf, after = kInf;
  int shared = 0;
  for (int t : ring) {
    const Tri& x = tris_[static_cast<std::size_t>(t)];
    before = std::min(before, quality(x[0], x[1], x[2]));
    if (x[0] == w || x[1] == w || x[2] == w) {
      ++shared;
      continue;
    }
    Tri y = x;
    for (int& u : y)
      if (u == v) u = w;
    if (!valid(y[0], y[1], y[2])) return false;
    after = std::min(after, quality(y[0], y[1], y[2]));
    if (!untangle)
      for (int u : y)
        if (u != w && edge_ratio(w, u) > kSplitRatio) return false;
  }
  if (shared != 2) return false;
  // Untangling: any collapse that raises the worst triangle around v; otherwise the worst may
  // drop to 0.3 at most.
  if (untangle ? !(after > before) : after < std::min(0.3, before)) return false;
  for (int t : ring) {
    Tri y = tris_[static_cast<std::size_t>(t)];
    kill_tri(t);
    if (y[0] == w || y[1] == w || y[2] == w) continue;
    for (int& u : y)
      if (u == v) u = w;
    add_tri(y);
  }
  return true;
}

bool FaceMesher::smooth(int v) {
  if (verts_[v].boundary) return false;
  const auto& ring = vt_[static_cast<std::size_t>(v)];
  if (ring.empty()) return false;
  double before = kInf, mean_before = 0;
  Uv target{0, 0};
  int count = 0;
  for (int t : ring) {
    const Tri& x = tris_[static_cast<std::size_t>(t)];
    const double q = quality(x[0], x[1], x[2]);
    before = std::min(before, q);
    mean_before += q / static_cast<double>(ring.size());
    for (int u : x) {
      if (u == v) continue;
      target[0] += verts_[u].uv[0];
      target[1] += verts_[u].uv[1];
      ++count;
    }
  }
  target = {target[0] / count, target[1] / count};
  const Vertex saved = verts_[v];
  for (double w : {1.0, 0.5, 0.25}) {
    verts_[v].uv = {saved.uv[0] + w * (target[0] - saved.uv[0]), saved.uv[1] + w * (target[1] - saved.uv[1])};
    verts_[v].xyz = eval(verts_[v].uv);
    verts_[v].normal = normal(verts_[v].uv);
    double after = kInf, mean_after = 0;
    bool ok = true;
    for (int t : ring) {
      const Tri& x = tris_[static_cast<std::size_t>(t)];
      if (!valid(x[0], x[1], x[2])) {
        ok = false;
        break;
      }
      const double q = quality(x[0], x[1], x[2]);
      after = std::min(after, q);
      mean_after += q / static_cast<double>(ring.size());
    }
    // Applied when the worst triangle around gets better, or when the mean does and the worst
    // stays at least min(the worst before, kSmoothKeep): the typical triangle gets better too,
    // not only the worst of each ring.
    const double keep = std::min(before, kSmoothKeep);
    if (ok && (after > before + 1e-9 || (after >= keep && mean_after > mean_before + 1e-9))) {
      verts_[v].size = size_at(verts_[v].uv, verts_[v].xyz);
      return true;
    }
  }
  verts_[v] = saved;
  return false;
}

int FaceMesher::split_pass() {
  std::vector<std::pair<double, std::pair<int, int>>> candidates;
  for (const auto& [a, b] : interior_edges()) {
    const double r = edge_ratio(a, b);
    if (r > kSplitRatio) candidates.push_back({r, {a, b}});
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  int done = 0;
  for (const auto& [r, e] : candidates) {
    // A split edge's neighbours may have been split already; the edge is then gone or shorter.
    const auto [t0, t1] = edge_tris(e.first, e.second);
    if (t0 < 0 || t1 < 0) continue;
    if (!seam_pair(e.first, e.second) && dist(verts_[e.first].xyz, verts_[e.second].xyz) < 2 * floor_) continue;
    done += split(e.first, e.second) ? 1 : 0;
  }
  return done;
}

int FaceMesher::collapse_pass() {
  std::vector<std::pair<double, std::pair<int, int>>> candidates;
  for (const auto& [a, b] : interior_edges()) {
    if (verts_[a].boundary && verts_[b].boundary) continue;
    const double r = edge_ratio(a, b);
    if (r < kCollapseRatio) candidates.push_back({r, {a, b}});
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  int done = 0;
  for (const auto& [r, e] : candidates) {
    const auto [t0, t1] = edge_tris(e.first, e.second);
    if (t0 < 0 || t1 < 0) continue;
    if (collapse(e.first, e.second) || collapse(e.second, e.first)) ++done;
  }
  return done;
}

/// Lawson's order: every edge once, then the four outer edges of each flipped quad again, until
/// no flip raises a quality (each flip raises the worse of its two triangles, so this ends; a
/// cap of 50 flips per triangle bounds it anyway). A fan of needles across a long thin face
/// unwinds in one pass this way, where sweeps over all edges would need one sweep per step.
int FaceMesher::flip_pass() {
  std::vector<std::pair<int, int>> stack = interior_edges();
  std::reverse(stack.begin(), stack.end());  // pop in sorted order first
  const std::size_t cap = 50 * tris_.size() + 1000;
  int total = 0;
  while (!stack.empty() && static_cast<std::size_t>(total) < cap) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const auto [t0, t1] = edge_tris(a, b);
    if (t0 < 0 || t1 < 0) continue;
    const int c = opposite(tris_[static_cast<std::size_t>(t0)], a, b);
    const int d = opposite(tris_[static_cast<std::size_t>(t1)], a, b);
    if (!flip(a, b)) continue;
    ++total;
    for (const auto& e : {std::make_pair(a, c), std::make_pair(c, b), std::make_pair(b, d), std::make_pair(d, a)})
      stack.push_back(e);
  }
  return total;
}

/// The start triangulation flipped in the surface's metric rather than in 3D: each quad (two
/// triangles on an edge) is measured in the first fundamental form at its (u, v) centroid, and
/// its diagonal is flipped when that raises the smaller metric shape of its two triangles
/// (Lawson's order, as flip_pass). Ear cutting joins boundary nodes that are close in (u, v) but
/// may be far apart on the surface (a thread's strip winds around its axis over a short u
/// interval): a fan of needles a whole turn long, folded in 3D in places and, elsewhere, thin
/// chords that face the surface's way and so look valid. A flip judged on the 3D chords has
/// nothing better to go to there, while in the metric every flip heads for the triangulation
/// the surface's own lengths ask for; a fan is undone from its ends inwards, across triangles
/// that are not folded too, so once the start holds a fold every quad is considered, not only
/// those with one. A start with no fold (the usual case: a face whose (u, v) is proportionate)
/// is left to flip_pass alone, and quads with a pole corner too (the metric degenerates there).
int FaceMesher::metric_flip_pass() {
  bool folded = false;
  for (std::size_t t = 0; t < tris_.size() && !folded; ++t) {
    const Tri& x = tris_[t];
    folded = alive_[t] && !verts_[x[0]].pole && !verts_[x[1]].pole && !verts_[x[2]].pole &&
             !(quality(x[0], x[1], x[2]) > 0);
  }
  if (!folded) return 0;
  std::vector<std::pair<int, int>> stack = interior_edges();
  std::reverse(stack.begin(), stack.end());
  const std::size_t cap = 50 * tris_.size() + 1000;
  int total = 0;
  while (!stack.empty() && static_cast<std::size_t>(total) < cap) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const auto [t0, t1] = edge_tris(a, b);
    if (t0 < 0 || t1 < 0) continue;
    const int c = opposite(tris_[static_cast<std::size_t>(t0)], a, b);
    const int d = opposite(tris_[static_cast<std::size_t>(t1)], a, b);
    if (c == d || seam_pair(c, d)) continue;
    if (verts_[a].pole || verts_[b].pole || verts_[c].pole || verts_[d].pole) continue;
    if (!valid(a, d, c) || !valid(d, b, c)) continue;
    const Uv &ua = verts_[a].uv, &ub = verts_[b].uv, &uc = verts_[c].uv, &ud = verts_[d].uv;
    const auto m = metric({0.25 * (ua[0] + ub[0] + uc[0] + ud[0]), 0.25 * (ua[1] + ub[1] + uc[1] + ud[1])});
    const double before = std::min(metric_shape(ua, ub, uc, m), metric_shape(ub, ua, ud, m));
    const double after = std::min(metric_shape(ua, ud, uc, m), metric_shape(ud, ub, uc, m));
    if (!(after > before)) continue;
    kill_tri(t0);
    kill_tri(t1);
    add_tri({a, d, c});
    add_tri({d, b, c});
    ++total;
    for (const auto& e : {std::make_pair(a, c), std::make_pair(c, b), std::make_pair(b, d), std::make_pair(d, a)})
      stack.push_back(e);
  }
  return total;
}

/// Triangles that still face against the surface (a fold: the start's ear-cut triangles near a
/// pole or across a strongly curved patch) are flipped away judged in 3D alone (both new
/// triangles must face the surface's way), or collapsed, or split, whichever raises the worst
/// triangle there.
int FaceMesher::untangle_pass() {
  int total = 0;
  for (int sweep = 0; sweep < 8; ++sweep) {
    int done = 0;
    const std::size_t count = tris_.size();  // triangles made in this sweep wait for the next
    for (std::size_t t = 0; t < count; ++t) {
      if (!alive_[t]) continue;
      const Tri x = tris_[t];
      if (quality(x[0], x[1], x[2]) > 0) continue;
      for (int i = 0; i < 3 && alive_[t]; ++i)
        if (flip(x[i], x[(i + 1) % 3], /*in_3d=*/true)) ++done;
      for (int i = 0; i < 3 && alive_[t]; ++i) {
        const int a = x[i], b = x[(i + 1) % 3];
        if (collapse(a, b, /*untangle=*/true) || collapse(b, a, /*untangle=*/true)) ++done;
      }
      for (int i = 0; i < 3 && alive_[t]; ++i)
        if (dist(verts_[x[i]].xyz, verts_[x[(i + 1) % 3]].xyz) > 2 * floor_ &&
            split(x[i], x[(i + 1) % 3], /*untangle=*/true))
          ++done;
    }
    total += done;
    if (done == 0) break;
  }
  return total;
}

int FaceMesher::smooth_pass() {
  int done = 0;
  for (int v = 0; v < static_cast<int>(verts_.size()); ++v) done += smooth(v) ? 1 : 0;
  return done;
}

FaceMesh FaceMesher::run(const std::vector<std::vector<BoundaryNode>>& loops, Index first_new_node) {
  std::vector<Uv> uv;
  std::vector<std::vector<int>> index_loops;
  for (const auto& loop : loops) {
    std::vector<int> ids;
    const std::size_t n = loop.size();
    for (std::size_t i = 0; i < n; ++i) {
      const BoundaryNode& b = loop[i];
      // Local spacing: the mean of the two boundary segments at the node (degenerated-edge
      // nodes have zero-length segments: they set no size).
      double sum = 0;
      int count = 0;
      for (const BoundaryNode* o : {&loop[(i + n - 1) % n], &loop[(i + 1) % n]}) {
        if (o->node == b.node) continue;
        sum += dist(o->xyz, b.xyz);
        ++count;
      }
      const double s = count ? sum / count : kInf;
      ids.push_back(static_cast<int>(verts_.size()));
      const bool pole = loop[(i + n - 1) % n].node == b.node || loop[(i + 1) % n].node == b.node;
      // A pole has no normal of its own: evaluated at its (u, v), rounding may even put it on
      // the far side of a cone's apex, where the normal is reversed.
      verts_.push_back({b.uv, b.xyz, b.node, true, pole, std::isfinite(s) ? s : options_.face_size,
                        pole ? Vec3{0, 0, 0} : normal(b.uv)});
      vt_.emplace_back();
      uv.push_back(b.uv);
      if (std::isfinite(s)) boundary_sizes_.emplace_back(b.xyz, s);
    }
    index_loops.push_back(std::move(ids));
  }
  boundary_sizes_.insert(boundary_sizes_.end(), options_.size_sources.begin(), options_.size_sources.end());
  floor_ = options_.min_size;
  for (const auto& bs : boundary_sizes_) floor_ = std::min(floor_, bs.second);
  for (const auto& t : triangulate_polygon(uv, index_loops)) add_tri({t[0], t[1], t[2]});

  metric_flip_pass();  // the ear-cut fan into the surface's own shapes,
  flip_pass();         // then into better 3D shapes: splits then spread points evenly
  for (int round = 0; round < options_.max_rounds; ++round) {
    const int splits = split_pass();
    flip_pass();
    const int collapses = collapse_pass();
    flip_pass();
    smooth_pass();
    flip_pass();
    if (splits == 0 && collapses == 0) break;
  }
  for (int round = 0; round < 3; ++round) {
    untangle_pass();
    const int moved = smooth_pass();
    const int flipped = flip_pass();
    if (moved == 0 && flipped == 0) break;
  }

  FaceMesh out;
  Index next = first_new_node;
  for (std::size_t i = 0; i < verts_.size(); ++i) {
    Vertex& v = verts_[i];
    if (v.node >= 0 || vt_[i].empty()) continue;  // boundary, or collapsed away
    v.node = next++;
    out.new_xyz.push_back(v.xyz);
    out.new_uv.push_back(v.uv);
  }
  for (std::size_t t = 0; t < tris_.size(); ++t) {
    if (!alive_[t]) continue;
    const Tri& x = tris_[t];
    if (same_node(x[0], x[1]) || same_node(x[1], x[2]) || same_node(x[2], x[0])) continue;
    const double q = quality(x[0], x[1], x[2]);
    out.min_quality = std::min(out.min_quality, q);
    if (q <= 0) ++out.folds;
    out.triangles.push_back({verts_[x[0]].node, verts_[x[1]].node, verts_[x[2]].node});
  }
  return out;
}

}  // namespace

FaceMesh mesh_face(const TopoDS_Face& forward_face, const std::vector<std::vector<BoundaryNode>>& loops,
                   const FaceMeshOptions& options, Index first_new_node) {
  FaceMesher mesher(forward_face, options);
  return mesher.run(loops, first_new_node);
}

}  // namespace bsptet::cad
