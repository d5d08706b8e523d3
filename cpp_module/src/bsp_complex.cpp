#include "bsptet/bsp_complex.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>

#include "bsptet/errors.h"

namespace bsptet {

BspComplex::BspComplex(ImplicitGeometry& geo, const SurfaceMesh& surface, std::vector<Index> tri_plane)
    : geo_(geo), surface_(surface), tri_plane_(std::move(tri_plane)) {
  make_box();
}

Index BspComplex::new_face(BspFace f) {
  faces_.push_back(std::move(f));
  const Index id = static_cast<Index>(faces_.size() - 1);
  register_edges(id);
  return id;
}

void BspComplex::register_edges(Index f) {
  const auto& v = faces_[f].verts;
  for (std::size_t i = 0; i < v.size(); ++i) edge_faces_[edge_key(v[i], v[(i + 1) % v.size()])].push_back(f);
}

void BspComplex::unregister_edges(Index f) {
  const auto& v = faces_[f].verts;
  for (std::size_t i = 0; i < v.size(); ++i) {
    auto it = edge_faces_.find(edge_key(v[i], v[(i + 1) % v.size()]));
    if (it == edge_faces_.end()) continue;
    auto& list = it->second;
    list.erase(std::remove(list.begin(), list.end(), f), list.end());
    if (list.empty()) edge_faces_.erase(it);
  }
}

std::vector<Vec3> BspComplex::box_corners(const SurfaceMesh& surface) {
  // Strictly larger than the input's bounding box (by a quarter of its largest extent on every
  // side), so no box plane is an input plane and every input point lies strictly inside.
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (Index i = 0; i < surface.num_points(); ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], surface.xyz[3 * i + k]);
      hi[k] = std::max(hi[k], surface.xyz[3 * i + k]);
    }
  double ext = 0;
  for (int k = 0; k < 3; ++k) ext = std::max(ext, hi[k] - lo[k]);
  const double margin = 0.25 * ext;
  std::vector<Vec3> out;
  for (int bits = 0; bits < 8; ++bits) {
    double c[3];
    for (int k = 0; k < 3; ++k) c[k] = (bits >> k & 1) ? hi[k] + margin : lo[k] - margin;
    out.push_back({c[0], c[1], c[2]});
  }
  return out;
}

void BspComplex::make_box() {
  // The geometry's last 8 explicit points (and vertices of the same ids) are box_corners(), in
  // bit order x + 2y + 4z.
  corner0_ = geo_.num_explicit() - 8;
  const Index corner0 = corner0_;
  // Cell 0 is the box.
  cells_.push_back({});
  cells_[0].conflict.resize(surface_.num_triangles());
  for (Index t = 0; t < surface_.num_triangles(); ++t) cells_[0].conflict[t] = t;
  // Faces: for axis k, side s (0 = low, 1 = high); corners in (u, v) bit order (0,0),(1,0),(1,1),(0,1).
  for (int k = 0; k < 3; ++k)
    for (int s = 0; s < 2; ++s) {
      const int u = (k + 1) % 3, v = (k + 2) % 3;
      std::array<Index, 4> q;
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int i = 0; i < 4; ++i) {
        const int bits = (s << k) | (uv[i][0] << u) | (uv[i][1] << v);
        q[i] = corner0 + bits;
      }
      // (u, v, k) is a right-handed cyclic permutation, so this cycle is CCW around +axis k;
      // outward is +k for s = 1 and -k for s = 0.
      if (s == 0) std::reverse(q.begin(), q.end());
      BspFace f;
      f.plane = geo_.add_plane(geo_.explicit_id(q[0]), geo_.explicit_id(q[1]), geo_.explicit_id(q[2]));
      f.verts.assign(q.begin(), q.end());
      f.cell[0] = -1;  // outward normal: the positive side is outside
      f.cell[1] = 0;
      for (Index c : q) geo_.note_on_plane(c, f.plane);
      cells_[0].faces.push_back(new_face(std::move(f)));
    }
  // Box edges: the two box planes through each.
  for (const auto& [key, users] : edge_faces_) {
    if (users.size() != 2) throw MeshingError(ErrorCode::kInternal, "bsp", -1, "box edge not shared by two faces");
    edge_line_[key] = {faces_[users[0]].plane, faces_[users[1]].plane};
  }
}

