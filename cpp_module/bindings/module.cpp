// SPDX-License-Identifier: LGPL-2.1-or-later
// pybind11 bindings of the FemBspTet core: `FemBspTet._bsptet`, everything but the FEM pipeline
// from CAD (cad_module.cpp, `_bsptet_cad`): it links no OpenCASCADE, so a triangle surface
// meshes without loading it. Converts and validates only; the public Python API lives in
// FemBspTet/kernel/core.py. Messages name the expected array shapes.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

#include "binding_support.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/core/mesher.h"
#include "bsptet/pieces/out_of_core.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/input/surface_check.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/tet10.h"

namespace py = pybind11;
using namespace bsptet;
using namespace bsptet::bindings;

namespace {

py::dict quality_dict(const QualityStats& q) {
  py::dict d;
  d["tets"] = q.tets;
  d["min_dihedral_deg"] = q.min_dihedral_deg;
  d["max_dihedral_deg"] = q.max_dihedral_deg;
  d["p1_dihedral_deg"] = q.p1_dihedral_deg;
  d["median_dihedral_deg"] = q.median_dihedral_deg;
  d["median_tet_min_dihedral_deg"] = q.median_tet_min_dihedral_deg;
  d["max_radius_edge_ratio"] = q.max_radius_edge_ratio;
  d["median_radius_edge_ratio"] = q.median_radius_edge_ratio;
  d["dihedral_histogram"] = q.dihedral_histogram;
  return d;
}

SurfaceMesh surface_from(const DoubleArray& points, const IndexArray& triangles, const char* points_name = "points",
                         const char* triangles_name = "triangles") {
  SurfaceMesh s;
  s.xyz = points_from(points, points_name);
  s.tri = indices_from(triangles, triangles_name, 3);
  return s;
}

TetMesh tetmesh_from(const DoubleArray& points, const IndexArray& tets) {
  TetMesh m;
  m.xyz = points_from(points, "points");
  m.tet = indices_from(tets, "tets", 4, 10);
  m.nodes_per_tet = (tets.ndim() == 2 && tets.shape(1) == 10) ? 10 : 4;
  return m;
}

// The statistics dict of a run in pieces (out_of_core.h PieceStats).
py::dict piece_stats_dict(const PieceStats& ps, std::int64_t max_piece_triangles) {
  py::dict d;
  d["pieces"] = ps.pieces;
  d["cuts"] = ps.cuts;
  d["cuts_refused"] = ps.cuts_refused;
  d["cap_triangles"] = ps.cap_triangles;
  d["cap_points"] = ps.cap_points;
  d["largest_piece_triangles"] = ps.largest_piece_triangles;
  d["max_piece_triangles"] = max_piece_triangles;
  d["points"] = ps.points;
  d["tets"] = ps.tets;
  d["steiner_points"] = ps.steiner_points;
  d["pieces_checked"] = ps.pieces_checked;
  d["seconds_cutting"] = ps.seconds_cutting;
  d["seconds_meshing"] = ps.seconds_meshing;
  d["seconds_writing"] = ps.seconds_writing;
  d["uncut"] = ps.uncut;
  return d;
}

// MeshOptions as the bindings take it, refused when out of range.
const MeshOptions& checked_core_options(const MeshOptions& o) {
  if (o.steiner_effort < 0) throw py::value_error("steiner_effort must be >= 0 (0: no bound)");
  return o;
}

// The statistics dicts, built from the schemas (core/mesher.h for_each_mesh_stat;
// refine/quality_refine.h for_each_refine_stat where refine_quality is bound).
py::dict mesh_stats_dict(const MeshStats& st) {
  py::dict d;
  for_each_mesh_stat([&](const char* key, auto member) { d[key] = st.*member; });
  d["interior_steiner_points"] = st.steiner_points - st.boundary_steiner_points;
  d["bsp_seed"] = st.delaunay_seeded ? "delaunay" : "box";  // what the mesh came from
  return d;
}

}  // namespace

