// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage's polish that keeps room for curved tet10 elements (curved_room.h).
#include "bsptet/refine/curved_room.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "bsptet/mesh/tet_shape.h"
#include "bsptet/refine/tet10.h"

namespace bsptet {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// polish stops after this many rounds in a row that did not raise the mesh's worst tet, and after
// kPolishMaxRounds in all.
constexpr int kPolishPatienceRounds = 4;
constexpr int kPolishMaxRounds = 64;
// lift first makes room for curved elements without a tet below this (or below the worst tet a
// change replaces), then goes down to 1 degree.
constexpr double kCurvingGoodDeg = 10.0;

}  // namespace

// Tries to make the invalid curved element t valid by changing the connectivity around it: 2-3
// flips of its interior faces, 3-2 flips and removals of its interior edges, then collapses of
// its interior Steiner corners onto a neighbour. A change is applied when it lowers the number of invalid
// curved elements among the tets it replaces and none of its new tets is below min(floor_deg_,
// the worst old tet's) (as the lifts below). The surface never changes. True when one was made.
template <class CurvedOk, class Corners>
bool CurvedRoom::reconnect_for_curving(Index t, const CurvedOk& curved_ok, const Corners& corners) {
  static const int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  const TetsAccept accept = [&](const std::vector<std::array<Index, 4>>& removed,
                                const std::vector<std::array<Index, 4>>& created) {
    int bad_before = 0;
    double worst_before = 180;
    for (const auto& r : removed) {
      const auto P = corners(r);
      bad_before += !curved_ok(r, P);
      worst_before = std::min(worst_before, tet_min_dihedral_deg(P[0], P[1], P[2], P[3]));
    }
    const double floor_deg = std::min(floor_deg_, worst_before);
    int bad_after = 0;
    for (const auto& c : created) {
      const auto P = corners(c);
      if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) < floor_deg) return false;
      bad_after += !curved_ok(c, P);
      if (bad_after >= bad_before) return false;
    }
    return bad_after < bad_before;
  };
  const auto q = m_.tet(t);
  for (int k = 0; k < 4; ++k)
    if (m_.flip23(t, k, accept)) {
      ++st_.flips23;
      return true;
    }
  for (const auto& e : kEdge)
    if (m_.flip32(q[e[0]], q[e[1]], accept)) {
      ++st_.flips32;
      return true;
    }
  for (const auto& e : kEdge)
    if (m_.remove_edge(q[e[0]], q[e[1]], MeshOptimizer::kMaxEdgeRing, accept, 4)) {
      ++st_.edge_removals;
      return true;
    }
  for (int k = 0; k < 4; ++k) {
    const Index d = q[k];
    if (m_.support(d).kind != Support::kInterior) continue;
    std::vector<Index> nbrs;
    for (Index s : m_.tets_around_point(d))
      for (Index w : m_.tet(s))
        if (w != d) nbrs.push_back(w);
    std::sort(nbrs.begin(), nbrs.end());
    nbrs.erase(std::unique(nbrs.begin(), nbrs.end()), nbrs.end());
    for (Index w : nbrs)
      if (m_.collapse_edge(d, w, 0.0, kInf, accept)) {
        ++st_.collapses;
        return true;
      }
  }
  return false;
}

// The fallback of curved_room.h. With a projection hook and order 2, each boundary mid-node goes
// onto the true surface, off its chord by the chord's sag. A tet whose interior apex stands lower
// over its boundary face than that sag becomes an invalid curved element with straight interior
// mid-nodes. Such apexes (interior Steiner points only) are lifted towards the height of a
// regular tet over the face, when every tet around stays positive (exact), the number of invalid
// curved elements around goes down, and no tet around drops below min(floor_deg_, the worst
// before): a valid curved mesh is worth a worse linear angle there. Failing that, a new interior
// point above one of the tet's faces (Bowyer-Watson), accepted when all its new tets are valid
// curved elements of at least floor_deg_. All this runs twice: first with floor_deg_ =
// kCurvingGoodDeg, then with 1 degree for the elements that first pass left. Splitting the
// sagging edges instead was tried and made more invalid elements (docs/design/quality-stage.md).
// Sets curving_conflicts_left.
void CurvedRoom::lift() {
  if (!o_.projection || o_.order != 2) return;
  prepare_check();
  // First no new tet below kCurvingGoodDeg (or the worst a change replaces); then down to
  // 1 degree for what that left.
  for (double floor_deg : {kCurvingGoodDeg, 1.0}) {
    floor_deg_ = floor_deg;
    lift_rounds();
  }
}

