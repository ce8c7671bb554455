#include "tests/bench/render_sweep_report.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace tessera::bench {

namespace {

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string num(double v) { return std::isinf(v) ? (v > 0 ? "inf" : "-inf") : fmt("%.6g", v); }

std::ofstream openOut(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  return out;
}

// The ET values of the sweep, in the order the plots list them.
int stepIndex(double step_l0) { return step_l0 < 0.75 ? 0 : step_l0 < 1.5 ? 1 : step_l0 < 3 ? 2 : 3; }

}  // namespace

std::string etLabel(double et) {
  if (et > 1) return "off";
  if (std::abs(et - (1.0 - 0.5 / 255)) < 1e-6) return "1-0.5/255";  // CSV keeps 6 digits
  return fmt("%g", et);
}

double skippedPercent(const SweepRow& r) {
  const double total = double(r.samples + r.skipped + r.terminated);
  return total > 0 ? 100.0 * double(r.skipped) / total : 0.0;
}

void writeCsv(const std::string& path, const std::vector<SweepRow>& rows) {
  auto out = openOut(path);
  out << "scene,size,width,height,step_l0,et,et_label,skip,default,ms_best,ms_median,cpu_ms_best,samples,skipped,terminated,"
         "skipped_pct,max_abs,rmse,psnr_db,skip_vs_noskip_max_abs\n";
  for (const auto& r : rows)
    out << r.scene << ',' << r.size << ',' << r.width << ',' << r.height << ',' << num(r.step_l0) << ','
        << num(r.et) << ',' << etLabel(r.et) << ',' << int(r.skip) << ',' << int(r.is_default) << ','
        << fmt("%.2f", r.ms_best) << ',' << fmt("%.2f", r.ms_median) << ',' << fmt("%.2f", r.cpu_ms_best) << ',' << r.samples << ',' << r.skipped << ','
        << r.terminated << ',' << fmt("%.2f", skippedPercent(r)) << ',' << num(r.max_abs) << ',' << num(r.rmse)
        << ',' << num(r.psnr) << ',' << (r.skip ? num(r.skip_vs_noskip) : "") << '\n';
  if (!out) throw std::runtime_error(path + ": write failed");
}

std::vector<SweepRow> readCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  std::getline(in, line);  // header
  std::vector<SweepRow> rows;
  for (int n = 2; std::getline(in, line); ++n) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    if (f.size() < 19) throw std::runtime_error(path + ":" + std::to_string(n) + ": expected 20 columns");
    SweepRow r;
    try {
      r.scene = f[0];
      r.size = std::stoi(f[1]);
      r.width = std::stoi(f[2]);
      r.height = std::stoi(f[3]);
      r.step_l0 = std::stod(f[4]);
      r.et = std::stod(f[5]);
      r.skip = f[7] == "1";
      r.is_default = f[8] == "1";
      r.ms_best = std::stod(f[9]);
      r.ms_median = std::stod(f[10]);
      r.cpu_ms_best = std::stod(f[11]);
      r.samples = std::stoull(f[12]);
      r.skipped = std::stoull(f[13]);
      r.terminated = std::stoull(f[14]);
      r.max_abs = std::stod(f[16]);
      r.rmse = std::stod(f[17]);
      r.psnr = std::stod(f[18]);  // stod reads "inf"
      if (f.size() > 19 && !f[19].empty()) r.skip_vs_noskip = std::stod(f[19]);
    } catch (const std::exception&) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": bad number");
    }
    rows.push_back(r);
  }
  return rows;
}

