// tessera-dump-volume: writes a built-in generated volume (common/volume.cpp) as raw
// little-endian float32 (normalised [0,1], x fastest) so other tools, e.g. VTK in
// tests/bench/vtk_compare.py, render exactly the voxels Tessera renders.
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

#include "common/volume.h"

int main(int argc, char** argv) {
  CLI::App app{"tessera-dump-volume: write a built-in generated volume as raw little-endian float32"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  tessera::GeneratorSpec spec;
  std::string out_path;
  app.add_option("generator", spec.name, "hollow-shell | marschner-lobb | noise-cloud")->required();
  app.add_option("size", spec.size, "cube edge in voxels")->required()->check(CLI::Range(2, 4096));
  app.add_option("seed", spec.seed, "generator seed")->required();
  app.add_option("out", out_path, "output file (.raw)")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const tessera::Volume v = tessera::generateVolume(spec);
    std::ofstream out(out_path, std::ios::binary);
    // The machines Tessera targets are little-endian; floats are written as in memory.
    out.write(reinterpret_cast<const char*>(v.values.data()), (std::streamsize)(v.values.size() * sizeof(float)));
    if (!out) throw std::runtime_error(out_path + ": write failed");
    std::printf("wrote %s (%d^3 float32, %s seed %u)\n", out_path.c_str(), spec.size, spec.name.c_str(), spec.seed);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera-dump-volume: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
