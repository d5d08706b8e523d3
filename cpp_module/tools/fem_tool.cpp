// bsptet_fem: a CAD file to a surface mesh at an element size (and, later stages, a volume mesh).
//
//   bsptet_fem PART.step [--size H] [--off OUT.off]
//
// Prints the surface mesher's figures; with --off writes each solid's surface (OUT.off for one
// solid, OUT_<k>.off for several).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bsptet/cad/cad_model.h"
#include "bsptet/cad/cad_surface.h"
#include "bsptet/errors.h"
#include "bsptet/mesh_io.h"

int main(int argc, char** argv) {
  using namespace bsptet;
  if (argc < 2) {
    std::fprintf(stderr, "usage: bsptet_fem PART [--size H] [--off OUT.off]\n");
    return 2;
  }
  std::string path = argv[1], off;
  cad::CadSurfaceOptions options;
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--size") && i + 1 < argc) options.size.size = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--off") && i + 1 < argc) off = argv[++i];
  }
  try {
    const cad::CadModel model = cad::read_cad_file(path);
    cad::CadSurfaceStats st;
    const cad::CadSurface surface = cad::mesh_cad_surface(model, options, &st);
    std::printf("%s: %d solids %d faces; h %.4g min %.4g; nodes %lld triangles %lld; folds %lld; min quality %.3f; %.3f s\n",
                path.c_str(), model.num_solids(), model.num_faces(), st.size, st.min_size, (long long)st.nodes,
                (long long)st.triangles, (long long)st.folds, st.min_quality, st.seconds);
    if (!off.empty()) {
      for (int s = 0; s < model.num_solids(); ++s) {
        std::string name = off;
        if (model.num_solids() > 1) name = off.substr(0, off.size() - 4) + "_" + std::to_string(s) + ".off";
        write_off(name, surface.solid_surface(s));
      }
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "INPUT ERROR: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ERROR: %s\n", e.what());
    return 1;
  }
  return 0;
}
