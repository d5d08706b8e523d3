// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: nodes along a CAD edge at the size field.
//
//   EdgeSizing sample_edge_sizing(edge, base_size, field)
//   std::vector<double> place_edge_nodes(sizing, size_at_start, size_at_end, grading, min_segments)
//
// The edge is taken FORWARD: parameters increase from its first vertex to its last. The number of
// segments N is the rounded integral of 1 / size along the arc length (at least min_segments), and
// the nodes split that integral into N equal parts, so segment lengths follow the size field. The
// size along the edge is the base size (the smallest size of the faces around the edge), lowered
// by the curve's curvature and graded from the sizes asked at its two ends.
#pragma once

#include <vector>

#include <TopoDS_Edge.hxx>

#include "bsptet/cad/size_field.h"

namespace bsptet::cad {

/// Fine samples of one edge: parameter, arc length from the first vertex, size there.
struct EdgeSizing {
  std::vector<double> t, arc, size;
  double length() const { return arc.empty() ? 0 : arc.back(); }
};

/// Samples a non-degenerated edge: at least 64 samples, more on long edges relative to min_size.
EdgeSizing sample_edge_sizing(const TopoDS_Edge& edge, double base_size, const SizeField& field);

/// Parameters of the nodes (first and last parameter included, increasing), after grading the
/// sizes from the two ends (size_at_start at the first vertex, size_at_end at the last).
std::vector<double> place_edge_nodes(EdgeSizing& sizing, double size_at_start, double size_at_end,
                                     double grading, int min_segments);

}  // namespace bsptet::cad
