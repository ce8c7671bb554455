// Raw volume loading (all three types, error messages) and the procedural generators.
#include "common/volume.h"
#include "common/volume_summary.h"

#include "tests/common/raw_spec.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

using namespace tessera;
namespace fs = std::filesystem;

namespace {
using test::TempDir;

// Pages of the file in the page cache.
size_t cachedPages(const std::string& file) {
  const size_t len = fs::file_size(file), page = (size_t)::sysconf(_SC_PAGESIZE);
  const int fd = ::open(file.c_str(), O_RDONLY);
  void* map = ::mmap(nullptr, len, PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  std::vector<unsigned char> in((len + page - 1) / page);
  ::mincore(map, len, in.data());
  ::munmap(map, len);
  return (size_t)std::count_if(in.begin(), in.end(), [](unsigned char c) { return c & 1; });
}

std::string errorOf(const RawVolumeSpec& s) {
  try {
    loadRawVolume(s);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "<no error>";
}
}  // namespace

TEST(Volume, HalfExtent) {
  Volume v;
  v.dims = {10, 20, 40};
  v.spacing = {1, 1, 0.5};
  Vec3 h = v.halfExtent();  // extents 10, 20, 20 -> largest is 1
  EXPECT_DOUBLE_EQ(h.x, 0.25);
  EXPECT_DOUBLE_EQ(h.y, 0.5);
  EXPECT_DOUBLE_EQ(h.z, 0.5);
  EXPECT_DOUBLE_EQ(v.boxMin().y, -0.5);
}

TEST(Volume, LoadUInt8LayoutAndNormalisation) {
  TempDir t("volume");
  uint8_t data[2 * 3 * 4];
  for (int i = 0; i < 24; ++i) data[i] = (uint8_t)(i * 10);
  RawVolumeSpec s = test::rawSpec(t.write("a.raw", data, sizeof data), {2, 3, 4}, VoxelType::UInt8, {1, 1, 1}, false, {0, 255});
  Volume v = loadRawVolume(s);
  EXPECT_EQ(v.dims, (std::array<int, 3>{2, 3, 4}));
  // No range: the data's own 0..230 maps to 0..1, like ParaView's first colour map.
  EXPECT_FLOAT_EQ(v.at(1, 2, 3), 1.0f);  // x fastest: 1 + 2*(2 + 3*3) = 23, the largest value
  EXPECT_FLOAT_EQ(v.at(1, 0, 0), 10.0f / 230);
  EXPECT_EQ(v.data_range, (std::array<double, 2>{0, 230}));
  EXPECT_EQ(v.mapped_range, (std::array<double, 2>{0, 230}));
  s.has_range = true;
  s.range = {10, 110};
  v = loadRawVolume(s);
  EXPECT_FLOAT_EQ(v.at(0, 0, 0), 0.0f);  // below the range clamps
  EXPECT_FLOAT_EQ(v.at(0, 1, 0), 0.1f);  // 20 -> (20-10)/100
  EXPECT_FLOAT_EQ(v.at(1, 2, 3), 1.0f);
}

TEST(Volume, LoadUInt16LittleEndian) {
  TempDir t("volume");
  const uint8_t bytes[4] = {0xff, 0xff, 0x00, 0x01};  // 65535 and 256
  RawVolumeSpec s = test::rawSpec(t.write("b.raw", bytes, 4), {2, 1, 1}, VoxelType::UInt16, {1, 1, 1}, false, {0, 0});
  Volume v = loadRawVolume(s);
  EXPECT_FLOAT_EQ(v.values[0], 1.0f);  // 65535 is the largest value
  EXPECT_FLOAT_EQ(v.values[1], 0.0f);  // 256 the smallest
  EXPECT_EQ(v.data_range, (std::array<double, 2>{256, 65535}));
  s.has_range = true;
  s.range = {0, 512};
  EXPECT_FLOAT_EQ(loadRawVolume(s).values[1], 0.5f);
}

TEST(Volume, ARangeThatMissesTheDataIsNamedWithTheDataValues) {
  TempDir t("volume");
  uint16_t values[4] = {0, 250, 500, 1000};
  RawVolumeSpec s = test::rawSpec(t.write("g.raw", values, sizeof values), {4, 1, 1}, VoxelType::UInt16, {1, 1, 1}, true, {5000, 6000});
  const std::string why = rangeProblem(loadRawVolume(s));
  EXPECT_NE(why.find("range [5000, 6000] lies above every value"), std::string::npos) << why;
  EXPECT_NE(why.find("0 .. 1000"), std::string::npos) << why;
  s.range = {-10, -1};
  EXPECT_NE(rangeProblem(loadRawVolume(s)).find("lies below"), std::string::npos);
  s.range = {500, 6000};  // overlaps the data: fine
  EXPECT_EQ(rangeProblem(loadRawVolume(s)), "");
  s.has_range = false;
  EXPECT_EQ(rangeProblem(loadRawVolume(s)), "");
}

TEST(Volume, LoadFloat32DefaultRangeIsDataMinMax) {
  TempDir t("volume");
  const float f[4] = {-2.0f, 0.0f, 6.0f, 4.0f};
  RawVolumeSpec s = test::rawSpec(t.write("c.raw", f, sizeof f), {4, 1, 1}, VoxelType::Float32, {1, 1, 1}, false, {0, 0});
  Volume v = loadRawVolume(s);
  EXPECT_FLOAT_EQ(v.values[0], 0.0f);
  EXPECT_FLOAT_EQ(v.values[1], 0.25f);
  EXPECT_FLOAT_EQ(v.values[2], 1.0f);
  EXPECT_FLOAT_EQ(v.values[3], 0.75f);
}

TEST(Volume, ErrorsAreSpecific) {
  TempDir t("volume");
  uint8_t data[10] = {};
  RawVolumeSpec s = test::rawSpec(t.write("d.raw", data, 10), {2, 2, 2}, VoxelType::UInt16, {1, 1, 1}, false, {0, 0});
  std::string e = errorOf(s);
  EXPECT_NE(e.find("d.raw"), std::string::npos) << e;
  EXPECT_NE(e.find("10 bytes"), std::string::npos) << e;  // the file's size
  EXPECT_NE(e.find("16 bytes"), std::string::npos) << e;  // what dims x type need
  s.file = (t.path / "nope.raw").string();
  EXPECT_NE(errorOf(s).find("not found"), std::string::npos);

  float f[2 * 3 * 2] = {};
  f[1 + 2 * (2 + 3 * 1)] = NAN;  // voxel (1, 2, 1), linear 11
  RawVolumeSpec n = test::rawSpec(t.write("e.raw", f, sizeof f), {2, 3, 2}, VoxelType::Float32, {1, 1, 1}, false, {0, 0});
  e = errorOf(n);
  EXPECT_NE(e.find("(1, 2, 1)"), std::string::npos) << e;
  EXPECT_NE(e.find("linear index 11"), std::string::npos) << e;

  RawVolumeSpec r = test::rawSpec(t.write("f.raw", data, 8), {2, 2, 2}, VoxelType::UInt8, {1, 1, 1}, true, {5, 5});
  EXPECT_NE(errorOf(r).find("range"), std::string::npos);
}

TEST(Volume, GeneratorsAreDeterministicAndNormalised) {
  for (const char* name : {"hollow-shell", "marschner-lobb", "noise-cloud", "head"}) {
    GeneratorSpec g{name, 24, 3, {1, 1, 1}};
    Volume a = generateVolume(g), b = generateVolume(g);
    ASSERT_EQ(a.voxelCount(), 24u * 24 * 24) << name;
    EXPECT_EQ(a.values, b.values) << name;
    for (float x : a.values) ASSERT_TRUE(x >= 0.0f && x <= 1.0f) << name << " value " << x;
  }
  GeneratorSpec c{"noise-cloud", 24, 3, {1, 1, 1}};
  Volume c3 = generateVolume(c);
  c.seed = 4;
  EXPECT_NE(generateVolume(c).values, c3.values);  // the seed matters
  size_t zeros = 0;
  for (float x : c3.values) zeros += x == 0.0f;
  EXPECT_GT(zeros, c3.voxelCount() / 3);  // substantial empty space, exactly 0
}

TEST(Volume, HollowShellShape) {
  Volume v = generateVolume({"hollow-shell", 64, 1, {1, 1, 1}});
  EXPECT_EQ(v.at(0, 0, 0), 0.0f);     // outside: exactly empty
  EXPECT_EQ(v.at(32, 32, 32), 1.0f);  // solid core
  EXPECT_EQ(v.at(32, 32, 16), 0.0f);  // between core and shell: exactly empty
  float shell = 0;
  for (int x = 32; x < 64; ++x) shell = std::max(shell, v.at(x, 32, 32));
  EXPECT_FLOAT_EQ(shell, 1.0f);       // core is on this line too
  float rim = 0;
  for (int x = 48; x < 64; ++x) rim = std::max(rim, v.at(x, 32, 32));
  EXPECT_FLOAT_EQ(rim, 0.5f);         // the shell plateau
}

TEST(Volume, MarschnerLobbMatchesFormula) {
  Volume v = generateVolume({"marschner-lobb", 16, 1, {1, 1, 1}});
  // Voxel (8,8,8) sits at (1/16, 1/16, 1/16) in [-1,1]^3.
  double u = 1.0 / 16, r = std::sqrt(2 * u * u), pi = std::acos(-1.0);
  double want = (1 - std::sin(pi * u / 2) + 0.25 * (1 + std::cos(2 * pi * 6 * std::cos(pi * r / 2)))) / 2.5;
  EXPECT_NEAR(v.at(8, 8, 8), want, 1e-6);  // float storage
}

TEST(Volume, GeneratorRejectsBadSpecs) {
  EXPECT_THROW(generateVolume({"teapot", 16, 1, {1, 1, 1}}), std::invalid_argument);
  EXPECT_THROW(generateVolume({"hollow-shell", 1, 1, {1, 1, 1}}), std::invalid_argument);
  EXPECT_THROW(generateVolume({"hollow-shell", 8, 1, {1, 0, 1}}), std::invalid_argument);
}

// Issue 8: the loader says what is wrong before it allocates or opens.
TEST(Volume, NotARegularFileSaysWhatItIs) {
  TempDir t("volume");
  RawVolumeSpec s = test::rawSpec(t.path.string(), {1, 1, 1}, VoxelType::UInt8, {1, 1, 1}, false, {0, 255});
  EXPECT_NE(errorOf(s).find("is a directory"), std::string::npos) << errorOf(s);
  s.file = (t.path / "absent.raw").string();
  EXPECT_NE(errorOf(s).find("file not found"), std::string::npos) << errorOf(s);
}

TEST(Volume, HugeSparseFileNamesTheBytesInsteadOfBadAlloc) {
  TempDir t("volume");
  const std::string f = t.write("huge.raw", "", 0);
  const std::array<int, 3> dims{65536, 65536, 64};  // 2^38 voxels of uint8: 256 GiB of file
  std::filesystem::resize_file(f, (uintmax_t)1 << 38);  // sparse: no disk used
  RawVolumeSpec s = test::rawSpec(f, dims, VoxelType::UInt8, {1, 1, 1}, false, {0, 255});
  const std::string m = errorOf(s);
  EXPECT_NE(m.find("voxels need 1099511627776 bytes"), std::string::npos) << m;  // 4 bytes a voxel
  EXPECT_EQ(m.find("bad_alloc"), std::string::npos) << m;
}

// Every voxel of a window equals the same voxel of the whole volume.
static void expectWindowOfWhole(const Volume& window, const Volume& whole, const VoxelBox& box) {
  ASSERT_EQ(window.origin, box.lo);
  ASSERT_EQ(window.wholeDims(), whole.dims);
  for (int a = 0; a < 3; ++a) ASSERT_EQ(window.dims[a], box.hi[a] - box.lo[a]);
  EXPECT_EQ(window.halfExtent(), whole.halfExtent()) << "a window sits in the whole volume's box";
  for (int z = 0; z < window.dims[2]; ++z)
    for (int y = 0; y < window.dims[1]; ++y)
      for (int x = 0; x < window.dims[0]; ++x)
        ASSERT_EQ(window.at(x, y, z), whole.at(x + box.lo[0], y + box.lo[1], z + box.lo[2])) << x << "," << y << "," << z;
}

TEST(Volume, ARawWindowHoldsOnlyItsBoxAndEqualsThatPartOfTheWhole) {
  TempDir t("volume");
  const std::array<int, 3> n{13, 11, 9};
  std::vector<uint16_t> data((size_t)n[0] * n[1] * n[2]);
  for (size_t i = 0; i < data.size(); ++i) data[i] = (uint16_t)(100 + (i * 7919) % 3001);
  RawVolumeSpec s = test::rawSpec(t.write("w.raw", data.data(), data.size() * 2), n, VoxelType::UInt16, {1, 2, 1}, false, {0, 0});
  const Volume whole = loadRawVolume(s);
  // Interior, whole rows, whole slices, one voxel, the whole volume.
  for (const VoxelBox& box : {VoxelBox{{2, 3, 1}, {7, 9, 4}}, VoxelBox{{0, 2, 3}, {13, 5, 9}}, VoxelBox{{0, 0, 4}, {13, 11, 6}},
                              VoxelBox{{12, 10, 8}, {13, 11, 9}}, VoxelBox{{0, 0, 0}, n}}) {
    const Volume w = loadRawVolume(s, box);
    expectWindowOfWhole(w, whole, box);
    // No range given: every window normalises with the whole file's min..max.
    EXPECT_EQ(w.mapped_range, whole.mapped_range);
    EXPECT_EQ(w.data_range, whole.data_range);
  }
  s.has_range = true;
  s.range = {500, 2500};
  const Volume ranged = loadRawVolume(s);
  expectWindowOfWhole(loadRawVolume(s, VoxelBox{{1, 1, 1}, {12, 4, 8}}), ranged, VoxelBox{{1, 1, 1}, {12, 4, 8}});
  EXPECT_THROW(loadRawVolume(s, VoxelBox{{0, 0, 0}, {14, 11, 9}}), std::runtime_error);
  EXPECT_THROW(loadRawVolume(s, VoxelBox{{3, 0, 0}, {3, 11, 9}}), std::runtime_error);
}

namespace {
// Drops a file from the page cache; false where that cannot be done (tmpfs).
bool dropFromPageCache(const std::string& file) {
  const int fd = ::open(file.c_str(), O_RDONLY);
  const bool ok = fd >= 0 && ::fdatasync(fd) == 0 && ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED) == 0;
  if (fd >= 0) ::close(fd);
  return ok && cachedPages(file) == 0;
}
}  // namespace

// Normalising (four voxels at a time) is the double formula for every voxel, pieces' tails
// included; a series step not in the page cache is read past it (O_DIRECT through an aligned
// buffer) with the same samples, for a header offset and windows that align to nothing.
TEST(Volume, AStepReadPastThePageCacheHasTheBufferedReadsExactSamples) {
  TempDir t("volume");
  const std::array<int, 3> n{130, 131, 70};  // 4.8 MB: several 256 KiB pieces and 4 MiB direct reads
  std::vector<float> f(3 + (size_t)n[0] * n[1] * n[2]);  // 12 header bytes first
  uint32_t seed = 5;
  for (float& x : f) seed = seed * 1664525u + 1013904223u, x = (float)((seed >> 8) / 16777216.0 * 14 - 2);
  RawVolumeSpec s = test::rawSpec(t.write("s.raw", f.data(), f.size() * 4), n, VoxelType::Float32, {1, 1, 1}, true, {0, 10});
  s.offset = 12;
  const Volume whole = loadRawVolume(s);
  for (size_t i = 0; i < whole.values.size(); ++i)
    ASSERT_EQ(whole.values[i], (float)std::clamp((f[3 + i] - 0.0) * (1.0 / 10), 0.0, 1.0)) << i;
  EXPECT_EQ(whole.data_range[0], *std::min_element(f.begin() + 3, f.end()));
  EXPECT_EQ(whole.data_range[1], *std::max_element(f.begin() + 3, f.end()));
  s.read_once = true;
  for (const VoxelBox& box : {VoxelBox{{0, 0, 0}, n}, VoxelBox{{3, 5, 7}, {61, 64, 30}}, VoxelBox{{0, 0, 11}, {130, 131, 60}}}) {
    expectWindowOfWhole(loadRawVolume(s, box), whole, box);  // cached: buffered
    if (!dropFromPageCache(s.file)) GTEST_SKIP() << "cannot drop " << s.file << " from the page cache (tmpfs?)";
    expectWindowOfWhole(loadRawVolume(s, box), whole, box);
    if (box.hi[0] - box.lo[0] == n[0]) {  // whole rows (a renderer's slab); short rows are read buffered
      EXPECT_EQ(cachedPages(s.file), 0u) << "the read went through the page cache";
    }
  }
}

TEST(Volume, AWindowWithoutARangeStillRefusesANonFiniteValueAnywhere) {
  TempDir t("volume");
  std::vector<float> f(4 * 4 * 4, 1.0f);
  f[3 + 4 * (3 + 4 * 3)] = NAN;  // the last voxel, outside the window below
  RawVolumeSpec s = test::rawSpec(t.write("n.raw", f.data(), f.size() * 4), {4, 4, 4}, VoxelType::Float32, {1, 1, 1}, false, {0, 0});
  try {
    loadRawVolume(s, VoxelBox{{0, 0, 0}, {2, 2, 2}});
    FAIL() << "the NaN went unseen";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite value nan at voxel (3, 3, 3)"), std::string::npos) << e.what();
  }
}

// A finite float64 sample beyond float32's range is not a NaN to replace: the message says so.
TEST(Volume, AFloat64SampleBeyondFloat32SaysSoRatherThanNaN) {
  TempDir t("volume");
  std::vector<double> d(2 * 2 * 2, 1.0);
  d[1] = -1e300;
  RawVolumeSpec s = test::rawSpec(t.write("big.raw", d.data(), d.size() * 8), {2, 2, 2}, VoxelType::Float64, {1, 1, 1}, false, {0, 0});
  try {
    loadRawVolume(s);
    FAIL() << "-1e300 went unseen";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("big.raw: -infinite or beyond float32's range (3.4e38) at voxel (1, 0, 0)"),
              std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("NaN"), std::string::npos) << e.what();
  }
}

