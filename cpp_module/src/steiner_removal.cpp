#include "bsptet/steiner_removal.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include "bsptet/errors.h"
#include "bsptet/predicates.h"

namespace bsptet {

namespace {

// The working tet complex: tets and boundary faces with vertex -> element lists.
class TetComplex {
 public:
  TetComplex(ImplicitGeometry& geo, const SurfaceMesh& surface, const std::vector<Index>& tri_plane)
      : geo_(geo), surface_(surface), tri_plane_(tri_plane), np_(surface.num_points()) {}

  void grow() {
    const std::size_t nv = static_cast<std::size_t>(geo_.num_vertices());
    if (vt_.size() < nv) vt_.resize(nv), vb_.resize(nv);
  }
  Index add_tet(const std::array<Index, 4>& t) {
    grow();
    const Index id = static_cast<Index>(tets_.size());
    tets_.push_back(t);
    talive_.push_back(1);
    for (Index v : t) vt_[v].push_back(id);
    return id;
  }
  void kill_tet(Index id) {
    talive_[id] = 0;
    for (Index v : tets_[id]) erase(vt_[v], id);
  }
  Index add_face(const std::array<Index, 3>& f, Index label) {
    grow();
    const Index id = static_cast<Index>(faces_.size());
    faces_.push_back(f);
    label_.push_back(label);
    falive_.push_back(1);
    for (Index v : f) vb_[v].push_back(id);
    return id;
  }
  void kill_face(Index id) {
    falive_[id] = 0;
    for (Index v : faces_[id]) erase(vb_[v], id);
  }

