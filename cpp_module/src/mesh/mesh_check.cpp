// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/mesh/mesh_check.h"

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <sstream>
#include <unordered_map>

#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

namespace {

// Outward faces of a positively oriented tet (a, b, c, d), as local vertex indices (types.h).
constexpr int kOutwardFace[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

struct PointKey {
  std::uint64_t b[3];
  bool operator==(const PointKey& o) const {
    return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2];
  }
};
struct PointKeyHash {
  std::size_t operator()(const PointKey& k) const {
    std::uint64_t h = k.b[0] * 0x9E3779B97F4A7C15ull;
    h ^= k.b[1] + 0x7F4A7C159E3779B9ull + (h << 6) + (h >> 2);
    h ^= k.b[2] + 0x94D049BB133111EBull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

std::uint64_t double_bits(double d) {
  if (d == 0.0) d = 0.0;  // -0.0 and 0.0 are the same point
  std::uint64_t u = 0;
  std::memcpy(&u, &d, sizeof u);
  return u;
}

PointKey key_of(const Vec3& p) { return {{double_bits(p.x), double_bits(p.y), double_bits(p.z)}}; }

class Messages {
 public:
  explicit Messages(int cap) : cap_(cap) {}
  template <typename F>
  void add(F&& make) {
    if (static_cast<int>(out_.size()) < cap_) out_.push_back(make());
  }
  std::vector<std::string> take() { return std::move(out_); }

 private:
  int cap_;
  std::vector<std::string> out_;
};

std::string tet_str(const TetMesh& m, Index t) {
  std::ostringstream s;
  s << "tet " << t << " (points";
  for (int k = 0; k < 4; ++k) s << ' ' << m.tet[static_cast<std::size_t>(t) * m.nodes_per_tet + k];
  s << ')';
  return s.str();
}

std::string face_str(Index a, Index b, Index c) {
  std::ostringstream s;
  s << "face (" << a << ' ' << b << ' ' << c << ')';
  return s.str();
}

// Exact integer coordinates on a common binary scale, for exact volume sums.
class ScaledIntegers {
 public:
  explicit ScaledIntegers(std::int64_t min_exp) : min_exp_(min_exp) {}
  static std::int64_t lowest_bit_exponent(double d) {
    int e = 0;
    const double frac = std::frexp(d, &e);
    auto m = static_cast<std::int64_t>(std::ldexp(frac, 53));
    if (m < 0) m = -m;
    return static_cast<std::int64_t>(e) - 53 + __builtin_ctzll(static_cast<unsigned long long>(m));
  }
  mpz_class convert(double d) const {
    if (d == 0.0) return 0;
    int e = 0;
    const double frac = std::frexp(d, &e);
    auto m = static_cast<std::int64_t>(std::ldexp(frac, 53));
    const int tz = __builtin_ctzll(static_cast<unsigned long long>(m < 0 ? -m : m));
    m /= (std::int64_t{1} << tz);  // exact: drops trailing zero bits
    mpz_class r = static_cast<long>(m);
    const std::int64_t shift = static_cast<std::int64_t>(e) - 53 + tz - min_exp_;  // >= 0 by choice of min_exp_
    mpz_mul_2exp(r.get_mpz_t(), r.get_mpz_t(), static_cast<mp_bitcnt_t>(shift));
    return r;
  }

 private:
  std::int64_t min_exp_;
};

// det[b - a, c - a, d - a] on integer coordinates.
mpz_class det3(const mpz_class* a, const mpz_class* b, const mpz_class* c, const mpz_class* d) {
  const mpz_class bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
  const mpz_class cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
  const mpz_class dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
  return mpz_class(bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx));
}

// Uniform grid over triangle bounding boxes, a candidate filter only: exact tests decide.
class TriangleGrid {
 public:
  TriangleGrid(const SurfaceMesh& s) {
    const Index nt = s.num_triangles();
    lo_ = {INFINITY, INFINITY, INFINITY};
    std::array<double, 3> hi = {-INFINITY, -INFINITY, -INFINITY};
    for (Index i = 0; i < s.num_points(); ++i)
      for (int k = 0; k < 3; ++k) {
        lo_[k] = std::min(lo_[k], s.xyz[3 * i + k]);
        hi[k] = std::max(hi[k], s.xyz[3 * i + k]);
      }
    double diag = 0;
    for (int k = 0; k < 3; ++k) diag = std::max(diag, hi[k] - lo_[k]);
    margin_ = diag * 1e-9 + 1e-300;
    const int n = std::max(1, std::min(128, static_cast<int>(std::cbrt(static_cast<double>(nt)) * 1.5)));
    for (int k = 0; k < 3; ++k) {
      lo_[k] -= 2 * margin_;
      const double ext = (hi[k] + 2 * margin_) - lo_[k];
      dims_[k] = ext > 0 ? n : 1;
      cell_[k] = ext > 0 ? ext / n : 1.0;
    }
    cells_.assign(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2], {});
    for (Index t = 0; t < nt; ++t) {
      std::array<int, 3> a{}, b{};
      for (int k = 0; k < 3; ++k) {
        double mn = INFINITY, mx = -INFINITY;
        for (int v = 0; v < 3; ++v) {
          const double x = s.xyz[3 * s.tri[3 * t + v] + k];
          mn = std::min(mn, x);
          mx = std::max(mx, x);
        }
        a[k] = clamp_cell(k, mn - margin_);
        b[k] = clamp_cell(k, mx + margin_);
      }
      for (int i = a[0]; i <= b[0]; ++i)
        for (int j = a[1]; j <= b[1]; ++j)
          for (int l = a[2]; l <= b[2]; ++l) cells_[index(i, j, l)].push_back(t);
    }
  }
  const std::vector<Index>& candidates(const std::array<double, 3>& p) const {
    return cells_[index(clamp_cell(0, p[0]), clamp_cell(1, p[1]), clamp_cell(2, p[2]))];
  }