// Values whose spread is small next to their size (a pressure of 101325 Pa varying by 1e-4, a
// count near 1e8) keep every level: they are held relative to a value near the data's before
// float32 rounds them, not rounded first (which left 2 of 64 levels). Whole, as a window, with
// and without a declared range, and in the master's summary of the file's blocks.
TEST(Volume, WideTypesWithALargeOffsetKeepEveryLevel) {
  TempDir t("volume");
  std::vector<double> d(4 * 4 * 4);
  std::vector<int32_t> n(d.size());
  for (size_t i = 0; i < d.size(); ++i) d[i] = 101325 + 1e-4 * (double)i, n[i] = 100000000 + (int32_t)i;
  const std::string fd = t.write("p.raw", d.data(), d.size() * 8), fi = t.write("n.raw", n.data(), n.size() * 4);
  for (const RawVolumeSpec& s : {test::rawSpec(fd, {4, 4, 4}, VoxelType::Float64, {1, 1, 1}, false, {0, 0}),
                                 test::rawSpec(fd, {4, 4, 4}, VoxelType::Float64, {1, 1, 1}, true, {d.front(), d.back()}),
                                 test::rawSpec(fi, {4, 4, 4}, VoxelType::Int32, {1, 1, 1}, false, {0, 0})}) {
    const Volume v = loadRawVolume(s);
    for (size_t i = 0; i < d.size(); ++i) ASSERT_NEAR(v.values[i], (double)i / 63, 1e-5) << s.file << " voxel " << i;
    EXPECT_NEAR(v.data_range[1] - v.data_range[0], s.type == VoxelType::Int32 ? 63 : 63e-4, 1e-9) << s.file;
    const Volume w = loadRawVolume(s, VoxelBox{{1, 2, 1}, {4, 4, 3}});
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x)
          EXPECT_NEAR(w.at(x, y, z), v.at(x + 1, y + 2, z + 1), 1e-6) << s.file << " window";
    Scene scene = defaultScene();
    scene.volume = s;
    const VolumeSummary sum = summarizeVolume(scene);
    EXPECT_NEAR(sum.lo.front(), 0, 1e-5) << s.file;
    EXPECT_NEAR(*std::max_element(sum.hi.begin(), sum.hi.end()), 1, 1e-5) << s.file;
    EXPECT_LT(*std::min_element(sum.hi.begin(), sum.hi.end()), 0.5) << s.file << ": a block's bounds lost the levels";
  }
}

TEST(Volume, AGeneratedWindowEqualsThatPartOfTheWholeVolume) {
  for (const char* name : {"hollow-shell", "marschner-lobb", "noise-cloud"}) {
    const GeneratorSpec spec{name, 24, 3, {1, 1, 1}};
    const Volume whole = generateVolume(spec);
    const VoxelBox box{{5, 0, 11}, {17, 24, 20}};
    expectWindowOfWhole(generateVolume(spec, box), whole, box);
  }
  EXPECT_THROW(generateVolume(GeneratorSpec{"hollow-shell", 24, 1, {1, 1, 1}}, VoxelBox{{0, 0, 0}, {25, 1, 1}}),
               std::invalid_argument);
}

TEST(Volume, SpacingLimits) {
  EXPECT_EQ(spacingProblem({1, 2, 3}), "");
  EXPECT_NE(spacingProblem({1, 1e-7, 1}).find("ratio"), std::string::npos);
  EXPECT_NE(spacingProblem({INFINITY, 1, 1}).find("finite"), std::string::npos);
  EXPECT_THROW(generateVolume({"hollow-shell", 8, 1, {1, 1, 1e-9}}), std::invalid_argument);
}
