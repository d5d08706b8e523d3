// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/refine/refine_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/mesh/ring_triangulation.h"
#include "bsptet/mesh/tet_shape.h"

namespace bsptet {

namespace {

constexpr auto& kOppositeFace = kTetOppositeFace;  // types.h

constexpr double kImprovement = 1e-9;  // degrees: a flip or move must raise the worst angle by more

bool finite(const Vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }
bool same(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
Vec3 lerp(const Vec3& a, const Vec3& b, double t) {
  return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
}

// Parity of the permutation taking `from` to `to` (both hold the same four values): true if even.
bool even_permutation(std::array<Index, 4> from, const std::array<Index, 4>& to) {
  bool even = true;
  for (int i = 0; i < 4; ++i) {
    if (from[i] == to[i]) continue;
    for (int j = i + 1; j < 4; ++j)
      if (from[j] == to[i]) {
        std::swap(from[i], from[j]);
        even = !even;
        break;
      }
  }
  return even;
}

// p inside the closed input triangle (a, b, c), exactly: coplanar, and on the inner side of (or
// on) each edge line in a projection where the triangle is not degenerate.
bool in_closed_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  if (orient3d(a, b, c, p) != Sign::kZero) return false;
  for (int axis = 0; axis < 3; ++axis) {
    const Sign s = orient2d_projected(a, b, c, axis);
    if (s == Sign::kZero) continue;
    const Sign o = opposite(s);
    return orient2d_projected(a, b, p, axis) != o && orient2d_projected(b, c, p, axis) != o &&
           orient2d_projected(c, a, p, axis) != o;
  }
  return false;
}

bool collinear(const Vec3& a, const Vec3& b, const Vec3& p) {
  for (int axis = 0; axis < 3; ++axis)
    if (orient2d_projected(a, b, p, axis) != Sign::kZero) return false;
  return true;
}

}  // namespace

std::size_t RefineMesh::FaceKeyHash::operator()(const FaceKey& k) const {
  std::uint64_t h = 1469598103934665603ull;
  for (Index v : k) {
    h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(v));
    h *= 1099511628211ull;
  }
  return static_cast<std::size_t>(h);
}

RefineMesh::FaceKey RefineMesh::face_key(Index a, Index b, Index c) {
  FaceKey k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

RefineMesh::RefineMesh(const SurfaceMesh& surface, const TetMesh& mesh, ProjectionHook hook,
                       SurfacePoints surface_points)
    : surface_(surface), hook_(std::move(hook)), surface_points_(surface_points) {
  if (mesh.nodes_per_tet != 4)
    throw MeshingError(ErrorCode::kBadArgument, "refine", -1, "refinement needs a linear (4-node) tet mesh");
  const Index np = mesh.num_points();
  xyz_.resize(static_cast<std::size_t>(np));
  for (Index i = 0; i < np; ++i) xyz_[static_cast<std::size_t>(i)] = mesh.point(i);
  stamp_.assign(xyz_.size(), 0);
  support_.assign(static_cast<std::size_t>(np), PointSupport{});
  point_alive_.assign(static_cast<std::size_t>(np), 1);
  ball_.resize(static_cast<std::size_t>(np));
  first_added_point_ = np;
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    std::array<Index, 4> v{};
    for (int k = 0; k < 4; ++k) v[k] = mesh.tet[static_cast<std::size_t>(4 * t + k)];
    add_tet(v);
  }

  // Input points, recognized by their coordinates.
  std::map<std::array<double, 3>, Index> surface_index;
  for (Index i = 0; i < surface.num_points(); ++i) {
    const Vec3 p = surface.point(i);
    surface_index.emplace(std::array<double, 3>{p.x, p.y, p.z}, i);
  }
  std::vector<Index> surf_to_mesh(static_cast<std::size_t>(surface.num_points()), -1);
  std::vector<Index> mesh_to_surf(static_cast<std::size_t>(np), -1);
  for (Index i = 0; i < np; ++i) {
    const Vec3& p = xyz_[static_cast<std::size_t>(i)];
    auto it = surface_index.find({p.x, p.y, p.z});
    if (it == surface_index.end()) continue;
    support_[static_cast<std::size_t>(i)].kind = Support::kInputVertex;
    surf_to_mesh[static_cast<std::size_t>(it->second)] = i;
    mesh_to_surf[static_cast<std::size_t>(i)] = it->second;
  }

  // Boundary faces (faces of one tet) and the input triangle each lies on.
  std::map<FaceKey, Index> input_triangle;
  std::vector<std::vector<Index>> triangles_at(static_cast<std::size_t>(surface.num_points()));
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    const Index* v = &surface.tri[static_cast<std::size_t>(3 * t)];
    input_triangle.emplace(face_key(v[0], v[1], v[2]), t);
    for (int k = 0; k < 3; ++k) triangles_at[static_cast<std::size_t>(v[k])].push_back(t);
  }
  std::map<FaceKey, int> face_count;
  for (const auto& t : tets_)
    for (int k = 0; k < 4; ++k) face_count[face_key(t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4])]++;
  auto in_triangle = [&](Index tri, Index v) {
    const Index* s = &surface.tri[static_cast<std::size_t>(3 * tri)];
    return in_closed_triangle(surface.point(s[0]), surface.point(s[1]), surface.point(s[2]), point(v));
  };
  for (const auto& [key, count] : face_count) {
    if (count != 1) continue;
    Index parent = -1;
    std::array<Index, 3> sk{};
    bool all_input = true;
    for (int k = 0; k < 3; ++k) {
      sk[k] = mesh_to_surf[static_cast<std::size_t>(key[k])];
      all_input = all_input && sk[k] >= 0;
    }
    if (all_input) {
      auto it = input_triangle.find(face_key(sk[0], sk[1], sk[2]));
      if (it != input_triangle.end()) parent = it->second;
    }
    if (parent < 0) {
      std::set<Index> candidates;
      for (int k = 0; k < 3; ++k)
        if (sk[k] >= 0)
          candidates.insert(triangles_at[static_cast<std::size_t>(sk[k])].begin(),
                            triangles_at[static_cast<std::size_t>(sk[k])].end());
      if (candidates.empty())
        for (Index t = 0; t < surface.num_triangles(); ++t) candidates.insert(t);
      for (Index t : candidates)
        if (in_triangle(t, key[0]) && in_triangle(t, key[1]) && in_triangle(t, key[2])) {
          parent = t;
          break;
        }
    }
    if (parent < 0)
      throw MeshingError(ErrorCode::kInternal, "refine", key[0],
                         "boundary face (" + std::to_string(key[0]) + ", " + std::to_string(key[1]) + ", " +
                             std::to_string(key[2]) +
                             ") lies on no input triangle: the mesh given to the refinement is not a valid "
                             "mesh of its surface");
    boundary_.emplace(key, parent);
  }

  // Supports of boundary Steiner points (the core may leave some with allow_boundary_steiner).
  std::map<Index, std::set<Index>> parents_of;
  for (const auto& [key, parent] : boundary_)
    for (Index v : key)
      if (support_[static_cast<std::size_t>(v)].kind != Support::kInputVertex) parents_of[v].insert(parent);
  for (const auto& [v, parents] : parents_of) {
    PointSupport& s = support_[static_cast<std::size_t>(v)];
    if (parents.size() == 1) {
      s.kind = Support::kInputFace;
      s.tri = *parents.begin();
      continue;
    }
    if (parents.size() != 2)
      throw MeshingError(ErrorCode::kInternal, "refine", v,
                         "boundary Steiner point " + std::to_string(v) + " lies on " +
                             std::to_string(parents.size()) + " input triangles");
    const Index t0 = *parents.begin(), t1 = *parents.rbegin();
    std::vector<Index> common;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (surface.tri[static_cast<std::size_t>(3 * t0 + i)] == surface.tri[static_cast<std::size_t>(3 * t1 + j)])
          common.push_back(surface.tri[static_cast<std::size_t>(3 * t0 + i)]);
    if (common.size() != 2 || surf_to_mesh[static_cast<std::size_t>(common[0])] < 0 ||
        surf_to_mesh[static_cast<std::size_t>(common[1])] < 0)
      throw MeshingError(ErrorCode::kInternal, "refine", v,
                         "boundary Steiner point " + std::to_string(v) + " lies on two input triangles (" +
                             std::to_string(t0) + ", " + std::to_string(t1) + ") without a common edge");
    s.kind = Support::kInputEdge;
    s.tri = t0;
    s.other_tri = t1;
    s.edge_from = std::min(surf_to_mesh[static_cast<std::size_t>(common[0])], surf_to_mesh[static_cast<std::size_t>(common[1])]);
    s.edge_to = std::max(surf_to_mesh[static_cast<std::size_t>(common[0])], surf_to_mesh[static_cast<std::size_t>(common[1])]);
  }
  // Points no tet uses are dropped from the output.
  for (Index i = 0; i < np; ++i)
    if (ball_[static_cast<std::size_t>(i)].empty()) point_alive_[static_cast<std::size_t>(i)] = 0;
}

