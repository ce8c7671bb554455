// Part (c) of tessera-geometry-bench: the sort-first farm through tessera-up on one scene,
// static against balanced tiling, every configuration in interleaved rounds. Prints markdown
// tables to stdout and progress to stderr. Sets LP_NUM_THREADS in this process's environment.
#pragma once
#include <string>
#include <vector>

namespace tessera::bench {

struct FarmConfig {
  std::string out;         // the runs go to <out>/farm
  std::string scene_text;  // the scene file's text (corner.yaml, possibly resized)
  bool resized = false;    // says "(resized)" in the table title
  int frames = 24, rounds = 3;
  std::vector<int> renderers{1, 2, 4};
  std::vector<std::string> lp_threads{"default"};
};

// Returns false if a run failed or a farm image differs from the one-process render.
bool geometryFarm(const FarmConfig& c);

}  // namespace tessera::bench
