// SPDX-License-Identifier: LGPL-2.1-or-later
// What the two extension modules share: `FemBspTet._bsptet` (the core, the quality stage, the
// checks; no OpenCASCADE, so a triangle surface meshes without loading it) and
// `FemBspTet._bsptet_cad` (the FEM pipeline from CAD, which links OpenCASCADE). Array
// conversions with messages that name the expected shapes, the GIL-free run with Python's
// progress and cancel callbacks, options structs as classes, and the translation of the core's
// errors into the Python exception types `_bsptet` defines (InputError, MeshingError), which
// `_bsptet_cad` raises too.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "bsptet/input/surface_check.h"
#include "bsptet/mesh/types.h"
#include "bsptet/numerics/errors.h"

namespace bsptet::bindings {

namespace py = pybind11;

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

// An (n, 3) float array as a flat vector; ValueError naming `name` otherwise.
inline std::vector<double> points_from(const DoubleArray& a, const char* name) {
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw py::value_error(std::string(name) + " must have shape (n, 3), got ndim " + std::to_string(a.ndim()));
  return std::vector<double>(a.data(), a.data() + a.size());
}

// An (m, cols_a) or (m, cols_b) integer array as 32-bit indices; ValueError naming `name` otherwise.
inline std::vector<Index> indices_from(const IndexArray& a, const char* name, int cols_a, int cols_b = -1) {
  const bool ok = a.ndim() == 2 && (a.shape(1) == cols_a || a.shape(1) == cols_b);
  if (!ok && !(a.size() == 0))
    throw py::value_error(std::string(name) + " must have shape (m, " + std::to_string(cols_a) +
                          (cols_b > 0 ? " or " + std::to_string(cols_b) : std::string()) + ")");
  std::vector<Index> out(static_cast<std::size_t>(a.size()));
  const std::int64_t* d = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i) {
    if (d[i] < INT32_MIN || d[i] > INT32_MAX)
      throw py::value_error(std::string(name) + " entry " + std::to_string(i) + " = " + std::to_string(d[i]) +
                            " does not fit a 32-bit index");
    out[static_cast<std::size_t>(i)] = static_cast<Index>(d[i]);
  }
  return out;
}

// A mesh's points as an (n, 3) float array and its tets as an (m, nodes_per_tet) int64 array.
inline py::array_t<double> points_array(const TetMesh& m) {
  py::array_t<double> a({static_cast<py::ssize_t>(m.num_points()), static_cast<py::ssize_t>(3)});
  std::copy(m.xyz.begin(), m.xyz.end(), a.mutable_data());
  return a;
}
inline py::array_t<std::int64_t> tets_array(const TetMesh& m) {
  py::array_t<std::int64_t> a({static_cast<py::ssize_t>(m.num_tets()), static_cast<py::ssize_t>(m.nodes_per_tet)});
  std::copy(m.tet.begin(), m.tet.end(), a.mutable_data());
  return a;
}

// Runs `run` (a call of the core) without the GIL, with the options' `cancelled` and `progress`
// callbacks wired to Python (they take the GIL for each call). Ctrl-C (a pending SIGINT) cancels
// the run and raises KeyboardInterrupt; `cancel()` returning True cancels it with the core's
// MeshingError (code "cancelled"). Options: MeshOptions, RefineOptions or FemOptions.
template <class Options, class Run>
void run_without_gil(Options& o, const py::object& progress, const py::object& cancel, Run&& run) {
  std::atomic<bool> interrupted{false};  // set from whichever thread polls (out_of_core.h workers)
  o.cancelled = [&]() {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      PyErr_Clear();
      interrupted = true;
      return true;
    }
    return !cancel.is_none() && cancel().cast<bool>();
  };
  if (!progress.is_none())
    o.progress = [&](const std::string& stage, double f) {
      py::gil_scoped_acquire gil;
      progress(stage, f);
    };
  try {
    py::gil_scoped_release release;
    run();
  } catch (const MeshingError& e) {
    if (e.code() == ErrorCode::kCancelled && interrupted) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      throw py::error_already_set();
    }
    throw;
  }
  o.cancelled = nullptr;
  o.progress = nullptr;
}

// An options struct as a Python class, from its schema table (for_each calls f(name, member) for
// every option): a default constructor, one attribute per option, and the class attribute
// `names`, the options in the table's order.
template <class Options, class ForEach>
py::class_<Options> bind_options(py::module_& m, const char* name, const char* doc, ForEach for_each) {
  py::class_<Options> c(m, name, doc);
  c.def(py::init<>());
  for_each([&](const char* option, auto member) { c.def_readwrite(option, member); });
  c.def_property_readonly_static("names", [for_each](py::object) {
    py::list names;
    for_each([&](const char* option, auto) { names.append(option); });
    return names;
  });
  return c;
}

// The Python exception types the core's errors become: `_bsptet.InputError` (a ValueError) and
// `_bsptet.MeshingError` (a RuntimeError). Each carries `code` (the error code's name) and
// `index` (the element the error names, -1: none); a self-intersection's InputError also
// carries `pairs` (k, 2) and `complete`.
struct ErrorTypes {
  py::handle input_error;
  py::handle meshing_error;
};

// Sets the Python error for a self-intersection and throws error_already_set.
[[noreturn]] inline void raise_self_intersection(const ErrorTypes& types, const SelfIntersectionError& e) {
  py::array_t<std::int64_t> pairs({static_cast<py::ssize_t>(e.pairs().size()), static_cast<py::ssize_t>(2)});
  auto out = pairs.mutable_unchecked<2>();
  for (std::size_t i = 0; i < e.pairs().size(); ++i) {
    out(static_cast<py::ssize_t>(i), 0) = e.pairs()[i][0];
    out(static_cast<py::ssize_t>(i), 1) = e.pairs()[i][1];
  }
  py::object exc = py::reinterpret_borrow<py::object>(types.input_error)(e.what());
  exc.attr("code") = error_code_name(e.code());
  exc.attr("index") = e.index();
  exc.attr("pairs") = pairs;
  exc.attr("complete") = e.complete();
  PyErr_SetObject(types.input_error.ptr(), exc.ptr());
  throw py::error_already_set();
}

// An exception translator's body: the core's errors in `p` as the Python types; anything else
// is rethrown for the next translator.
inline void translate_core_errors(std::exception_ptr p, const ErrorTypes& types) {
  auto raise = [](py::handle type, const Error& e) {
    py::object exc = py::reinterpret_borrow<py::object>(type)(e.what());
    exc.attr("code") = error_code_name(e.code());
    exc.attr("index") = e.index();
    PyErr_SetObject(type.ptr(), exc.ptr());
  };
  try {
    if (p) std::rethrow_exception(p);
  } catch (const SelfIntersectionError& e) {
    try {
      raise_self_intersection(types, e);
    } catch (py::error_already_set& set) {
      set.restore();
    }
  } catch (const InputError& e) {
    raise(types.input_error, e);
  } catch (const MeshingError& e) {
    raise(types.meshing_error, e);
  }
}

}  // namespace bsptet::bindings
