// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/bsp_complex.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <unordered_set>

#include "bsptet/numerics/errors.h"

namespace bsptet {

BspComplex::BspComplex(ImplicitGeometry& geo, const SurfaceMesh& surface, std::vector<Index> tri_plane,
                       BspSeed seed, std::int64_t max_seed_conflicts)
    : geo_(geo), surface_(surface), tri_plane_(std::move(tri_plane)) {
  tri_box_.resize(static_cast<std::size_t>(surface_.num_triangles()));
  for (Index t = 0; t < surface_.num_triangles(); ++t) {
    const Vec3 a = surface_.point(triangle_vertex(t, 0)), b = surface_.point(triangle_vertex(t, 1)),
               c = surface_.point(triangle_vertex(t, 2));
    tri_box_[t] = {Interval(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x})),
                   Interval(std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y})),
                   Interval(std::min({a.z, b.z, c.z}), std::max({a.z, b.z, c.z}))};
  }
  if (seed == BspSeed::kDelaunay)
    seed_delaunay(max_seed_conflicts);
  else
    make_box();
}

FaceBox FaceBox::enclosing(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  FaceBox b;
  for (int k = 0; k < 3; ++k) {
    // The cast rounds to nearest; one step outward where it went inward. Comparisons of a float
    // with a double are exact, and the steps saturate at +-FLT_MAX / +-infinity outward.
    float l = static_cast<float>(lo[k]), h = static_cast<float>(hi[k]);
    if (static_cast<double>(l) > lo[k]) l = std::nextafter(l, -std::numeric_limits<float>::infinity());
    if (static_cast<double>(h) < hi[k]) h = std::nextafter(h, std::numeric_limits<float>::infinity());
    if (!std::isfinite(l) || !std::isfinite(h)) return FaceBox{};  // beyond floats: no box
    b.lo[k] = l;
    b.hi[k] = h;
  }
  return b;
}

Index BspComplex::new_face(BspFace f) {
  FaceBox box;  // not ok unless every vertex has a box
  bool ok = !f.verts.empty();
  std::array<double, 3> lo{{INFINITY, INFINITY, INFINITY}}, hi{{-INFINITY, -INFINITY, -INFINITY}};
  for (Index v : f.verts) {
    const std::array<Interval, 3>* b = geo_.vertex_box(v);
    if (!b) {
      ok = false;
      break;
    }
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], (*b)[k].lo());
      hi[k] = std::max(hi[k], (*b)[k].hi());
    }
  }
  if (ok) box = FaceBox::enclosing(lo, hi);
  faces_.push_back(std::move(f));
  face_boxes_.push_back(box);
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
    const std::uint64_t key = edge_key(v[i], v[(i + 1) % v.size()]);
    EdgeFaceList* list = edge_faces_.find(key);
    if (!list) continue;
    list->remove(f);
    if (list->empty()) edge_faces_.erase(key);
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
      const Index id = new_face(std::move(f));
      cells_[0].faces.push_back(id);
      cells_[0].boxes.push_back(face_box(id));
    }
  // Box edges: the two box planes through each.
  edge_faces_.for_each([&](std::uint64_t key, const EdgeFaceList& users) {
    if (users.size() != 2) throw MeshingError(ErrorCode::kInternal, "bsp", -1, "box edge not shared by two faces");
    edge_line_[key] = {faces_[users[0]].plane, faces_[users[1]].plane};
  });
}

void BspComplex::classify_triangle(Index t, Index p, int& mn, int& mx) {
  // The triangle's box first (its corners are doubles: the box is exact), then each vertex.
  const Sign whole = geo_.side_of_box(p, tri_box_[t]);
  if (whole != Sign::kZero) {
    mn = mx = to_int(whole);
    return;
  }
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
    const Index p = tri_plane_[list[(i * n / ncand + candidate_shift_) % n]];
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
  const std::array<Index, 2>* line = edge_line_.find(edge_key(u, w));
  if (!line) throw MeshingError(ErrorCode::kInternal, "bsp", u, "edge without its supporting planes");
  return *line;
}