void CurvedRoom::lift_rounds() {
  constexpr auto& kFace = kTetOppositeFace;  // types.h
  auto curved_ok = [&](const std::array<Index, 4>& q, const std::array<Vec3, 4>& P) {
    return element_ok(q, P);
  };
  auto corners = [&](const std::array<Index, 4>& q) {
    return std::array<Vec3, 4>{m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3])};
  };
  for (int round = 0; round < 6; ++round) {
    poll_refine(o_, "making room for curved tet10 elements", 0.95);
    std::vector<Index> bad;
    for (Index t = 0; t < m_.num_tet_slots(); ++t)
      if (m_.tet_alive(t) && !curved_ok(m_.tet(t), corners(m_.tet(t)))) bad.push_back(t);
    st_.curving_conflicts_left = static_cast<std::int64_t>(bad.size());
    if (bad.empty()) return;
    std::int64_t lifted = 0;
    for (Index t : bad) {
      if (!m_.tet_alive(t) || curved_ok(m_.tet(t), corners(m_.tet(t)))) continue;
      const auto q = m_.tet(t);
      bool done = reconnect_for_curving(t, curved_ok, corners);
      if (done) ++lifted;
      for (int k = 0; k < 4 && !done; ++k) {
        const Index d = q[k];
        if (m_.support(d).kind != Support::kInterior) continue;
        const Vec3& D = m_.point(d);
        FaceFrame fr;
        if (!face_frame(m_.point(q[kFace[k][0]]), m_.point(q[kFace[k][1]]), m_.point(q[kFace[k][2]]), D, &fr))
          continue;
        const std::vector<Index> ball = m_.tets_around_point(d);
        int bad_before = 0;
        double worst_before = 180;
        for (Index s2 : ball) {
          bad_before += !curved_ok(m_.tet(s2), corners(m_.tet(s2)));
          worst_before = std::min(worst_before, m_.tet_quality(s2));
        }
        const double floor_deg = std::min(floor_deg_, worst_before);
        // Targets in order: towards the apex of a regular tet over the face at 1, 0.75, 0.5,
        // 0.35 and 0.25 of its height, all the way or half way; then small lifts straight up
        // from the face's plane by 1, 3 or 7 times the apex's own height (over a long needle
        // face even a quarter of a regular tet's height moves the apex too far for the tets
        // around it).
        std::vector<Vec3> targets;
        for (double f : {1.0, 0.75, 0.5, 0.35, 0.25}) {
          const Vec3 full = fr.apex(f);
          for (double lambda : {1.0, 0.5})
            targets.push_back({D.x + lambda * (full.x - D.x), D.y + lambda * (full.y - D.y), D.z + lambda * (full.z - D.z)});
        }
        const double height = (D.x - fr.centroid.x) * fr.normal.x + (D.y - fr.centroid.y) * fr.normal.y +
                              (D.z - fr.centroid.z) * fr.normal.z;
        if (height > 0)
          for (double times : {1.0, 3.0, 7.0})
            targets.push_back({D.x + times * height * fr.normal.x, D.y + times * height * fr.normal.y,
                               D.z + times * height * fr.normal.z});
        auto accept = [&](const std::vector<std::array<Vec3, 4>>& moved) {
          int bad_after = 0;
          double w = 180;
          for (std::size_t i = 0; i < moved.size(); ++i) {
            const auto& c4 = moved[i];
            w = std::min(w, tet_min_dihedral_deg(c4[0], c4[1], c4[2], c4[3]));
            bad_after += !curved_ok(m_.tet(ball[i]), c4);
          }
          return w >= floor_deg && bad_after < bad_before;
        };
        for (const Vec3& target : targets) {
          if (m_.relocate_point_if(d, target, accept)) {
            ++st_.curving_lifts;
            ++lifted;
            done = true;
            break;
          }
        }
      }
      // Else a new interior point above each face of the tet, Bowyer-Watson, accepted when its
      // new tets are all valid curved elements of at least floor_deg_.
      for (int k = 0; k < 4 && !done; ++k) {
        const Vec3& D = m_.point(q[k]);
        FaceFrame fr;
        if (!face_frame(m_.point(q[kFace[k][0]]), m_.point(q[kFace[k][1]]), m_.point(q[kFace[k][2]]), D, &fr))
          continue;
        const Vec3& G = fr.centroid;
        auto accept = [&](const std::vector<std::array<Index, 4>>& cone, const Vec3& p) {
          for (const auto& c4 : cone) {
            const std::array<Vec3, 4> P{m_.point(c4[0]), m_.point(c4[1]), m_.point(c4[2]), p};
            if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) < floor_deg_ || !curved_ok(c4, P)) return false;
          }
          return true;
        };
        // Over the face at the height of a regular tet (or less), then on the segment from the
        // face's centroid to the opposite corner (thin walls, where the first points fall out).
        std::vector<Vec3> cand;
        for (double f : {1.0, 0.5, 0.25}) cand.push_back(fr.apex(f));
        for (double lambda : {0.5, 0.33, 0.67})
          cand.push_back({G.x + lambda * (D.x - G.x), G.y + lambda * (D.y - G.y), G.z + lambda * (D.z - G.z)});
        for (const Vec3& x : cand) {
          Index np = -1;
          if (m_.insert_point(t, x, 0.05 * fr.mean_edge, &np, 256, false, accept) == InsertOutcome::kInserted) {
            ++st_.insertions;
            ++st_.curving_lifts;
            ++lifted;
            done = true;
            break;
          }
        }
      }
    }
    if (lifted == 0) return;
  }
}

