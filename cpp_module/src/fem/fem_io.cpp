// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet FEM pipeline: VTU output (see fem_io.h).
#include "bsptet/fem/fem_io.h"

#include <cstdint>
#include <fstream>
#include <limits>

#include "bsptet/numerics/errors.h"

namespace bsptet::fem {

void write_vtu(const std::string& path, const FemMesh& m) {
  std::ofstream f(path);
  if (!f) throw InputError(ErrorCode::kBadArgument, "fem_io", -1, path + ": cannot be written");
  f.precision(std::numeric_limits<double>::max_digits10);
  const Index nk = m.mesh.num_tets(), nf = m.num_triangles();
  const int npt = m.mesh.nodes_per_tet, npf = m.nodes_per_triangle;
  f << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << m.mesh.num_points() << "\" NumberOfCells=\"" << nk + nf
    << "\">\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < m.mesh.xyz.size(); i += 3)
    f << m.mesh.xyz[i] << ' ' << m.mesh.xyz[i + 1] << ' ' << m.mesh.xyz[i + 2] << '\n';
  f << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (Index k = 0; k < nk; ++k) {
    for (int i = 0; i < npt; ++i) f << m.mesh.tet[static_cast<std::size_t>(npt * k + i)] << (i + 1 < npt ? ' ' : '\n');
  }
  for (Index t = 0; t < nf; ++t) {
    for (int i = 0; i < npf; ++i) f << m.tri[static_cast<std::size_t>(npf * t + i)] << (i + 1 < npf ? ' ' : '\n');
  }
  f << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  std::int64_t offset = 0;
  for (Index k = 0; k < nk; ++k) f << (offset += npt) << '\n';
  for (Index t = 0; t < nf; ++t) f << (offset += npf) << '\n';
  f << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  const int tet_type = npt == 10 ? 24 : 10, tri_type = npf == 6 ? 22 : 5;
  for (Index k = 0; k < nk; ++k) f << tet_type << '\n';
  for (Index t = 0; t < nf; ++t) f << tri_type << '\n';
  f << "</DataArray>\n</Cells>\n<CellData Scalars=\"solid\">\n<DataArray type=\"Int32\" Name=\"solid\" format=\"ascii\">\n";
  for (Index k = 0; k < nk; ++k) f << m.tet_solid[static_cast<std::size_t>(k)] << '\n';
  for (Index t = 0; t < nf; ++t) f << -1 << '\n';
  f << "</DataArray>\n<DataArray type=\"Int32\" Name=\"face\" format=\"ascii\">\n";
  for (Index k = 0; k < nk; ++k) f << -1 << '\n';
  for (Index t = 0; t < nf; ++t) f << m.tri_face[static_cast<std::size_t>(t)] << '\n';
  f << "</DataArray>\n</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  if (!f) throw InputError(ErrorCode::kBadArgument, "fem_io", -1, path + ": write failed");
}

}  // namespace bsptet::fem