std::int32_t RefineMesh::tag_of(Index tri) const {
  return surface_.tag.empty() ? -1 : surface_.tag[static_cast<std::size_t>(tri)];
}

Index RefineMesh::add_point(const Vec3& p, const PointSupport& s) {
  xyz_.push_back(p);
  support_.push_back(s);
  point_alive_.push_back(1);
  ball_.emplace_back();
  stamp_.push_back(++clock_);
  return static_cast<Index>(xyz_.size() - 1);
}

void RefineMesh::touch(const std::array<Index, 4>& t) {
  ++clock_;
  for (Index v : t) stamp_[static_cast<std::size_t>(v)] = clock_;
}

std::uint64_t RefineMesh::tet_stamp(Index t) const {
  std::uint64_t s = 0;
  for (Index v : tet(t)) s = std::max(s, stamp_[static_cast<std::size_t>(v)]);
  return s;
}

Index RefineMesh::add_tet(const std::array<Index, 4>& t) {
  const Index id = static_cast<Index>(tets_.size());
  tets_.push_back(t);
  tet_alive_.push_back(1);
  neighbour_.insert(neighbour_.end(), 4, kUnknownNeighbour);
  quality_.push_back(quality_of(t));
  touch(t);
  for (Index v : t) ball_[static_cast<std::size_t>(v)].push_back(id);
  ++alive_tets_;
  return id;
}

void RefineMesh::kill_tet(Index t) {
  tet_alive_[static_cast<std::size_t>(t)] = 0;
  touch(tets_[static_cast<std::size_t>(t)]);
  // Out of its corners' balls at once (their order kept): balls are read far more often than
  // tets die.
  for (Index v : tets_[static_cast<std::size_t>(t)]) {
    auto& b = ball_[static_cast<std::size_t>(v)];
    const auto it = std::find(b.begin(), b.end(), t);
    if (it != b.end()) b.erase(it);
  }
  --alive_tets_;
}

bool RefineMesh::positive(const std::array<Index, 4>& t) const {
  return orient3d(point(t[0]), point(t[1]), point(t[2]), point(t[3])) == Sign::kPositive;
}

bool RefineMesh::positive_with(const std::array<Index, 4>& t, Index moved, const Vec3& p) const {
  Vec3 q[4];
  for (int k = 0; k < 4; ++k) q[k] = t[k] == moved ? p : point(t[k]);
  return orient3d(q[0], q[1], q[2], q[3]) == Sign::kPositive;
}

double RefineMesh::worst_tet_quality() const {
  double w = 180;
  for (Index t = 0; t < num_tet_slots(); ++t)
    if (tet_alive(t)) w = std::min(w, tet_quality(t));
  return w;
}

double RefineMesh::quality_of(const std::array<Index, 4>& t) const {
  return tet_min_dihedral_deg(point(t[0]), point(t[1]), point(t[2]), point(t[3]));
}

const std::vector<Index>& RefineMesh::tets_around_point(Index v) { return ball_[static_cast<std::size_t>(v)]; }

void RefineMesh::tets_around_edge(Index u, Index v, std::vector<Index>& out) {
  out.clear();
  for (Index t : tets_around_point(u)) {
    const auto& q = tet(t);
    if (q[0] == v || q[1] == v || q[2] == v || q[3] == v) out.push_back(t);
  }
}

std::vector<Index> RefineMesh::tets_around_edge(Index u, Index v) {
  std::vector<Index> out;
  tets_around_edge(u, v, out);
  return out;
}

bool RefineMesh::edge_exists(Index u, Index v) {
  for (Index t : tets_around_point(u)) {
    const auto& q = tet(t);
    if (q[0] == v || q[1] == v || q[2] == v || q[3] == v) return true;
  }
  return false;
}

EdgeKind RefineMesh::edge_kind(Index u, Index v, Index* tri_a, Index* tri_b) {
  // A boundary edge has both ends on the boundary; an interior point never is (supports are kept
  // exact: only surface splits and the constructor make boundary points).
  if (support(u).kind == Support::kInterior || support(v).kind == Support::kInterior) return EdgeKind::kInterior;
  std::vector<std::pair<FaceKey, Index>> found;
  for (Index t : tets_around_edge(u, v))
    for (Index x : tet(t)) {
      if (x == u || x == v || support(x).kind == Support::kInterior) continue;
      auto it = boundary_.find(face_key(u, v, x));
      if (it == boundary_.end()) continue;
      if (std::find_if(found.begin(), found.end(), [&](const auto& f) { return f.first == it->first; }) == found.end())
        found.emplace_back(it->first, it->second);
    }
  if (found.empty()) return EdgeKind::kInterior;
  if (found.size() != 2)
    throw MeshingError(ErrorCode::kInternal, "refine", u,
                       "boundary edge (" + std::to_string(u) + ", " + std::to_string(v) + ") has " +
                           std::to_string(found.size()) + " boundary faces");
  std::sort(found.begin(), found.end());
  if (tri_a) *tri_a = std::min(found[0].second, found[1].second);
  if (tri_b) *tri_b = std::max(found[0].second, found[1].second);
  return found[0].second == found[1].second ? EdgeKind::kInFace : EdgeKind::kOnInputEdge;
}