// Once the surface is final: the tags of each boundary edge's faces, for the projection hook.
void CurvedRoom::prepare_check() {
  edge_tags_ = m_.boundary_edge_tags();
  projected_.release();
}

// True when the tet10 of corners q at positions P, its boundary edges' mid-nodes on the true
// surface (projection hook) and the others straight, has a Jacobian determinant certified
// positive (certify_tet10); straight elements are true at once (their corner tet is positive).
bool CurvedRoom::element_ok(const std::array<Index, 4>& q, const std::array<Vec3, 4>& P) {
  static const int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  double x[30];
  bool curved = false;
  for (int k = 0; k < 4; ++k) x[3 * k] = P[k].x, x[3 * k + 1] = P[k].y, x[3 * k + 2] = P[k].z;
  for (int e = 0; e < 6; ++e) {
    const int i = kEdge[e][0], j = kEdge[e][1];
    Vec3 mid{0.5 * (P[i].x + P[j].x), 0.5 * (P[i].y + P[j].y), 0.5 * (P[i].z + P[j].z)};
    const std::uint64_t key = edge_key(q[i], q[j]);
    if (const auto* tt = edge_tags_.find(key)) {
      Vec3* pr = projected_.find(key);  // boundary points never move: a safe cache
      if (!pr) {
        Vec3 y = o_.projection(mid, (*tt)[0], (*tt)[1] != (*tt)[0] ? (*tt)[1] : -1);
        if (!std::isfinite(y.x) || !std::isfinite(y.y) || !std::isfinite(y.z)) y = mid;
        pr = &(projected_[key] = y);
      }
      curved = curved || squared_distance(*pr, mid) > 0;
      mid = *pr;
    }
    x[3 * (4 + e)] = mid.x, x[3 * (4 + e) + 1] = mid.y, x[3 * (4 + e) + 2] = mid.z;
  }
  return !curved || certify_tet10(x) == Tet10Validity::kCertified;
}