  bool used(Index v) const { return v < static_cast<Index>(vt_.size()) && !vt_[v].empty(); }
  /// Input triangles containing the surface faces at v, sorted (empty: v is interior).
  std::vector<Index> labels(Index v) const {
    std::vector<Index> out;
    for (Index f : vb_[v]) out.push_back(label_[f]);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  bool is_corner(Index u, Index t) const {
    return surface_.tri[3 * t] == u || surface_.tri[3 * t + 1] == u || surface_.tri[3 * t + 2] == u;
  }
  /// Neighbours of v: input points first, then by id.
  std::vector<Index> neighbours(Index v) const {
    std::vector<Index> out;
    for (Index t : vt_[v])
      for (Index u : tets_[t])
        if (u != v) out.push_back(u);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;  // ids below np_ (input points) already come first
  }

  /// The support rule (header comment): may Steiner point v move onto vertex u?
  bool may_move_onto(Index v, Index u) const {
    if (v < np_) return false;
    const std::vector<Index> lv = labels(v);
    if (lv.empty()) return true;
    if (u < np_) {
      for (Index t : lv)
        if (!is_corner(u, t)) return false;
      return true;
    }
    const std::vector<Index> lu = labels(u);
    if (lv.size() == 1) return std::binary_search(lu.begin(), lu.end(), lv[0]);
    if (lv.size() == 2) return lu == lv;
    return false;
  }

  bool try_collapse(Index v, Index u) {
    std::vector<std::array<Index, 4>> repl;
    const std::vector<Index> star = vt_[v];
    for (Index id : star) {
      std::array<Index, 4> t = tets_[id];
      if (std::find(t.begin(), t.end(), u) != t.end()) continue;
      for (Index& x : t)
        if (x == v) x = u;
      if (geo_.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive) return false;
      repl.push_back(t);
    }
    // A new tet must not duplicate one u already has (a topological safeguard; geometry rules it out).
    for (const auto& t : repl) {
      std::array<Index, 4> key = t;
      std::sort(key.begin(), key.end());
      for (Index id : vt_[u]) {
        std::array<Index, 4> k2 = tets_[id];
        std::sort(k2.begin(), k2.end());
        if (k2 == key && std::find(star.begin(), star.end(), id) == star.end()) return false;
      }
    }
    for (Index id : star) kill_tet(id);
    for (const auto& t : repl) add_tet(t);
    const std::vector<Index> fstar = vb_[v];
    for (Index id : fstar) {
      std::array<Index, 3> f = faces_[id];
      const Index lab = label_[id];
      kill_face(id);
      if (std::find(f.begin(), f.end(), u) != f.end()) continue;
      for (Index& x : f)
        if (x == v) x = u;
      add_face(f, lab);
    }
    return true;
  }

  /// Replaces v by vertex w in every tet of v if all stay positive.
  bool try_replace(Index v, Index w) {
    std::vector<std::array<Index, 4>> repl;
    for (Index id : vt_[v]) {
      std::array<Index, 4> t = tets_[id];
      for (Index& x : t)
        if (x == v) x = w;
      if (geo_.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive) return false;
      repl.push_back(t);
    }
    const std::vector<Index> star = vt_[v];
    for (Index id : star) kill_tet(id);
    for (const auto& t : repl) add_tet(t);
    const std::vector<Index> fstar = vb_[v];
    for (Index id : fstar) {
      std::array<Index, 3> f = faces_[id];
      const Index lab = label_[id];
      kill_face(id);
      for (Index& x : f)
        if (x == v) x = w;
      add_face(f, lab);
    }
    return true;
  }

  /// Moves surface Steiner point v to a double point just inside (header comment). Returns false
  /// when no candidate passes the exact checks.
  std::string why;  ///< why the last relocate() failed
  bool relocate(Index v) {
    std::map<Index, std::vector<std::array<Index, 3>>> groups;  // input triangle -> faces (v, x, y)
    for (Index id : vb_[v]) {
      std::array<Index, 3> f = faces_[id];
      while (f[0] != v) std::rotate(f.begin(), f.begin() + 1, f.end());
      groups[label_[id]].push_back(f);
    }
    if (groups.empty() || groups.size() > 2) return fail("its surface faces lie in " + std::to_string(groups.size()) + " input triangles");
    std::vector<std::array<Index, 3>> new_faces;
    std::vector<Index> new_labels;
    Vec3 dir{0, 0, 0};
    for (const auto& [t, fs] : groups) {
      const Index plane = tri_plane_[t];
      const int axis = geo_.projection_axis(plane);
      const Sign s0 = geo_.orient2d(fs[0][0], fs[0][1], fs[0][2], axis);
      std::map<Index, Index> next;
      std::map<Index, int> has_prev;
      for (const auto& f : fs) next[f[1]] = f[2], has_prev[f[2]] = 1;
      Index start = fs[0][1];
      if (groups.size() == 2) {
        start = -1;
        for (const auto& kv : next)
          if (!has_prev.count(kv.first)) start = kv.first;
        if (start < 0) return fail("its surface faces on an input edge do not form a path");
      } else {
        start = next.begin()->first;  // deterministic
      }
      std::vector<Index> poly{start};
      for (Index x = start; next.count(x);) {
        x = next[x];
        if (x == start) break;
        poly.push_back(x);
        if (poly.size() > fs.size() + 1) return fail("its surface faces do not form a simple polygon");
      }
      if (poly.size() < 3) return fail("its surface polygon has fewer than 3 vertices");
      // Ear clipping of a simple polygon (possibly with flat vertices): an ear is strictly convex
      // and its closed triangle holds no other polygon vertex.
      while (poly.size() > 3) {
        const std::size_t n = poly.size();
        bool clipped = false;
        for (std::size_t i = 0; i < n && !clipped; ++i) {
          const Index p = poly[(i + n - 1) % n], c = poly[i], q = poly[(i + 1) % n];
          if (geo_.orient2d(p, c, q, axis) != s0) continue;
          bool empty = true;
          for (std::size_t j = 0; j < n && empty; ++j) {
            const Index y = poly[j];
            if (y == p || y == c || y == q) continue;
            if (geo_.orient2d(p, c, y, axis) != opposite(s0) && geo_.orient2d(c, q, y, axis) != opposite(s0) &&
                geo_.orient2d(q, p, y, axis) != opposite(s0))
              empty = false;
          }
          if (!empty) continue;
          new_faces.push_back({p, c, q});
          new_labels.push_back(t);
          poly.erase(poly.begin() + static_cast<std::ptrdiff_t>(i));
          clipped = true;
        }
        if (!clipped) return fail("no ear in its surface polygon");
      }
      if (geo_.orient2d(poly[0], poly[1], poly[2], axis) != s0) return fail("degenerate last ear");
      new_faces.push_back({poly[0], poly[1], poly[2]});
      new_labels.push_back(t);
      // Inward unit normal of input triangle t.
      const Vec3 a = surface_.point(surface_.tri[3 * t]), b = surface_.point(surface_.tri[3 * t + 1]),
                 c = surface_.point(surface_.tri[3 * t + 2]);
      const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
      double nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
      const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
      dir.x -= nx / len, dir.y -= ny / len, dir.z -= nz / len;
    }
    // Candidate points w = v + eps * d, found in doubles, decided exactly below. Every cavity face
    // (v's link faces and the new surface triangles) is a half-space m . (w - a) > 0 (m unit). Faces
    // whose plane passes (nearly) through v constrain the direction d; the others bound eps.
    const Vec3 vr = geo_.rounded(v);
    struct HalfSpace {
      Vec3 m, a;
      double dist;
    };
    std::vector<HalfSpace> hs;
    auto add_half_space = [&](const Vec3& a, const Vec3& b, const Vec3& c, double sign) {
      // (a, b, c, X) positive: ((b - a) x (c - a)) . (X - a) > 0
      const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
      Vec3 m{sign * (uy * wz - uz * wy), sign * (uz * wx - ux * wz), sign * (ux * wy - uy * wx)};
      const double len = std::sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
      if (!(len > 0)) return;
      m = {m.x / len, m.y / len, m.z / len};
      hs.push_back({m, a, m.x * (vr.x - a.x) + m.y * (vr.y - a.y) + m.z * (vr.z - a.z)});
    };
    double lref = 0;
    for (Index id : vt_[v]) {
      const auto& t = tets_[id];
      const int k = static_cast<int>(std::find(t.begin(), t.end(), v) - t.begin());
      std::array<Index, 4> u = t;
      std::swap(u[k], u[3]);  // v last; an odd permutation unless k == 3
      const Vec3 a = geo_.rounded(u[0]), b = geo_.rounded(u[1]), c = geo_.rounded(u[2]);
      add_half_space(a, b, c, k == 3 ? 1.0 : -1.0);
      for (const Vec3& q : {a, b, c})
        lref = std::max(lref, std::sqrt((q.x - vr.x) * (q.x - vr.x) + (q.y - vr.y) * (q.y - vr.y) +
                                        (q.z - vr.z) * (q.z - vr.z)));
    }
    for (const auto& f : new_faces)
      add_half_space(geo_.rounded(f[0]), geo_.rounded(f[2]), geo_.rounded(f[1]), 1.0);
    auto unit = [](Vec3 d) {
      const double len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
      return len > 0 ? Vec3{d.x / len, d.y / len, d.z / len} : Vec3{0, 0, 0};
    };
    // Two tolerances for "through v": rounding noise only (the surface planes and faces through v's
    // edge), then a coarser one for planes that pass within a sliver's width of v.
    const double mag = std::max({std::fabs(vr.x), std::fabs(vr.y), std::fabs(vr.z), lref});
    std::vector<Vec3> candidates;
    for (const double tau : {256 * 2.220446049250313e-16 * mag, 1e-9 * lref}) {
      std::vector<Vec3> near;
      for (const auto& h : hs)
        if (h.dist <= tau) near.push_back(h.m);
      std::vector<Vec3> dirs{unit(dir)};
      Vec3 sum{0, 0, 0};
      for (const Vec3& m : near) {
        dirs.push_back(m);
        sum = {sum.x + m.x, sum.y + m.y, sum.z + m.z};
      }
      dirs.push_back(unit(sum));
      for (std::size_t i = 0; i < near.size(); ++i)
        for (std::size_t j = i + 1; j < near.size(); ++j)
          dirs.push_back(unit({near[i].x + near[j].x, near[i].y + near[j].y, near[i].z + near[j].z}));
      std::vector<std::pair<double, Vec3>> scored;
      for (const Vec3& d : dirs) {
        double score = INFINITY;
        for (const Vec3& m : near) score = std::min(score, m.x * d.x + m.y * d.y + m.z * d.z);
        if (score > 0) scored.push_back({score, d});
      }
      std::stable_sort(scored.begin(), scored.end(), [](const auto& p, const auto& q) { return p.first > q.first; });
      if (scored.size() > 6) scored.resize(6);
      for (const auto& [score, d] : scored) {
        double eps_max = lref;
        for (const auto& h : hs) {
          const double md = h.m.x * d.x + h.m.y * d.y + h.m.z * d.z;
          if (h.dist > tau && md < 0) eps_max = std::min(eps_max, h.dist / -md);
        }
        for (double f : {0.5, 0.2, 0.05, 0.01, 1e-3})
          candidates.push_back({vr.x + f * eps_max * d.x, vr.y + f * eps_max * d.y, vr.z + f * eps_max * d.z});
      }
    }
    // Fallbacks for a v inside a slab thinner than a double's precision: points towards its
    // neighbours off the surface, and towards the centroids of its tets.
    for (Index id : vt_[v]) {
      Vec3 c{0, 0, 0};
      for (Index x : tets_[id]) {
        const Vec3 q = geo_.rounded(x);
        c = {c.x + 0.25 * q.x, c.y + 0.25 * q.y, c.z + 0.25 * q.z};
      }
      for (double f : {0.5, 0.1, 0.01})
        candidates.push_back({vr.x + f * (c.x - vr.x), vr.y + f * (c.y - vr.y), vr.z + f * (c.z - vr.z)});
    }
    for (Index x : neighbours(v)) {
      if (!labels(x).empty()) continue;
      const Vec3 q = geo_.rounded(x);
      for (double f : {0.5, 0.1, 0.01})
        candidates.push_back({vr.x + f * (q.x - vr.x), vr.y + f * (q.y - vr.y), vr.z + f * (q.z - vr.z)});
    }
    if (candidates.empty() || !(lref > 0)) {
      if (std::getenv("BSPTET_DEBUG")) {
        std::fprintf(stderr, "stuck %d (%s) lref %g:\n", v, geo_.is_explicit(v) ? "explicit" : "tpi", lref);
        for (const auto& h : hs)
          std::fprintf(stderr, "  m (%.6f %.6f %.6f) dist %.3g\n", h.m.x, h.m.y, h.m.z, h.dist);
      }
      return fail("no direction into the solid sees all its faces");
    }
    for (std::size_t attempt = 0; attempt < candidates.size(); ++attempt) {
      const Vec3 w = candidates[attempt];
      // Double pre-checks are not exact; everything is decided on the new vertex below.
      const Index wid = geo_.add_explicit_point(w);
      bool ok = true;
      std::vector<std::array<Index, 4>> repl;
      for (Index id : vt_[v]) {
        std::array<Index, 4> t = tets_[id];
        for (Index& x : t)
          if (x == v) x = wid;
        if (geo_.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive) {
          ok = false;
          break;
        }
        repl.push_back(t);
      }
      for (std::size_t i = 0; ok && i < new_faces.size(); ++i) {
        const auto& f = new_faces[i];  // outward: (f0, f2, f1, w) is positive
        const std::array<Index, 4> t{f[0], f[2], f[1], wid};
        if (geo_.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive) ok = false;
        repl.push_back(t);
      }
      if (!ok) {
        if (std::getenv("BSPTET_DEBUG")) {
          int bad_old = 0, bad_new = 0;
          for (Index id : vt_[v]) {
            std::array<Index, 4> t = tets_[id];
            for (Index& x : t) if (x == v) x = wid;
            bad_old += geo_.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive;
          }
          for (const auto& f : new_faces) bad_new += geo_.orient3d(f[0], f[2], f[1], wid) != Sign::kPositive;
          std::fprintf(stderr, "relocate %d attempt %zu: bad old %d/%zu bad new %d/%zu\n", v, attempt, bad_old,
                       vt_[v].size(), bad_new, new_faces.size());
        }
        continue;
      }
      const std::vector<Index> star = vt_[v];
      for (Index id : star) kill_tet(id);
      for (const auto& t : repl) add_tet(t);
      const std::vector<Index> fstar = vb_[v];
      for (Index id : fstar) kill_face(id);
      for (std::size_t i = 0; i < new_faces.size(); ++i) add_face(new_faces[i], new_labels[i]);
      return true;
    }
    return fail("no double-precision point just inside keeps its tets positive");
  }
  bool fail(const std::string& reason) {
    why = reason;
    return false;
  }

  /// Moves interior Steiner point z towards the centroid of its neighbours (exact check); used to
  /// fatten a surface point's neighbourhood before moving it.
  bool smooth_interior(Index z, Index first_steiner) {
    if (z < first_steiner || !labels(z).empty()) return false;
    const Vec3 r = geo_.rounded(z);
    Vec3 c{0, 0, 0};
    const auto nb = neighbours(z);
    for (Index u : nb) {
      const Vec3 p = geo_.rounded(u);
      c = {c.x + p.x / nb.size(), c.y + p.y / nb.size(), c.z + p.z / nb.size()};
    }
    for (double a : {1.0, 0.7, 0.4, 0.2}) {
      const Vec3 p{(1 - a) * r.x + a * c.x, (1 - a) * r.y + a * c.y, (1 - a) * r.z + a * c.z};
      if (try_replace(z, geo_.add_explicit_point(p))) return true;
    }
    return false;
  }

  std::vector<std::array<Index, 4>> alive_tets() const {
    std::vector<std::array<Index, 4>> out;
    for (std::size_t i = 0; i < tets_.size(); ++i)
      if (talive_[i]) out.push_back(tets_[i]);
    return out;
  }
  const std::vector<Index>& star(Index v) const { return vt_[v]; }
  const std::array<Index, 4>& tet(Index id) const { return tets_[id]; }

 private:
  static void erase(std::vector<Index>& list, Index id) {
    auto it = std::find(list.begin(), list.end(), id);
    if (it != list.end()) {
      *it = list.back();
      list.pop_back();
    }
  }
  ImplicitGeometry& geo_;
  const SurfaceMesh& surface_;
  const std::vector<Index>& tri_plane_;
  const Index np_;
  std::vector<std::array<Index, 4>> tets_;
  std::vector<char> talive_;
  std::vector<std::vector<Index>> vt_;
  std::vector<std::array<Index, 3>> faces_;
  std::vector<Index> label_;
  std::vector<char> falive_;
  std::vector<std::vector<Index>> vb_;
};

}  // namespace

std::vector<std::array<Index, 4>> remove_steiner_points(ImplicitGeometry& geo, const SurfaceMesh& surface,
                                                        const std::vector<Index>& tri_plane, const CellTets& cells,
                                                        const SteinerRemovalOptions& options,
                                                        SteinerRemovalStats* stats_out) {
  SteinerRemovalStats st;
  const Index np = surface.num_points();
  TetComplex mesh(geo, surface, tri_plane);
  for (const auto& t : cells.tets) mesh.add_tet(t);
  for (std::size_t i = 0; i < cells.boundary.size(); ++i) mesh.add_face(cells.boundary[i], cells.boundary_triangle[i]);

  auto steiner_vertices = [&]() {
    std::vector<Index> out;
    for (Index v = np; v < geo.num_vertices(); ++v)
      if (mesh.used(v)) out.push_back(v);
    return out;
  };
  auto check_cancel = [&]() {
    if (options.cancelled && options.cancelled())
      throw MeshingError(ErrorCode::kCancelled, "steiner", -1, "cancelled");
  };
  auto progress = [&](double f) {
    if (options.progress) options.progress(f);
  };
  {
    const auto sv = steiner_vertices();
    st.steiner_before = static_cast<std::int64_t>(sv.size());
    for (Index v : sv) st.boundary_steiner_before += !mesh.labels(v).empty();
  }
  auto collapse_passes = [&](double f0, double f1) {
    for (int pass = 0; pass < 50; ++pass) {
      bool changed = false;
      const auto sv = steiner_vertices();
      for (std::size_t i = 0; i < sv.size(); ++i) {
        const Index v = sv[i];
        if ((i & 255) == 0) {
          check_cancel();
          progress(f0 + (f1 - f0) * (pass + static_cast<double>(i) / sv.size()) / (pass + 2));
        }
        if (!mesh.used(v)) continue;
        for (Index u : mesh.neighbours(v)) {
          if (!mesh.may_move_onto(v, u)) continue;
          if (mesh.try_collapse(v, u)) {
            ++st.collapsed;
            changed = true;
            break;
          }
        }
      }
      if (!changed) break;
    }
  };
  collapse_passes(0.0, 0.5);

  // Surface Steiner points that remain: kept only when allowed and exactly doubles; otherwise moved
  // inside.
  // A point that cannot move yet may be able to once its neighbours have moved or collapsed: retry
  // in rounds while anything changes.
  for (int round = 0;; ++round) {
    std::int64_t moved = 0;
    Index stuck = -1;
    std::string why;
    for (Index v : steiner_vertices()) {
      check_cancel();
      const std::vector<Index> lv = mesh.labels(v);
      if (lv.empty()) continue;
      if (options.allow_boundary_steiner) {
        const Index w = geo.add_explicit_point(geo.rounded(v));
        // Kept only where the double is the point itself (a rounded point could leave its triangle
        // for a coplanar neighbour, or the plane).
        bool on = true;
        if (!geo.is_explicit(v))
          for (Index p : geo.tpi_planes(v)) on = on && p >= 0 && geo.side(p, w) == Sign::kZero;
        if (on && mesh.try_replace(v, w)) {
          ++st.rounded;
          ++moved;
          continue;
        }
      }
      bool ok = mesh.relocate(v);
      if (!ok) {
        bool smoothed = false;
        for (Index z : mesh.neighbours(v)) smoothed = mesh.smooth_interior(z, np) || smoothed;
        if (smoothed) ok = mesh.relocate(v);
      }
      if (ok) {
        ++st.relocated;
        ++moved;
      } else if (stuck < 0) {
        stuck = v;
        why = mesh.why;
      }
    }
    if (stuck < 0) break;
    const std::int64_t collapsed_before = st.collapsed;
    collapse_passes(0.5, 0.6);
    if (moved == 0 && st.collapsed == collapsed_before) {
      const Vec3 p = geo.rounded(stuck);
      throw MeshingError(ErrorCode::kInternal, "steiner", stuck,
                         "could not move the surface Steiner point at (" + std::to_string(p.x) + ", " +
                             std::to_string(p.y) + ", " + std::to_string(p.z) + ") on input triangle " +
                             std::to_string(mesh.labels(stuck)[0]) + " inside the solid: " + why);
    }
  }
  collapse_passes(0.5, 0.9);

  // Round the implicit points left.
  for (Index v : steiner_vertices()) {
    if (geo.is_explicit(v)) continue;
    check_cancel();
    const Vec3 r = geo.rounded(v);
    bool done = mesh.try_replace(v, geo.add_explicit_point(r));
    if (done) {
      ++st.rounded;
      continue;
    }
    Vec3 centroid{0, 0, 0};
    const auto nb = mesh.neighbours(v);
    for (Index u : nb) {
      const Vec3 p = geo.rounded(u);
      centroid.x += p.x / nb.size(), centroid.y += p.y / nb.size(), centroid.z += p.z / nb.size();
    }
    for (double a : {0.05, 0.2, 0.4, 0.6, 0.8, 0.95}) {
      const Vec3 p{(1 - a) * r.x + a * centroid.x, (1 - a) * r.y + a * centroid.y, (1 - a) * r.z + a * centroid.z};
      if ((done = mesh.try_replace(v, geo.add_explicit_point(p)))) break;
    }
    if (!done)
      throw MeshingError(ErrorCode::kInternal, "steiner", v,
                         "no double-precision position keeps the tets around the Steiner point at (" +
                             std::to_string(r.x) + ", " + std::to_string(r.y) + ", " + std::to_string(r.z) +
                             ") positive");
    ++st.rounded;
    ++st.rounded_moved;
  }
  for (Index v : steiner_vertices()) st.boundary_steiner_after += !mesh.labels(v).empty();
  progress(1.0);
  if (stats_out) *stats_out = st;
  return mesh.alive_tets();
}

}  // namespace bsptet
