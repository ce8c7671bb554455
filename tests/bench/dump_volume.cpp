// tessera-dump-volume: writes a built-in generated volume (common/volume.cpp) as raw
// little-endian float32 (normalised [0,1], x fastest) so other tools, e.g. VTK in
// tests/bench/vtk_compare.py, render exactly the voxels Tessera renders.
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/volume.h"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s <hollow-shell|marschner-lobb|noise-cloud> <size> <seed> <out.raw>\n", argv[0]);
    return 2;
  }
  try {
    tessera::GeneratorSpec spec;
    spec.name = argv[1];
    spec.size = std::stoi(argv[2]);
    spec.seed = (uint32_t)std::stoul(argv[3]);
    const tessera::Volume v = tessera::generateVolume(spec);
    std::ofstream out(argv[4], std::ios::binary);
    // The machines Tessera targets are little-endian; floats are written as in memory.
    out.write(reinterpret_cast<const char*>(v.values.data()), (std::streamsize)(v.values.size() * sizeof(float)));
    if (!out) throw std::runtime_error(std::string(argv[4]) + ": write failed");
    std::printf("wrote %s (%d^3 float32, %s seed %u)\n", argv[4], spec.size, spec.name.c_str(), spec.seed);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera-dump-volume: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