bool RefineMesh::is_interior_edge(Index u, Index v, const std::vector<Index>& shell) const {
  if (support(u).kind == Support::kInterior || support(v).kind == Support::kInterior) return true;
  for (Index t : shell)
    for (Index x : tet(t))
      if (x != u && x != v && is_boundary_face(u, v, x)) return false;
  return true;
}

std::vector<std::array<Index, 2>> RefineMesh::edges() const {
  // Point by point, from each point's ball: its larger neighbours, sorted. This gives the edges in
  // sorted order without sorting all six edges of every tet.
  std::vector<std::array<Index, 2>> out;
  out.reserve(static_cast<std::size_t>(alive_tets_) * 7 / 5 + 16);
  std::vector<Index> larger;
  for (Index v = 0; v < num_points(); ++v) {
    larger.clear();
    for (Index t : ball_[static_cast<std::size_t>(v)]) {
      if (!tet_alive(t)) continue;
      for (Index w : tet(t))
        if (w > v) larger.push_back(w);
    }
    std::sort(larger.begin(), larger.end());
    larger.erase(std::unique(larger.begin(), larger.end()), larger.end());
    for (Index w : larger) out.push_back({v, w});
  }
  return out;
}

void RefineMesh::set_fixed_tags(std::vector<std::int32_t> tags) {
  std::sort(tags.begin(), tags.end());
  tags.erase(std::unique(tags.begin(), tags.end()), tags.end());
  fixed_tags_ = std::move(tags);
}

void RefineMesh::set_sliding_points(const std::vector<char>& input_points) {
  slide_tag_.assign(xyz_.size(), -1);
  if (!hook_ || surface_.tag.empty()) return;
  // The one tag of each input point's triangles (-2: more than one).
  std::vector<std::int32_t> tag(static_cast<std::size_t>(surface_.num_points()), -1);
  for (Index t = 0; t < surface_.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) {
      std::int32_t& g = tag[static_cast<std::size_t>(surface_.tri[static_cast<std::size_t>(3 * t + k)])];
      const std::int32_t tt = surface_.tag[static_cast<std::size_t>(t)];
      g = g == -1 || g == tt ? tt : -2;
    }
  std::map<std::array<double, 3>, Index> index_of;
  for (Index i = 0; i < surface_.num_points(); ++i) {
    const Vec3 p = surface_.point(i);
    index_of.emplace(std::array<double, 3>{p.x, p.y, p.z}, i);
  }
  for (Index v = 0; v < num_points(); ++v) {
    if (support(v).kind != Support::kInputVertex || !point_alive(v)) continue;
    const Vec3& p = point(v);
    const auto it = index_of.find({p.x, p.y, p.z});
    if (it == index_of.end()) continue;
    const std::size_t i = static_cast<std::size_t>(it->second);
    if (i >= input_points.size() || !input_points[i] || tag[i] < 0) continue;
    if (std::binary_search(fixed_tags_.begin(), fixed_tags_.end(), tag[i])) continue;
    slide_tag_[static_cast<std::size_t>(v)] = tag[i];
  }
}

std::vector<Index> RefineMesh::boundary_neighbours(Index v) {
  std::vector<Index> out;
  for (Index t : tets_around_point(v)) {
    const auto& q = tet(t);
    for (int k = 0; k < 4; ++k) {
      const Index a = q[(k + 1) % 4], b = q[(k + 2) % 4], c = q[(k + 3) % 4];
      if (q[k] == v || !is_boundary_face(a, b, c)) continue;
      for (Index w : {a, b, c})
        if (w != v) out.push_back(w);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// Smallest angle of triangle abc, degrees.
double triangle_min_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c) {
  const auto angle = [](const Vec3& o, const Vec3& x, const Vec3& y) {
    const double ux = x.x - o.x, uy = x.y - o.y, uz = x.z - o.z, wx = y.x - o.x, wy = y.y - o.y, wz = y.z - o.z;
    const double cx = uy * wz - uz * wy, cy = uz * wx - ux * wz, cz = ux * wy - uy * wx;
    return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), ux * wx + uy * wy + uz * wz) * 180.0 / kPi;
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

// Unit normal of triangle abc (zero when degenerate).
Vec3 unit_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
  Vec3 n{uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx};
  const double l = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
  return l > 0 ? Vec3{n.x / l, n.y / l, n.z / l} : Vec3{0, 0, 0};
}

}  // namespace

bool RefineMesh::slide_point_if(Index v, const Vec3& target,
                                const std::function<bool(const std::vector<std::array<Vec3, 4>>&)>& accept) {
  if (!slides(v) || !finite(target)) return false;
  const std::vector<Index> ball = tets_around_point(v);
  std::vector<std::array<Vec3, 4>> moved(ball.size());
  const double min_cos = std::cos(kSlideMaxTiltDeg * kPi / 180.0);
  // All the checks with v at p; the angles only rank, positivity is exact.
  const auto passes = [&](const Vec3& p) {
    double worst_before = 180, worst_after = 180;
    for (std::size_t i = 0; i < ball.size(); ++i) {
      const auto& t = tet(ball[i]);
      if (!positive_with(t, v, p)) return false;
      for (int k = 0; k < 4; ++k) moved[i][static_cast<std::size_t>(k)] = t[k] == v ? p : point(t[k]);
      for (int k = 0; k < 4; ++k) {
        if (t[k] == v) continue;
        const Index a = t[(k + 1) % 4], b = t[(k + 2) % 4], c = t[(k + 3) % 4];
        if (!is_boundary_face(a, b, c)) continue;
        const auto at = [&](Index w) { return w == v ? p : point(w); };
        worst_before = std::min(worst_before, triangle_min_angle_deg(point(a), point(b), point(c)));
        worst_after = std::min(worst_after, triangle_min_angle_deg(at(a), at(b), at(c)));
        const Vec3 n0 = unit_normal(point(a), point(b), point(c)), n1 = unit_normal(at(a), at(b), at(c));
        if (n0.x * n1.x + n0.y * n1.y + n0.z * n1.z < min_cos) return false;
      }
    }
    return worst_after >= std::min(worst_before, kSlideKeepTriangleDeg) && accept(moved);
  };
  // The target's move along the surface (its component along the area-weighted normal of the
  // boundary faces around v taken off) is tried first: the hook (a search on the CAD surface)
  // runs only for a move likely to be taken, and its answer is then checked again.
  const Vec3 old = point(v);
  Vec3 n{0, 0, 0};
  for (Index t : ball) {
    const auto& q = tet(t);
    for (int k = 0; k < 4; ++k) {
      if (q[k] == v) continue;
      static const int outward[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};  // types.h
      const Index a = q[outward[k][0]], b = q[outward[k][1]], c = q[outward[k][2]];
      if (!is_boundary_face(a, b, c)) continue;
      const Vec3 &A = point(a), &B = point(b), &C = point(c);
      const double ux = B.x - A.x, uy = B.y - A.y, uz = B.z - A.z, wx = C.x - A.x, wy = C.y - A.y, wz = C.z - A.z;
      n.x += uy * wz - uz * wy, n.y += uz * wx - ux * wz, n.z += ux * wy - uy * wx;
    }
  }
  const double nn = n.x * n.x + n.y * n.y + n.z * n.z;
  Vec3 along = target;
  if (nn > 0) {
    const double d = ((target.x - old.x) * n.x + (target.y - old.y) * n.y + (target.z - old.z) * n.z) / nn;
    along = {target.x - d * n.x, target.y - d * n.y, target.z - d * n.z};
  }
  if (!passes(along)) return false;
  const Vec3 p = hook_(along, slide_tag_[static_cast<std::size_t>(v)], -1);
  if (!finite(p) || (p.x == old.x && p.y == old.y && p.z == old.z) || !passes(p)) return false;
  move_point(v, p, ball, moved);
  return true;
}

