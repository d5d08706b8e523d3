// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/refine/quality_refine.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <queue>
#include <string>
#include <tuple>
#include <vector>

#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/refine/curved_room.h"
#include "bsptet/refine/mesh_optimizer.h"
#include "bsptet/refine/size_refine.h"
#include "bsptet/refine/target_sizes.h"
#include "bsptet/refine/tet10.h"

namespace bsptet {

namespace {

// Tets below this get the last polish, which keeps room for curved elements (CurvedRoom::polish).
constexpr double kPolishCurvedBelowDeg = 15.0;

void check_options(const RefineOptions& o) {
  auto bad = [](const std::string& what) { throw InputError(ErrorCode::kBadArgument, "refine", -1, what); };
  if (!(o.size > 0)) bad("size must be a positive length (or infinity for none), got " + std::to_string(o.size));
  if (!(o.min_size >= 0) || !std::isfinite(o.min_size)) bad("min_size must be >= 0, got " + std::to_string(o.min_size));
  for (const auto& [tag, s] : o.size_by_tag)
    if (!(s > 0) || !std::isfinite(s))
      bad("the size of face tag " + std::to_string(tag) + " must be a positive length, got " + std::to_string(s));
  if (!(o.thickness_ratio >= 0) || !std::isfinite(o.thickness_ratio))
    bad("thickness_ratio must be 0 (off) or a positive number, got " + std::to_string(o.thickness_ratio));
  if (!(o.grading > 0)) bad("grading must be positive, got " + std::to_string(o.grading));
  if (!(o.collapse_ratio >= 0 && o.collapse_ratio < o.split_ratio))
    bad("collapse_ratio must be in [0, split_ratio), got " + std::to_string(o.collapse_ratio));
  if (!(o.collapse_min_dihedral_deg >= 0 && o.collapse_min_dihedral_deg <= 180))
    bad("collapse_min_dihedral_deg must be in [0, 180], got " + std::to_string(o.collapse_min_dihedral_deg));
  if (!(o.split_ratio >= 1) || !std::isfinite(o.split_ratio))
    bad("split_ratio must be at least 1, got " + std::to_string(o.split_ratio));
  if (!(o.radius_edge_bound == 0 || o.radius_edge_bound >= 0.7))
    bad("radius_edge_bound must be 0 (off) or at least 0.7 (a regular tet has 0.612), got " +
        std::to_string(o.radius_edge_bound));
  if (!(o.min_dihedral_deg >= 0 && o.min_dihedral_deg < 70.5))
    bad("min_dihedral_deg must be in [0, 70.5), got " + std::to_string(o.min_dihedral_deg));
  if (o.order != 1 && o.order != 2) bad("order must be 1 or 2, got " + std::to_string(o.order));
  if (o.max_passes < 0 || o.optimize_rounds < 0) bad("max_passes and optimize_rounds must be >= 0");
}

// The stage's driver: the steps of quality_refine.h in order, over the pieces that do them
// (target_sizes.h, size_refine.h, mesh_optimizer.h, curved_room.h), and separate_face_tags.
class Refiner {
 public:
  Refiner(RefineMesh& m, const RefineOptions& o, RefineStats& st)
      : m_(m), o_(o), st_(st), size_(m, o), opt_(m, o, st, size_), sizing_(m, o, st, size_, opt_),
        curved_(m, o, st, size_, opt_) {}

  void run() {
    timed_pass(st_, "targets", [&] { size_.compute(); return 0; });
    timed_pass(st_, "size", [&] { sizing_.delaunay_refine(); return 0; });
    timed_pass(st_, "size", [&] { sizing_.split_long_edges(); return 0; });
    tets_after_size_ = m_.num_alive_tets();
    opt_.optimize(o_.optimize_rounds, tets_after_size_);
    // Collapses and smoothing may have left some edges long again: one more short round, whose
    // splits never make a tet worse than the worst of the tets they replace (after the
    // optimization, a free split here could leave a sliver no later pass removes: the
    // Schoenhardt polyhedron went from 11 to 1.6 degrees).
    if (o_.max_passes > 0) {
      timed_pass(st_, "size", [&] { sizing_.split_long_edges(180.0); return 0; });
      opt_.optimize(std::min(2, o_.optimize_rounds), tets_after_size_);
    }
    if (o_.separate_face_tags && !m_.surface().tag.empty()) {
      timed_pass(st_, "separate_face_tags", [&] { separate_face_tags(); return 0; });
      // Its splits end where the optimization has stopped. Only moves of interior points follow
      // (a flip could join three points of one CAD face into an interior face again; a move
      // changes no connectivity), each raising the worst tet around the point.
      for (int round = 0; round < 3 && opt_.smooth_pass(30.0) > 0; ++round) {
      }
    }
    st_.worst_deg_optimized = m_.worst_tet_quality();
    timed_pass(st_, "curving", [&] { return curved_.polish(kPolishCurvedBelowDeg); });
    st_.worst_deg = m_.worst_tet_quality();
    // Counted last (the smoothing after separate_face_tags and the lifts move points too) against
    // the asked sizes: the targets raised around edges that could not be split do not count.
    size_.compute(false);
    for (const auto& e : m_.edges())
      if (size_.is_long(e[0], e[1])) ++st_.long_edges_left;
  }