 private:
  int clamp_cell(int k, double x) const {
    const double f = std::floor((x - lo_[k]) / cell_[k]);
    if (!(f >= 0)) return 0;
    if (f >= dims_[k]) return dims_[k] - 1;
    return static_cast<int>(f);
  }
  std::size_t index(int i, int j, int l) const {
    return (static_cast<std::size_t>(i) * dims_[1] + j) * dims_[2] + l;
  }
  std::array<double, 3> lo_{}, cell_{};
  std::array<int, 3> dims_{};
  double margin_ = 0;
  std::vector<std::vector<Index>> cells_;
};

// An axis whose projection keeps triangle (a, b, c) non-degenerate; -1 if the triangle is flat.
int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
  const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double n[3] = {std::fabs(uy * vz - uz * vy), std::fabs(uz * vx - ux * vz),
                       std::fabs(ux * vy - uy * vx)};
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int i, int j) { return n[i] > n[j]; });
  for (int axis : order)
    if (orient2d_projected(a, b, c, axis) != Sign::kZero) return axis;
  return -1;
}

ExactFloat projected_area2(const Vec3& a, const Vec3& b, const Vec3& c, int axis) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const ExactFloat au(a[u]), av(a[v]);
  return (ExactFloat(b[u]) - au) * (ExactFloat(c[v]) - av) -
         (ExactFloat(b[v]) - av) * (ExactFloat(c[u]) - au);
}

}  // namespace

