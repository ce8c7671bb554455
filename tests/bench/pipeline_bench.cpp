// tessera-pipeline-bench: throughput of the farm with `window` frames in flight against
// one frame at a time, and against 1/(slowest stage) and 1/(sum of stages). Runs the real
// farm through tessera-up and compose.yaml, reads the master's metrics (one JSON line per
// frame), prints one row per frame, then a summary. Not a timed test.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

struct Row {
  int frame;
  double render, render_encode, composite, composite_codec, display, latency, done;
  double bytes_raw, bytes_encoded, imbalance;
};

struct Summary {
  int window;
  double fps, slowest_ms, sum_ms, encode_share, ratio_raw;
};

std::vector<Row> readMetrics(const fs::path& p) {
  std::vector<Row> rows;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) {
    auto j = nlohmann::json::parse(line);
    rows.push_back({j["frame"].get<int>(), j["render_ms_max"], j["render_encode_ms_max"], j["composite_ms_max"],
                    j["composite_encode_ms_max"].get<double>() + j["composite_decode_ms_max"].get<double>(), j["display_ms"], j["latency_ms"], j["done_ms"],
                    j["render_bytes_raw"], j["render_bytes_encoded"], j["render_imbalance_time"]});
  }
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.frame < b.frame; });
  return rows;
}

double mean(const std::vector<Row>& rows, double Row::*f, size_t skip) {
  double s = 0;
  for (size_t i = skip; i < rows.size(); ++i) s += rows[i].*f;
  return rows.size() > skip ? s / (rows.size() - skip) : 0;
}

Summary summarize(int window, const std::vector<Row>& rows) {
  const size_t warm = std::min<size_t>(2, rows.size() / 4);  // first frames include start-up
  Summary s{window, 0, 0, 0, 0, 0};
  if (rows.size() < warm + 2) return s;
  s.fps = (rows.size() - 1 - warm) * 1000.0 / (rows.back().done - rows[warm].done);
  double render = mean(rows, &Row::render, warm) + mean(rows, &Row::render_encode, warm);
  double composite = mean(rows, &Row::composite, warm) + mean(rows, &Row::composite_codec, warm);
  double display = mean(rows, &Row::display, warm);
  s.slowest_ms = std::max({render, composite, display});
  s.sum_ms = render + composite + display;
  s.encode_share = (mean(rows, &Row::render_encode, warm) + mean(rows, &Row::composite_codec, warm)) * s.fps / 1000.0;
  s.ratio_raw = mean(rows, &Row::bytes_encoded, warm) / std::max(1.0, mean(rows, &Row::bytes_raw, warm));
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Tessera pipeline throughput: window N against window 1"};
  std::string scene, out = "bench-out/pipeline", codec = "lzo", format = "rgba16f";
  int frames = 24, renderers = 2, compositors = 1, window = 3;
  app.add_option("--scene", scene, "scene file (default: the built-in 256^3 hollow shell at 1024x1024)");
  app.add_option("--frames", frames, "frames per run")->check(CLI::Range(4, 10000));
  app.add_option("--renderers", renderers)->check(CLI::Range(1, 64));
  app.add_option("--compositors", compositors)->check(CLI::Range(1, 64));
  app.add_option("--in-flight", window, "frames in flight to compare with 1")->check(CLI::Range(2, 64));
  app.add_option("--codec", codec);
  app.add_option("--format", format);
  app.add_option("--out", out, "folder for metrics and frames");
  CLI11_PARSE(app, argc, argv);

  fs::path self = fs::canonical("/proc/self/exe").parent_path();
  fs::path compose = fs::path(TESSERA_SOURCE_DIR) / "compose.yaml";
  std::vector<Summary> summaries;
  std::cout << "| window | frame | render ms | crop+pack+compress+send ms | composite ms | decode+strips+compress ms "
               "| display ms | latency ms | bytes raw | bytes compressed | render imbalance |\n";
  for (int c = 0; c < 11; ++c) std::cout << "|---";
  std::cout << "|\n";
  for (int w : {1, window}) {
    fs::path dir = fs::absolute(out) / ("window" + std::to_string(w));
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::string cmd = fmt::format(
        "{}/tessera-up {} --env TESSERA_SCENE={} --env TESSERA_FRAMES={} --env TESSERA_RENDERERS={} "
        "--env TESSERA_COMPOSITORS={} --env TESSERA_IN_FLIGHT={} --env TESSERA_CODEC={} --env TESSERA_FORMAT={} "
        "--env TESSERA_OUT={} --env TESSERA_ENDPOINTS=ipc://{}/sockets --env TESSERA_WINDOW=off "
        "--env TESSERA_LOG=warn > {}/farm.log 2>&1",
        self.string(), compose.string(), scene, frames, renderers, compositors, w, codec, format, dir.string(),
        dir.string(), dir.string());
    std::cerr << "running the farm with window " << w << " (" << frames << " frames)...\n";
    if (std::system(cmd.c_str()) != 0) {
      std::cerr << "farm failed; see " << dir / "farm.log" << "\n";
      return 1;
    }
    auto rows = readMetrics(dir / "metrics.jsonl");
    for (const auto& r : rows)
      std::cout << fmt::format("| {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.0f} | {:.0f} | {:.2f} |\n",
                               w, r.frame, r.render, r.render_encode, r.composite, r.composite_codec, r.display,
                               r.latency, r.bytes_raw, r.bytes_encoded, r.imbalance);
    summaries.push_back(summarize(w, rows));
  }
  std::cout << "\n| window | fps | 1/slowest stage (fps) | 1/sum of stages (fps) | fps / (1/slowest) | "
               "codec+transport share of frame time | compressed/raw |\n|---|---|---|---|---|---|---|\n";
  for (const auto& s : summaries)
    std::cout << fmt::format("| {} | {:.2f} | {:.2f} | {:.2f} | {:.0f}% | {:.1f}% | {:.1f}% |\n", s.window, s.fps,
                             1000.0 / s.slowest_ms, 1000.0 / s.sum_ms, 100.0 * s.fps * s.slowest_ms / 1000.0,
                             100.0 * s.encode_share, 100.0 * s.ratio_raw);
  if (summaries.size() == 2 && summaries[0].fps > 0)
    std::cout << fmt::format("\nwindow {} / window 1 throughput: {:.2f}x\n", window, summaries[1].fps / summaries[0].fps);
  return 0;
}