std::string markdownTable(const std::vector<SweepRow>& rows) {
  std::ostringstream o;
  o << "| scene | step (L0) | ET | skip | ms | CPU ms | Msamples | skipped % | PSNR dB |\n";
  o << "|---|---:|---|---|---:|---:|---:|---:|---:|\n";
  for (const auto& r : rows)
    o << "| " << r.scene << (r.is_default ? " **default**" : "") << " | " << fmt("%g", r.step_l0) << " | "
      << etLabel(r.et) << " | " << (r.skip ? "on" : "off") << " | " << fmt("%.1f", r.ms_best) << " | "
      << fmt("%.0f", r.cpu_ms_best) << " | " << fmt("%.1f", double(r.samples) / 1e6) << " | " << fmt("%.1f", skippedPercent(r)) << " | "
      << (std::isinf(r.psnr) ? std::string("inf") : fmt("%.2f", r.psnr)) << " |\n";
  return o.str();
}

std::string defaultSummary(const std::vector<SweepRow>& rows) {
  // Default quality with skipping on, and the same configuration with skipping off.
  std::ostringstream o;
  o << "| scene | default ms (skip on) | skip off ms | speedup (wall) | speedup (CPU) | PSNR dB vs reference | max abs "
       "| skip changes image by |\n";
  o << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& on : rows) {
    if (!on.is_default) continue;
    const SweepRow* off = nullptr;
    for (const auto& r : rows)
      if (r.scene == on.scene && !r.skip && r.step_l0 == on.step_l0 && r.et == on.et) off = &r;
    o << "| " << on.scene << " | " << fmt("%.1f", on.ms_best) << " | " << (off ? fmt("%.1f", off->ms_best) : "-")
      << " | " << (off ? fmt("%.2fx", off->ms_best / on.ms_best) : "-") << " | "
      << (off ? fmt("%.2fx", off->cpu_ms_best / on.cpu_ms_best) : "-") << " | " << fmt("%.2f", on.psnr) << " | "
      << fmt("%.2e", on.max_abs) << " | " << fmt("%.2e", on.skip_vs_noskip) << " |\n";
  }
  return o.str();
}