QualityStats tet_quality(const TetMesh& mesh) {
  QualityStats q;
  q.dihedral_histogram.assign(180, 0);
  const Index nk = mesh.num_tets();
  q.tets = nk;
  if (nk == 0) return q;
  std::vector<double> angles;
  angles.reserve(static_cast<std::size_t>(nk) * 6);
  std::vector<double> ratios;
  ratios.reserve(nk);
  std::vector<double> tet_min_angles;
  tet_min_angles.reserve(nk);
  constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (Index t = 0; t < nk; ++t) {
    std::array<std::array<double, 3>, 4> p{};
    for (int k = 0; k < 4; ++k) {
      const Index v = mesh.tet[static_cast<std::size_t>(t) * mesh.nodes_per_tet + k];
      p[k] = {mesh.xyz[3 * v], mesh.xyz[3 * v + 1], mesh.xyz[3 * v + 2]};
    }
    // Outward face normals, face f opposite vertex f.
    std::array<std::array<double, 3>, 4> n{};
    for (int f = 0; f < 4; ++f) {
      const int* fv = kOutwardFace[3 - f];  // kOutwardFace[3 - f] is the face opposite vertex f
      const auto& a = p[fv[0]];
      const auto& b = p[fv[1]];
      const auto& c = p[fv[2]];
      const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
      const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
      double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
      const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
      if (len > 0) nx /= len, ny /= len, nz /= len;
      n[f] = {nx, ny, nz};
    }
    double min_edge2 = INFINITY;
    for (const auto& e : kEdge) {
      // The dihedral angle at edge (i, j) is between the faces opposite the two other vertices.
      int other[2], m = 0;
      for (int k = 0; k < 4; ++k)
        if (k != e[0] && k != e[1]) other[m++] = k;
      const auto& n1 = n[other[0]];
      const auto& n2 = n[other[1]];
      double c = -(n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]);
      c = std::max(-1.0, std::min(1.0, c));
      angles.push_back(std::acos(c) * 180.0 / M_PI);
      double l2 = 0;
      for (int k = 0; k < 3; ++k) l2 += (p[e[1]][k] - p[e[0]][k]) * (p[e[1]][k] - p[e[0]][k]);
      min_edge2 = std::min(min_edge2, l2);
    }
    tet_min_angles.push_back(*std::min_element(angles.end() - 6, angles.end()));
    // Circumradius from the three edge vectors at vertex 0.
    std::array<double, 3> a{}, b{}, c{};
    for (int k = 0; k < 3; ++k) {
      a[k] = p[1][k] - p[0][k];
      b[k] = p[2][k] - p[0][k];
      c[k] = p[3][k] - p[0][k];
    }
    auto cross = [](const std::array<double, 3>& x, const std::array<double, 3>& y) {
      return std::array<double, 3>{x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2],
                                   x[0] * y[1] - x[1] * y[0]};
    };
    auto dot = [](const std::array<double, 3>& x, const std::array<double, 3>& y) {
      return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    };
    const auto bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
    const double det = dot(a, bc);
    std::array<double, 3> num{};
    for (int k = 0; k < 3; ++k) num[k] = dot(a, a) * bc[k] + dot(b, b) * ca[k] + dot(c, c) * ab[k];
    const double radius = std::sqrt(dot(num, num)) / (2.0 * std::fabs(det));
    const double ratio = (det != 0 && min_edge2 > 0) ? radius / std::sqrt(min_edge2) : INFINITY;
    ratios.push_back(ratio);
  }
  for (double a : angles) {
    int bin = static_cast<int>(a);
    bin = std::max(0, std::min(179, bin));
    q.dihedral_histogram[bin]++;
  }
  auto quantile = [](std::vector<double>& v, double f) {
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(f * (v.size() - 1)));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  };
  q.min_dihedral_deg = *std::min_element(angles.begin(), angles.end());
  q.max_dihedral_deg = *std::max_element(angles.begin(), angles.end());
  q.p1_dihedral_deg = quantile(angles, 0.01);
  q.median_tet_min_dihedral_deg = quantile(tet_min_angles, 0.5);
  q.median_dihedral_deg = quantile(angles, 0.5);
  q.max_radius_edge_ratio = *std::max_element(ratios.begin(), ratios.end());
  q.median_radius_edge_ratio = quantile(ratios, 0.5);
  return q;
}

