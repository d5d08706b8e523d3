// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/input/triangle_intersection.h"

#include <algorithm>

#include "bsptet/numerics/predicates.h"

namespace bsptet {

namespace {

int sgn(Sign s) { return to_int(s); }

// An axis along which the triangle (a, b, c) projects to a non-degenerate 2D triangle; points of
// its plane keep every incidence under that projection. Precondition: not collinear.
int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  for (int k : {2, 0, 1})
    if (orient2d_projected(a, b, c, k) != Sign::kZero) return k;
  return 2;  // unreachable for a non-degenerate triangle
}

// x lies on the closed segment [p, q]; precondition: the three are collinear in projection k.
bool on_segment_2d(const Vec3& p, const Vec3& q, const Vec3& x, int k) {
  const int u = (k + 1) % 3, v = (k + 2) % 3;
  return std::min(p[u], q[u]) <= x[u] && x[u] <= std::max(p[u], q[u]) && std::min(p[v], q[v]) <= x[v] &&
         x[v] <= std::max(p[v], q[v]);
}

// Closed segments [p, q] and [r, s] meet, all four points in one plane not parallel to axis k.
bool segments_meet_2d(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, int k) {
  const int o1 = sgn(orient2d_projected(p, q, r, k)), o2 = sgn(orient2d_projected(p, q, s, k));
  const int o3 = sgn(orient2d_projected(r, s, p, k)), o4 = sgn(orient2d_projected(r, s, q, k));
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  return (o1 == 0 && on_segment_2d(p, q, r, k)) || (o2 == 0 && on_segment_2d(p, q, s, k)) ||
         (o3 == 0 && on_segment_2d(r, s, p, k)) || (o4 == 0 && on_segment_2d(r, s, q, k));
}

// x in the closed triangle (a, b, c), all in one plane not parallel to axis k.
bool in_triangle_2d(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, int k) {
  const int s = sgn(orient2d_projected(a, b, c, k));
  return sgn(orient2d_projected(a, b, x, k)) * s >= 0 && sgn(orient2d_projected(b, c, x, k)) * s >= 0 &&
         sgn(orient2d_projected(c, a, x, k)) * s >= 0;
}

// The closed segment [p, q] meets the closed triangle (a, b, c), all in one plane.
bool coplanar_segment_meets_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int k = projection_axis(a, b, c);
  return in_triangle_2d(p, a, b, c, k) || in_triangle_2d(q, a, b, c, k) || segments_meet_2d(p, q, a, b, k) ||
         segments_meet_2d(p, q, b, c, k) || segments_meet_2d(p, q, c, a, k);
}

// The direction x - v lies in the closed angle of triangle (v, b1, b2) at v; x in that plane.
bool in_corner_cone(const Vec3& v, const Vec3& b1, const Vec3& b2, const Vec3& x) {
  const int k = projection_axis(v, b1, b2);
  const int s = sgn(orient2d_projected(v, b1, b2, k));
  return sgn(orient2d_projected(v, b1, x, k)) * s >= 0 && sgn(orient2d_projected(v, x, b2, k)) * s >= 0;
}

}  // namespace

namespace {

// classify_segment_triangle with the signs op, oq of p and q against the triangle's plane known.
SegmentTriangleContact classify_with_signs(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                                           int op, int oq) {
  if (op * oq > 0) return SegmentTriangleContact::kNone;
  if (op == 0 && oq == 0)
    return coplanar_segment_meets_triangle(p, q, a, b, c) ? SegmentTriangleContact::kDegenerate
                                                          : SegmentTriangleContact::kNone;
  // The line through p and q crosses the plane once: it meets the closed triangle exactly when it
  // passes on no strictly different sides of the three edges.
  const int s1 = sgn(orient3d(p, q, a, b)), s2 = sgn(orient3d(p, q, b, c)), s3 = sgn(orient3d(p, q, c, a));
  const bool pos = s1 > 0 || s2 > 0 || s3 > 0, neg = s1 < 0 || s2 < 0 || s3 < 0;
  if (pos && neg) return SegmentTriangleContact::kNone;
  if (op == 0 || oq == 0 || s1 == 0 || s2 == 0 || s3 == 0) return SegmentTriangleContact::kDegenerate;
  return SegmentTriangleContact::kCrossing;
}

}  // namespace