// Curved tet10 through a hook: the tets below `below` degrees, worst first, get 3-2 and 2-3
// flips, edge removals, moves of their interior corners (towards their neighbours' centroid, then
// steepest ascent), collapses of their interior Steiner corners and new interior points
// (insert_keeping_curved). A change is applied when the worst tet it makes is better than the
// worst it replaces and the curved elements it makes invalid are not more than those it removes.
// Input points and the surface never move. Rounds while something changes and the mesh's worst
// tet rose in one of the last kPolishPatienceRounds rounds (at most kPolishMaxRounds); returns the
// changes made. No change lowers the worst tet it replaces, so the mesh's worst never drops here.
// Then counts the invalid curved elements left (curving_conflicts_left).
std::int64_t CurvedRoom::polish(double below) {
  if (!o_.projection || o_.order != 2) return 0;
  prepare_check();
  const TetsAccept accept = [&](const std::vector<std::array<Index, 4>>& removed,
                                const std::vector<std::array<Index, 4>>& created) {
    double worst_before = 180;
    int bad_before = 0;
    for (const auto& r : removed) {
      const auto P = corner_points(m_, r);
      worst_before = std::min(worst_before, tet_min_dihedral_deg(P[0], P[1], P[2], P[3]));
      bad_before += !element_ok(r, P);
    }
    std::vector<std::array<Vec3, 4>> made;
    made.reserve(created.size());
    for (const auto& c : created) {
      made.push_back(corner_points(m_, c));
      const auto& P = made.back();
      if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) <= worst_before) return false;
    }
    int bad_after = 0;
    for (std::size_t i = 0; i < created.size(); ++i)
      if (!element_ok(created[i], made[i]) && ++bad_after > bad_before) return false;
    return true;
  };
  std::int64_t changes = 0;
  double worst = m_.worst_tet_quality();
  for (int round = 0, idle = 0; round < kPolishMaxRounds && idle < kPolishPatienceRounds; ++round) {
    poll_refine(o_, "optimizing curved elements", 0.97);
    std::int64_t now = 0;
    for (Index t : opt_.tets_below(below)) {
      if (!m_.tet_alive(t) || m_.tet_quality(t) >= below) continue;
      const auto q = m_.tet(t);
      bool done = false;
      for (int i = 0; i < 4 && !done; ++i)
        for (int j = i + 1; j < 4 && !done; ++j)
          if (m_.flip32(q[i], q[j], accept)) {
            ++st_.flips32;
            done = true;
          }
      for (int k = 0; k < 4 && !done; ++k)
        if (m_.flip23(t, k, accept)) {
          ++st_.flips23;
          done = true;
        }
      for (int i = 0; i < 4 && !done; ++i)
        for (int j = i + 1; j < 4 && !done; ++j)
          if (m_.remove_edge(q[i], q[j], MeshOptimizer::kMaxEdgeRing, accept, 4)) {
            ++st_.edge_removals;
            done = true;
          }
      for (int k = 0; k < 4 && !done; ++k)
        if (move_keeping_curved(q[k])) {
          ++st_.relocations;
          done = true;
        }
      for (int k = 0; k < 4 && !done; ++k) {
        const Index from = q[k];
        if (m_.support(from).kind != Support::kInterior) continue;
        std::vector<std::pair<double, Index>> near;
        for (Index s2 : m_.tets_around_point(from))
          for (Index w : m_.tet(s2))
            if (w != from) near.emplace_back(size_.length(from, w), w);
        std::sort(near.begin(), near.end());
        near.erase(std::unique(near.begin(), near.end()), near.end());
        for (const auto& [l, to] : near) {
          const double lim = o_.split_ratio * size_.target(to);
          if (m_.collapse_edge(from, to, 0.0, std::isfinite(lim) ? lim * lim : kInf, accept)) {
            ++st_.collapses;
            done = true;
            break;
          }
        }
      }
      if (!done && insert_keeping_curved(t)) {
        ++st_.insertions;
        done = true;
      }
      now += done;
    }
    changes += now;
    if (now == 0) break;
    const double now_worst = m_.worst_tet_quality();
    idle = now_worst > worst ? 0 : idle + 1;
    worst = now_worst;
  }
  st_.curving_conflicts_left = 0;
  for (Index t = 0; t < m_.num_tet_slots(); ++t)
    if (m_.tet_alive(t) && !element_ok(m_.tet(t), corner_points(m_, m_.tet(t)))) ++st_.curving_conflicts_left;
  return changes;
}

