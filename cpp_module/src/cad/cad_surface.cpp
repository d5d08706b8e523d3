// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: edges, then faces, then each solid's surface (see cad_surface.h).
#include "bsptet/cad/cad_surface.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>

#include "bsptet/cad/edge_mesher.h"
#include "bsptet/cad/face_mesher.h"
#include "bsptet/numerics/errors.h"

namespace bsptet::cad {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct EdgeNodes {
  std::vector<double> t;     ///< parameters, increasing (the edge FORWARD)
  std::vector<Index> node;   ///< node ids, first and last the vertices
  bool degenerated = false;
};

[[noreturn]] void input_error(const CadModel& model, const std::string& what) {
  throw InputError(ErrorCode::kBadArgument, "cad_surface", -1, model.source + ": " + what);
}

/// Faces around each edge, as indices.
std::vector<std::vector<int>> faces_of_edges(const CadModel& model) {
  TopTools_IndexedDataMapOfShapeListOfShape map;
  TopExp::MapShapesAndAncestors(model.shape, TopAbs_EDGE, TopAbs_FACE, map);
  std::vector<std::vector<int>> out(static_cast<std::size_t>(model.num_edges()));
  for (int e = 0; e < model.num_edges(); ++e) {
    const int k = map.FindIndex(model.edges(e + 1));
    if (k == 0) continue;
    for (const TopoDS_Shape& f : map(k)) {
      const int fi = model.face_index(f);
      if (fi >= 0 && std::find(out[e].begin(), out[e].end(), fi) == out[e].end()) out[e].push_back(fi);
    }
    std::sort(out[e].begin(), out[e].end());
  }
  return out;
}

/// Refuses a solid whose boundary has an edge on one face only (not a seam, not degenerated).
void check_closed_solids(const CadModel& model) {
  for (int s = 1; s <= model.num_solids(); ++s) {
    TopTools_IndexedDataMapOfShapeListOfShape map;
    TopExp::MapShapesAndAncestors(model.solids(s), TopAbs_EDGE, TopAbs_FACE, map);
    std::set<int> open_faces;
    for (int k = 1; k <= map.Extent(); ++k) {
      const TopoDS_Edge& edge = TopoDS::Edge(map.FindKey(k));
      if (BRep_Tool::Degenerated(edge)) continue;
      std::set<int> faces;
      bool seam = false;
      for (const TopoDS_Shape& f : map(k)) {
        faces.insert(model.face_index(f));
        seam = seam || BRep_Tool::IsClosed(edge, TopoDS::Face(f));
      }
      if (faces.size() == 1 && !seam) open_faces.insert(*faces.begin());
    }
    if (!open_faces.empty()) {
      std::ostringstream what;
      what << "Solid" << s << " is not closed: these faces have edges no other face meets:";
      int shown = 0;
      for (int f : open_faces) {
        if (++shown > 12) {
          what << " ...";
          break;
        }
        what << " Face" << f + 1;
      }
      what << ". Close the shell in the CAD program (or FreeCAD's Part > Check geometry, then Part > Shape "
              "builder) and export it again";
      input_error(model, what.str());
    }
  }
}

/// Shifts a chain of (u, v) points by whole periods so that it starts where `previous` ended.
void align_periodic(std::vector<Uv>& chain, const Uv& previous, const BRepAdaptor_Surface& surface) {
  for (int axis = 0; axis < 2; ++axis) {
    const bool periodic = axis == 0 ? surface.IsUPeriodic() : surface.IsVPeriodic();
    if (!periodic) continue;
    const double period = axis == 0 ? surface.UPeriod() : surface.VPeriod();
    const double shift = std::round((previous[axis] - chain.front()[axis]) / period) * period;
    if (shift != 0)
      for (Uv& p : chain) p[axis] += shift;
  }
}

double loop_area(const std::vector<BoundaryNode>& loop) {
  double a = 0;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Uv& p = loop[i].uv;
    const Uv& q = loop[(i + 1) % loop.size()].uv;
    a += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * a;
}

}  // namespace