void RefineMesh::move_point(Index v, const Vec3& p, const std::vector<Index>& ball,
                            const std::vector<std::array<Vec3, 4>>& moved) {
  xyz_[static_cast<std::size_t>(v)] = p;
  for (std::size_t i = 0; i < ball.size(); ++i) {
    const auto& c = moved[i];
    quality_[static_cast<std::size_t>(ball[i])] = tet_min_dihedral_deg(c[0], c[1], c[2], c[3]);
    touch(tet(ball[i]));
  }
}

SplitOutcome RefineMesh::split_edge(Index u, Index v, double min_quality, Index* new_point) {
  const std::vector<Index> shell = tets_around_edge(u, v);
  if (shell.empty()) return SplitOutcome::kNoEdge;
  Index ta = -1, tb = -1;
  const EdgeKind kind = edge_kind(u, v, &ta, &tb);
  if (kind != EdgeKind::kInterior && !fixed_tags_.empty() &&
      (std::binary_search(fixed_tags_.begin(), fixed_tags_.end(), tag_of(ta)) ||
       std::binary_search(fixed_tags_.begin(), fixed_tags_.end(), tag_of(tb))))
    return SplitOutcome::kFixedSurface;
  const Vec3 pu = point(u), pv = point(v);
  const Vec3 mid{0.5 * (pu.x + pv.x), 0.5 * (pu.y + pv.y), 0.5 * (pu.z + pv.z)};

  PointSupport s;
  if (kind == EdgeKind::kInFace) {
    s.kind = Support::kInputFace;
    s.tri = ta;
  } else if (kind == EdgeKind::kOnInputEdge) {
    s.kind = Support::kInputEdge;
    s.tri = ta;
    s.other_tri = tb;
    const PointSupport& su = support(u);
    const PointSupport& sv = support(v);
    if (su.kind == Support::kInputEdge) {
      s.edge_from = su.edge_from;
      s.edge_to = su.edge_to;
    } else if (sv.kind == Support::kInputEdge) {
      s.edge_from = sv.edge_from;
      s.edge_to = sv.edge_to;
    } else {
      s.edge_from = std::min(u, v);
      s.edge_to = std::max(u, v);
    }
  }

  std::vector<Vec3> candidates;
  if (kind == EdgeKind::kInterior) {
    candidates = {mid, lerp(pu, pv, 0.45), lerp(pu, pv, 0.55), lerp(pu, pv, 0.35), lerp(pu, pv, 0.65)};
  } else if (hook_) {
    const std::int32_t tag = tag_of(ta);
    const std::int32_t other = (kind == EdgeKind::kOnInputEdge && tag_of(tb) != tag) ? tag_of(tb) : -1;
    const Vec3 p = hook_(mid, tag, other);
    if (!finite(p)) return SplitOutcome::kBadProjection;
    candidates = {p};
  } else if (surface_points_ == SurfacePoints::kRounded) {
    candidates = {mid, lerp(pu, pv, 0.45), lerp(pu, pv, 0.55)};
  } else {
    // Exact mode: the point must lie exactly on the edge's support (see refine_mesh.h).
    const Index* t = &surface_.tri[static_cast<std::size_t>(3 * ta)];
    const Vec3 a = surface_.point(t[0]), b = surface_.point(t[1]), c = surface_.point(t[2]);
    std::vector<Vec3> tries = {mid};
    for (double f : {0.5, 0.375, 0.625, 0.25, 0.75, 0.4375, 0.5625}) {
      tries.push_back(lerp(pu, pv, f));
      tries.push_back(lerp(pv, pu, 1.0 - f));
    }
    for (const Vec3& p : tries) {
      const bool on = kind == EdgeKind::kInFace ? orient3d(a, b, c, p) == Sign::kZero : collinear(pu, pv, p);
      if (on && std::none_of(candidates.begin(), candidates.end(), [&](const Vec3& q) { return same(p, q); }))
        candidates.push_back(p);
      if (candidates.size() >= 2) break;
    }
    if (candidates.empty()) return SplitOutcome::kNoExactPoint;
  }

  double old_min = 180;
  for (Index t : shell) old_min = std::min(old_min, tet_quality(t));
  const double floor = std::min(min_quality, old_min);
  for (const Vec3& p : candidates) {
    if (same(p, pu) || same(p, pv)) continue;
    bool ok = true;
    for (Index t : shell) {
      std::array<Index, 4> a = tet(t), b = tet(t);
      for (int k = 0; k < 4; ++k) {
        if (a[k] == v) a[k] = -1;
        if (b[k] == u) b[k] = -1;
      }
      Vec3 qa[4], qb[4];
      for (int k = 0; k < 4; ++k) {
        qa[k] = a[k] < 0 ? p : point(a[k]);
        qb[k] = b[k] < 0 ? p : point(b[k]);
      }
      if (orient3d(qa[0], qa[1], qa[2], qa[3]) != Sign::kPositive ||
          orient3d(qb[0], qb[1], qb[2], qb[3]) != Sign::kPositive ||
          (floor > 0 && (tet_min_dihedral_deg(qa[0], qa[1], qa[2], qa[3]) < floor ||
                         tet_min_dihedral_deg(qb[0], qb[1], qb[2], qb[3]) < floor))) {
        ok = false;
        break;
      }
    }
    if (!ok) continue;
    // Commit.
    const Index n = add_point(p, s);
    std::vector<std::pair<FaceKey, Index>> old_faces;
    for (Index t : shell)
      for (Index x : tet(t)) {
        if (x == u || x == v) continue;
        auto it = boundary_.find(face_key(u, v, x));
        if (it != boundary_.end()) old_faces.emplace_back(it->first, it->second);
      }
    for (const auto& [key, parent] : old_faces) {
      if (boundary_.erase(key) == 0) continue;
      Index x = -1;
      for (Index w : key)
        if (w != u && w != v) x = w;
      boundary_.emplace(face_key(u, n, x), parent);
      boundary_.emplace(face_key(n, v, x), parent);
    }
    for (Index t : shell) {
      std::array<Index, 4> a = tet(t), b = tet(t);
      for (int k = 0; k < 4; ++k) {
        if (a[k] == v) a[k] = n;
        if (b[k] == u) b[k] = n;
      }
      kill_tet(t);
      add_tet(a);
      add_tet(b);
    }
    if (new_point) *new_point = n;
    return SplitOutcome::kSplit;
  }
  return SplitOutcome::kInverted;
}