void BspComplex::classify_triangle(Index t, Index p, int& mn, int& mx) {
  mn = 1;
  mx = -1;
  for (int k = 0; k < 3; ++k) {
    const int s = to_int(geo_.side(p, surface_.tri[3 * t + k]));
    mn = std::min(mn, s);
    mx = std::max(mx, s);
  }
}

Index BspComplex::choose_plane(Index c) {
  // Paper Sec. 4.3 (after Naylor): the candidate plane that splits the fewest faces, sampled so
  // that the cost per split stays bounded: up to 8 candidate planes, each scored on up to 48
  // triangles of the conflict list. Ties: more coplanar triangles, then the lower plane id.
  const auto& list = cells_[c].conflict;
  const std::size_t n = list.size();
  const std::size_t ncand = std::min<std::size_t>(8, n), nsample = std::min<std::size_t>(48, n);
  Index best = -1;
  long best_splits = 0, best_coplanar = 0;
  for (std::size_t i = 0; i < ncand; ++i) {
    const Index p = tri_plane_[list[i * n / ncand]];
    long splits = 0, coplanar = 0;
    for (std::size_t j = 0; j < nsample; ++j) {
      const Index t = list[j * n / nsample];
      if (tri_plane_[t] == p) {
        ++coplanar;
        continue;
      }
      int mn = 0, mx = 0;
      classify_triangle(t, p, mn, mx);
      if (mn < 0 && mx > 0) ++splits;
    }
    if (best < 0 || splits < best_splits || (splits == best_splits && coplanar > best_coplanar) ||
        (splits == best_splits && coplanar == best_coplanar && p < best)) {
      best = p;
      best_splits = splits;
      best_coplanar = coplanar;
    }
  }
  return best;
}

std::array<Index, 2> BspComplex::edge_line(Index u, Index w) const {
  auto it = edge_line_.find(edge_key(u, w));
  if (it == edge_line_.end())
    throw MeshingError(ErrorCode::kInternal, "bsp", u, "edge without its supporting planes");
  return it->second;
}

void BspComplex::split_edge(Index u, Index w, Index x) {
  const std::array<Index, 2> line = edge_line(u, w);
  edge_line_[edge_key(u, x)] = line;
  edge_line_[edge_key(x, w)] = line;
  auto it = edge_faces_.find(edge_key(u, w));
  if (it == edge_faces_.end()) return;
  const std::vector<Index> users = it->second;  // copy: registration changes the map
  for (Index g : users) {
    unregister_edges(g);
    auto& v = faces_[g].verts;
    const std::size_t n = v.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Index a = v[i], b = v[(i + 1) % n];
      if ((a == u && b == w) || (a == w && b == u)) {
        v.insert(v.begin() + static_cast<std::ptrdiff_t>(i + 1), x);
        break;
      }
    }
    register_edges(g);
  }
}

void BspComplex::cut_crossing_edges(Index f, Index q, std::map<Index, int>& sign) {
  for (std::size_t i = 0; i < faces_[f].verts.size(); ++i) {
    const auto& v = faces_[f].verts;
    const Index a = v[i], b = v[(i + 1) % v.size()];
    if (sign[a] * sign[b] < 0) {
      const std::array<Index, 2> line = edge_line(a, b);
      const Index x = geo_.add_tpi_vertex(line[0], line[1], q);
      ++stats_.bsp_points;
      sign[x] = 0;
      split_edge(a, b, x);  // for every face using the edge: conformity
    }
  }
}

