// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: edge discretization (see edge_mesher.h).
#include "bsptet/cad/edge_mesher.h"

#include <algorithm>
#include <cmath>

#include <BRepAdaptor_Curve.hxx>
#include <TopAbs_Orientation.hxx>
#include <TopoDS.hxx>
#include <gp_Pnt.hxx>

namespace bsptet::cad {

EdgeSizing sample_edge_sizing(const TopoDS_Edge& edge, double base_size, const SizeField& field) {
  const TopoDS_Edge forward = TopoDS::Edge(edge.Oriented(TopAbs_FORWARD));
  BRepAdaptor_Curve curve(forward);
  const double t0 = curve.FirstParameter(), t1 = curve.LastParameter();
  auto sample = [&](int n, EdgeSizing& out) {
    out.t.resize(static_cast<std::size_t>(n) + 1);
    out.arc.resize(out.t.size());
    out.size.resize(out.t.size());
    gp_Pnt previous;
    for (int i = 0; i <= n; ++i) {
      const double t = t0 + (t1 - t0) * i / n;
      const gp_Pnt p = curve.Value(t);
      out.t[static_cast<std::size_t>(i)] = t;
      out.arc[static_cast<std::size_t>(i)] = i == 0 ? 0 : out.arc[static_cast<std::size_t>(i) - 1] + p.Distance(previous);
      out.size[static_cast<std::size_t>(i)] = field.clamp(std::min(base_size, field.curve_curvature_size(curve, t)));
      previous = p;
    }
  };
  EdgeSizing sizing;
  sample(64, sizing);
  // Enough samples that every segment of the smallest size spans several of them.
  const double smallest = *std::min_element(sizing.size.begin(), sizing.size.end());
  const int wanted = static_cast<int>(std::min(20000.0, std::ceil(8 * sizing.length() / std::max(smallest, 1e-300))));
  if (wanted > 64) sample(wanted, sizing);
  return sizing;
}

std::vector<double> place_edge_nodes(EdgeSizing& sizing, double size_at_start, double size_at_end, double grading,
                                     int min_segments) {
  const std::size_t n = sizing.t.size();
  const double length = sizing.length();
  for (std::size_t i = 0; i < n; ++i) {
    const double from_start = size_at_start + grading * sizing.arc[i];
    const double from_end = size_at_end + grading * (length - sizing.arc[i]);
    sizing.size[i] = std::min(sizing.size[i], std::min(from_start, from_end));
  }
  // Integral of 1 / size over the arc length (trapezoids).
  std::vector<double> integral(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) {
    const double ds = sizing.arc[i] - sizing.arc[i - 1];
    integral[i] = integral[i - 1] + 0.5 * ds * (1 / sizing.size[i] + 1 / sizing.size[i - 1]);
  }
  const int segments = std::max(min_segments, static_cast<int>(std::lround(integral.back())));
  std::vector<double> params;
  params.reserve(static_cast<std::size_t>(segments) + 1);
  params.push_back(sizing.t.front());
  std::size_t j = 1;
  for (int k = 1; k < segments; ++k) {
    const double target = integral.back() * k / segments;
    while (j + 1 < n && integral[j] < target) ++j;
    const double span = integral[j] - integral[j - 1];
    const double w = span > 0 ? (target - integral[j - 1]) / span : 0.5;
    params.push_back(sizing.t[j - 1] + w * (sizing.t[j] - sizing.t[j - 1]));
  }
  params.push_back(sizing.t.back());
  return params;
}

}  // namespace bsptet::cad