SurfaceMesh CadSurface::solid_surface(int s, std::vector<Index>* node_of) const {
  const auto& tri = solid_tri[static_cast<std::size_t>(s)];
  std::vector<Index> used(tri.begin(), tri.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::map<Index, Index> local;
  SurfaceMesh out;
  for (Index n : used) {
    local[n] = static_cast<Index>(local.size());
    for (int k = 0; k < 3; ++k) out.xyz.push_back(xyz[3 * static_cast<std::size_t>(n) + k]);
  }
  for (Index n : tri) out.tri.push_back(local[n]);
  out.tag = solid_tag[static_cast<std::size_t>(s)];
  if (node_of) *node_of = used;
  return out;
}

CadSurface mesh_cad_surface(const CadModel& model, const CadSurfaceOptions& options, CadSurfaceStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  check_closed_solids(model);
  const SizeField field(model, options.size);
  auto progress = [&](const char* stage, double f) {
    if (options.progress) options.progress(stage, f);
  };
  auto check_cancel = [&] {
    if (options.cancelled && options.cancelled())
      throw MeshingError(ErrorCode::kCancelled, "cad_surface", -1, "cancelled");
  };

  CadSurface out;
  auto add_node = [&](const gp_Pnt& p, int dim, int entity) {
    out.xyz.insert(out.xyz.end(), {p.X(), p.Y(), p.Z()});
    out.node_dim.push_back(static_cast<std::int8_t>(dim));
    out.node_entity.push_back(entity);
    return static_cast<Index>(out.node_dim.size() - 1);
  };
  for (int v = 0; v < model.num_vertices(); ++v) add_node(BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(v + 1))), 0, v);

  // ---- Edges: sizes, graded from their vertices, then nodes. ----
  const auto edge_faces = faces_of_edges(model);
  const int n_edges = model.num_edges();
  std::vector<EdgeSizing> sizing(static_cast<std::size_t>(n_edges));
  std::vector<std::array<int, 2>> ends(static_cast<std::size_t>(n_edges), {-1, -1});
  std::vector<double> vertex_size(static_cast<std::size_t>(model.num_vertices()), kInf);
  std::vector<EdgeNodes> edge_nodes(static_cast<std::size_t>(n_edges));
  for (int e = 0; e < n_edges; ++e) {
    const TopoDS_Edge edge = TopoDS::Edge(model.edges(e + 1).Oriented(TopAbs_FORWARD));
    TopoDS_Vertex v0, v1;
    TopExp::Vertices(edge, v0, v1);
    ends[e] = {model.vertex_index(v0), model.vertex_index(v1)};
    if (BRep_Tool::Degenerated(edge)) {
      edge_nodes[e].degenerated = true;
      continue;
    }
    double base = field.size();
    for (int f : edge_faces[e]) base = std::min(base, field.face_size(f));
    sizing[e] = sample_edge_sizing(edge, base, field);
    // A vertex asks for the smallest size at the ends of its edges, and for short edges' lengths
    // (so that faces grade down to a short edge instead of meeting it with long triangles;
    // below the automatic floor too, SizeField::short_edge_size).
    const double length = sizing[e].length();
    for (int k = 0; k < 2; ++k) {
      const int v = ends[e][k];
      if (v < 0) continue;
      const double at_end = k == 0 ? sizing[e].size.front() : sizing[e].size.back();
      vertex_size[v] = std::min({vertex_size[v], at_end, field.short_edge_size(length)});
    }
  }
  for (int e = 0; e < n_edges; ++e) {
    EdgeNodes& en = edge_nodes[e];
    if (en.degenerated) continue;
    const TopoDS_Edge edge = TopoDS::Edge(model.edges(e + 1));
    BRepAdaptor_Curve curve(TopoDS::Edge(edge.Oriented(TopAbs_FORWARD)));
    const bool closed = ends[e][0] == ends[e][1];
    const int min_segments = closed ? 3 : (curve.GetType() == GeomAbs_Line ? 1 : 2);
    en.t = place_edge_nodes(sizing[e], vertex_size[ends[e][0]], vertex_size[ends[e][1]], field.grading(), min_segments);
    en.node.push_back(ends[e][0]);
    for (std::size_t i = 1; i + 1 < en.t.size(); ++i) en.node.push_back(add_node(curve.Value(en.t[i]), 1, e));
    en.node.push_back(ends[e][1]);
  }
  progress("edges", 1.0);

  // ---- Each face's boundary loops in its parameter plane. ----
  // seg[l][i] names the edge segment from loops[l][i] to the next node: (edge, index of the
  // segment in the edge's FORWARD node list), edge -1 on a degenerated edge.
  struct FaceLoops {
    std::vector<std::vector<BoundaryNode>> loops;
    std::vector<std::vector<std::array<int, 2>>> seg;
  };
  auto build_loops = [&](int f) {
    FaceLoops fl;
    const TopoDS_Face face = TopoDS::Face(model.faces(f + 1).Oriented(TopAbs_FORWARD));
    const BRepAdaptor_Surface surface(face, false);
    const TopoDS_Wire outer = BRepTools::OuterWire(face);
    std::size_t outer_loop = 0;
    for (TopExp_Explorer wires(face, TopAbs_WIRE); wires.More(); wires.Next()) {
      const TopoDS_Wire wire = TopoDS::Wire(wires.Current());
      const bool is_outer = wire.IsSame(outer);
      std::vector<BoundaryNode> loop;
      std::vector<std::array<int, 2>> seg;
      bool first_chain = true;
      Uv previous_end{0, 0}, loop_start{0, 0};
      for (BRepTools_WireExplorer we(wire, face); we.More(); we.Next()) {
        const TopoDS_Edge edge = we.Current();
        const int e = model.edge_index(edge);
        double p0, p1;
        const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, p0, p1);
        if (pcurve.IsNull()) {
          std::ostringstream what;
          what << "Face" << f + 1 << ": Edge" << e + 1 << " has no curve in the face's parameters (pcurve)";
          input_error(model, what.str());
        }
        std::vector<double> t;
        std::vector<Index> ids;
        const bool degenerated = edge_nodes[e].degenerated;
        if (degenerated) {
          // A degenerated edge (a pole, an apex): several (u, v) nodes, one 3D node.
          const int segments = 8;
          for (int i = 0; i <= segments; ++i) {
            t.push_back(p0 + (p1 - p0) * i / segments);
            ids.push_back(ends[e][0]);
          }
        } else {
          t = edge_nodes[e].t;
          ids = edge_nodes[e].node;
        }
        const bool reversed = edge.Orientation() == TopAbs_REVERSED;
        if (reversed) {
          std::reverse(t.begin(), t.end());
          std::reverse(ids.begin(), ids.end());
        }
        std::vector<Uv> chain;
        for (double ti : t) {
          const gp_Pnt2d q = pcurve->Value(ti);
          chain.push_back({q.X(), q.Y()});
        }
        if (first_chain) {
          loop_start = chain.front();
        } else {
          align_periodic(chain, previous_end, surface);
        }
        first_chain = false;
        previous_end = chain.back();
        const int n_seg = static_cast<int>(chain.size()) - 1;
        for (int i = 0; i < n_seg; ++i) {
          const Index id = ids[static_cast<std::size_t>(i)];
          const Vec3 p{out.xyz[3 * static_cast<std::size_t>(id)], out.xyz[3 * static_cast<std::size_t>(id) + 1],
                       out.xyz[3 * static_cast<std::size_t>(id) + 2]};
          loop.push_back({chain[static_cast<std::size_t>(i)], id, p});
          seg.push_back({degenerated ? -1 : e, reversed ? n_seg - 1 - i : i});
        }
      }
      if (loop.size() < 2) continue;
      // The loop must close: real files leave gaps between consecutive pcurves within the
      // vertices' tolerance (harmless: each chain starts at its own point); a face on a periodic
      // surface without a seam edge closes only modulo the period, which this mesher cannot take.
      for (int axis = 0; axis < 2; ++axis) {
        const bool periodic = axis == 0 ? surface.IsUPeriodic() : surface.IsVPeriodic();
        if (!periodic) continue;
        const double period = axis == 0 ? surface.UPeriod() : surface.VPeriod();
        if (std::abs(previous_end[axis] - loop_start[axis]) > 0.25 * period) {
          std::ostringstream what;
          what << "Face" << f + 1 << ": a boundary loop does not close in the face's parameters (a periodic face "
                  "without a seam edge?); FreeCAD's Part > Refine shape or Part > Check geometry may mend it";
          input_error(model, what.str());
        }
      }
      if (is_outer) outer_loop = fl.loops.size();
      fl.loops.push_back(std::move(loop));
      fl.seg.push_back(std::move(seg));
    }
    if (fl.loops.empty()) return fl;
    std::swap(fl.loops[0], fl.loops[outer_loop]);
    std::swap(fl.seg[0], fl.seg[outer_loop]);
    // Material on the left: the outer loop counter-clockwise, holes clockwise. Reversing a loop
    // moves each segment's name one place (segment i joined nodes i and i + 1).
    auto reverse_loop = [&](std::size_t l) {
      auto& loop = fl.loops[l];
      auto& seg = fl.seg[l];
      std::reverse(loop.begin(), loop.end());
      std::reverse(seg.begin(), seg.end());
      std::rotate(seg.begin(), seg.begin() + 1, seg.end());
    };
    if (loop_area(fl.loops[0]) < 0)
      for (std::size_t l = 0; l < fl.loops.size(); ++l) reverse_loop(l);
    for (std::size_t l = 1; l < fl.loops.size(); ++l)
      if (loop_area(fl.loops[l]) > 0) reverse_loop(l);
    return fl;
  };

  // ---- Boundaries made simple: where two segments of a face's loops cross or touch in (u, v)
  // (chords of curved edges on a thin face), both edge segments are split at their parameter
  // midpoint, for every face at once, until no face has such a pair. ----
  const int n_faces = model.num_faces();
  constexpr int kSimplePasses = 12;
  for (int pass = 0;; ++pass) {
    std::set<std::array<int, 2>> to_split;
    for (int f = 0; f < n_faces; ++f) {
      const FaceLoops fl = build_loops(f);
      struct Seg {
        Uv a, b;
        double umin, umax;
        std::size_t loop, index, size;
      };
      std::vector<Seg> segs;
      for (std::size_t l = 0; l < fl.loops.size(); ++l) {
        const auto& loop = fl.loops[l];
        for (std::size_t i = 0; i < loop.size(); ++i) {
          const Uv& a = loop[i].uv;
          const Uv& b = loop[(i + 1) % loop.size()].uv;
          segs.push_back({a, b, std::min(a[0], b[0]), std::max(a[0], b[0]), l, i, loop.size()});
        }
      }
      std::sort(segs.begin(), segs.end(), [](const Seg& x, const Seg& y) { return x.umin < y.umin; });
      for (std::size_t i = 0; i < segs.size(); ++i) {
        for (std::size_t j = i + 1; j < segs.size() && segs[j].umin <= segs[i].umax; ++j) {
          const Seg &x = segs[i], &y = segs[j];
          if (x.loop == y.loop && ((x.index + 1) % x.size == y.index || (y.index + 1) % y.size == x.index)) continue;
          if (!uv_segments_meet(x.a, x.b, y.a, y.b)) continue;
          for (const Seg* z : {&x, &y}) {
            const auto& name = fl.seg[z->loop][z->index];
            if (name[0] >= 0) to_split.insert(name);
          }
        }
      }
    }
    if (to_split.empty()) break;
    if (pass == kSimplePasses) {
      std::ostringstream what;
      what << "the boundary of a face crosses itself in its parameter plane after " << kSimplePasses
           << " refinements of Edge" << (*to_split.begin())[0] + 1 << "; check the part (FreeCAD's Part > Check geometry)";
      input_error(model, what.str());
    }
    // Split from the last segment of each edge backwards, so earlier indices stay valid.
    for (auto it = to_split.rbegin(); it != to_split.rend(); ++it) {
      const int e = (*it)[0], j = (*it)[1];
      EdgeNodes& en = edge_nodes[static_cast<std::size_t>(e)];
      BRepAdaptor_Curve curve(TopoDS::Edge(model.edges(e + 1).Oriented(TopAbs_FORWARD)));
      const double tm = 0.5 * (en.t[static_cast<std::size_t>(j)] + en.t[static_cast<std::size_t>(j) + 1]);
      en.t.insert(en.t.begin() + j + 1, tm);
      en.node.insert(en.node.begin() + j + 1, add_node(curve.Value(tm), 1, e));
    }
  }

  // ---- Faces, each once. ----
  std::vector<std::vector<std::array<Index, 3>>> face_tris(static_cast<std::size_t>(n_faces));
  CadSurfaceStats st;
  for (int f = 0; f < n_faces; ++f) {
    check_cancel();
    const TopoDS_Face face = TopoDS::Face(model.faces(f + 1).Oriented(TopAbs_FORWARD));
    const BRepAdaptor_Surface surface(face, false);
    std::vector<std::vector<BoundaryNode>> loops = build_loops(f).loops;
    if (loops.empty()) continue;

    FaceMeshOptions fo;
    fo.face_size = field.face_size(f);
    fo.min_size = field.min_size();
    fo.grading = field.grading();
    if (field.face_has_local_curvature(f)) fo.local_curvature_points_per_circle = field.points_per_circle();
    fo.max_rounds = options.face_rounds;
    if (const auto it = options.size_sources.find(f); it != options.size_sources.end()) fo.size_sources = it->second;
    FaceMesh fm;
    try {
      fm = mesh_face(face, loops, fo, static_cast<Index>(out.node_dim.size()));
    } catch (const std::runtime_error& e) {
      std::ostringstream what;
      what << "Face" << f + 1 << ": " << e.what();
      throw MeshingError(ErrorCode::kInternal, "cad_surface", f, model.source + ": " + what.str());
    }
    for (const Vec3& p : fm.new_xyz) add_node(gp_Pnt(p.x, p.y, p.z), 2, f);
    st.folds += fm.folds;
    if (fm.folds > 0) st.folded_faces.emplace_back(f, fm.folds);
    st.min_quality = std::min(st.min_quality, fm.min_quality);
    face_tris[f] = std::move(fm.triangles);
    progress("faces", double(f + 1) / n_faces);
  }

  // ---- Every face once, as the shape orients it. ----
  for (int f = 0; f < n_faces; ++f) {
    const bool reversed = model.faces(f + 1).Orientation() == TopAbs_REVERSED;
    for (const auto& t : face_tris[f]) {
      out.face_tri.insert(out.face_tri.end(), {t[0], reversed ? t[2] : t[1], reversed ? t[1] : t[2]});
      out.face_tag.push_back(f);
    }
  }

  // ---- Solids: their faces, oriented outward. ----
  for (int s = 1; s <= model.num_solids(); ++s) {
    std::vector<Index> tri;
    std::vector<std::int32_t> tag;
    std::set<int> seen;
    for (TopExp_Explorer faces(model.solids(s), TopAbs_FACE); faces.More(); faces.Next()) {
      const int f = model.face_index(faces.Current());
      if (!seen.insert(f).second) continue;
      const bool reversed = faces.Current().Orientation() == TopAbs_REVERSED;
      for (const auto& t : face_tris[f]) {
        if (reversed) {
          tri.insert(tri.end(), {t[0], t[2], t[1]});
        } else {
          tri.insert(tri.end(), {t[0], t[1], t[2]});
        }
        tag.push_back(f);
      }
    }
    // A solid whose shell is inside out (negative volume) is turned the right way.
    double volume6 = 0;
    auto P = [&](Index n) { return Vec3{out.xyz[3 * n], out.xyz[3 * n + 1], out.xyz[3 * n + 2]}; };
    for (std::size_t k = 0; k < tri.size(); k += 3) {
      const Vec3 a = P(tri[k]), b = P(tri[k + 1]), c = P(tri[k + 2]);
      volume6 += a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) + a.z * (b.x * c.y - b.y * c.x);
    }
    if (volume6 < 0)
      for (std::size_t k = 0; k < tri.size(); k += 3) std::swap(tri[k + 1], tri[k + 2]);
    st.triangles += static_cast<std::int64_t>(tag.size());
    out.solid_tri.push_back(std::move(tri));
    out.solid_tag.push_back(std::move(tag));
  }
  st.nodes = static_cast<std::int64_t>(out.node_dim.size());
  st.size = field.size();
  st.min_size = field.min_size();
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = st;
  return out;
}

}  // namespace bsptet::cad
