// tessera-write-series: writes a time-varying generated volume (moving-blobs) as a series in
// each format Tessera reads, with a scene file for each, so tests and benchmarks need no
// data files:
//   raw     step_00000.raw ...      series-raw.yaml    (series: {pattern, first, last})
//   list    (the same files)        series-list.yaml   (series: [file, ...])
//   series  (the same files)        steps.series       ParaView's JSON, series-series.yaml
//   nifti   series.nii (4-D, dim[4] = steps)           series-nifti.yaml
//   nrrd    series.nrrd (4-D, time the last axis)      series-nrrd.yaml
// Samples are the generator's normalised values as float32 (or round(v x 65535) as uint16),
// and every scene declares the type's full range, so each renders as the generator itself.
// A step is generated and written a slab at a time.
#include <nifti2_io.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/volume.h"

namespace fs = std::filesystem;
using tessera::GeneratorSpec;

namespace {

struct Args {
  GeneratorSpec spec{"moving-blobs", 64, 1, {1, 1, 1}, 0};
  int steps = 20;
  std::string dir, type = "float32";
  std::vector<std::string> formats{"raw", "list", "series", "nifti", "nrrd"};
};

// Step `step`'s samples in the file type, a slab of z at a time, to `out`.
template <class Out>
void writeStep(const Args& a, int step, Out&& out) {
  GeneratorSpec g = a.spec;
  g.time = (double)step / a.steps;  // as stepVolume gives a generator
  const int n = g.size;
  std::vector<uint16_t> u16;
  for (int z0 = 0; z0 < n; z0 += 16) {
    const tessera::Volume v = tessera::generateVolume(g, {{0, 0, z0}, {n, n, std::min(n, z0 + 16)}});
    if (a.type == "float32") {
      out(v.values.data(), v.values.size() * sizeof(float));
    } else {
      u16.resize(v.values.size());
      for (size_t i = 0; i < u16.size(); ++i) u16[i] = (uint16_t)std::lround(v.values[i] * 65535.0);
      out(u16.data(), u16.size() * sizeof(uint16_t));
    }
  }
}

void writeFile(const Args& a, const fs::path& path, int first_step, int steps, const std::string& header = "") {
  std::ofstream f(path, std::ios::binary);
  f << header;
  for (int s = first_step; s < first_step + steps; ++s)
    writeStep(a, s, [&](const void* p, size_t bytes) { f.write(static_cast<const char*>(p), (std::streamsize)bytes); });
  if (!f) throw std::runtime_error(path.string() + ": write failed");
}

std::string rangeLine(const Args& a) { return a.type == "float32" ? "  range: [0, 1]\n" : "  range: [0, 65535]\n"; }

std::string rawKeys(const Args& a) {
  const std::string n = std::to_string(a.spec.size);
  return "  dims: [" + n + ", " + n + ", " + n + "]\n  type: " + a.type + "\n" + rangeLine(a);
}

void writeScene(const Args& a, const std::string& format, const std::string& volume) {
  std::ofstream(fs::path(a.dir) / ("series-" + format + ".yaml")) << "volume:\n" << volume << "time: {play: true}\n";
}

void writeNifti(const Args& a) {
  const int64_t n = a.spec.size, dims[8] = {4, n, n, n, a.steps, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(dims, a.type == "float32" ? DT_FLOAT32 : DT_UINT16, 0);
  if (!nim) throw std::runtime_error("nifticlib could not make an image");
  const std::string path = (fs::path(a.dir) / "series.nii").string();
  nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;  // one .nii file
  if (nifti_set_filenames(nim, path.c_str(), 0, 1) != 0) throw std::runtime_error(path + ": nifticlib refused the name");
  // The header through nifticlib (no data: a series may not fit in memory), then the
  // samples a step at a time from vox_offset.
  znzFile fp = nifti_image_write_hdr_img(nim, 0, "wb");
  if (!znz_isnull(fp)) znzclose(fp);
  const int64_t at = nim->iname_offset;
  nifti_image_free(nim);
  std::fstream f(path, std::ios::binary | std::ios::in | std::ios::out);
  f.seekp(at);
  for (int s = 0; s < a.steps; ++s)
    writeStep(a, s, [&](const void* p, size_t bytes) { f.write(static_cast<const char*>(p), (std::streamsize)bytes); });
  if (!f) throw std::runtime_error(path + ": write failed");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tessera-write-series: a generated time series in every volume format Tessera reads"};
  Args a;
  app.add_option("dir", a.dir, "output folder (made if missing)")->required();
  app.add_option("--size", a.spec.size, "cube edge in voxels")->capture_default_str()->check(CLI::Range(2, 4096));
  app.add_option("--steps", a.steps, "time steps")->capture_default_str()->check(CLI::Range(1, 1000000));
  app.add_option("--seed", a.spec.seed, "generator seed")->capture_default_str();
  app.add_option("--type", a.type, "float32 | uint16")->capture_default_str()->check(CLI::IsMember({"float32", "uint16"}));
  app.add_option("--formats", a.formats, "raw list series nifti nrrd")->delimiter(',')->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    fs::create_directories(a.dir);
    auto has = [&](const char* f) { return std::find(a.formats.begin(), a.formats.end(), f) != a.formats.end(); };
    auto stepName = [](int s) {
      char b[32];
      std::snprintf(b, sizeof b, "step_%05d.raw", s);
      return std::string(b);
    };
    if (has("raw") || has("list") || has("series"))
      for (int s = 0; s < a.steps; ++s) writeFile(a, fs::path(a.dir) / stepName(s), s, 1);
    if (has("raw"))
      writeScene(a, "raw", "  series: {pattern: step_%05d.raw, first: 0, last: " + std::to_string(a.steps - 1) + "}\n" + rawKeys(a));
    if (has("list")) {
      std::string list = "  series:\n";
      for (int s = 0; s < a.steps; ++s) list += "    - " + stepName(s) + "\n";
      writeScene(a, "list", list + rawKeys(a));
    }
    if (has("series")) {
      std::ofstream j(fs::path(a.dir) / "steps.series");
      j << "{\n  \"file-series-version\": \"1.0\",\n  \"files\": [\n";
      for (int s = 0; s < a.steps; ++s)
        j << "    {\"name\": \"" << stepName(s) << "\", \"time\": " << 0.5 * s << "}" << (s + 1 < a.steps ? ",\n" : "\n");
      j << "  ]\n}\n";
      writeScene(a, "series", "  series: steps.series\n" + rawKeys(a));
    }
    if (has("nifti")) {
      writeNifti(a);
      writeScene(a, "nifti", "  file: series.nii\n" + rangeLine(a));
    }
    if (has("nrrd")) {
      const std::string n = std::to_string(a.spec.size);
      const std::string header = "NRRD0004\ntype: " + std::string(a.type == "float32" ? "float" : "ushort") +
                                 "\ndimension: 4\nsizes: " + n + " " + n + " " + n + " " + std::to_string(a.steps) +
                                 "\nkinds: domain domain domain time\nencoding: raw\nendian: little\n\n";
      writeFile(a, fs::path(a.dir) / "series.nrrd", 0, a.steps, header);
      writeScene(a, "nrrd", "  file: series.nrrd\n" + rangeLine(a));
    }
    std::printf("wrote %d steps of %d^3 %s moving-blobs (seed %u) to %s\n", a.steps, a.spec.size, a.type.c_str(),
                a.spec.seed, a.dir.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera-write-series: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