// A new interior point for tet t (Bowyer-Watson, t forced into the cavity, the smallest angle
// of the new tets above the replaced ones', every new curved element valid): above each face
// of t at 1, 1/2 and 1/4 of a regular tet's height, then its circumcentre and centroid; no
// point closer than a quarter of t's mean edge to a corner of its cavity. What lifts a flat
// tet whose four corners lie on the surface, which no flip mends. True when one went in.
bool CurvedRoom::insert_keeping_curved(Index t) {
  constexpr auto& kFace = kTetOppositeFace;  // types.h
  const auto q = m_.tet(t);
  const auto P = corner_points(m_, q);
  double mean = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) mean += size_.length(q[i], q[j]) / 6;
  std::vector<Vec3> cand;
  for (int k = 0; k < 4; ++k) {
    FaceFrame fr;
    if (face_frame(P[kFace[k][0]], P[kFace[k][1]], P[kFace[k][2]], P[k], &fr))
      for (double f : {1.0, 0.5, 0.25}) cand.push_back(fr.apex(f));
  }
  Vec3 cc;
  double r2 = 0;
  if (tet_circumsphere(P[0], P[1], P[2], P[3], &cc, &r2)) cand.push_back(cc);
  cand.push_back({(P[0].x + P[1].x + P[2].x + P[3].x) / 4, (P[0].y + P[1].y + P[2].y + P[3].y) / 4,
                  (P[0].z + P[1].z + P[2].z + P[3].z) / 4});
  auto accept = [&](const std::vector<std::array<Index, 4>>& cone, const Vec3& p) {
    for (const auto& c4 : cone) {
      const std::array<Vec3, 4> C{m_.point(c4[0]), m_.point(c4[1]), m_.point(c4[2]), p};
      if (!element_ok(c4, C)) return false;
    }
    return true;
  };
  for (const Vec3& x : cand) {
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) continue;
    Index np = -1;
    if (m_.insert_point(t, x, 0.25 * mean, &np, 256, true, accept, t) == InsertOutcome::kInserted) {
      size_.set_target(np, 0.25 * (size_.target(q[0]) + size_.target(q[1]) + size_.target(q[2]) + size_.target(q[3])));
      return true;
    }
  }
  return false;
}

// Moves interior point v where the worst tet around it gets better and no curved element
// around it becomes invalid that was valid: towards its neighbours' centroid (all, half, a
// quarter, a tenth of the way), then steepest ascent (ascend_point). True when v moved.
bool CurvedRoom::move_keeping_curved(Index v) {
  if (!m_.point_alive(v) || m_.support(v).kind != Support::kInterior) return false;
  const std::vector<Index> ball = m_.tets_around_point(v);
  double worst_before = 180;
  int bad_before = 0;
  Vec3 c{0, 0, 0};
  int k = 0;
  double mean_edge = 0;
  for (Index t : ball) {
    worst_before = std::min(worst_before, m_.tet_quality(t));
    bad_before += !element_ok(m_.tet(t), corner_points(m_, m_.tet(t)));
    for (Index w : m_.tet(t))
      if (w != v) {
        c.x += m_.point(w).x, c.y += m_.point(w).y, c.z += m_.point(w).z;
        mean_edge += size_.length(v, w);
        ++k;
      }
  }
  if (k == 0) return false;
  c = {c.x / k, c.y / k, c.z / k};
  mean_edge /= k;
  const MoveAccept accept = [&](const std::vector<std::array<Vec3, 4>>& moved) {
    for (const auto& P : moved)
      if (tet_min_dihedral_deg(P[0], P[1], P[2], P[3]) <= worst_before) return false;
    int bad_after = 0;
    for (std::size_t i = 0; i < moved.size(); ++i)
      if (!element_ok(m_.tet(ball[i]), moved[i]) && ++bad_after > bad_before) return false;
    return true;
  };
  const Vec3 p = m_.point(v);
  for (double f : {1.0, 0.5, 0.25, 0.1})
    if (m_.relocate_point_if(v, {p.x + f * (c.x - p.x), p.y + f * (c.y - p.y), p.z + f * (c.z - p.z)}, accept))
      return true;
  return opt_.ascend_point(v, mean_edge, &accept);
}

}  // namespace bsptet