MeshCheckReport check_mesh(const SurfaceMesh& surface, const TetMesh& mesh,
                           const MeshCheckOptions& options) {
  MeshCheckReport r;
  Messages msg(options.max_messages);
  const Index np = mesh.num_points();
  const Index nk = mesh.num_tets();
  const Index nsp = surface.num_points();
  const Index nst = surface.num_triangles();
  const int npt = mesh.nodes_per_tet;
  r.points = np;
  r.tets = nk;

  // ---- 1. Indices, finite coordinates, duplicates, usage. --------------------------------------
  if (npt != 4 && npt != 10) {
    msg.add([&] { return std::string("tets must have 4 or 10 nodes"); });
    r.bad_indices = 1;
    r.messages = msg.take();
    return r;
  }
  for (std::size_t i = 0; i < mesh.tet.size(); ++i)
    if (mesh.tet[i] < 0 || mesh.tet[i] >= np) {
      ++r.bad_indices;
      msg.add([&] {
        std::ostringstream s;
        s << "tet " << i / npt << " refers to point " << mesh.tet[i] << ", out of range [0, " << np
          << ")";
        return s.str();
      });
    }
  for (std::size_t i = 0; i < surface.tri.size(); ++i)
    if (surface.tri[i] < 0 || surface.tri[i] >= nsp) {
      ++r.bad_indices;
      msg.add([&] {
        std::ostringstream s;
        s << "input triangle " << i / 3 << " refers to point " << surface.tri[i]
          << ", out of range [0, " << nsp << ")";
        return s.str();
      });
    }
  for (Index i = 0; i < np; ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(mesh.xyz[3 * i + k])) {
        ++r.nonfinite_points;
        msg.add([&] { return "point " + std::to_string(i) + " has a non-finite coordinate"; });
        break;
      }
  for (Index i = 0; i < nsp; ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(surface.xyz[3 * i + k])) {
        ++r.nonfinite_points;
        msg.add([&] { return "input point " + std::to_string(i) + " has a non-finite coordinate"; });
        break;
      }
  if (r.bad_indices || r.nonfinite_points || nk == 0 || nst == 0) {
    if (nk == 0) msg.add([] { return std::string("the mesh has no tets"); });
    if (nst == 0) msg.add([] { return std::string("the input surface has no triangles"); });
    r.messages = msg.take();
    return r;
  }

  // Canonical surface point per coordinate triple (an input may repeat a point).
  std::unordered_map<PointKey, Index, PointKeyHash> surface_index;
  surface_index.reserve(static_cast<std::size_t>(nsp) * 2);
  std::vector<Index> surface_canon(nsp);
  for (Index i = 0; i < nsp; ++i) surface_canon[i] = surface_index.emplace(key_of(surface.point(i)), i).first->second;

  std::vector<Index> as_surface(np, -1);  // tet point -> canonical surface point, or -1
  {
    std::unordered_map<PointKey, Index, PointKeyHash> seen;
    seen.reserve(static_cast<std::size_t>(np) * 2);
    for (Index i = 0; i < np; ++i) {
      const PointKey k = key_of(mesh.point(i));
      auto ins = seen.emplace(k, i);
      if (!ins.second) {
        ++r.duplicate_points;
        msg.add([&] {
          return "points " + std::to_string(ins.first->second) + " and " + std::to_string(i) +
                 " have the same coordinates (the mesh is not conforming there)";
        });
      }
      auto it = surface_index.find(k);
      if (it != surface_index.end()) as_surface[i] = it->second;
    }
  }
  {
    std::vector<char> used(np, 0);
    for (Index v : mesh.tet) used[v] = 1;
    for (Index i = 0; i < np; ++i)
      if (!used[i]) {
        ++r.unreferenced_points;
        msg.add([&] { return "point " + std::to_string(i) + " is used by no tet"; });
      }
  }

  // ---- 2. Orientation. ------------------------------------------------------------------------
  auto corner = [&](Index t, int k) { return mesh.tet[static_cast<std::size_t>(t) * npt + k]; };
  for (Index t = 0; t < nk; ++t) {
    const Sign s = orient3d(mesh.point(corner(t, 0)), mesh.point(corner(t, 1)),
                            mesh.point(corner(t, 2)), mesh.point(corner(t, 3)));
    if (s == Sign::kPositive) continue;
    if (s == Sign::kZero) {
      ++r.flat_tets;
      msg.add([&] { return tet_str(mesh, t) + " is flat (zero volume)"; });
    } else {
      ++r.inverted_tets;
      msg.add([&] { return tet_str(mesh, t) + " is inverted (negative orientation)"; });
    }
  }

  // ---- 3. Face pairing. -----------------------------------------------------------------------
  struct FaceRec {
    std::array<Index, 3> key;  // sorted
    std::int64_t slot;         // tet * 4 + local face
    bool parity;               // orientation relative to the sorted key
  };
  std::vector<FaceRec> faces;
  faces.reserve(static_cast<std::size_t>(nk) * 4);
  for (Index t = 0; t < nk; ++t)
    for (int f = 0; f < 4; ++f) {
      std::array<Index, 3> v = {corner(t, kOutwardFace[f][0]), corner(t, kOutwardFace[f][1]),
                                corner(t, kOutwardFace[f][2])};
      std::array<Index, 3> s = v;
      std::sort(s.begin(), s.end());
      // (v0, v1, v2) is an even permutation of the sorted key iff it is one of its rotations.
      const bool even = (v == std::array<Index, 3>{s[0], s[1], s[2]}) ||
                        (v == std::array<Index, 3>{s[1], s[2], s[0]}) ||
                        (v == std::array<Index, 3>{s[2], s[0], s[1]});
      faces.push_back({s, static_cast<std::int64_t>(t) * 4 + f, even});
    }
  std::sort(faces.begin(), faces.end(), [](const FaceRec& a, const FaceRec& b) {
    return a.key != b.key ? a.key < b.key : a.slot < b.slot;
  });
  std::vector<std::int64_t> boundary_slots;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    const std::size_t cnt = j - i;
    if (cnt == 1) {
      boundary_slots.push_back(faces[i].slot);
    } else if (cnt == 2) {
      ++r.interior_faces;
      if (faces[i].parity == faces[i + 1].parity) {
        ++r.same_orientation_faces;
        msg.add([&] {
          return face_str(faces[i].key[0], faces[i].key[1], faces[i].key[2]) + " of tets " +
                 std::to_string(faces[i].slot / 4) + " and " + std::to_string(faces[i + 1].slot / 4) +
                 " has the same orientation in both (overlapping or duplicated tets)";
        });
      }
    } else {
      ++r.overshared_faces;
      msg.add([&] {
        std::string s = face_str(faces[i].key[0], faces[i].key[1], faces[i].key[2]) + " is shared by " +
                        std::to_string(cnt) + " tets:";
        for (std::size_t k = i; k < j && k < i + 6; ++k) s += ' ' + std::to_string(faces[k].slot / 4);
        return s;
      });
    }
    i = j;
  }
  r.boundary_faces = static_cast<std::int64_t>(boundary_slots.size());

  // ---- 4. The boundary tiles the input surface. ------------------------------------------------
  // Input triangles by canonical vertex triple.
  struct TriRec {
    std::array<Index, 3> key;
    Index tri;
  };
  std::vector<TriRec> tri_by_key(nst);
  for (Index t = 0; t < nst; ++t) {
    std::array<Index, 3> s = {surface_canon[surface.tri[3 * t]], surface_canon[surface.tri[3 * t + 1]],
                              surface_canon[surface.tri[3 * t + 2]]};
    std::sort(s.begin(), s.end());
    tri_by_key[t] = {s, t};
  }
  std::sort(tri_by_key.begin(), tri_by_key.end(), [](const TriRec& a, const TriRec& b) {
    return a.key != b.key ? a.key < b.key : a.tri < b.tri;
  });
  auto find_tri = [&](const std::array<Index, 3>& key) -> Index {
    auto it = std::lower_bound(tri_by_key.begin(), tri_by_key.end(), key,
                               [](const TriRec& a, const std::array<Index, 3>& k) { return a.key < k; });
    return (it != tri_by_key.end() && it->key == key) ? it->tri : -1;
  };
  auto same_cyclic = [](const std::array<Index, 3>& x, const std::array<Index, 3>& y) {
    return (x[0] == y[0] && x[1] == y[1] && x[2] == y[2]) || (x[0] == y[1] && x[1] == y[2] && x[2] == y[0]) ||
           (x[0] == y[2] && x[1] == y[0] && x[2] == y[1]);
  };

  std::vector<int> tri_axis(nst, -2);  // lazily computed projection axis; -1 = degenerate
  auto axis_of = [&](Index t) {
    if (tri_axis[t] == -2)
      tri_axis[t] = projection_axis(surface.point(surface.tri[3 * t]), surface.point(surface.tri[3 * t + 1]),
                                    surface.point(surface.tri[3 * t + 2]));
    return tri_axis[t];
  };
  // Faces assigned to each input triangle: exact copies are counted, others listed.
  std::vector<int> exact_copies(nst, 0);
  std::vector<std::vector<std::array<Index, 3>>> partial(nst);
  std::unique_ptr<TriangleGrid> grid;
  std::unordered_map<std::uint64_t, int> directed_edges;
  directed_edges.reserve(boundary_slots.size() * 4);
  std::vector<char> on_boundary(np, 0);

  for (std::int64_t slot : boundary_slots) {
    const Index t = static_cast<Index>(slot / 4);
    const int f = static_cast<int>(slot % 4);
    const std::array<Index, 3> v = {corner(t, kOutwardFace[f][0]), corner(t, kOutwardFace[f][1]),
                                    corner(t, kOutwardFace[f][2])};
    for (int k = 0; k < 3; ++k) {
      on_boundary[v[k]] = 1;
      const std::uint64_t e = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(v[k])) << 32) |
                              static_cast<std::uint32_t>(v[(k + 1) % 3]);
      directed_edges[e]++;
    }
    // Fast path: the face is an input triangle.
    if (as_surface[v[0]] >= 0 && as_surface[v[1]] >= 0 && as_surface[v[2]] >= 0) {
      const std::array<Index, 3> sv = {as_surface[v[0]], as_surface[v[1]], as_surface[v[2]]};
      std::array<Index, 3> key = sv;
      std::sort(key.begin(), key.end());
      const Index tri = find_tri(key);
      if (tri >= 0) {
        const std::array<Index, 3> tv = {surface_canon[surface.tri[3 * tri]],
                                          surface_canon[surface.tri[3 * tri + 1]],
                                          surface_canon[surface.tri[3 * tri + 2]]};
        if (same_cyclic(sv, tv)) {
          exact_copies[tri]++;
        } else {
          ++r.boundary_faces_inward;
          msg.add([&] {
            return "boundary " + face_str(v[0], v[1], v[2]) + " of tet " + std::to_string(t) +
                   " lies on input triangle " + std::to_string(tri) +
                   " but faces inward (the tets are on the outside of the surface there)";
          });
        }
        continue;
      }
    }
    // General path: find an input triangle that contains the face, exactly.
    if (!grid) grid = std::make_unique<TriangleGrid>(surface);
    const Vec3 p[3] = {mesh.point(v[0]), mesh.point(v[1]), mesh.point(v[2])};
    const std::array<double, 3> centroid = {(p[0].x + p[1].x + p[2].x) / 3, (p[0].y + p[1].y + p[2].y) / 3,
                                            (p[0].z + p[1].z + p[2].z) / 3};
    Index found = -1;
    bool found_inward = false;
    for (Index tri : grid->candidates(centroid)) {
      const Vec3 a = surface.point(surface.tri[3 * tri]);
      const Vec3 b = surface.point(surface.tri[3 * tri + 1]);
      const Vec3 c = surface.point(surface.tri[3 * tri + 2]);
      const int axis = axis_of(tri);
      if (axis < 0) continue;
      bool inside = true;
      for (int k = 0; k < 3 && inside; ++k) inside = orient3d(a, b, c, p[k]) == Sign::kZero;
      if (!inside) continue;
      const Sign ts = orient2d_projected(a, b, c, axis);
      for (int k = 0; k < 3 && inside; ++k)
        inside = orient2d_projected(a, b, p[k], axis) != opposite(ts) &&
                 orient2d_projected(b, c, p[k], axis) != opposite(ts) &&
                 orient2d_projected(c, a, p[k], axis) != opposite(ts);
      if (!inside) continue;
      if (orient2d_projected(p[0], p[1], p[2], axis) == ts) {
        found = tri;
        break;
      }
      found_inward = true;
    }
    if (found >= 0) {
      partial[found].push_back(v);
    } else if (found_inward) {
      ++r.boundary_faces_inward;
      msg.add([&] {
        return "boundary " + face_str(v[0], v[1], v[2]) + " of tet " + std::to_string(t) +
               " lies on the input surface but faces inward";
      });
    } else {
      ++r.boundary_faces_off_surface;
      msg.add([&] {
        return "boundary " + face_str(v[0], v[1], v[2]) + " of tet " + std::to_string(t) +
               " lies on no input triangle (a hole in the mesh, or tets outside the surface)";
      });
    }
  }
  {
    std::vector<std::pair<std::uint64_t, int>> unpaired;
    for (const auto& [e, cnt] : directed_edges) {
      const std::uint64_t rev = (e << 32) | (e >> 32);
      auto it = directed_edges.find(rev);
      const int back = it == directed_edges.end() ? 0 : it->second;
      if (back != cnt) unpaired.emplace_back(e, cnt);
    }
    std::sort(unpaired.begin(), unpaired.end());  // deterministic messages
    r.unpaired_boundary_edges = static_cast<std::int64_t>(unpaired.size());
    for (const auto& [e, cnt] : unpaired)
      msg.add([&, e = e, cnt = cnt] {
        return "boundary edge (" + std::to_string(e >> 32) + ' ' + std::to_string(e & 0xffffffffu) +
               ") is used " + std::to_string(cnt) +
               " times on the boundary but its reverse is not (the boundary is not closed there)";
      });
  }
  for (Index tri = 0; tri < nst; ++tri) {
    if (exact_copies[tri] == 1 && partial[tri].empty()) continue;
    bool ok = false;
    const int axis = axis_of(tri);
    if (axis >= 0 && exact_copies[tri] <= 1) {
      const Vec3 a = surface.point(surface.tri[3 * tri]);
      const Vec3 b = surface.point(surface.tri[3 * tri + 1]);
      const Vec3 c = surface.point(surface.tri[3 * tri + 2]);
      const ExactFloat whole = projected_area2(a, b, c, axis);
      ExactFloat sum;
      if (exact_copies[tri] == 1) sum = whole;
      for (const auto& v : partial[tri])
        sum += projected_area2(mesh.point(v[0]), mesh.point(v[1]), mesh.point(v[2]), axis);
      ok = sum == whole;
      if (!ok)
        msg.add([&] {
          const double frac = sum.to_double() / whole.to_double();
          std::ostringstream s;
          s << "input triangle " << tri << " is covered " << frac
            << " times by the boundary faces on it (must be exactly once)";
          return s.str();
        });
    } else {
      msg.add([&] {
        return "input triangle " + std::to_string(tri) +
               (axis < 0 ? std::string(" is degenerate (zero area)")
                         : " is covered by " + std::to_string(exact_copies[tri]) + " identical faces");
      });
    }
    if (!ok) ++r.miscovered_triangles;
  }

  // ---- 5. Volume. ------------------------------------------------------------------------------
  {
    std::int64_t min_exp = INT64_MAX;
    auto scan = [&](const std::vector<double>& xyz) {
      for (double d : xyz)
        if (d != 0.0) min_exp = std::min(min_exp, ScaledIntegers::lowest_bit_exponent(d));
    };
    scan(mesh.xyz);
    scan(surface.xyz);
    if (min_exp == INT64_MAX) min_exp = 0;
    const ScaledIntegers conv(min_exp);
    auto to_int = [&](const std::vector<double>& xyz) {
      std::vector<mpz_class> out(xyz.size());
      for (std::size_t i = 0; i < xyz.size(); ++i) out[i] = conv.convert(xyz[i]);
      return out;
    };
    const std::vector<mpz_class> ti = to_int(mesh.xyz);
    const std::vector<mpz_class> si = to_int(surface.xyz);
    mpz_class tet_sum = 0, surf_sum = 0;
    for (Index t = 0; t < nk; ++t)
      tet_sum += det3(&ti[3 * corner(t, 0)], &ti[3 * corner(t, 1)], &ti[3 * corner(t, 2)],
                      &ti[3 * corner(t, 3)]);
    const mpz_class* o = &si[0];
    for (Index t = 0; t < nst; ++t)
      surf_sum += det3(o, &si[3 * surface.tri[3 * t]], &si[3 * surface.tri[3 * t + 1]],
                       &si[3 * surface.tri[3 * t + 2]]);
    r.volume_equal = tet_sum == surf_sum;
    auto to_volume = [&](const mpz_class& v) {
      long e = 0;
      const double m = mpz_get_d_2exp(&e, v.get_mpz_t());
      return std::ldexp(m, static_cast<int>(e + 3 * min_exp)) / 6.0;
    };
    r.tet_volume = to_volume(tet_sum);
    r.surface_volume = to_volume(surf_sum);
    if (!r.volume_equal)
      msg.add([&] {
        std::ostringstream s;
        s.precision(17);
        s << "the tets' total volume " << r.tet_volume << " differs from the enclosed volume "
          << r.surface_volume;
        return s.str();
      });
  }

  // ---- 6. Mid-nodes. ----------------------------------------------------------------------------
  if (npt == 10) {
    constexpr int kMidEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
    std::unordered_map<std::uint64_t, Index> mid_of_edge;
    std::unordered_map<Index, std::uint64_t> edge_of_mid;
    for (Index t = 0; t < nk; ++t)
      for (int m = 0; m < 6; ++m) {
        Index a = corner(t, kMidEdge[m][0]), b = corner(t, kMidEdge[m][1]);
        if (a > b) std::swap(a, b);
        const std::uint64_t e = (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
        const Index mid = corner(t, 4 + m);
        auto i1 = mid_of_edge.emplace(e, mid);
        auto i2 = edge_of_mid.emplace(mid, e);
        bool bad = i1.first->second != mid || i2.first->second != e;
        for (int k = 0; k < 4; ++k) bad = bad || corner(t, k) == mid;
        if (bad) {
          ++r.inconsistent_midnodes;
          msg.add([&] {
            return "mid-node " + std::to_string(mid) + " of edge (" + std::to_string(a) + ' ' +
                   std::to_string(b) + ") in tet " + std::to_string(t) +
                   " is not the edge's mid-node in another tet";
          });
        }
      }
  }

  // Steiner points: tet corner points that are not input vertices.
  {
    std::vector<char> is_corner(np, 0);
    for (Index t = 0; t < nk; ++t)
      for (int k = 0; k < 4; ++k) is_corner[corner(t, k)] = 1;
    for (Index i = 0; i < np; ++i)
      if (is_corner[i] && as_surface[i] < 0) {
        ++r.steiner_points;
        if (on_boundary[i]) ++r.boundary_steiner_points;
      }
  }

  r.valid = r.bad_indices == 0 && r.nonfinite_points == 0 && r.duplicate_points == 0 &&
            r.unreferenced_points == 0 && r.inverted_tets == 0 && r.flat_tets == 0 &&
            r.overshared_faces == 0 && r.same_orientation_faces == 0 &&
            r.boundary_faces_off_surface == 0 && r.boundary_faces_inward == 0 &&
            r.unpaired_boundary_edges == 0 && r.miscovered_triangles == 0 && r.volume_equal &&
            r.inconsistent_midnodes == 0;
  if (options.compute_quality) r.quality = tet_quality(mesh);
  r.messages = msg.take();
  return r;
}

SurfaceMesh boundary_surface(const TetMesh& mesh) {
  static const int outward[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::map<std::array<Index, 3>, std::array<Index, 3>> faces;
  for (Index t = 0; t < mesh.num_tets(); ++t) {
    const Index* q = &mesh.tet[static_cast<std::size_t>(mesh.nodes_per_tet) * static_cast<std::size_t>(t)];
    for (const auto& f : outward) {
      std::array<Index, 3> face{q[f[0]], q[f[1]], q[f[2]]}, key = face;
      std::sort(key.begin(), key.end());
      if (!faces.erase(key)) faces.emplace(key, face);
    }
  }
  SurfaceMesh out;
  out.xyz = mesh.xyz;
  out.tri.reserve(3 * faces.size());
  for (const auto& kv : faces) out.tri.insert(out.tri.end(), kv.second.begin(), kv.second.end());
  return out;
}

}  // namespace bsptet
