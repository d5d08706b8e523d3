// SPDX-License-Identifier: LGPL-2.1-or-later
// pybind11 bindings of the FEM pipeline from CAD: `FemBspTet._bsptet_cad`, the one extension that
// links OpenCASCADE (through the cad and fem layers). It imports `_bsptet` when it loads and
// raises that module's InputError and MeshingError (binding_support.h). Converts and validates
// only; the public Python API lives in FemBspTet/fem/cad_mesh.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <functional>
#include <map>
#include <string>

#include "binding_support.h"
#include "bsptet/cad/cad_distance.h"
#include "bsptet/cad/cad_model.h"
#include "bsptet/fem/fem_faces.h"
#include "bsptet/fem/fem_mesh.h"
#include "bsptet/numerics/errors.h"

namespace py = pybind11;
using namespace bsptet;
using namespace bsptet::bindings;

namespace {

// The statistics dict, built from the schema (fem/fem_mesh.h for_each_fem_stat).
py::dict fem_stats_dict(const fem::FemStats& st) {
  py::dict d;
  fem::for_each_fem_stat([&](const char* name, auto member) { d[name] = st.*member; });
  return d;
}

// The FEM pipeline (fem/fem_mesh.h, or fem/fem_faces.h in 2D) on a model read by `read`.
// Returns (points (n, 3), tets (k, 4 or 10; none in 2D), tet_solid (k,), triangles (f, 3 or 6),
// triangle_face (f,), stats dict, solid names, face names).
py::tuple mesh_cad(const std::function<cad::CadModel(cad::CadContent)>& read, int dimension,
                   fem::FemOptions o, const py::object& progress, const py::object& cancel) {
  if (dimension != 2 && dimension != 3)
    throw InputError(ErrorCode::kBadArgument, "fem", -1,
                     "option dimension must be 2 (the faces) or 3 (the solids), got " + std::to_string(dimension));
  fem::FemMesh fm;
  fem::FemStats st;
  run_without_gil(o, progress, cancel, [&]() {
    if (dimension == 3) {
      fm = fem::mesh_cad_model(read(cad::CadContent::kSolids), o, &st);
    } else {
      fm = fem::mesh_cad_faces(read(cad::CadContent::kFaces), o, &st);
    }
  });
  py::array_t<std::int64_t> tet_solid(static_cast<py::ssize_t>(fm.tet_solid.size()));
  std::copy(fm.tet_solid.begin(), fm.tet_solid.end(), tet_solid.mutable_data());
  py::array_t<std::int64_t> tri({static_cast<py::ssize_t>(fm.num_triangles()),
                                 static_cast<py::ssize_t>(fm.nodes_per_triangle)});
  std::copy(fm.tri.begin(), fm.tri.end(), tri.mutable_data());
  py::array_t<std::int64_t> tri_face(static_cast<py::ssize_t>(fm.tri_face.size()));
  std::copy(fm.tri_face.begin(), fm.tri_face.end(), tri_face.mutable_data());
  py::dict d = fem_stats_dict(st);
  d["order"] = o.order;
  d["dimension"] = dimension;
  return py::make_tuple(points_array(fm.mesh), tets_array(fm.mesh), tet_solid, tri, tri_face, d,
                        py::cast(fm.solid_names), py::cast(fm.face_names));
}

}  // namespace