namespace {

// points.dat: scene_index ms psnr skip step_index is_default (PSNR capped so "inf" plots).
void writePoints(const std::string& dir, const std::vector<SweepRow>& rows, const std::vector<std::string>& scenes) {
  std::map<std::string, int> scene_index;
  for (size_t i = 0; i < scenes.size(); ++i) scene_index[scenes[i]] = int(i);
  auto out = openOut(dir + "/points.dat");
  for (const auto& r : rows)
    out << scene_index[r.scene] << ' ' << r.ms_best << ' ' << std::min(r.psnr, 99.0) << ' ' << int(r.skip) << ' '
        << stepIndex(r.step_l0) << ' ' << int(r.is_default) << '\n';
}

// speedup.dat: one line per (step, ET); one column per scene: CPU ms(skip off) / CPU ms(skip
// on). CPU time, because wall time on a shared machine swings by 2x between neighbours.
void writeSpeedup(const std::string& dir, const std::vector<SweepRow>& rows, const std::vector<std::string>& scenes) {
  auto out = openOut(dir + "/speedup.dat");
  std::map<std::pair<double, double>, std::map<std::string, std::pair<double, double>>> by_config;
  std::vector<std::pair<double, double>> order;
  for (const auto& r : rows) {
    const auto key = std::make_pair(r.step_l0, r.et);
    if (!by_config.count(key)) order.push_back(key);
    auto& ms = by_config[key][r.scene];
    (r.skip ? ms.second : ms.first) = r.cpu_ms_best;
  }
  out << "# config";
  for (const auto& s : scenes) out << ' ' << s;
  out << '\n';
  for (const auto& key : order) {
    out << '"' << fmt("%g", key.first) << " L0, ET " << etLabel(key.second) << '"';
    for (const auto& s : scenes) {
      const auto& ms = by_config[key][s];
      out << ' ' << (ms.first > 0 && ms.second > 0 ? ms.first / ms.second : 0.0);
    }
    out << '\n';
  }
}

// plot.gp: one time-vs-PSNR panel per scene, then the speedup histogram.
void writeScript(const std::string& dir, const std::vector<SweepRow>& rows, const std::vector<std::string>& scenes) {
  const SweepRow& any = rows.front();
  const std::string what = std::to_string(any.size) + "^3 volumes, " + std::to_string(any.width) + "x" +
                           std::to_string(any.height) + " images";
  auto g = openOut(dir + "/plot.gp");
  g << "set terminal pngcairo size " << 600 * scenes.size() << ",560 font 'Sans,10'\n"
    << "set output '" << dir << "/render-sweep.png'\n"
    << "set multiplot layout 1," << scenes.size() << " title 'Run time vs error against the reference ("
    << what << "); colour: skipping, shape: step, circle: default quality'\n"
    << "set logscale x\nset grid\nset xlabel 'run time per frame (ms, log)'\nset ylabel 'PSNR vs reference (dB)'\n"
    << "set key below maxrows 3 font ',8'\nset bmargin 9\nset xlabel offset 0,0.3\n"
    << "steps = '0.5 1 2 4'\n";
  for (size_t i = 0; i < scenes.size(); ++i) {
    g << "set title '" << scenes[i] << "'\n"
      << "plot 40 with lines dt 2 lc 'gray' title '40 dB (contract)'";
    for (int skip = 0; skip <= 1; ++skip)
      for (int st = 0; st < 4; ++st)
        g << ", '" << dir << "/points.dat' using ($1==" << i << " && $4==" << skip << " && $5==" << st
          << " ? $2 : NaN):3 with points pt " << (st == 0 ? 5 : st == 1 ? 7 : st == 2 ? 9 : 13) << " ps 1.2 lc '"
          << (skip ? "#d62728" : "#1f77b4") << "' title 'skip " << (skip ? "on" : "off") << ", step "
          << (st == 0 ? "0.5" : st == 1 ? "1" : st == 2 ? "2" : "4") << " L0'";
    g << ", '' using ($1==" << i << " && $6==1 ? $2 : NaN):3 with points pt 6 ps 3 lc 'black' title 'default'\n";
  }
  g << "unset multiplot\n"
    << "set terminal pngcairo size 1200,560 font 'Sans,10'\n"
    << "set output '" << dir << "/render-sweep-speedup.png'\n"
    << "unset logscale x\nset bmargin\nset title 'Empty-space skipping: speedup = CPU ms(skip off) / CPU ms(skip on), same run ("
    << what << ")'\n"
    << "set style data histograms\nset style histogram clustered gap 1\nset style fill solid 0.8 border -1\n"
    << "set xtics rotate by -45 font ',8'\nset xlabel 'step, early termination'\nset ylabel 'speedup (x)'\n"
    << "set yrange [0:*]\nset key inside top right\n"
    << "set arrow from graph 0, first 1 to graph 1, first 1 nohead dt 2 lc 'gray'\n"
    << "plot ";
  for (size_t i = 0; i < scenes.size(); ++i)
    g << (i ? ", '" : "'") << dir << "/speedup.dat' using " << (i + 2) << ":xtic(1) title '" << scenes[i] << "'";
  g << '\n';
}

bool runGnuplot(const std::string& dir) {
  const std::string cmd = "gnuplot '" + dir + "/plot.gp' 2>'" + dir + "/gnuplot.log'";
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    std::fprintf(stderr, "tessera-sweep: gnuplot not found (apt-get install gnuplot-nox); no plots\n");
    return false;
  }
  if (std::system(cmd.c_str()) != 0) {
    std::fprintf(stderr, "tessera-sweep: gnuplot failed, see %s/gnuplot.log\n", dir.c_str());
    return false;
  }
  return true;
}

}  // namespace

bool plot(const std::string& dir, const std::vector<SweepRow>& rows, const std::vector<std::string>& scenes) {
  if (rows.empty() || scenes.empty()) return false;
  writePoints(dir, rows, scenes);
  writeSpeedup(dir, rows, scenes);
  writeScript(dir, rows, scenes);
  return runGnuplot(dir);
}

}  // namespace tessera::bench