std::array<Index, 2> BspComplex::split_face(Index f, Index q, std::map<Index, int>& sign) {
  // The face is convex and q crosses its interior: exactly two zero vertices bound the runs of
  // positive and negative vertices. Returns {positive half, negative half}; f dies.
  const std::vector<Index> v = faces_[f].verts;
  const std::size_t n = v.size();
  std::size_t start = n;
  for (std::size_t i = 0; i < n; ++i)
    if (sign[v[i]] == 0 && sign[v[(i + 1) % n]] > 0) start = i;
  if (start == n) throw MeshingError(ErrorCode::kInternal, "bsp", f, "face split without a zero vertex");
  BspFace h[2];
  for (auto& hf : h) {
    hf.plane = faces_[f].plane;
    hf.cell[0] = faces_[f].cell[0];
    hf.cell[1] = faces_[f].cell[1];
  }
  std::size_t i = start;
  h[0].verts.push_back(v[i]);
  i = (i + 1) % n;
  while (sign[v[i]] > 0) {
    h[0].verts.push_back(v[i]);
    i = (i + 1) % n;
  }
  if (sign[v[i]] != 0) throw MeshingError(ErrorCode::kInternal, "bsp", f, "face split: sign run broken");
  h[0].verts.push_back(v[i]);
  h[1].verts.push_back(v[i]);
  i = (i + 1) % n;
  while (i != start) {
    if (sign[v[i]] > 0) throw MeshingError(ErrorCode::kInternal, "bsp", f, "face not convex");
    h[1].verts.push_back(v[i]);
    i = (i + 1) % n;
  }
  h[1].verts.push_back(v[start]);
  edge_line_[edge_key(h[0].verts.front(), h[0].verts.back())] = {faces_[f].plane, q};
  for (Index t : faces_[f].coplanar) {
    int mn = 0, mx = 0;
    classify_triangle(t, q, mn, mx);
    if (mx > 0) h[0].coplanar.push_back(t);
    if (mn < 0) h[1].coplanar.push_back(t);
  }
  unregister_edges(f);
  faces_[f].alive = false;
  const Index i0 = new_face(std::move(h[0]));
  const Index i1 = new_face(std::move(h[1]));
  return {i0, i1};
}

