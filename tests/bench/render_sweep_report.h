// Output of tessera-sweep: one Row per (scene, step, early termination, skipping) and the
// files made from them: sweep.csv, speedup.dat, a markdown table, gnuplot PNG plots.
// Plain functions; not thread-safe (they write files).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace tessera::bench {

struct SweepRow {
  std::string scene;
  int size = 0, width = 0, height = 0;
  double step_l0 = 1;          // step in units of L0
  double et = 2;               // early-termination threshold; > 1: off
  bool skip = true;            // empty-space skipping
  bool is_default = false;     // the shipped "default" quality (step L0, ET 1-0.5/255, skip on)
  double ms_best = 0, ms_median = 0;  // wall time
  double cpu_ms_best = 0;             // process CPU time (all threads) of the fastest-CPU repeat
  uint64_t samples = 0, skipped = 0, terminated = 0;
  double max_abs = 0, rmse = 0, psnr = 0;  // vs the reference render
  double skip_vs_noskip = -1;  // skip-on rows: max abs difference to the same config without skipping
};

std::string etLabel(double et);  // "0.95", "1-0.5/255", "off"
// Share of the ray's sample grid passed over by empty-space skipping, in percent.
double skippedPercent(const SweepRow& r);

void writeCsv(const std::string& path, const std::vector<SweepRow>& rows);
// Reads what writeCsv wrote (for --replot); throws std::runtime_error naming the line.
std::vector<SweepRow> readCsv(const std::string& path);
// Markdown table for the README (one line per row) followed by a summary of the default quality.
std::string markdownTable(const std::vector<SweepRow>& rows);
std::string defaultSummary(const std::vector<SweepRow>& rows);
// Writes speedup.dat and a gnuplot script into dir and runs gnuplot. Returns false (with a
// message on stderr) when gnuplot is missing or fails; the CSV is the primary output.
bool plot(const std::string& dir, const std::vector<SweepRow>& rows, const std::vector<std::string>& scenes);

}  // namespace tessera::bench
