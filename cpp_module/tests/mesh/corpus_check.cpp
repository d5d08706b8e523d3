// SPDX-License-Identifier: LGPL-2.1-or-later
// Corpus driver (CTest label `corpus`): runs `tetgen -pYQ` on one corpus surface, reads the mesh
// back and runs the exact checker, which must agree with the expectation given on the command
// line ("valid" or "invalid"). TetGen is run as a separate program (it is AGPL: never linked).
//
//   bsptet_corpus_check SURFACE.off valid|invalid
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/mesh/mesh_io.h"

using namespace bsptet;

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s SURFACE.off valid|invalid\n", argv[0]);
    return 2;
  }
  const std::string off = argv[1], expect = argv[2];
  std::string tmpl = (std::filesystem::temp_directory_path() / "bsptet_corpus_XXXXXX").string();
  if (!mkdtemp(tmpl.data())) return 2;
  const std::filesystem::path dir(tmpl);
  int status = 1;
  try {
    const SurfaceMesh s = read_off(off);
    write_off((dir / "surface.off").string(), s);
    const std::string cmd = "tetgen -pYQ '" + (dir / "surface.off").string() + "' > /dev/null 2>&1";
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("tetgen failed: " + cmd);
    const TetMesh m = read_tetgen((dir / "surface.1").string());
    const MeshCheckReport r = check_mesh(s, m);
    std::printf("%s: %d tets, %lld Steiner points, checker says %s\n", off.c_str(), m.num_tets(),
                static_cast<long long>(r.steiner_points), r.valid ? "valid" : "invalid");
    for (const auto& msg : r.messages) std::printf("  %s\n", msg.c_str());
    status = (r.valid == (expect == "valid")) ? 0 : 1;
    if (status) std::printf("FAILED: expected %s\n", expect.c_str());
  } catch (const std::exception& e) {
    std::printf("FAILED: %s\n", e.what());
  }
  std::filesystem::remove_all(dir);
  return status;
}