bool BspComplex::split_cell(Index c, Index p) {
  // 1. Classify the cell's vertices.
  std::map<Index, int> sign;
  for (Index f : cells_[c].faces)
    for (Index v : faces_[f].verts)
      if (!sign.count(v)) sign[v] = to_int(geo_.side(p, v));
  bool pos = false, neg = false;
  for (const auto& [v, s] : sign) {
    pos = pos || s > 0;
    neg = neg || s < 0;
  }
  if (!pos || !neg) return false;

  // 2. Cut the crossing edges (for every face that uses them: conformity).
  for (std::size_t fi = 0; fi < cells_[c].faces.size(); ++fi) {
    const Index f = cells_[c].faces[fi];
    cut_crossing_edges(f, p, sign);
  }

  // 3. Split the crossing faces, for both of their cells.
  const Index cneg = static_cast<Index>(cells_.size());
  cells_.push_back({});
  std::vector<Index> pos_faces, neg_faces;
  const std::vector<Index> old_faces = cells_[c].faces;
  for (Index f : old_faces) {
    bool fp = false, fn = false;
    for (Index v : faces_[f].verts) {
      fp = fp || sign[v] > 0;
      fn = fn || sign[v] < 0;
    }
    if (fp && fn) {
      const auto [ip, in] = split_face(f, p, sign);
      // The neighbour across f gets both halves.
      for (int side = 0; side < 2; ++side) {
        const Index other = faces_[ip].cell[side];
        if (other < 0 || other == c) continue;
        auto& fl = cells_[other].faces;
        auto it = std::find(fl.begin(), fl.end(), f);
        if (it == fl.end()) throw MeshingError(ErrorCode::kInternal, "bsp", f, "face missing from its cell");
        *it = ip;
        fl.push_back(in);
      }
      pos_faces.push_back(ip);
      neg_faces.push_back(in);
    } else if (fp) {
      pos_faces.push_back(f);
    } else if (fn) {
      neg_faces.push_back(f);
    } else {
      throw MeshingError(ErrorCode::kInternal, "bsp", f, "a cell face lies on the splitting plane");
    }
  }

  // 4. The new face on p: chain the zero edges of the positive half, each traversed as the
  // outward cycle of its face (as stored when the cell is on the face's negative side).
  std::unordered_map<Index, Index> next;
  for (Index f : pos_faces) {
    std::vector<Index> v = faces_[f].verts;
    if (faces_[f].cell[1] != c) std::reverse(v.begin(), v.end());
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Index a = v[i], b = v[(i + 1) % v.size()];
      if (sign[a] == 0 && sign[b] == 0) next[a] = b;
    }
  }
  BspFace cut;
  cut.plane = p;
  cut.cell[0] = c;
  cut.cell[1] = cneg;
  {
    Index start = next.begin()->first;
    for (const auto& kv : next) start = std::min(start, kv.first);  // deterministic start
    Index v = start;
    do {
      cut.verts.push_back(v);
      auto it = next.find(v);
      if (it == next.end() || cut.verts.size() > next.size())
        throw MeshingError(ErrorCode::kInternal, "bsp", c, "the cut polygon is not a cycle");
      v = it->second;
    } while (v != start);
    if (cut.verts.size() != next.size())
      throw MeshingError(ErrorCode::kInternal, "bsp", c, "the cut polygon has several cycles");
  }
  for (Index v : cut.verts) geo_.note_on_plane(v, p);

  // 5. Distribute the conflict list.
  std::vector<Index> list_pos, list_neg;
  for (Index t : cells_[c].conflict) {
    if (tri_plane_[t] == p) {
      cut.coplanar.push_back(t);
      continue;
    }
    int mn = 0, mx = 0;
    classify_triangle(t, p, mn, mx);
    if (mx > 0) list_pos.push_back(t);
    if (mn < 0) list_neg.push_back(t);
  }
  const Index cut_id = new_face(std::move(cut));

  // 6. The two cells.
  for (Index f : neg_faces)
    for (int side = 0; side < 2; ++side)
      if (faces_[f].cell[side] == c) faces_[f].cell[side] = cneg;
  pos_faces.push_back(cut_id);
  neg_faces.push_back(cut_id);
  cells_[c].faces = std::move(pos_faces);
  cells_[c].conflict = std::move(list_pos);
  cells_[cneg].faces = std::move(neg_faces);
  cells_[cneg].conflict = std::move(list_neg);
  ++stats_.splits;
  return true;
}

void BspComplex::build(const std::function<bool()>& cancelled, const std::function<void(double)>& progress) {
  std::vector<Index> work = {0};
  const double total = std::max<double>(1.0, static_cast<double>(surface_.num_triangles()));
  std::int64_t done_triangles = 0;
  while (!work.empty()) {
    if (cancelled && cancelled())
      throw MeshingError(ErrorCode::kCancelled, "bsp", -1, "cancelled");
    const Index c = work.back();
    if (cells_[c].conflict.empty()) {
      work.pop_back();
      ++stats_.leaves;
      continue;
    }
    const Index p = choose_plane(c);
    if (!split_cell(c, p)) {
      auto& list = cells_[c].conflict;
      const std::size_t before = list.size();
      list.erase(std::remove_if(list.begin(), list.end(), [&](Index t) { return tri_plane_[t] == p; }),
                 list.end());
      done_triangles += static_cast<std::int64_t>(before - list.size());
      continue;
    }
    work.push_back(static_cast<Index>(cells_.size() - 1));
    if (debug_checks_) check_consistency();
    if (progress && (stats_.splits & 255) == 0) progress(std::min(0.99, done_triangles / total));
  }
}