  /// The fallback of curved_room.h on a mesh that run() refined: room for the curved elements,
  /// then the polish again.
  void make_room_for_curving() {
    size_.compute(false);
    timed_pass(st_, "curving", [&] { curved_.lift(); return 0; });
    timed_pass(st_, "curving", [&] { return curved_.polish(kPolishCurvedBelowDeg); });
    st_.worst_deg = m_.worst_tet_quality();
  }

 private:
  // ---- separate_face_tags (see the option) ---------------------------------------------------
  // The offending tets (see the option), each with the edges whose split would mend it, best
  // first: interior edges (their midpoint is off every face), then edges of other tags' faces;
  // longer first.
  std::vector<std::pair<Index, std::vector<std::array<Index, 2>>>> tag_conflicts() {
    using Key3 = std::array<Index, 3>;
    std::map<Key3, std::int32_t> face_tag;                                // sorted boundary face -> tag
    std::map<std::array<Index, 2>, std::vector<std::int32_t>> edge_tags;  // boundary edge -> tags
    std::vector<std::vector<std::int32_t>> point_tags(static_cast<std::size_t>(m_.num_points()));
    for (const auto& [face, parent] : m_.boundary_faces()) {
      const std::int32_t tag = m_.tag_of(parent);
      Key3 key = face;
      std::sort(key.begin(), key.end());
      face_tag[key] = tag;
      for (int i = 0; i < 3; ++i) {
        auto& pt = point_tags[static_cast<std::size_t>(face[i])];
        if (std::find(pt.begin(), pt.end(), tag) == pt.end()) pt.push_back(tag);
        std::array<Index, 2> e{std::min(face[i], face[(i + 1) % 3]), std::max(face[i], face[(i + 1) % 3])};
        auto& et = edge_tags[e];
        if (std::find(et.begin(), et.end(), tag) == et.end()) et.push_back(tag);
      }
    }
    auto on_tag = [&](Index v, std::int32_t tag) {
      const auto& pt = point_tags[static_cast<std::size_t>(v)];
      return std::find(pt.begin(), pt.end(), tag) != pt.end();
    };
    std::vector<std::pair<Index, std::vector<std::array<Index, 2>>>> out;
    for (Index t = 0; t < m_.num_tet_slots(); ++t) {
      if (!m_.tet_alive(t)) continue;
      const auto q = m_.tet(t);
      std::vector<std::int32_t> tags;
      for (Index v : q)
        for (std::int32_t tag : point_tags[static_cast<std::size_t>(v)])
          if (std::find(tags.begin(), tags.end(), tag) == tags.end()) tags.push_back(tag);
      std::sort(tags.begin(), tags.end());
      for (std::int32_t tag : tags) {
        std::vector<Index> on;
        for (Index v : q)
          if (on_tag(v, tag)) on.push_back(v);
        if (on.size() < 3) continue;
        if (on.size() == 3) {
          Key3 key{on[0], on[1], on[2]};
          std::sort(key.begin(), key.end());
          const auto it = face_tag.find(key);
          if (it != face_tag.end() && it->second == tag) continue;
        }
        std::vector<std::tuple<bool, double, Index, Index>> ranked;
        for (std::size_t i = 0; i < on.size(); ++i)
          for (std::size_t j = i + 1; j < on.size(); ++j) {
            const Index a = std::min(on[i], on[j]), b = std::max(on[i], on[j]);
            const auto it = edge_tags.find({a, b});
            const bool boundary = it != edge_tags.end();
            if (boundary && std::find(it->second.begin(), it->second.end(), tag) != it->second.end()) continue;
            ranked.emplace_back(boundary, -size_.length(a, b), a, b);
          }
        std::sort(ranked.begin(), ranked.end());
        std::vector<std::array<Index, 2>> edges;
        for (const auto& r : ranked) edges.push_back({std::get<2>(r), std::get<3>(r)});
        out.emplace_back(t, std::move(edges));
        break;
      }
    }
    return out;
  }

  static constexpr double kTagSplitMinDihedral = 1.0;  // degrees

