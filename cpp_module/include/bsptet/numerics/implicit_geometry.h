// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the exact geometry of the BSP. Every point the BSP creates stays implicit: it is
// either an EXPLICIT point (an input vertex or a bounding-box corner, double coordinates) or the
// intersection of three planes (TPI). Every plane passes through three explicit points, so all
// coordinates are exact rationals of the input doubles and nothing is rounded until the output
// (see snap_round.h). Predicates: an interval filter, then exact arithmetic (ExactFloat).
//
// Sign conventions (stated once):
//  * Plane (a, b, c) has normal n = (b - a) x (c - a). side(plane, v) = sign(n . (v - a)):
//    POSITIVE on the side n points to. For an explicit v this is orient3d(a, b, c, v).
//  * orient2d(u, v, w, axis): the orientation of the three vertices projected along `axis`, in the
//    convention of predicates.h (orient2d_projected): a triangle with normal m projects
//    positively exactly when m[axis] > 0.
#pragma once

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/interval.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/numerics/vec3.h"

namespace bsptet {

struct PlaneDef {
  Index a, b, c;  ///< explicit point ids
};

class ImplicitGeometry {
 public:
  explicit ImplicitGeometry(std::vector<Vec3> explicit_points);

  Index num_explicit() const { return static_cast<Index>(points_.size()); }
  const Vec3& explicit_point(Index i) const { return points_[i]; }
  Index num_planes() const { return static_cast<Index>(planes_.size()); }
  const PlaneDef& plane(Index p) const { return planes_[p]; }
  Index num_vertices() const { return static_cast<Index>(verts_.size()); }

  /// Adds an explicit point and a vertex at it; returns the vertex id.
  Index add_explicit_point(const Vec3& p);
  /// Adds a plane through three explicit points (must not be collinear: checked, throws).
  Index add_plane(Index a, Index b, Index c);
  /// Adds a vertex at explicit point `point`.
  Index add_explicit_vertex(Index point);
  /// Adds the vertex where planes p, q, r meet (they must meet in one point: caller's duty).
  Index add_tpi_vertex(Index p, Index q, Index r);
  /// Adds the vertex at the centroid of four vertices (exact homogeneous coordinates). Inside a
  /// convex cell with those four non-coplanar vertices it is strictly inside the cell.
  Index add_centroid_vertex(const std::array<Index, 4>& of);
  /// Records that vertex v lies on plane p (a fact known combinatorially), so side() returns
  /// ZERO without arithmetic.
  void note_on_plane(Index v, Index p);

  /// The planes v is known to lie on (its TPI planes, its triangles' planes, cut planes).
  const std::vector<Index>& known_planes(Index v) const { return verts_[v].on_planes; }
  bool is_explicit(Index v) const { return verts_[v].explicit_id >= 0; }
  Index explicit_id(Index v) const { return verts_[v].explicit_id; }
  const std::array<Index, 3>& tpi_planes(Index v) const { return verts_[v].planes; }

  /// sign(n . (v - a)) for plane (a, b, c), exact.
  Sign side(Index plane, Index v);
  /// A filter for many vertices at once: POSITIVE (NEGATIVE) when every point of the box (intervals
  /// of x, y, z) is strictly on that side of the plane, ZERO when that is not certain. No exact step.
  Sign side_of_box(Index plane, const std::array<Interval, 3>& box);
  /// Intervals enclosing vertex v's coordinates (x, y, z), or nullptr when none are available.
  const std::array<Interval, 3>* vertex_box(Index v) { return box(v); }
  /// Exact orient3d of four vertices of any kind (predicates.h convention: POSITIVE when d lies on
  /// the side of the right-hand normal of (a, b, c)). Explicit-only calls use the double predicate.
  Sign orient3d(Index a, Index b, Index c, Index d);
  /// Exact orientation of vertices u, v, w projected along axis (see header comment).
  Sign orient2d(Index u, Index v, Index w, int axis);
  /// An axis along which the plane's projection is one-to-one (its normal component there is
  /// non-zero), decided exactly; and the sign of that normal component.
  int projection_axis(Index plane, Sign* normal_sign = nullptr);

  /// True when vertex v is known (combinatorially or from an earlier exact zero) to lie on plane p.
  bool known_on_plane(Index v, Index p) const {
    const auto& l = verts_[v].on_planes;
    return std::find(l.begin(), l.end(), p) != l.end();
  }