void BspComplex::identify_input_vertices(Index first) {
  std::map<std::array<double, 3>, Index> input_at;
  for (Index i = 0; i < surface_.num_points(); ++i) {
    const Vec3 p = surface_.point(i);
    input_at.emplace(std::array<double, 3>{p.x + 0.0, p.y + 0.0, p.z + 0.0}, i);
  }
  std::unordered_map<Index, Index> replace;
  for (Index v = std::max(first, corner0_ + 8); v < geo_.num_vertices(); ++v) {
    if (geo_.is_explicit(v)) continue;
    const Vec3 r = geo_.rounded(v);
    auto it = input_at.find({r.x + 0.0, r.y + 0.0, r.z + 0.0});
    if (it == input_at.end()) continue;
    const auto& pl = geo_.tpi_planes(v);
    bool same = true;
    for (Index q : pl) same = same && geo_.side(q, it->second) == Sign::kZero;
    if (same) replace[v] = it->second;
  }
  if (replace.empty()) return;
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    if (!faces_[f].alive) continue;
    bool touched = false;
    for (Index v : faces_[f].verts) touched = touched || replace.count(v);
    if (!touched) continue;
    unregister_edges(static_cast<Index>(f));
    for (Index& v : faces_[f].verts) {
      auto it = replace.find(v);
      if (it != replace.end()) v = it->second;
    }
    register_edges(static_cast<Index>(f));
  }
  // Edge lines move to the new keys; planes known to contain the vertex carry over.
  std::unordered_map<std::uint64_t, std::array<Index, 2>> moved;
  for (const auto& [key, line] : edge_line_) {
    Index u = static_cast<Index>(key >> 32), w = static_cast<Index>(key & 0xffffffffu);
    auto iu = replace.find(u), iw = replace.find(w);
    if (iu != replace.end()) u = iu->second;
    if (iw != replace.end()) w = iw->second;
    moved[edge_key(u, w)] = line;
  }
  edge_line_ = std::move(moved);
  for (const auto& [from, to] : replace)
    for (Index q : geo_.tpi_planes(from)) geo_.note_on_plane(to, q);
}

bool BspComplex::face_overlaps_triangle(Index f, Index t, int axis, int fo) {
  // Separating-axis test in the plane: convex polygons have disjoint interiors iff an edge line of
  // one leaves the other on its closed outer side.
  const Index tv[3] = {triangle_vertex(t, 0), triangle_vertex(t, 1), triangle_vertex(t, 2)};
  const int to = to_int(geo_.orient2d(tv[0], tv[1], tv[2], axis));
  const auto& fv = faces_[f].verts;
  for (std::size_t i = 0; i < fv.size(); ++i) {
    bool out = true;
    for (Index y : tv)
      if (fo * to_int(geo_.orient2d(fv[i], fv[(i + 1) % fv.size()], y, axis)) > 0) {
        out = false;
        break;
      }
    if (out) return false;
  }
  for (int k = 0; k < 3; ++k) {
    bool out = true;
    for (Index y : fv)
      if (to * to_int(geo_.orient2d(tv[k], tv[(k + 1) % 3], y, axis)) > 0) {
        out = false;
        break;
      }
    if (out) return false;
  }
  return true;
}

Index BspComplex::edge_plane(Index a, Index b, Index face_plane) {
  // A plane through input edge (a, b) and an explicit point off the face plane: a box corner.
  const std::uint64_t key = edge_key(a, b) ^ (static_cast<std::uint64_t>(face_plane) * 0x9E3779B97F4A7C15ull);
  auto it = edge_planes_.find(key);
  if (it != edge_planes_.end()) return it->second;
  for (Index c = corner0_; c < corner0_ + 8; ++c)
    if (geo_.side(face_plane, c) != Sign::kZero) {
      const Index q = geo_.add_plane(geo_.explicit_id(a), geo_.explicit_id(b), geo_.explicit_id(c));
      geo_.note_on_plane(a, q);
      geo_.note_on_plane(b, q);
      edge_planes_.emplace(key, q);
      return q;
    }
  throw MeshingError(ErrorCode::kInternal, "bsp", a, "no box corner off a face plane");
}