  void separate_face_tags() {
    for (int pass = 0; pass < 16; ++pass) {
      poll_refine(o_, "separating CAD faces", 0.9);
      std::int64_t done = 0;
      // A split may not make a tet flatter than kTagSplitMinDihedral: where the face is flat
      // (a plane, a nearly flat strip) the midpoint of an interior edge between two of its
      // points lies on it, and splitting there made flat tets on the face instead of mending
      // one (part.step: 0.0025 degrees). Then a new interior point above the tet
      // (MeshOptimizer::insert_for).
      for (const auto& [t, edges] : tag_conflicts()) {
        bool mended = false;
        // split_edge bounds new tets by min(this, the worst old tet): a flat conflict tet gets
        // no split (it would only make more flat tets), only insert_for below (MeshOptimizer)
        const bool flat = m_.tet_alive(t) && m_.tet_quality(t) < kTagSplitMinDihedral;
        for (const auto& e : edges)
          if (!flat && m_.point_alive(e[0]) && m_.point_alive(e[1]) && size_.split(e[0], e[1], kTagSplitMinDihedral, st_)) {
            ++st_.tag_splits;
            mended = true;
            break;
          }
        if (!mended && m_.tet_alive(t) && opt_.insert_for(t)) {
          ++st_.tag_splits;
          mended = true;
        }
        if (mended) ++done;
      }
      if (done == 0) break;
    }
    st_.tag_conflicts_left = static_cast<std::int64_t>(tag_conflicts().size());
  }

  RefineMesh& m_;
  const RefineOptions& o_;
  RefineStats& st_;
  TargetSizes size_;
  MeshOptimizer opt_;
  SizeRefiner sizing_;
  CurvedRoom curved_;
  Index tets_after_size_ = 0;  ///< live tets after the first size phase (MeshOptimizer::optimize)
};


}  // namespace

TetMesh refine_quality(const SurfaceMesh& surface, const TetMesh& mesh, const RefineOptions& options,
                       RefineStats* stats, SurfaceMesh* boundary) {
  const auto start = std::chrono::steady_clock::now();
  check_options(options);
  RefineStats st;
  auto m = std::make_unique<RefineMesh>(surface, mesh, options.projection, options.surface_points);
  m->set_fixed_tags(options.fixed_tags);
  m->set_sliding_points(options.sliding_points);
  Refiner(*m, options, st).run();
  TetMesh out;
  if (options.order == 2) {
    // The tet10 lift; when it straightened mid-nodes, once more from the linear mesh as it was,
    // with room made for the curved elements first (curved_room.h), keeping the better one.
    auto lift = [&](RefineMesh& mesh, SecondOrderStats* so_out, RefineStats& timed) {
      const auto lift_start = std::chrono::steady_clock::now();
      TetMesh lifted = make_second_order(mesh, options.projection, so_out);
      timed.seconds_by_pass["tet10"] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - lift_start).count();
      return lifted;
    };
    std::unique_ptr<RefineMesh> before;
    if (options.projection) before = std::make_unique<RefineMesh>(*m);
    SecondOrderStats so;
    out = lift(*m, &so, st);
    if (so.straightened > 0 && before) {
      RefineStats st2 = st;
      Refiner(*before, options, st2).make_room_for_curving();
      SecondOrderStats so2;
      TetMesh out2 = lift(*before, &so2, st2);
      if (so2.straightened < so.straightened) {
        m = std::move(before);
        out = std::move(out2);
        so = so2;
        st = st2;
      } else {
        st.seconds_by_pass = st2.seconds_by_pass;  // the time was spent either way
      }
    }
    st.midnodes_projected = so.projected;
    st.midnodes_straightened = so.straightened;
    st.midnodes_relaxed_tets = so.relaxed;
    st.midnodes_moved_interior = so.interior_moved;
    st.midnodes_moved_surface = so.surface_moved;
    st.lift_insertions = so.points_inserted;
    if (so.points_inserted > 0) st.worst_deg = m->worst_tet_quality();  // its points made new tets
  }
  // The linear mesh once: the order-1 result, the corner count, and the numbering of the result
  // (make_second_order's corners too) for the boundary.
  std::vector<Index> old_to_new;
  TetMesh linear = m->to_tet_mesh(&old_to_new);
  st.points = linear.num_points();
  if (options.order != 2) out = std::move(linear);
  if (boundary) {
    *boundary = SurfaceMesh{};
    for (const auto& [face, parent] : m->boundary_faces()) {
      for (Index v : face) boundary->tri.push_back(old_to_new[static_cast<std::size_t>(v)]);
      boundary->tag.push_back(m->tag_of(parent));
    }
  }
  st.tets = out.num_tets();
  st.nodes = out.num_points();
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) *stats = st;
  return out;
}

}  // namespace bsptet