  /// Lifted (Delaunay) predicates with symbolic perturbation (cell_delaunay.h uses them).
  /// Every vertex v is lifted to height H(v) = |v|^2 + eps^k(v), eps -> 0+, where k(v) is strictly
  /// decreasing in the global vertex id: the vertex with the largest id has the dominant
  /// perturbation. One global rule, so every caller (both cells of a face, the 2D and the 3D test)
  /// decides every tie the same way.
  ///
  /// lifted_det3(a, b, c, d, e) = sign det [x y z H 1] over the rows a..e (5 x 5). ZERO only when
  /// the five vertices are coplanar (all its perturbation cofactors vanish). For a positive tet
  /// (a, b, c, d), e is strictly inside the (perturbed) circumsphere iff the result is NEGATIVE.
  Sign lifted_det3(Index a, Index b, Index c, Index d, Index e);
  /// lifted_det2(a, b, c, d, axis) = sign det [u v H 1] over the rows a..d (4 x 4), (u, v) the
  /// coordinates kept when dropping `axis` (orient2d's convention), H the 3D lift above. For four
  /// vertices on one plane and orient2d(a, b, c, axis) = s != 0, d is strictly inside the
  /// (perturbed) circumcircle of a, b, c (in the plane's own metric) iff the result is s.
  /// ZERO only when the four are collinear in the projection.
  Sign lifted_det2(Index a, Index b, Index c, Index d, int axis);

  /// The coordinates of vertex v rounded to doubles (each coordinate within one ulp).
  Vec3 rounded(Index v);
  /// Counters, for the statistics.
  long long exact_fallbacks() const { return exact_fallbacks_; }

 private:
  struct PlaneCache {
    bool ready = false;
    std::array<Interval, 3> n_iv;
    Interval d_iv;
    std::unique_ptr<std::array<ExactFloat, 4>> exact;  // n (3) and d = n . a
  };
  struct Vertex {
    Index explicit_id = -1;
    std::array<Index, 3> planes{{-1, -1, -1}};  ///< TPI planes; all -1 for explicit and centroid vertices
    std::array<Index, 4> centroid_of{{-1, -1, -1, -1}};
    std::vector<Index> on_planes;  // planes known to contain the vertex
    bool iv_ready = false;
    std::array<Interval, 4> iv;  // homogeneous (X, Y, Z, W)
    std::unique_ptr<std::array<ExactFloat, 4>> exact;
    bool rounded_ready = false;
    Vec3 rounded;  ///< cache of rounded()
    signed char is_double = -1;  ///< cache of exact_double(): -1 unknown, 0 no, 1 yes
    signed char box_state = -1;  ///< cache of box(): -1 unknown, 0 unavailable, 1 ready
    std::array<Interval, 3> box;  ///< intervals enclosing x, y, z (X / W)
  };
  /// True when vertex v's coordinates are exactly doubles (then *p holds them); decided exactly,
  /// once per vertex. Lets exact fallbacks on such vertices run on doubles (same signs, cheaper).
  bool exact_double(Index v, Vec3* p);
  /// A sufficient condition for coplanarity (no arithmetic): the four vertices are known to lie on
  /// one plane, or three of them on one line (two defining planes of a TPI vertex).
  bool known_coplanar(Index a, Index b, Index c, Index d) const;
  /// A sufficient condition for collinearity (no arithmetic): one of them is a TPI vertex and the
  /// other two lie on two of its defining planes.
  bool known_collinear(Index x, Index y, Index z) const;
  /// A double point m with every coordinate within r of vertex v's exact one (explicit: the point
  /// itself, r = 0; else the centre and width of box(v)); false when there is no box.
  bool approximate(Index v, Vec3* m, double* r);
  /// approximate() for each of `ids`; false when one has no box.
  template <std::size_t N>
  bool approximate_all(const std::array<Index, N>& ids, std::array<Vec3, N>& m, std::array<double, N>& r);
  /// Intervals enclosing the vertex's Cartesian coordinates (a filter input tighter and cheaper
  /// than the homogeneous intervals); nullptr when W's interval contains zero or overflows.
  const std::array<Interval, 3>* box(Index v);
  void prepare_plane(Index p);
  const std::array<ExactFloat, 4>& plane_exact(Index p);
  const std::array<Interval, 4>& vertex_interval(Index v);
  const std::array<ExactFloat, 4>& vertex_exact(Index v);

  std::vector<Vec3> points_;
  std::vector<PlaneDef> planes_;
  std::vector<std::unique_ptr<PlaneCache>> plane_cache_;  ///< allocated by prepare_plane
  std::vector<Vertex> verts_;
  long long exact_fallbacks_ = 0;
};

}  // namespace bsptet