void BspComplex::refine_covered_faces() {
  std::vector<Index> work;
  for (std::size_t f = 0; f < faces_.size(); ++f)
    if (faces_[f].alive && !faces_[f].coplanar.empty()) work.push_back(static_cast<Index>(f));
  std::reverse(work.begin(), work.end());
  while (!work.empty()) {
    const Index f = work.back();
    work.pop_back();
    Sign ns = Sign::kZero;
    const int axis = geo_.projection_axis(faces_[f].plane, &ns);
    const int fo = to_int(ns);
    Index cover = -1;
    for (Index t : faces_[f].coplanar)
      if (face_overlaps_triangle(f, t, axis, fo)) {
        cover = t;
        break;
      }
    if (cover < 0) {
      faces_[f].coplanar.clear();
      continue;
    }
    // Contained in the covering triangle? Otherwise split along an edge of it that crosses f.
    const Index tv[3] = {triangle_vertex(cover, 0), triangle_vertex(cover, 1), triangle_vertex(cover, 2)};
    const int to = to_int(geo_.orient2d(tv[0], tv[1], tv[2], axis));
    int cut_edge = -1;
    for (int k = 0; k < 3 && cut_edge < 0; ++k) {
      bool in = false, out = false;
      for (Index y : faces_[f].verts) {
        const int s = to * to_int(geo_.orient2d(tv[k], tv[(k + 1) % 3], y, axis));
        in = in || s > 0;
        out = out || s < 0;
      }
      if (in && out) cut_edge = k;
    }
    if (cut_edge < 0) {
      faces_[f].coplanar = {cover};
      continue;
    }
    const Index q = edge_plane(tv[cut_edge], tv[(cut_edge + 1) % 3], faces_[f].plane);
    std::map<Index, int> sign;
    for (Index v : faces_[f].verts) sign[v] = to_int(geo_.side(q, v));
    cut_crossing_edges(f, q, sign);
    const auto [i0, i1] = split_face(f, q, sign);
    for (int side = 0; side < 2; ++side) {
      const Index c = faces_[i0].cell[side];
      if (c < 0) continue;
      auto& fl = cells_[c].faces;
      auto it = std::find(fl.begin(), fl.end(), f);
      if (it == fl.end()) throw MeshingError(ErrorCode::kInternal, "bsp", f, "face missing from its cell");
      *it = i0;
      fl.push_back(i1);
    }
    work.push_back(i1);
    work.push_back(i0);
    if (debug_checks_) check_consistency();
  }
}

void BspComplex::check_consistency() const {
  for (std::size_t c = 0; c < cells_.size(); ++c) {
    for (Index f : cells_[c].faces) {
      if (!faces_[f].alive || (faces_[f].cell[0] != static_cast<Index>(c) && faces_[f].cell[1] != static_cast<Index>(c)))
        throw MeshingError(ErrorCode::kInternal, "bsp", static_cast<std::int64_t>(c),
                           "cell " + std::to_string(c) + " lists face " + std::to_string(f) + " which does not list it");
    }
    // Closed: every edge of the cell's faces is used exactly twice, in opposite directions when
    // each face is oriented outward.
    std::map<std::pair<Index, Index>, int> directed;
    for (Index f : cells_[c].faces) {
      std::vector<Index> v = faces_[f].verts;
      if (faces_[f].cell[1] != static_cast<Index>(c)) std::reverse(v.begin(), v.end());
      for (std::size_t i = 0; i < v.size(); ++i) directed[{v[i], v[(i + 1) % v.size()]}]++;
    }
    for (const auto& [e, n] : directed) {
      auto it = directed.find({e.second, e.first});
      if (n != 1 || it == directed.end() || it->second != 1)
        throw MeshingError(ErrorCode::kInternal, "bsp", static_cast<std::int64_t>(c),
                           "cell " + std::to_string(c) + " is not closed at edge (" + std::to_string(e.first) +
                               " " + std::to_string(e.second) + ")");
    }
  }
}

}  // namespace bsptet