bool RefineMesh::support_allows_collapse(Index from, Index to) const {
  const PointSupport& f = support(from);
  const PointSupport& t = support(to);
  switch (f.kind) {
    case Support::kInputVertex:
      return false;
    case Support::kInterior:
      return true;
    case Support::kInputEdge:
      return to == f.edge_from || to == f.edge_to ||
             (t.kind == Support::kInputEdge && t.edge_from == f.edge_from && t.edge_to == f.edge_to);
    case Support::kInputFace: {
      if (t.kind == Support::kInputFace) return t.tri == f.tri;
      if (t.kind == Support::kInterior) return false;
      // `to` must be a corner of f.tri or lie on one of its edges: compare coordinates with the
      // input triangle's corners.
      const Index* c = &surface_.tri[static_cast<std::size_t>(3 * f.tri)];
      auto is_corner = [&](Index m) {
        for (int k = 0; k < 3; ++k)
          if (same(point(m), surface_.point(c[k]))) return true;
        return false;
      };
      if (t.kind == Support::kInputVertex) return is_corner(to);
      return is_corner(t.edge_from) && is_corner(t.edge_to);
    }
  }
  return false;
}

bool RefineMesh::collapse_edge(Index from, Index to, double min_quality, double max_edge2,
                               const TetsAccept& accept) {
  if (!support_allows_collapse(from, to)) return false;
  if (!edge_exists(from, to)) return false;
  if (support(from).kind != Support::kInterior && edge_kind(from, to) == EdgeKind::kInterior) return false;
  const std::vector<Index> ball = tets_around_point(from);  // a copy: the ball changes below
  double old_min = 180;
  for (Index t : ball) old_min = std::min(old_min, tet_quality(t));
  const double floor = std::min(min_quality, old_min);
  const Vec3 target = point(to);
  std::vector<std::array<Index, 4>> created;
  for (Index t : ball) {
    std::array<Index, 4> q = tet(t);
    if (std::find(q.begin(), q.end(), to) != q.end()) continue;
    for (Index& w : q)
      if (w == from) w = to;
    if (!positive(q)) return false;
    if (tet_min_dihedral_deg(point(q[0]), point(q[1]), point(q[2]), point(q[3])) < floor) return false;
    for (Index w : q)
      if (w != to && squared_distance(point(w), target) > max_edge2) return false;
    created.push_back(q);
  }
  if (accept) {
    std::vector<std::array<Index, 4>> removed;
    for (Index t : ball) removed.push_back(tet(t));
    if (!accept(removed, created)) return false;
  }
  // Boundary faces around `from`: the ones with `to` vanish, the others move onto `to`.
  std::vector<std::pair<FaceKey, Index>> faces;
  for (Index t : ball) {
    const auto& q = tet(t);
    for (int k = 0; k < 4; ++k) {
      if (q[k] == from) continue;
      const FaceKey key = face_key(q[(k + 1) % 4], q[(k + 2) % 4], q[(k + 3) % 4]);
      if (std::find(key.begin(), key.end(), from) == key.end()) continue;
      auto it = boundary_.find(key);
      if (it != boundary_.end() &&
          std::find_if(faces.begin(), faces.end(), [&](const auto& f) { return f.first == key; }) == faces.end())
        faces.emplace_back(key, it->second);
    }
  }
  std::vector<std::pair<FaceKey, Index>> moved;
  for (const auto& [key, parent] : faces) {
    if (std::find(key.begin(), key.end(), to) != key.end()) continue;
    FaceKey k = key;
    for (Index& w : k)
      if (w == from) w = to;
    k = face_key(k[0], k[1], k[2]);
    if (boundary_.count(k)) return false;
    moved.emplace_back(k, parent);
  }
  for (const auto& f : faces) boundary_.erase(f.first);
  for (const auto& f : moved) boundary_.emplace(f.first, f.second);
  for (Index t : ball) kill_tet(t);
  for (const auto& q : created) add_tet(q);
  point_alive_[static_cast<std::size_t>(from)] = 0;
  ball_[static_cast<std::size_t>(from)].clear();
  return true;
}

bool RefineMesh::flip23(Index t, int opposite_vertex, const TetsAccept& accept) {
  if (!tet_alive(t)) return false;
  const auto& q = tet(t);
  const Index a = q[opposite_vertex];
  const Index x = q[kOppositeFace[opposite_vertex][0]], y = q[kOppositeFace[opposite_vertex][1]], z = q[kOppositeFace[opposite_vertex][2]];
  if (is_boundary_face(x, y, z)) return false;
  Index other = -1, b = -1;
  for (Index s : tets_around_point(x)) {
    if (s == t) continue;
    const auto& r0 = tet(s);
    if (std::find(r0.begin(), r0.end(), y) == r0.end()) continue;
    const auto& r = tet(s);
    if (std::find(r.begin(), r.end(), z) == r.end()) continue;
    other = s;
    for (Index w : r)
      if (w != x && w != y && w != z) b = w;
  }
  if (other < 0 || edge_exists(a, b)) return false;
  const std::array<std::array<Index, 4>, 3> created = {{{y, x, a, b}, {z, y, a, b}, {x, z, a, b}}};
  const double old_min = std::min(tet_quality(t), tet_quality(other));
  for (const auto& c : created)
    if (!positive(c) || (!accept && quality_of(c) <= old_min + kImprovement)) return false;
  if (accept && !accept({tet(t), tet(other)}, {created.begin(), created.end()})) return false;
  kill_tet(t);
  kill_tet(other);
  for (const auto& c : created) add_tet(c);
  return true;
}