SegmentTriangleContact classify_segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                                 const Vec3& c) {
  return classify_with_signs(p, q, a, b, c, sgn(orient3d(a, b, c, p)), sgn(orient3d(a, b, c, q)));
}

bool segment_meets_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  return classify_segment_triangle(p, q, a, b, c) != SegmentTriangleContact::kNone;
}

namespace {

// The signs of the corners of `s` against the plane of `t` (0 for corners shared with t, without
// computing them). Returns false when every corner not shared lies strictly on one side: then s
// meets t's plane only in shared vertices, and the triangles cannot intersect beyond them.
bool plane_signs(const IndexedTriangle& s, const IndexedTriangle& t, const bool shared[3], int out[3]) {
  int pos = 0, neg = 0, zero = 0;
  for (int i = 0; i < 3; ++i) {
    out[i] = shared[i] ? 0 : sgn(orient3d(t.p[0], t.p[1], t.p[2], s.p[i]));
    pos += out[i] > 0;
    neg += out[i] < 0;
    zero += !shared[i] && out[i] == 0;
  }
  return !((pos == 0 || neg == 0) && zero == 0);
}

// Some point of the edge i of s (from corner i to corner i + 1), other than the shared vertices,
// lies in t. `os` are the signs of s's corners against t's plane.
bool edge_meets_beyond_shared(const IndexedTriangle& s, int i, const bool shared_s[3], const int os[3],
                              const IndexedTriangle& t) {
  const int j = (i + 1) % 3;
  if (shared_s[i] && shared_s[j]) return false;  // the shared edge itself
  if (!shared_s[i] && !shared_s[j])
    return classify_with_signs(s.p[i], s.p[j], t.p[0], t.p[1], t.p[2], os[i], os[j]) != SegmentTriangleContact::kNone;
  // One end v is a corner of t: the edge meets t beyond v only if it runs in t's plane, into t's
  // angle at v.
  const int iv = shared_s[i] ? i : j, ix = shared_s[i] ? j : i;
  if (os[ix] != 0) return false;
  int tv = 0;
  while (t.id[tv] != s.id[iv]) ++tv;
  return in_corner_cone(t.p[tv], t.p[(tv + 1) % 3], t.p[(tv + 2) % 3], s.p[ix]);
}

}  // namespace

bool triangles_intersect(const IndexedTriangle& s, const IndexedTriangle& t) {
  bool s_shared[3] = {false, false, false}, t_shared[3] = {false, false, false};
  int shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (s.id[i] == t.id[j]) {
        ++shared;
        s_shared[i] = t_shared[j] = true;
      }
  if (shared == 3) return true;
  int os[3], ot[3];  // s's corners against t's plane, t's corners against s's plane
  if (!plane_signs(s, t, s_shared, os)) return false;
  const bool coplanar = os[0] == 0 && os[1] == 0 && os[2] == 0;
  if (coplanar) {
    ot[0] = ot[1] = ot[2] = 0;  // s spans t's plane
  } else if (!plane_signs(t, s, t_shared, ot)) {
    return false;
  }
  if (shared == 2 && !coplanar) return false;  // the planes meet in the shared edge's line
  if (shared == 2) {
    // Coplanar on a shared edge (u, w): a fold when the third corners lie on one side of it.
    int iu = -1, iw = -1, ia = -1, ib = -1;
    for (int i = 0; i < 3; ++i) {
      if (!s_shared[i]) ia = i;
      else if (iu < 0) iu = i;
      else iw = i;
      if (!t_shared[i]) ib = i;
    }
    const int k = projection_axis(s.p[0], s.p[1], s.p[2]);
    return orient2d_projected(s.p[iu], s.p[iw], s.p[ia], k) == orient2d_projected(s.p[iu], s.p[iw], t.p[ib], k);
  }
  // Otherwise the triangles meet beyond their shared vertices exactly when some boundary point of
  // one, not a shared vertex, lies in the other (the intersection is convex; its extreme points
  // are such boundary points).
  for (int i = 0; i < 3; ++i)
    if (edge_meets_beyond_shared(s, i, s_shared, os, t) || edge_meets_beyond_shared(t, i, t_shared, ot, s))
      return true;
  return false;
}

}  // namespace bsptet
