// tessera-dump-volume: writes a built-in generated volume (common/volume.cpp) as raw
// little-endian float32 (normalised [0,1], x fastest) so other tools, e.g. VTK in
// tests/bench/vtk_compare.py, render exactly the voxels Tessera renders; or as uint16
// (round(value x 65535)), the big test volumes of the memory benchmark. Generated and
// written a slab at a time: a volume bigger than this machine's memory can be written.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/volume.h"

int main(int argc, char** argv) {
  CLI::App app{"tessera-dump-volume: write a built-in generated volume as a raw little-endian file"};
  // --help shows the defaults of the options; the positionals are all required, so have none.
  tessera::GeneratorSpec spec;
  std::string out_path, type = "float32";
  app.add_option("generator", spec.name, tessera::generatorNames())->required();
  app.add_option("size", spec.size, "cube edge in voxels")->required()->check(CLI::Range(2, 4096));
  app.add_option("seed", spec.seed, "generator seed")->required();
  app.add_option("out", out_path, "output file (.raw)")->required();
  app.add_option("--type", type, "float32 | uint16")->capture_default_str()->check(CLI::IsMember({"float32", "uint16"}));
  CLI11_PARSE(app, argc, argv);
  try {
    std::ofstream out(out_path, std::ios::binary);
    const int n = spec.size;
    std::vector<uint16_t> u16;
    for (int z0 = 0; z0 < n; z0 += 16) {
      const tessera::Volume v = tessera::generateVolume(spec, {{0, 0, z0}, {n, n, std::min(n, z0 + 16)}});
      // The machines Tessera targets are little-endian; values are written as in memory.
      if (type == "float32") {
        out.write(reinterpret_cast<const char*>(v.values.data()), (std::streamsize)(v.values.size() * sizeof(float)));
      } else {
        u16.resize(v.values.size());
        for (size_t i = 0; i < u16.size(); ++i) u16[i] = (uint16_t)std::lround(v.values[i] * 65535.0);
        out.write(reinterpret_cast<const char*>(u16.data()), (std::streamsize)(u16.size() * sizeof(uint16_t)));
      }
    }
    if (!out) throw std::runtime_error(out_path + ": write failed");
    std::printf("wrote %s (%d^3 %s, %s seed %u)\n", out_path.c_str(), n, type.c_str(), spec.name.c_str(), spec.seed);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera-dump-volume: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