void BspComplex::split_edge(Index u, Index w, Index x) {
  const std::array<Index, 2> line = edge_line(u, w);
  edge_line_[edge_key(u, x)] = line;
  edge_line_[edge_key(x, w)] = line;
  const EdgeFaceList* list = edge_faces_.find(edge_key(u, w));
  if (!list) return;
  const std::vector<Index> users = list->to_vector();  // copy: registration changes the map
  for (Index g : users) {
    if (face_untouched(g) >= 0)
      throw MeshingError(ErrorCode::kInternal, "bsp", g, "a split reached an edge of an untouched seed tet");
    geo_.note_on_plane(x, faces_[g].plane);  // x is on the edge, so on every face using it
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

void BspComplex::cut_crossing_edges(Index f, Index q, VertexSigns& sign) {
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

std::array<Index, 2> BspComplex::split_face(Index f, Index q, VertexSigns& sign) {
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
  if (face_untouched(f) >= 0)
    throw MeshingError(ErrorCode::kInternal, "bsp", f, "a split reached a face of an untouched seed tet");
  unregister_edges(f);
  faces_[f].alive = false;
  const Index i0 = new_face(std::move(h[0]));
  const Index i1 = new_face(std::move(h[1]));
  return {i0, i1};
}

Index BspComplex::split_cell(Index c, Index p) {
  // 1. Classify the cell's vertices. A face whose box is strictly on one side of p is not looked
  // at vertex by vertex (on a long chain of peeling splits most faces are far from the plane):
  // face_side is +1 / -1 for those, 0 for the faces whose vertices were decided.
  VertexSigns& sign = signs_;
  sign.reset();
  bool pos = false, neg = false;
  {
    BspCell& cell = cells_[c];
    if (cell.boxes.size() != cell.faces.size()) {
      cell.boxes.clear();
      for (Index f : cell.faces) cell.boxes.push_back(face_box(f));
    }
  }
  const std::vector<Index>& faces = cells_[c].faces;
  const std::vector<FaceBox>& boxes = cells_[c].boxes;
  std::vector<signed char>& face_side = face_side_;
  face_side.assign(faces.size(), 0);
  for (std::size_t fi = 0; fi < faces.size(); ++fi) {
    if (boxes[fi].ok()) {
      const Sign bs = geo_.side_of_box(p, boxes[fi].intervals());
      if (bs != Sign::kZero) {
        face_side[fi] = bs == Sign::kPositive ? 1 : -1;
        pos = pos || bs == Sign::kPositive;
        neg = neg || bs == Sign::kNegative;
        continue;
      }
    }
    for (Index v : faces_[faces[fi]].verts)
      if (!sign.count(v)) {
        const int s = to_int(geo_.side(p, v));
        sign[v] = s;
        pos = pos || s > 0;
        neg = neg || s < 0;
      }
  }
  if (!pos || !neg) return -1;

  // 2. Cut the crossing edges (for every face that uses them: conformity).
  for (std::size_t fi = 0; fi < faces.size(); ++fi)
    if (face_side[fi] == 0) cut_crossing_edges(faces[fi], p, sign);

  // 3. Split the crossing faces, for both of their cells.
  const Index cneg = static_cast<Index>(cells_.size());
  cells_.push_back({});
  std::vector<Index> pos_faces, neg_faces;
  std::vector<FaceBox> pos_boxes, neg_boxes;
  std::vector<char> decided_pos;  // per pos_faces entry: were its vertices decided?
  const std::vector<Index> old_faces = std::move(cells_[c].faces);
  const std::vector<FaceBox> old_boxes = std::move(cells_[c].boxes);
  cells_[c].faces.clear();
  cells_[c].boxes.clear();
  for (std::size_t fi = 0; fi < old_faces.size(); ++fi) {
    const Index f = old_faces[fi];
    if (face_side[fi] != 0) {
      if (face_side[fi] > 0) {
        pos_faces.push_back(f);
        pos_boxes.push_back(old_boxes[fi]);
        decided_pos.push_back(0);
      } else {
        neg_faces.push_back(f);
        neg_boxes.push_back(old_boxes[fi]);
      }
      continue;
    }
    bool fp = false, fn = false;
    for (Index v : faces_[f].verts) {
      fp = fp || sign[v] > 0;
      fn = fn || sign[v] < 0;
    }
    if (fp && fn) {
      const auto [ip, in] = split_face(f, p, sign);
      substitute_face(f, {ip, in}, c);  // the neighbour across f gets both halves
      pos_faces.push_back(ip);
      pos_boxes.push_back(face_box(ip));
      decided_pos.push_back(1);
      neg_faces.push_back(in);
      neg_boxes.push_back(face_box(in));
    } else if (fp) {
      pos_faces.push_back(f);
      pos_boxes.push_back(old_boxes[fi]);
      decided_pos.push_back(1);
    } else if (fn) {
      neg_faces.push_back(f);
      neg_boxes.push_back(old_boxes[fi]);
    } else {
      throw MeshingError(ErrorCode::kInternal, "bsp", f, "a cell face lies on the splitting plane");
    }
  }

  // 4. The new face on p: chain the zero edges of the positive half, each traversed as the
  // outward cycle of its face (as stored when the cell is on the face's negative side).
  // (A face strictly on the positive side has no vertex on p.)
  std::unordered_map<Index, Index> next;
  for (std::size_t pi = 0; pi < pos_faces.size(); ++pi) {
    if (!decided_pos[pi]) continue;
    const Index f = pos_faces[pi];
    std::vector<Index> v = faces_[f].verts;
    if (faces_[f].cell[1] != c) std::reverse(v.begin(), v.end());
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Index a = v[i], b = v[(i + 1) % v.size()];
      if (sign[a] == 0 && sign[b] == 0) next[a] = b;
    }
  }
  // The side with more faces keeps the id c (its faces need no relabelling).
  const bool neg_keeps = neg_faces.size() > pos_faces.size();
  const Index pid = neg_keeps ? cneg : c, nid = neg_keeps ? c : cneg;
  BspFace cut;
  cut.plane = p;
  cut.cell[0] = pid;
  cut.cell[1] = nid;
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
  for (Index f : neg_keeps ? pos_faces : neg_faces)
    for (int side = 0; side < 2; ++side)
      if (faces_[f].cell[side] == c) faces_[f].cell[side] = cneg;
  pos_faces.push_back(cut_id);
  neg_faces.push_back(cut_id);
  pos_boxes.push_back(face_box(cut_id));
  neg_boxes.push_back(face_box(cut_id));
  cells_[pid].faces = std::move(pos_faces);
  cells_[pid].boxes = std::move(pos_boxes);
  cells_[pid].conflict = std::move(list_pos);
  cells_[nid].faces = std::move(neg_faces);
  cells_[nid].boxes = std::move(neg_boxes);
  cells_[nid].conflict = std::move(list_neg);
  ++stats_.splits;
  return nid;
}

void BspComplex::require_split_data(const char* what) const {
  if (split_data_released_)
    throw MeshingError(ErrorCode::kInternal, "bsp", -1,
                       std::string(what) + " after release_split_data (a bug in the caller)");
}

void BspComplex::release_split_data() {
  split_data_released_ = true;
  std::vector<FaceBox>().swap(face_boxes_);
  for (BspCell& c : cells_) {
    std::vector<FaceBox>().swap(c.boxes);
    std::vector<Index>().swap(c.conflict);
  }
  edge_faces_.release();
  edge_line_.release();
  decltype(edge_planes_)().swap(edge_planes_);
  std::vector<std::array<Interval, 3>>().swap(tri_box_);
  std::vector<signed char>().swap(face_side_);
}

void BspComplex::build(const std::function<bool()>& cancelled, const std::function<void(double)>& progress) {
  require_split_data("build");
  std::vector<Index> work;  // every starting cell, the lowest id on top
  for (std::size_t c = cells_.size(); c-- > 0;) work.push_back(static_cast<Index>(c));
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
    const Index negative = split_cell(c, p);
    if (negative < 0) {
      auto& list = cells_[c].conflict;
      const std::size_t before = list.size();
      list.erase(std::remove_if(list.begin(), list.end(), [&](Index t) { return tri_plane_[t] == p; }),
                 list.end());
      done_triangles += static_cast<std::int64_t>(before - list.size());
      continue;
    }
    // The negative side next, then the positive one (the order before the ids were chosen by size).
    work.back() = negative == c ? static_cast<Index>(cells_.size() - 1) : c;
    work.push_back(negative);
    if (debug_checks_) check_consistency();
    if (progress && (stats_.splits & 255) == 0) progress(std::min(0.99, done_triangles / total));
  }
}

void BspComplex::identify_input_vertices(Index first) {
  require_split_data("identify_input_vertices");
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
  EdgeMap<std::array<Index, 2>> moved;
  moved.reserve(edge_line_.size());
  edge_line_.for_each([&](std::uint64_t key, const std::array<Index, 2>& line) {
    Index u = static_cast<Index>(key >> 32), w = static_cast<Index>(key & 0xffffffffu);
    auto iu = replace.find(u), iw = replace.find(w);
    if (iu != replace.end()) u = iu->second;
    if (iw != replace.end()) w = iw->second;
    moved[edge_key(u, w)] = line;
  });
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

bool BspComplex::segment_crosses_face(Index f, Index a, Index b, int axis, int fo) {
  // Separating lines in the plane: the segment's own line (the face on one closed side), or an
  // edge line of the face (both ends on its closed outer side). Neither exists iff the closed
  // segment meets the open face.
  const auto& fv = faces_[f].verts;
  bool pos = false, neg = false;
  for (Index y : fv) {
    const Sign s = geo_.orient2d(a, b, y, axis);
    pos = pos || s == Sign::kPositive;
    neg = neg || s == Sign::kNegative;
  }
  if (!pos || !neg) return false;
  for (std::size_t i = 0; i < fv.size(); ++i) {
    const Index u = fv[i], w = fv[(i + 1) % fv.size()];
    if (fo * to_int(geo_.orient2d(u, w, a, axis)) <= 0 && fo * to_int(geo_.orient2d(u, w, b, axis)) <= 0)
      return false;
  }
  return true;
}

void BspComplex::replace_face(Index f, std::vector<BspFace> pieces) {
  if (face_untouched(f) >= 0)
    throw MeshingError(ErrorCode::kInternal, "bsp", f, "a split reached a face of an untouched seed tet");
  unregister_edges(f);
  faces_[f].alive = false;
  std::vector<Index> ids;
  for (auto& piece : pieces) ids.push_back(new_face(std::move(piece)));
  substitute_face(f, ids);
}

void BspComplex::substitute_face(Index f, const std::vector<Index>& ids, Index skip_cell) {
  for (int side = 0; side < 2; ++side) {
    const Index c = faces_[ids[0]].cell[side];
    if (c < 0 || c == skip_cell) continue;
    auto& fl = cells_[c].faces;
    auto it = std::find(fl.begin(), fl.end(), f);
    if (it == fl.end()) throw MeshingError(ErrorCode::kInternal, "bsp", f, "face missing from its cell");
    const std::size_t at = static_cast<std::size_t>(it - fl.begin());
    *it = ids[0];
    fl.insert(fl.end(), ids.begin() + 1, ids.end());
    auto& bl = cells_[c].boxes;
    if (bl.size() + ids.size() - 1 == fl.size()) {  // in step: keep it so
      bl[at] = face_box(ids[0]);
      for (std::size_t i = 1; i < ids.size(); ++i) bl.push_back(face_box(ids[i]));
    } else {
      bl.clear();  // rebuilt by the next split_cell
    }
  }
}

void BspComplex::overlay_covered_face(Index f, const std::vector<Index>& over, int axis, int fo) {
  const Index plane = faces_[f].plane;
  // Triangle t's vertices counter-clockwise around the plane normal (as the face's cycle).
  auto ccw = [&](Index t) {
    std::array<Index, 3> tv{triangle_vertex(t, 0), triangle_vertex(t, 1), triangle_vertex(t, 2)};
    if (to_int(geo_.orient2d(tv[0], tv[1], tv[2], axis)) != fo) std::swap(tv[1], tv[2]);
    return tv;
  };
  // 1. Every point where an edge of a covering triangle meets an edge of f becomes a vertex of f
  // (for every face using that edge: conformity). Input vertices on f's edges are used as they are.
  // Each input edge once, as its first covering triangle has it: two covering triangles share most
  // edges, and the second visit could only find the crossings already made.
  std::unordered_set<std::uint64_t> seen;
  for (Index t : over) {
    const std::array<Index, 3> tv = ccw(t);
    for (int k = 0; k < 3; ++k) {
      const Index a = tv[k], b = tv[(k + 1) % 3];
      if (!seen.insert(edge_key(a, b)).second) continue;
      for (std::size_t i = 0; i < faces_[f].verts.size(); ++i) {
        const auto& v = faces_[f].verts;
        const Index u = v[i], w = v[(i + 1) % v.size()];
        if (to_int(geo_.orient2d(a, b, u, axis)) * to_int(geo_.orient2d(a, b, w, axis)) >= 0) continue;
        const int sa = to_int(geo_.orient2d(u, w, a, axis)), sb = to_int(geo_.orient2d(u, w, b, axis));
        if (sa == 0 || sb == 0) {
          const Index y = sa == 0 ? a : b;
          for (Index q : edge_line(u, w)) geo_.note_on_plane(y, q);
          split_edge(u, w, y);
        } else if (sa * sb < 0) {
          const std::array<Index, 2> line = edge_line(u, w);
          const Index x = geo_.add_tpi_vertex(line[0], line[1], edge_plane(a, b, plane));
          ++stats_.bsp_points;
          split_edge(u, w, x);
        }
      }
    }
  }
  // 2. The pieces f ∩ t, walked counter-clockwise: the runs of f's cycle inside closed t, joined
  // along t's edges through t's vertices strictly inside f.
  const std::vector<Index> cyc = faces_[f].verts;
  const std::size_t m = cyc.size();
  std::vector<BspFace> pieces;
  for (Index t : over) {
    const std::array<Index, 3> tv = ccw(t);
    std::vector<char> in(m);
    bool any_in = false, all_in = true;
    for (std::size_t i = 0; i < m; ++i) {
      bool inside = true;
      for (int k = 0; k < 3 && inside; ++k) inside = fo * to_int(geo_.orient2d(tv[k], tv[(k + 1) % 3], cyc[i], axis)) >= 0;
      in[i] = inside;
      any_in = any_in || inside;
      all_in = all_in && inside;
    }
    bool inner[3];
    for (int j = 0; j < 3; ++j) {
      inner[j] = true;
      for (std::size_t i = 0; i < m && inner[j]; ++i)
        inner[j] = fo * to_int(geo_.orient2d(cyc[i], cyc[(i + 1) % m], tv[j], axis)) > 0;
    }
    BspFace piece;
    piece.plane = plane;
    piece.cell[0] = faces_[f].cell[0];
    piece.cell[1] = faces_[f].cell[1];
    piece.coplanar = {t};
    if (all_in) {
      piece.verts = cyc;
    } else if (!any_in) {
      if (!inner[0] || !inner[1] || !inner[2])
        throw MeshingError(ErrorCode::kInternal, "bsp", f, "covering triangle " + std::to_string(t) + " not inside its face");
      piece.verts.assign(tv.begin(), tv.end());
    } else {
      std::size_t i0 = m;
      for (std::size_t i = 0; i < m && i0 == m; ++i)
        if (in[i] && !in[(i + m - 1) % m]) i0 = i;
      std::size_t i = i0;
      do {
        piece.verts.push_back(cyc[i]);
        const std::size_t nx = (i + 1) % m;
        if (in[nx]) {
          i = nx;
          continue;
        }
        // Leaving t at cyc[i]: follow t's boundary from the edge through it, in t's direction.
        const Index x = cyc[i];
        int on[3], count = 0;
        for (int k = 0; k < 3; ++k) {
          on[k] = geo_.orient2d(tv[k], tv[(k + 1) % 3], x, axis) == Sign::kZero;
          count += on[k];
        }
        int kx = -1;
        if (count == 1) {
          for (int k = 0; k < 3; ++k)
            if (on[k]) kx = k;
        } else if (count == 2) {
          for (int k = 0; k < 3; ++k)
            if (on[k] && on[(k + 2) % 3]) kx = k;  // x is tv[k]: leave along edge k
        }
        if (kx < 0)
          throw MeshingError(ErrorCode::kInternal, "bsp", f,
                             "face edge leaves covering triangle " + std::to_string(t) + " at no vertex");
        for (int j = (kx + 1) % 3, steps = 0; steps < 3 && inner[j]; j = (j + 1) % 3, ++steps) piece.verts.push_back(tv[j]);
        i = nx;
        while (!in[i]) i = (i + 1) % m;
      } while (i != i0);
    }
    // The piece must be a convex polygon, counter-clockwise.
    const std::size_t n = piece.verts.size();
    int corners = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const int o = fo * to_int(geo_.orient2d(piece.verts[k], piece.verts[(k + 1) % n], piece.verts[(k + 2) % n], axis));
      if (o < 0) throw MeshingError(ErrorCode::kInternal, "bsp", f, "a covered piece is not convex");
      corners += o > 0;
    }
    if (n < 3 || corners < 3) throw MeshingError(ErrorCode::kInternal, "bsp", f, "a covered piece is degenerate");
    // Lines of the new edges: along an edge of t.
    for (std::size_t k = 0; k < n; ++k) {
      const Index p = piece.verts[k], q = piece.verts[(k + 1) % n];
      if (edge_line_.contains(edge_key(p, q))) continue;
      Index along = -1;
      for (int e = 0; e < 3 && along < 0; ++e)
        if (geo_.orient2d(tv[e], tv[(e + 1) % 3], p, axis) == Sign::kZero &&
            geo_.orient2d(tv[e], tv[(e + 1) % 3], q, axis) == Sign::kZero)
          along = edge_plane(tv[e], tv[(e + 1) % 3], plane);
      if (along < 0) throw MeshingError(ErrorCode::kInternal, "bsp", f, "a covered piece's edge is on no line");
      edge_line_[edge_key(p, q)] = {plane, along};
    }
    pieces.push_back(std::move(piece));
  }
  replace_face(f, std::move(pieces));
}

std::array<Index, 2> BspComplex::split_face_in_plane(Index f, Index q) {
  VertexSigns& sign = signs_;
  sign.reset();
  for (Index v : faces_[f].verts) sign[v] = to_int(geo_.side(q, v));
  cut_crossing_edges(f, q, sign);
  const auto [i0, i1] = split_face(f, q, sign);
  substitute_face(f, {i0, i1});
  return {i0, i1};
}

std::vector<Index> BspComplex::faces_on_input_planes() const {
  std::vector<Index> work;
  for (std::size_t f = faces_.size(); f-- > 0;)
    if (faces_[f].alive && !faces_[f].coplanar.empty()) work.push_back(static_cast<Index>(f));
  return work;
}

void BspComplex::refine_covered_faces() {
  require_split_data("refine_covered_faces");
  // The input triangle across each input edge, to tell the edges where the surface leaves a plane
  // (patch boundaries) from those between two triangles of the same plane.
  std::unordered_map<std::uint64_t, std::array<Index, 2>> edge_tris;
  for (Index t = 0; t < surface_.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto& e = edge_tris.try_emplace(edge_key(triangle_vertex(t, k), triangle_vertex(t, (k + 1) % 3)),
                                      std::array<Index, 2>{-1, -1}).first->second;
      (e[0] < 0 ? e[0] : e[1]) = t;
    }
  auto patch_boundary = [&](Index t, int k) {
    const auto& e = edge_tris.at(edge_key(triangle_vertex(t, k), triangle_vertex(t, (k + 1) % 3)));
    const Index other = e[0] == t ? e[1] : e[0];
    return other < 0 || tri_plane_[other] != tri_plane_[t];
  };
  visit_faces_on_input_planes([&](Index f, int axis, int fo) -> Index {
    std::vector<Index> over;
    for (Index t : faces_[f].coplanar)
      if (face_overlaps_triangle(f, t, axis, fo)) over.push_back(t);
    if (over.empty()) {
      faces_[f].coplanar.clear();
      return -1;
    }
    // Where the plane's part of the surface ends inside f, split f along that edge's line: then
    // each half is covered entirely or not at all, whatever the triangles inside it.
    Index cut_a = -1, cut_b = -1;
    for (std::size_t j = 0; j < over.size() && cut_a < 0; ++j)
      for (int k = 0; k < 3 && cut_a < 0; ++k) {
        if (!patch_boundary(over[j], k)) continue;
        const Index a = triangle_vertex(over[j], k), b = triangle_vertex(over[j], (k + 1) % 3);
        if (segment_crosses_face(f, a, b, axis, fo)) cut_a = a, cut_b = b;
      }
    if (cut_a >= 0) return edge_plane(cut_a, cut_b, faces_[f].plane);
    // f lies in the union of the triangles it overlaps (no patch boundary crosses its interior):
    // one face per triangle, f ∩ t.
    if (over.size() == 1) {
      faces_[f].coplanar = over;
      return -1;
    }
    overlay_covered_face(f, over, axis, fo);
    if (debug_checks_) check_consistency();
    return -1;
  });
}

void BspComplex::refine_covered_faces_along_lines() {
  require_split_data("refine_covered_faces_along_lines");
  visit_faces_on_input_planes([&](Index f, int axis, int fo) -> Index {
    Index cover = -1;
    for (Index t : faces_[f].coplanar)
      if (face_overlaps_triangle(f, t, axis, fo)) {
        cover = t;
        break;
      }
    if (cover < 0) {
      faces_[f].coplanar.clear();
      return -1;
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
      return -1;
    }
    return edge_plane(tv[cut_edge], tv[(cut_edge + 1) % 3], faces_[f].plane);
  });
}

void BspComplex::visit_faces_on_input_planes(const std::function<Index(Index, int, int)>& visit) {
  std::vector<Index> work = faces_on_input_planes();
  while (!work.empty()) {
    const Index f = work.back();
    work.pop_back();
    Sign ns = Sign::kZero;
    const int axis = geo_.projection_axis(faces_[f].plane, &ns);
    const Index along = visit(f, axis, to_int(ns));
    if (along < 0) continue;
    const auto [i0, i1] = split_face_in_plane(f, along);
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