bool RefineMesh::flip32(Index u, Index v, const TetsAccept& accept) {
  return remove_edge(u, v, 3, accept, 3);
}

// The shell of edge (u, v): for every tet {u, v, p, q} (an even permutation of its corners) the
// link p -> q. False when a tet of the shell is degenerate in this respect.
bool RefineMesh::shell_links(Index u, Index v, const std::vector<Index>& shell,
                             std::vector<std::pair<Index, Index>>& links) const {
  links.clear();
  for (Index s : shell) {
    const auto& r = tet(s);
    Index p = -1, q = -1;
    for (Index w : r)
      if (w != u && w != v) (p < 0 ? p : q) = w;
    if (q < 0) return false;
    if (!even_permutation(r, {u, v, p, q})) std::swap(p, q);
    links.emplace_back(p, q);
  }
  return true;
}

bool RefineMesh::remove_edge(Index u, Index v, int max_ring, const TetsAccept& accept, int min_ring) {
  const std::vector<Index> shell = tets_around_edge(u, v);
  const int n = static_cast<int>(shell.size());
  if (n < std::max(3, min_ring) || n > max_ring) return false;
  if (!is_interior_edge(u, v, shell)) return false;
  std::vector<std::pair<Index, Index>> links;
  if (!shell_links(u, v, shell, links)) return false;
  std::vector<Index> ring{links[0].first};
  for (int i = 0; i < n; ++i) {
    auto it = std::find_if(links.begin(), links.end(), [&](const auto& l) { return l.first == ring.back(); });
    if (it == links.end()) return false;
    ring.push_back(it->second);
  }
  if (ring.back() != ring.front()) return false;
  ring.pop_back();
  return retriangulate_shell(u, v, shell, ring, /*open=*/false, -1, accept);
}

bool RefineMesh::flip_boundary_edge(Index u, Index v, int max_ring, const TetsAccept& accept, bool only_if_not_delaunay) {
  const std::vector<Index> shell = tets_around_edge(u, v);
  const int n = static_cast<int>(shell.size());
  if (n < 2 || n > max_ring) return false;
  Index parent = -1;
  if (edge_kind(u, v, &parent) != EdgeKind::kInFace) return false;
  if (std::binary_search(fixed_tags_.begin(), fixed_tags_.end(), tag_of(parent))) return false;
  std::vector<std::pair<Index, Index>> links;
  if (!shell_links(u, v, shell, links)) return false;
  // The open chain a = w_0 .. w_n = b: it starts at the link whose tail no link ends at.
  Index first = -1;
  for (const auto& l : links)
    if (std::none_of(links.begin(), links.end(), [&](const auto& m) { return m.second == l.first; })) {
      if (first >= 0) return false;
      first = l.first;
    }
  if (first < 0) return false;
  std::vector<Index> chain{first};
  for (int i = 0; i < n; ++i) {
    auto it = std::find_if(links.begin(), links.end(), [&](const auto& l) { return l.first == chain.back(); });
    if (it == links.end()) return false;
    chain.push_back(it->second);
  }
  // (u, v, a) and (u, v, b) must be the boundary faces, and the new edge (a, b) must not exist.
  if (!is_boundary_face(u, v, chain.front()) || !is_boundary_face(u, v, chain.back())) return false;
  if (edge_exists(chain.front(), chain.back())) return false;
  if (only_if_not_delaunay) {
    // The angles at a and b facing (u, v), in doubles (a choice, not a validity decision).
    const auto angle = [&](Index apex) {
      const Vec3 &p = point(apex), &x = point(u), &y = point(v);
      const double ax = x.x - p.x, ay = x.y - p.y, az = x.z - p.z, bx = y.x - p.x, by = y.y - p.y, bz = y.z - p.z;
      const double c = (ax * bx + ay * by + az * bz) /
                       std::sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz));
      return std::acos(std::max(-1.0, std::min(1.0, c)));
    };
    if (!(angle(chain.front()) + angle(chain.back()) > std::acos(-1.0))) return false;
  }
  return retriangulate_shell(u, v, shell, chain, /*open=*/true, parent, accept);
}

bool RefineMesh::retriangulate_shell(Index u, Index v, const std::vector<Index>& shell, const std::vector<Index>& ring,
                                     bool open, Index parent, const TetsAccept& accept) {
  const int n = static_cast<int>(ring.size());
  if (n > kMaxRingVertices) return false;
  {
    std::vector<Index> sorted = ring;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return false;
  }
  const auto W = [&](int i) { return ring[static_cast<std::size_t>(i)]; };
  // Tets of ring triangle (i, k, j), i < k < j in ring order.
  const auto tets_of = [&](int i, int k, int j) {
    return std::array<std::array<Index, 4>, 2>{{{W(k), W(i), W(j), u}, {W(i), W(k), W(j), v}}};
  };
  // Diagonals (i, j), j - i >= 2, (i, j) != (0, n - 1), must not be mesh edges yet (the caller
  // checked (0, n - 1) for an open chain); the single triangle of n = 3 must not be a mesh face.
  // A diagonal is looked up only for a sub-polygon that has a triangulation good enough to be
  // used (most have none), which gives the same optimum as checking every diagonal first.
  const auto diagonal_ok = [&](int i, int j) { return !edge_exists(W(i), W(j)); };
  if (n == 3)
    for (Index s : tets_around_edge(W(0), W(1)))
      if (std::find(tet(s).begin(), tet(s).end(), W(2)) != tet(s).end()) return false;
  double old_min = 180;
  for (Index s : shell) old_min = std::min(old_min, tet_quality(s));
  // Without `accept` only a triangulation better than the shell counts: a sub-polygon whose best
  // is no better than that is as good as none (the same optimum, found with fewer tets looked at).
  // A triangle's score is the worst angle of its two tets (mesh/ring_triangulation.h).
  const double kNone = -1;
  auto ring_polygon = make_ring_triangulation(
      n, accept ? kNone : old_min + kImprovement, std::numeric_limits<double>::infinity(),
      [&](int i, int k, int j, double bar) {
        double q = std::numeric_limits<double>::infinity();
        for (const auto& t : tets_of(i, k, j)) {
          if (!positive(t)) return kNone;
          q = std::min(q, quality_of(t));
          if (q <= bar) break;
        }
        return q;
      },
      diagonal_ok);
  // (Without `accept`, a result is better than the shell by construction: the floor above.)
  if (ring_polygon.best(0, n - 1) <= kNone) return false;
  std::vector<std::array<Index, 4>> created;
  ring_polygon.for_each_triangle(
      0, n - 1,
      [&](int i, int k, int j) {
        for (const auto& t : tets_of(i, k, j)) created.push_back(t);
      },
      /*right_first=*/true);
  if (accept) {
    std::vector<std::array<Index, 4>> removed;
    for (Index s : shell) removed.push_back(tet(s));
    if (!accept(removed, created)) return false;
  }
  for (Index s : shell) kill_tet(s);
  if (open) {
    // The two boundary faces on the old edge give way to the two on the new one, same parent.
    boundary_.erase(face_key(u, v, W(0)));
    boundary_.erase(face_key(u, v, W(n - 1)));
    boundary_.emplace(face_key(W(0), W(n - 1), u), parent);
    boundary_.emplace(face_key(W(0), W(n - 1), v), parent);
  }
  for (const auto& c : created) add_tet(c);
  return true;
}

