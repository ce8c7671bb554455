// tessera-render's geometry path: renders a mesh scene through GlRenderer in one process,
// whole or as a grid of tiles assembled like the farm, and measures anti-aliasing methods.
// Prints to stdout; throws on bad options. Not thread-safe (one OSMesa context).
#pragma once
#include <array>
#include <optional>
#include <string>

#include "common/scene.h"

namespace tessera::renderer {

struct MeshToolOptions {
  std::string out = "out.png";
  int width = 0, height = 0;  // 0: the scene's
  int frame = 0;
  int tile_cols = 1, tile_rows = 1;
  int repeat = 1;
  bool stats = false;
  bool compare_reference = false;  // error vs a 16x (4x4) supersampled render
  bool aa_sweep = false;           // time and error of every anti-aliasing method, as CSV
  std::string aa;                  // override the scene's antialiasing.method
  int aa_samples = 0;              // and its samples (0: the method's default)
  std::optional<std::array<double, 3>> background;
  std::string pam;                 // also write premultiplied rgba8 (writePam) here
};

// Returns the process exit code.
int renderMeshScene(const Scene& scene, const MeshToolOptions& opt);

}  // namespace tessera::renderer