PYBIND11_MODULE(_bsptet, m) {
  m.doc() = "FemBspTet C++ core (private; use FemBspTet.core)";
  m.attr("__version__") = FEMBSPTET_VERSION;

  // Core errors reach Python as these types; FemBspTet.core turns them into FemBspTet.errors.
  static py::exception<void> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<void> meshing_error(m, "MeshingError", PyExc_RuntimeError);
  // Shared with _bsptet_cad (binding_support.h translate_core_errors).
  static const ErrorTypes error_types{input_error, meshing_error};
  py::register_exception_translator([](std::exception_ptr p) { translate_core_errors(p, error_types); });

  {
    // The core's options schema (core/mesher.h for_each_mesh_option), as a class; picklable (a
    // cluster's workers get it with each piece).
    py::enum_<MeshOptions::Seed>(m, "BspSeed", "What the BSP starts from (mesher.h MeshOptions::seed).")
        .value("auto", MeshOptions::Seed::kAuto)
        .value("delaunay", MeshOptions::Seed::kDelaunay)
        .value("box", MeshOptions::Seed::kBox);
    auto options = bind_options<MeshOptions>(m, "MeshOptions", "Options of the exact core (mesher.h MeshOptions).",
                                             [](auto&& f) { for_each_mesh_option(f); });
    options.def(py::pickle(
        [](const MeshOptions& o) {
          py::dict d;
          for_each_mesh_option([&](const char* name, auto member) { d[name] = o.*member; });
          return d;
        },
        [](const py::dict& d) {
          MeshOptions o;
          for_each_mesh_option([&](const char* name, auto member) {
            if (d.contains(name)) o.*member = d[name].template cast<std::decay_t<decltype(o.*member)>>();
          });
          return o;
        }));
  }

  m.def(
      "tetrahedralize",
      [](const DoubleArray& points, const IndexArray& triangles, const MeshOptions& options, py::object progress,
         py::object cancel, py::object check) {
        const SurfaceMesh s = surface_from(points, triangles);
        MeshOptions o = checked_core_options(options);
        TetMesh mesh;
        MeshStats st;
        if (check.is_none()) {
          run_without_gil(o, progress, cancel, [&]() { mesh = tetrahedralize(s, o, &st); });
        } else {
          const py::dict c = check.cast<py::dict>();
          SurfaceCheckOptions co;
          co.reorient = c.contains("reorient") && c["reorient"].cast<bool>();
          if (c.contains("max_reported_pairs")) co.max_reported_pairs = c["max_reported_pairs"].cast<std::int64_t>();
          run_without_gil(o, progress, cancel, [&]() { mesh = check_and_tetrahedralize(s, co, o, &st); });
        }
        py::dict d = mesh_stats_dict(st);
        return py::make_tuple(points_array(mesh), tets_array(mesh), d);
      },
      py::arg("points"), py::arg("triangles"), py::arg("options") = MeshOptions{},
      py::arg("progress") = py::none(), py::arg("cancel") = py::none(), py::arg("check") = py::none(),
      "Tetrahedralizes the solid bounded by a closed triangle surface (see mesher.h). Returns "
      "(points (n, 3), tets (m, 4), stats dict). Raises InputError (bad surface) or MeshingError. "
      "options: a MeshOptions (allow_boundary_steiner; cone_cells: fill cells by cones, for comparison; "
      "steiner_effort: work the core may spend removing one interior Steiner point, 0: no bound; seed: "
      "BspSeed.auto, .delaunay (the BSP starts from the Delaunay tetrahedralization of the input points) "
      "or .box (one box cell, the paper's auto-partition); stats['bsp_seed'] says which one the mesh "
      "came from). "
      "check: None, or a dict (reorient, max_reported_pairs) to check the surface as check_surface "
      "does, its self-intersection search beside the core (mesher.h check_and_tetrahedralize; the mesh "
      "is made from the checked triangles, re-oriented when reorient is set).");

  // The out-of-core mode (out_of_core.h).
  m.def(
      "tetrahedralize_in_pieces",
      [](const DoubleArray& points, const IndexArray& triangles, const std::string& stem,
         std::int64_t max_piece_triangles, py::object progress, py::object cancel, const MeshOptions& options,
         bool check_pieces, int workers) {
        const SurfaceMesh s = surface_from(points, triangles);
        MeshOptions o = checked_core_options(options);
        PieceOptions po;
        po.max_piece_triangles = max_piece_triangles;
        po.check_pieces = check_pieces;
        po.workers = workers;
        PieceStats ps;
        run_without_gil(o, progress, cancel, [&]() { tetrahedralize_in_pieces(s, o, po, stem, &ps); });
        return piece_stats_dict(ps, max_piece_triangles);
      },
      py::arg("points"), py::arg("triangles"), py::arg("stem"), py::arg("max_piece_triangles"),
      py::arg("progress") = py::none(), py::arg("cancel") = py::none(), py::arg("options") = MeshOptions{},
      py::arg("check_pieces") = true, py::arg("workers") = 1,
      "Meshes the solid bounded by a checked closed surface in pieces of at most max_piece_triangles "
      "triangles, `workers` of them at a time on threads, streaming the mesh to stem.node / stem.ele "
      "(see out_of_core.h; the same mesh for every `workers`). Returns a stats dict. Raises InputError "
      "or MeshingError; nothing is written then.");

  // The steps of tetrahedralize_in_pieces, for engines that mesh the pieces elsewhere.
  m.def(
      "cut_into_pieces",
      [](const DoubleArray& points, const IndexArray& triangles, std::int64_t max_piece_triangles, py::object cancel,
         int workers) {
        const SurfaceMesh s = surface_from(points, triangles);
        MeshOptions o;
        PieceOptions po;
        po.max_piece_triangles = max_piece_triangles;
        po.workers = workers;
        PieceStats ps;
        SolidPieces solid;
        run_without_gil(o, py::none(), cancel, [&]() { solid = cut_into_pieces(s, o, po, &ps); });
        py::array_t<double> xyz({static_cast<py::ssize_t>(solid.xyz.size() / 3), static_cast<py::ssize_t>(3)});
        std::copy(solid.xyz.begin(), solid.xyz.end(), xyz.mutable_data());
        py::list pieces;
        for (const auto& piece : solid.pieces) {
          py::array_t<std::int64_t> a({static_cast<py::ssize_t>(piece.size() / 3), static_cast<py::ssize_t>(3)});
          std::copy(piece.begin(), piece.end(), a.mutable_data());
          pieces.append(a);
        }
        const std::vector<Index> ids = merged_point_ids(solid);
        py::array_t<std::int64_t> merged_ids(static_cast<py::ssize_t>(ids.size()));
        std::copy(ids.begin(), ids.end(), merged_ids.mutable_data());
        return py::make_tuple(xyz, pieces, merged_ids, piece_stats_dict(ps, max_piece_triangles));
      },
      py::arg("points"), py::arg("triangles"), py::arg("max_piece_triangles"), py::arg("cancel") = py::none(),
      py::arg("workers") = 1,
      "Step 1 of tetrahedralize_in_pieces (out_of_core.h cut_into_pieces): returns (xyz, pieces, "
      "merged_ids, stats), xyz the input points then the caps' own points, pieces a list of (k, 3) "
      "triangle arrays over xyz, merged_ids each xyz point's id in the merged mesh (merged_point_ids; "
      "-1: unused), stats those of tetrahedralize_in_pieces with the cutting figures filled.");
  m.def(
      "mesh_piece",
      [](const DoubleArray& points, const IndexArray& triangles, const std::string& name, bool check,
         const MeshOptions& options) {
        const SurfaceMesh s = surface_from(points, triangles);
        MeshOptions o = checked_core_options(options);
        TetMesh mesh;
        run_without_gil(o, py::none(), py::none(), [&]() { mesh = mesh_piece(s, o, check, name); });
        return py::make_tuple(points_array(mesh), tets_array(mesh));
      },
      py::arg("points"), py::arg("triangles"), py::arg("name"), py::arg("check") = true,
      py::arg("options") = MeshOptions{},
      "Step 2 of tetrahedralize_in_pieces (out_of_core.h mesh_piece) on a piece's own surface: returns "
      "(points, tets), the piece's points first, then its Steiner points; checked exactly with check.");

  m.def("piece_triangles_for_workers", &piece_triangles_for_workers, py::arg("triangles"), py::arg("workers"),
        "The piece size (triangles) for `workers` pieces meshed at once (out_of_core.h).");
  m.def("piece_triangles_for_budget", &piece_triangles_for_budget, py::arg("budget_bytes"),
        "The largest piece (triangles) the out-of-core mode's estimate fits in budget_bytes (out_of_core.h).");

  // The input surface check (surface_check.h). A self-intersection raises InputError
  // with `pairs` (k, 2) and `complete` besides `code` and `index`.
  m.def(
      "check_surface",
      [](const DoubleArray& points, const IndexArray& triangles, bool reorient, bool self_intersections,
         std::int64_t max_reported_pairs) {
        const SurfaceMesh s = surface_from(points, triangles);
        SurfaceCheckOptions o;
        o.reorient = reorient;
        o.self_intersections = self_intersections;
        o.max_reported_pairs = max_reported_pairs;
        SurfaceCheckResult r;
        try {
          py::gil_scoped_release release;
          r = check_surface(s, o);
        } catch (const SelfIntersectionError& e) {
          raise_self_intersection(error_types, e);
        }
        py::array_t<std::int64_t> tri({static_cast<py::ssize_t>(r.tri.size() / 3), static_cast<py::ssize_t>(3)});
        std::copy(r.tri.begin(), r.tri.end(), tri.mutable_data());
        py::dict d;
        d["flipped_triangles"] = r.flipped_triangles;
        d["shells"] = r.shells;
        d["merged_points"] = r.merged_points;
        return py::make_tuple(tri, d);
      },
      py::arg("points"), py::arg("triangles"), py::arg("reorient") = false, py::arg("self_intersections") = true,
      py::arg("max_reported_pairs") = 1000,
      "Checks a triangle surface before meshing (see surface_check.h). Returns (triangles (m, 3) with "
      "flipped ones reversed, info dict). Raises InputError naming the first problem.");
  // ---- Quality stage: refine_quality (quality_refine.h). ----
  {
    // The options schema (quality_refine.h for_each_refine_option), as a class.
    py::enum_<SurfacePoints>(m, "SurfacePoints", "Where new surface points go without a projection hook "
                                                 "(refine_mesh.h SurfacePoints).")
        .value("exact", SurfacePoints::kExact)
        .value("rounded", SurfacePoints::kRounded);
    bind_options<RefineOptions>(m, "RefineOptions",
                                "Options of the quality stage (quality_refine.h RefineOptions): size is "
                                "FreeCAD's CharacteristicLengthMax (infinity: none).",
                                [](auto&& f) { for_each_refine_option(f); });
  }
  m.def(
      "refine",
      [](const DoubleArray& surface_points, const IndexArray& surface_triangles, py::object surface_tags,
         const DoubleArray& points, const IndexArray& tets, RefineOptions o, py::object projection,
         py::object progress, py::object cancel) {
        SurfaceMesh s;
        s.xyz = points_from(surface_points, "surface_points");
        s.tri = indices_from(surface_triangles, "surface_triangles", 3);
        if (!surface_tags.is_none()) {
          const IndexArray t = surface_tags.cast<IndexArray>();
          if (t.ndim() != 1 || t.shape(0) != static_cast<py::ssize_t>(s.tri.size() / 3))
            throw py::value_error("surface_tags must have shape (m,), one tag per surface triangle");
          for (py::ssize_t i = 0; i < t.shape(0); ++i) s.tag.push_back(static_cast<std::int32_t>(t.data()[i]));
        }
        const TetMesh mesh = tetmesh_from(points, tets);
        if (!projection.is_none())
          o.projection = [projection](const Vec3& p, std::int32_t tag, std::int32_t other) {
            py::gil_scoped_acquire gil;
            py::array_t<double> a(3);
            a.mutable_data()[0] = p.x;
            a.mutable_data()[1] = p.y;
            a.mutable_data()[2] = p.z;
            const auto r = projection(a, tag, other).cast<std::array<double, 3>>();
            return Vec3{r[0], r[1], r[2]};
          };
        TetMesh out;
        RefineStats st;
        run_without_gil(o, progress, cancel, [&]() { out = refine_quality(s, mesh, o, &st); });
        py::dict d;
        for_each_refine_stat([&](const char* key, auto member) { d[key] = st.*member; });
        return py::make_tuple(points_array(out), tets_array(out), d);
      },
      py::arg("surface_points"), py::arg("surface_triangles"), py::arg("surface_tags"), py::arg("points"),
      py::arg("tets"), py::arg("options") = RefineOptions{}, py::arg("projection") = py::none(),
      py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
      "Refines a valid tet mesh of a closed surface to a size and quality (see quality_refine.h); options: "
      "a RefineOptions. projection(point (3,), tag, other_tag) -> point moves new surface points. Returns "
      "(points, tets (m, 4) or (m, 10), stats dict).");

  // ---- Validity of 10-node tets (tet10.h). ----
  m.def(
      "tet10_certify",
      [](const DoubleArray& points, const IndexArray& tets, int max_depth, bool scaled_jacobian) {
        if (tets.ndim() != 2 || tets.shape(1) != 10)
          throw py::value_error("tets must have shape (m, 10), nodes in types.h order (n1..n4 m12 m23 m31 m14 m24 m34)");
        if (max_depth < 0 || max_depth > 10) throw py::value_error("max_depth must be in [0, 10]");
        const std::vector<double> xyz = points_from(points, "points");
        const std::vector<Index> tet = indices_from(tets, "tets", 10);
        const std::size_t np = xyz.size() / 3, nk = tet.size() / 10;
        for (std::size_t i = 0; i < tet.size(); ++i)
          if (tet[i] < 0 || static_cast<std::size_t>(tet[i]) >= np)
            throw py::value_error("tets entry " + std::to_string(i) + " = " + std::to_string(tet[i]) +
                                  " is not a point index (points has " + std::to_string(np) + " rows)");
        py::array_t<std::int8_t> status(static_cast<py::ssize_t>(nk));
        py::array_t<double> bound(static_cast<py::ssize_t>(nk));
        py::array_t<double> scaled(static_cast<py::ssize_t>(scaled_jacobian ? nk : 0));
        std::int64_t count[3] = {0, 0, 0};
        {
          std::int8_t* st = status.mutable_data();
          double* b = bound.mutable_data();
          double* sj = scaled.mutable_data();
          py::gil_scoped_release release;
          for (std::size_t t = 0; t < nk; ++t) {
            double x[30];
            for (int k = 0; k < 10; ++k)
              for (int c = 0; c < 3; ++c) x[3 * k + c] = xyz[3 * static_cast<std::size_t>(tet[10 * t + k]) + c];
            const Tet10Validity v = certify_tet10(x, max_depth, &b[t]);
            st[t] = static_cast<std::int8_t>(v);
            ++count[static_cast<int>(v)];
            if (scaled_jacobian) sj[t] = tet10_min_scaled_jacobian(x);
          }
        }
        py::dict d;
        d["certified"] = count[0];
        d["invalid"] = count[1];
        d["undecided"] = count[2];
        d["status"] = status;
        d["min_bound"] = bound;
        if (scaled_jacobian) d["min_scaled_jacobian"] = scaled;
        return d;
      },
      py::arg("points"), py::arg("tets"), py::arg("max_depth") = 6, py::arg("scaled_jacobian") = false,
      "Certifies each 10-node tet (see tet10.h certify_tet10): det J > 0 over the whole element, "
      "proved with Bezier bounds, subdivision up to max_depth and rounding-error bounds. Returns a "
      "dict: counts 'certified', 'invalid' (det J <= 0 somewhere, proved), 'undecided' (treat as "
      "invalid); 'status' (m,) int8 (0 certified, 1 invalid, 2 undecided); 'min_bound' (m,) "
      "(certified: a lower bound of min det J; invalid: det J <= 0 at a point); with "
      "scaled_jacobian, 'min_scaled_jacobian' (m,): min det J / det J of the straight tet, a lower "
      "bound within 1e-3 (tet10_min_scaled_jacobian).");

  m.def(
      "bsp_cells_view",
      [](const DoubleArray& points, const IndexArray& triangles) {
        const SurfaceMesh s = surface_from(points, triangles);
        BspCellsView v;
        {
          py::gil_scoped_release release;
          v = bsp_cells_view(s);
        }
        py::array_t<double> pts({static_cast<py::ssize_t>(v.points.size()), static_cast<py::ssize_t>(3)});
        double* out = pts.mutable_data();
        for (const Vec3& p : v.points) *out++ = p.x, *out++ = p.y, *out++ = p.z;
        return py::make_tuple(pts, v.cells, v.inside);
      },
      py::arg("points"), py::arg("triangles"),
      "The BSP's leaf cells of the box partition by the input planes (mesher.h bsp_cells_view): "
      "(points (n, 3) rounded, cells: per cell a list of faces, each a list of vertex indices "
      "counter-clockwise seen from outside the cell, inside: per cell 1 or 0).");

  {
    // The error codes, as the exceptions' `code` attribute names them (error_code_name).
    py::enum_<ErrorCode> codes(m, "ErrorCode", "The core's error codes; .name is the snake_case code.");
    for (const ErrorCode c : {ErrorCode::kBadArgument, ErrorCode::kNonFiniteCoordinate, ErrorCode::kDegenerateTriangle,
                              ErrorCode::kDuplicateTriangle, ErrorCode::kOpenBoundary, ErrorCode::kNonManifold,
                              ErrorCode::kInconsistentOrientation, ErrorCode::kInwardFacing,
                              ErrorCode::kSelfIntersection, ErrorCode::kCancelled, ErrorCode::kInternal})
      codes.value(error_code_name(c), c);
  }

  m.def(
      "orient3d",
      [](std::array<double, 3> a, std::array<double, 3> b, std::array<double, 3> c, std::array<double, 3> d) {
        auto v = [](const std::array<double, 3>& p) { return Vec3{p[0], p[1], p[2]}; };
        return to_int(orient3d(v(a), v(b), v(c), v(d)));
      },
      "Exact sign of det[b-a, c-a, d-a]: +1 when d is on the side of the right-hand normal of (a,b,c).");

  m.def(
      "tet_quality",
      [](const DoubleArray& points, const IndexArray& tets) {
        const TetMesh mesh = tetmesh_from(points, tets);
        QualityStats q;
        {
          py::gil_scoped_release release;
          q = tet_quality(mesh);
        }
        return quality_dict(q);
      },
      py::arg("points"), py::arg("tets"), "Dihedral angles and radius-edge ratios of a tet mesh.");

  m.def(
      "check_mesh",
      [](const DoubleArray& surface_points, const IndexArray& surface_triangles, const DoubleArray& points,
         const IndexArray& tets, int max_messages, bool compute_quality) {
        const SurfaceMesh s = surface_from(surface_points, surface_triangles, "surface_points", "surface_triangles");
        const TetMesh mesh = tetmesh_from(points, tets);
        MeshCheckOptions o;
        o.max_messages = max_messages;
        o.compute_quality = compute_quality;
        MeshCheckReport r;
        {
          py::gil_scoped_release release;
          r = check_mesh(s, mesh, o);
        }
        py::dict d;
        d["valid"] = r.valid;
        d["points"] = r.points;
        d["tets"] = r.tets;
        d["boundary_faces"] = r.boundary_faces;
        d["interior_faces"] = r.interior_faces;
        d["bad_indices"] = r.bad_indices;
        d["nonfinite_points"] = r.nonfinite_points;
        d["duplicate_points"] = r.duplicate_points;
        d["unreferenced_points"] = r.unreferenced_points;
        d["inverted_tets"] = r.inverted_tets;
        d["flat_tets"] = r.flat_tets;
        d["overshared_faces"] = r.overshared_faces;
        d["same_orientation_faces"] = r.same_orientation_faces;
        d["boundary_faces_off_surface"] = r.boundary_faces_off_surface;
        d["boundary_faces_inward"] = r.boundary_faces_inward;
        d["unpaired_boundary_edges"] = r.unpaired_boundary_edges;
        d["miscovered_triangles"] = r.miscovered_triangles;
        d["inconsistent_midnodes"] = r.inconsistent_midnodes;
        d["volume_equal"] = r.volume_equal;
        d["tet_volume"] = r.tet_volume;
        d["surface_volume"] = r.surface_volume;
        d["steiner_points"] = r.steiner_points;
        d["boundary_steiner_points"] = r.boundary_steiner_points;
        d["messages"] = r.messages;
        if (compute_quality) d["quality"] = quality_dict(r.quality);
        return d;
      },
      py::arg("surface_points"), py::arg("surface_triangles"), py::arg("points"), py::arg("tets"),
      py::arg("max_messages") = 20, py::arg("compute_quality") = true,
      "Checks a tet mesh against its closed input surface, exactly (see mesh_check.h).");
}