Index RefineMesh::neighbour(Index t, int k) {
  // Tets are never edited in place (only added and killed), so a cached neighbour is right while
  // it lives, and a boundary face stays one for as long as t lives.
  Index& cached = neighbour_[static_cast<std::size_t>(t) * 4 + static_cast<std::size_t>(k)];
  if (cached == -1 || (cached >= 0 && tet_alive(cached))) return cached;
  const auto q = tet(t);
  const Index a = q[kOppositeFace[k][0]], b = q[kOppositeFace[k][1]], c = q[kOppositeFace[k][2]];
  if (is_boundary_face(a, b, c)) return cached = -1;
  for (Index n : tets_around_point(a)) {
    if (n == t) continue;
    const auto& r = tet(n);
    const bool hb = r[0] == b || r[1] == b || r[2] == b || r[3] == b;
    const bool hc = r[0] == c || r[1] == c || r[2] == c || r[3] == c;
    if (hb && hc) return cached = n;
  }
  return -1;  // not cached: a tet may be added across this face later
}

InsertOutcome RefineMesh::insert_point(
    Index start, const Vec3& p, double clearance, Index* new_point, Index max_cavity, bool must_improve,
    const std::function<bool(const std::vector<std::array<Index, 4>>&, const Vec3&)>& accept, Index must_contain) {
  if (!tet_alive(start)) return InsertOutcome::kWalkFailed;
  if (must_contain >= 0) {
    if (!tet_alive(must_contain)) return InsertOutcome::kWalkFailed;
    // A boundary face of must_contain stays a face of the cavity: p must see it from inside, and
    // with must_improve the tet it makes with p should be better than must_contain (exactly what
    // is asked when must_contain is the cavity's worst tet, as it is for the callers).
    const auto q = tet(must_contain);
    for (int k = 0; k < 4; ++k) {
      if (neighbour(must_contain, k) >= 0) continue;
      const Vec3 &a = point(q[kOppositeFace[k][0]]), &b = point(q[kOppositeFace[k][1]]), &c = point(q[kOppositeFace[k][2]]);
      if (orient3d(a, b, c, p) != Sign::kPositive) return InsertOutcome::kNoStarCavity;
      if (must_improve && tet_min_dihedral_deg(a, b, c, p) <= tet_quality(must_contain) + kImprovement)
        return InsertOutcome::kNoImprovement;
    }
  }
  // 1. Locate: step through a face that has p strictly beyond it (the faces are tried from a
  //    rotating first index so that the walk does not cycle on a fixed choice).
  Index t = start;
  bool found = false;
  for (int step = 0; step < 4096 && !found; ++step) {
    const auto q = tet(t);
    // A face with p beyond it; an interior one when there is one (in a non-convex solid a
    // boundary face can have p beyond it while p is inside, past another face of the tet).
    int beyond = -1;
    bool beyond_boundary = false;
    for (int i = 0; i < 4 && (beyond < 0 || beyond_boundary); ++i) {
      const int k = (i + step) % 4;
      if (orient3d(point(q[kOppositeFace[k][0]]), point(q[kOppositeFace[k][1]]), point(q[kOppositeFace[k][2]]), p) == Sign::kNegative) {
        const bool boundary = neighbour(t, k) < 0;
        if (beyond < 0 || !boundary) beyond = k, beyond_boundary = boundary;
      }
    }
    if (beyond < 0) {
      found = true;
      break;
    }
    if (beyond_boundary) return InsertOutcome::kOutside;
    t = neighbour(t, beyond);
  }
  if (!found) return InsertOutcome::kWalkFailed;
  // 2. Cavity: tets whose circumsphere contains p, through interior faces.
  if (cavity_mark_.size() < tets_.size()) cavity_mark_.resize(tets_.size(), 0);
  const std::uint64_t kIn = 2 * ++cavity_generation_, kDropped = kIn + 1;
  auto taken = [&](Index x) { return cavity_mark_[static_cast<std::size_t>(x)] >= kIn; };  // in or dropped
  auto inside = [&](Index x) { return cavity_mark_[static_cast<std::size_t>(x)] == kIn; };
  auto take = [&](Index x) { cavity_mark_[static_cast<std::size_t>(x)] = kIn; };
  std::vector<Index> cavity{t};
  take(t);
  if (must_contain >= 0 && must_contain != t) {
    cavity.push_back(must_contain);
    take(must_contain);
  }
  for (std::size_t i = 0; i < cavity.size() && static_cast<Index>(cavity.size()) < max_cavity; ++i)
    for (int k = 0; k < 4; ++k) {
      const Index n = neighbour(cavity[i], k);
      if (n < 0 || taken(n)) continue;
      const auto& r = tet(n);
      Vec3 c;
      double r2 = 0;
      if (!tet_circumsphere(point(r[0]), point(r[1]), point(r[2]), point(r[3]), &c, &r2)) continue;
      if (squared_distance(c, p) < r2) {
        take(n);
        cavity.push_back(n);
      }
    }
  // 2b. With must_contain: grow through every interior face of the cavity's boundary that p does
  //     not see from inside (the tet beyond lies between p and the cavity), to at most
  //     max_cavity tets; tets added are examined in turn.
  if (must_contain >= 0) {
    const std::size_t limit = static_cast<std::size_t>(max_cavity);
    for (std::size_t i = 0; i < cavity.size() && cavity.size() < limit; ++i) {
      const auto q = tet(cavity[i]);
      for (int k = 0; k < 4 && cavity.size() < limit; ++k) {
        const Index n = neighbour(cavity[i], k);
        if (n < 0 || taken(n)) continue;
        if (orient3d(point(q[kOppositeFace[k][0]]), point(q[kOppositeFace[k][1]]), point(q[kOppositeFace[k][2]]), p) !=
            Sign::kPositive) {
          take(n);
          cavity.push_back(n);
        }
      }
    }
  }
  // 3. Shrink until p sees every boundary face of the cavity strictly from inside (exact).
  struct BFace {
    std::array<Index, 3> v;
    Index owner;
  };
  std::vector<BFace> faces;
  for (;;) {
    faces.clear();
    std::vector<Index> drop;
    for (Index c : cavity) {
      if (!inside(c)) continue;
      const auto q = tet(c);
      for (int k = 0; k < 4; ++k) {
        const Index n = neighbour(c, k);
        if (n >= 0 && inside(n)) continue;
        const BFace f{{q[kOppositeFace[k][0]], q[kOppositeFace[k][1]], q[kOppositeFace[k][2]]}, c};
        if (orient3d(point(f.v[0]), point(f.v[1]), point(f.v[2]), p) != Sign::kPositive) drop.push_back(c);
        faces.push_back(f);
      }
    }
    if (drop.empty()) break;
    for (Index c : drop) {
      if (c == t || c == must_contain) return InsertOutcome::kNoStarCavity;
      cavity_mark_[static_cast<std::size_t>(c)] = kDropped;
    }
  }
  std::vector<Index> kept;
  for (Index c : cavity)
    if (inside(c)) kept.push_back(c);
  // 4. No vertex may disappear; clearance.
  std::vector<Index> on_boundary;
  for (const BFace& f : faces) on_boundary.insert(on_boundary.end(), f.v.begin(), f.v.end());
  std::sort(on_boundary.begin(), on_boundary.end());
  on_boundary.erase(std::unique(on_boundary.begin(), on_boundary.end()), on_boundary.end());
  for (Index c : kept)
    for (Index v : tet(c))
      if (!std::binary_search(on_boundary.begin(), on_boundary.end(), v)) return InsertOutcome::kNoStarCavity;
  for (Index v : on_boundary)
    if (squared_distance(point(v), p) < clearance * clearance) return InsertOutcome::kTooClose;
  if (must_improve) {
    double old_min = std::numeric_limits<double>::infinity();
    for (Index c : kept) old_min = std::min(old_min, tet_quality(c));
    for (const BFace& f : faces)
      if (tet_min_dihedral_deg(point(f.v[0]), point(f.v[1]), point(f.v[2]), p) <= old_min + kImprovement)
        return InsertOutcome::kNoImprovement;
  }
  if (accept) {
    std::vector<std::array<Index, 4>> cone;
    for (const BFace& f : faces) cone.push_back({f.v[0], f.v[1], f.v[2], -1});
    if (!accept(cone, p)) return InsertOutcome::kNoImprovement;
  }
  // 5. Replace the cavity by the cone from p (every new tet was checked positive in step 3).
  const Index n = add_point(p, PointSupport{});
  for (Index c : kept) kill_tet(c);
  for (const BFace& f : faces) add_tet({f.v[0], f.v[1], f.v[2], n});
  if (new_point) *new_point = n;
  return InsertOutcome::kInserted;
}

