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

#include <array>
#include <memory>
#include <vector>

#include "bsptet/exact_float.h"
#include "bsptet/interval.h"
#include "bsptet/predicates.h"
#include "bsptet/types.h"

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

  bool is_explicit(Index v) const { return verts_[v].explicit_id >= 0; }
  Index explicit_id(Index v) const { return verts_[v].explicit_id; }
  const std::array<Index, 3>& tpi_planes(Index v) const { return verts_[v].planes; }

  /// sign(n . (v - a)) for plane (a, b, c), exact.
  Sign side(Index plane, Index v);
  /// Exact orient3d of four vertices of any kind (predicates.h convention: POSITIVE when d lies on
  /// the side of the right-hand normal of (a, b, c)). Explicit-only calls use the double predicate.
  Sign orient3d(Index a, Index b, Index c, Index d);
  /// Exact orientation of vertices u, v, w projected along axis (see header comment).
  Sign orient2d(Index u, Index v, Index w, int axis);
  /// An axis along which the plane's projection is one-to-one (its normal component there is
  /// non-zero), decided exactly; and the sign of that normal component.
  int projection_axis(Index plane, Sign* normal_sign = nullptr);

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
  };
  void prepare_plane(Index p);
  const std::array<ExactFloat, 4>& plane_exact(Index p);
  const std::array<Interval, 4>& vertex_interval(Index v);
  const std::array<ExactFloat, 4>& vertex_exact(Index v);

  std::vector<Vec3> points_;
  std::vector<PlaneDef> planes_;
  std::vector<PlaneCache> plane_cache_;
  std::vector<Vertex> verts_;
  long long exact_fallbacks_ = 0;
};

}  // namespace bsptet
