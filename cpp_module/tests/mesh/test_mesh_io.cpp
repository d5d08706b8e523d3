// SPDX-License-Identifier: LGPL-2.1-or-later
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_io.h"

using namespace bsptet;

TEST(MeshIo, OffRoundTripIsExact) {
  SurfaceMesh s;
  s.xyz = {0.1, 0.2, 0.30000000000000004, 1e-300, -0.0, 12345.678901234567, 1, 1, 1};
  s.tri = {0, 1, 2};
  const std::string path = (std::filesystem::temp_directory_path() / "bsptet_io_test.off").string();
  write_off(path, s);
  const SurfaceMesh r = read_off(path);
  std::remove(path.c_str());
  EXPECT_EQ(r.xyz, s.xyz);
  EXPECT_EQ(r.tri, s.tri);
}

TEST(MeshIo, TetgenRoundTripKeepsQuadraticOrder) {
  TetMesh m;
  m.nodes_per_tet = 10;
  for (int i = 0; i < 10; ++i) m.xyz.insert(m.xyz.end(), {double(i), double(i * i), 0.5 * i});
  m.tet = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  const std::string stem = (std::filesystem::temp_directory_path() / "bsptet_io_tet").string();
  write_tetgen(stem, m);
  const TetMesh r = read_tetgen(stem);
  std::remove((stem + ".node").c_str());
  std::remove((stem + ".ele").c_str());
  EXPECT_EQ(r.tet, m.tet);
  EXPECT_EQ(r.xyz, m.xyz);
}

TEST(MeshIo, ErrorsNameTheLine) {
  try {
    parse_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "t.off");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.off:6"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("vertex 7"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_off("OFF\n3 1 0\n0 0 0\n1 nan 0\n", "n.off"), InputError);
  EXPECT_THROW(parse_off("PLY\n", "p.off"), InputError);
  EXPECT_THROW(parse_off("OFF\n3 1 0\n0 0 0\n", "short.off"), InputError);
}