bool RefineMesh::relocate_point(Index v, const Vec3& p) {
  if (support(v).kind != Support::kInterior || !finite(p)) return false;
  const std::vector<Index>& ball = tets_around_point(v);
  double old_min = 180;
  for (Index t : ball) old_min = std::min(old_min, tet_quality(t));
  std::vector<double> q(ball.size());
  for (std::size_t i = 0; i < ball.size(); ++i) {
    const auto& t = tet(ball[i]);
    if (!positive_with(t, v, p)) return false;
    Vec3 c[4];
    for (int k = 0; k < 4; ++k) c[k] = t[k] == v ? p : point(t[k]);
    q[i] = tet_min_dihedral_deg(c[0], c[1], c[2], c[3]);
    if (q[i] <= old_min + kImprovement) return false;
  }
  xyz_[static_cast<std::size_t>(v)] = p;
  for (std::size_t i = 0; i < ball.size(); ++i) {
    quality_[static_cast<std::size_t>(ball[i])] = q[i];
    touch(tet(ball[i]));
  }
  return true;
}

bool RefineMesh::relocate_point_if(Index v, const Vec3& p,
                                   const std::function<bool(const std::vector<std::array<Vec3, 4>>&)>& accept) {
  if (support(v).kind != Support::kInterior || !finite(p)) return false;
  const std::vector<Index> ball = tets_around_point(v);
  std::vector<std::array<Vec3, 4>> moved(ball.size());
  for (std::size_t i = 0; i < ball.size(); ++i) {
    const auto& t = tet(ball[i]);
    if (!positive_with(t, v, p)) return false;
    for (int k = 0; k < 4; ++k) moved[i][static_cast<std::size_t>(k)] = t[k] == v ? p : point(t[k]);
  }
  if (!accept(moved)) return false;
  move_point(v, p, ball, moved);
  return true;
}

TetMesh RefineMesh::to_tet_mesh(std::vector<Index>* old_to_new) const {
  std::vector<Index> renum(xyz_.size(), -1);
  for (Index t = 0; t < num_tet_slots(); ++t)
    if (tet_alive(t))
      for (Index v : tet(t)) renum[static_cast<std::size_t>(v)] = 0;
  TetMesh out;
  Index next = 0;
  for (std::size_t i = 0; i < xyz_.size(); ++i) {
    if (renum[i] < 0) continue;
    renum[i] = next++;
    out.xyz.insert(out.xyz.end(), {xyz_[i].x, xyz_[i].y, xyz_[i].z});
  }
  for (Index t = 0; t < num_tet_slots(); ++t)
    if (tet_alive(t))
      for (Index v : tet(t)) out.tet.push_back(renum[static_cast<std::size_t>(v)]);
  if (old_to_new) *old_to_new = std::move(renum);
  return out;
}

EdgeMap<std::array<std::int32_t, 2>> RefineMesh::boundary_edge_tags(const std::vector<Index>* renum) {
  EdgeMap<std::array<std::int32_t, 2>> out;
  for (const auto& [face, parent] : boundary_faces())
    for (int k = 0; k < 3; ++k) {
      Index a = face[k], b = face[(k + 1) % 3];
      if (renum) a = (*renum)[static_cast<std::size_t>(a)], b = (*renum)[static_cast<std::size_t>(b)];
      const std::uint64_t key = edge_key(a, b);
      const std::int32_t tag = tag_of(parent);
      if (auto* tags = out.find(key))
        (*tags)[1] = tag;
      else
        out[key] = {tag, tag};
    }
  return out;
}

std::vector<std::pair<std::array<Index, 3>, Index>> RefineMesh::boundary_faces() {
  std::vector<std::pair<std::array<Index, 3>, Index>> out;
  out.reserve(boundary_.size());
  for (const auto& [key, parent] : boundary_) {
    std::array<Index, 3> face = key;
    for (Index t : tets_around_edge(key[0], key[1])) {
      const auto& q = tet(t);
      int k = 0;
      while (k < 4 && (q[k] == key[0] || q[k] == key[1] || q[k] == key[2])) ++k;
      if (k == 4 || std::find(q.begin(), q.end(), key[2]) == q.end()) continue;
      // Outward face opposite q[k] (types.h).
      static const int outward[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
      face = {q[outward[k][0]], q[outward[k][1]], q[outward[k][2]]};
    }
    out.emplace_back(face, parent);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace bsptet