PYBIND11_MODULE(_bsptet_cad, m) {
  m.doc() = "FemBspTet FEM pipeline from CAD (private; use FemBspTet.fem.cad_mesh)";
  m.attr("__version__") = FEMBSPTET_VERSION;

  // The core's exception types, from the sibling module _bsptet (same package).
  const std::string name = py::str(m.attr("__name__"));
  const std::size_t dot = name.rfind('.');
  const py::module_ core = py::module_::import(
      (dot == std::string::npos ? std::string("_bsptet") : name.substr(0, dot) + "._bsptet").c_str());
  static const ErrorTypes error_types{py::object(core.attr("InputError")).release(),
                                      py::object(core.attr("MeshingError")).release()};
  py::register_local_exception_translator([](std::exception_ptr p) { translate_core_errors(p, error_types); });

  // ---- The FEM pipeline from CAD (fem/fem_mesh.h). ----
  const char* mesh_cad_doc =
      "dimension 3: meshes every solid of a CAD model: surface at the size field, exact core, refinement "
      "with new surface points and tet10 mid-nodes on the CAD, one mesh of all solids (fem/fem_mesh.h); "
      "dimension 2: every CAD face as triangles (tria6 mid-nodes on the CAD), no tets (fem/fem_faces.h). "
      "options: a FemOptions (size / min_size: CharacteristicLengthMax / Min in model units, 0: automatic, "
      "diagonal / 20 and size / 50; order 1 (tet4) or 2 (tet10); grading per unit length; points_per_circle "
      "for curved faces, 0: off; size_by_face {0-based face: size}). Returns (points (n, 3), tets (k, 4 or 10), "
      "tet_solid (k,), triangles (f, 3 or 6) of every CAD face once, triangle_face (f,) 0-based CAD "
      "face, stats dict). Raises InputError (unreadable or unmeshable CAD, bad option) or MeshingError.";
  {
    // The options schema (fem/fem_mesh.h for_each_fem_option) and the statistics, as classes.
    bind_options<fem::FemOptions>(m, "FemOptions",
                                  "Options of the FEM pipeline from CAD (fem/fem_mesh.h FemOptions); "
                                  "FreeCAD's CharacteristicLengthMax is size.",
                                  [](auto&& f) { fem::for_each_fem_option(f); });
    py::class_<fem::FemStats> stats(m, "FemStats", "Figures of a run of the FEM pipeline (fem/fem_mesh.h FemStats).");
    stats.def(py::init<>());
    fem::for_each_fem_stat([&](const char* name, auto member) { stats.def_readonly(name, member); });
    stats.def("to_dict", &fem_stats_dict, "The figures as the statistics dict (its keys are the field names).");
  }
  m.def(
      "mesh_cad_file",
      [](const std::string& path, int dimension, const fem::FemOptions& options, py::object progress,
         py::object cancel) {
        return mesh_cad([&](cad::CadContent content) { return cad::read_cad_file(path, content); }, dimension,
                        options, progress, cancel);
      },
      py::arg("path"), py::arg("dimension") = 3, py::arg("options") = fem::FemOptions{},
      py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
      (std::string("A STEP, BREP or IGES file (by extension). ") + mesh_cad_doc).c_str());
  m.def(
      "mesh_cad_brep",
      [](const std::string& brep, int dimension, const fem::FemOptions& options, py::object progress,
         py::object cancel) {
        return mesh_cad([&](cad::CadContent content) { return cad::read_brep_string(brep, "BREP string", content); },
                        dimension, options, progress, cancel);
      },
      py::arg("brep"), py::arg("dimension") = 3, py::arg("options") = fem::FemOptions{},
      py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
      (std::string("A shape in OpenCASCADE's BREP text (FreeCAD's Shape.exportBrepToString()). ") + mesh_cad_doc)
          .c_str());

  m.def(
      "cad_face_distances",
      [](const std::string& path, const DoubleArray& points,
         py::array_t<int, py::array::c_style | py::array::forcecast> faces) {
        const std::vector<double> xyz = points_from(points, "points");
        const std::size_t n = xyz.size() / 3;
        std::vector<Vec3> pts(n);
        for (std::size_t i = 0; i < n; ++i) pts[i] = Vec3{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
        std::vector<int> fs(faces.data(), faces.data() + faces.size());
        cad::FaceDistances d;
        {
          const cad::CadModel model = cad::read_cad_file(path);
          py::gil_scoped_release release;
          d = cad::distances_to_faces(model, pts, fs);
        }
        return py::make_tuple(py::array_t<double>(static_cast<py::ssize_t>(n), d.distance.data()),
                              py::array_t<int>(static_cast<py::ssize_t>(n), d.face.data()),
                              py::array_t<double>(static_cast<py::ssize_t>(d.face_tolerance.size()),
                                                  d.face_tolerance.data()));
      },
      py::arg("path"), py::arg("points"), py::arg("faces"),
      "Distances from points (n, 3) to the faces of the CAD file's model (cad/cad_distance.h): faces (n,) "
      "0-based, -1 for the nearest face, or empty for all nearest. Returns (distance (n,), face (n,), "
      "face_tolerance (faces of the model,)).");
}
