// PNG and raw float files written to a temporary folder and read back.
#include "common/io/image_io.h"

#include "tests/common/image_dump.h"
#include "tests/common/temp_dir.h"

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

using namespace tessera;
namespace fs = std::filesystem;

namespace {
using test::TempDir;
}  // namespace

TEST(ImageIo, OpaquePngRoundTripIsExact) {
  TempDir t("image_io");
  Image8 img(5, 3);
  for (size_t i = 0; i < img.px.size(); ++i) img.px[i] = (i % 4 == 3) ? 255 : (uint8_t)(i * 37);
  writePng(t.file("a.png"), img);
  EXPECT_EQ(readPng(t.file("a.png")), img);
}

// The PNG writer hands the compressor filtered rows 256 KiB at a time: images of one
// block, of several (a row per block boundary or many rows per block), and a 1x1 one must
// come back exactly through libpng, which checks every chunk's CRC and the stream's Adler-32.
TEST(ImageIo, OpaquePngRoundTripIsExactAcrossCompressionBlocks) {
  TempDir t("image_io");
  for (const auto& [w, h] : {std::pair{1, 1}, {700, 300}, {16, 16000}, {16384, 8}, {1024, 1024}, {1000, 1000}}) {
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    Image8 img(w, h);
    uint32_t seed = 12345;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        uint8_t* p = img.at(x, y);
        seed = seed * 1664525u + 1013904223u;
        // Noise in a disc, runs of one colour and zeros around it, as frames have; the last
        // image noise everywhere, which compresses to more than the buffer first made for it.
        const bool noise = w == 1000;
        const bool inside = noise || (x - w / 2) * (double)(x - w / 2) + (y - h / 2) * (double)(y - h / 2) < w * (double)h / 9;
        p[0] = inside ? (uint8_t)(seed >> 24) : 0;
        p[1] = inside ? (uint8_t)(noise ? seed >> 16 : x + y) : 0;
        p[2] = inside ? (uint8_t)(noise ? seed >> 8 : 200) : 0;
        p[3] = 255;
      }
    writePng(t.file("blocks.png"), img);
    EXPECT_EQ(readPng(t.file("blocks.png")), img);
    const std::vector<uint8_t> bytes = encodePng(img);
    std::ifstream in(t.file("blocks.png"), std::ios::binary);
    EXPECT_EQ(std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), {}), bytes);  // file == memory
  }
}

// A row wider than the writer's 256 KiB block (70000 pixels: past readPng's limit, so read
// with libpng's own API).
TEST(ImageIo, PngRowWiderThanACompressionBlock) {
  TempDir t("image_io");
  Image8 img(70000, 3);
  for (size_t i = 0; i < img.px.size(); ++i) img.px[i] = (i % 4 == 3) ? 255 : (uint8_t)(i * 7 / 5);
  writePng(t.file("wide.png"), img);
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&png, t.file("wide.png").c_str())) << png.message;
  png.format = PNG_FORMAT_RGBA;
  ASSERT_EQ(png.width, 70000u);
  std::vector<uint8_t> raw(PNG_IMAGE_SIZE(png));
  ASSERT_TRUE(png_image_finish_read(&png, nullptr, raw.data(), 0, nullptr)) << png.message;
  EXPECT_TRUE(raw == img.px);
}

TEST(ImageIo, BackgroundOutsideTheUnitIntervalIsRefused) {
  EXPECT_FALSE(backgroundColour({}).has_value());
  EXPECT_EQ(backgroundColour({0, 0.5, 1}), (std::array<double, 3>{0, 0.5, 1}));
  for (const std::vector<double>& bad : {std::vector<double>{1.5, 0, 0}, {0, -0.1, 0}, {0, 0, std::nan("")}, {0.5, 0.5}})
    EXPECT_THROW(backgroundColour(bad), std::invalid_argument);
  Image8 img(1, 1);
  EXPECT_THROW(pngPixels(img, std::array<double, 3>{0, std::nan(""), 0}), std::invalid_argument);
}

TEST(ImageIo, TranslucentPngRoundTripWithinOneLevel) {
  // Tolerance 1/255: un-premultiplying then premultiplying again rounds twice.
  TempDir t("image_io");
  Image8 img(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      uint8_t a = (uint8_t)(x * 16 + y), c = (uint8_t)(a * ((x + y) % 5) / 4);
      uint8_t* p = img.at(x, y);
      p[0] = c, p[1] = a, p[2] = 0, p[3] = a;
    }
  writePng(t.file("b.png"), img);
  Image8 back = readPng(t.file("b.png"));
  ASSERT_EQ(back.width, 16);
  for (size_t i = 0; i < img.px.size(); ++i) EXPECT_LE(std::abs(back.px[i] - img.px[i]), 1) << "byte " << i;
}

// What the file stores is straight alpha: every (alpha, premultiplied value) pair, read back
// raw with libpng, is round(255 * min(1, value / alpha)) (ties up), alpha unchanged, 0 where
// alpha is 0.
TEST(ImageIo, PngStoresStraightAlphaForEveryPair) {
  TempDir t("image_io");
  Image8 img(256, 256);
  for (int a = 0; a < 256; ++a)
    for (int v = 0; v < 256; ++v) {
      uint8_t* p = img.at(v, a);
      p[0] = p[1] = p[2] = (uint8_t)v;
      p[3] = (uint8_t)a;
    }
  writePng(t.file("pairs.png"), img);
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&png, t.file("pairs.png").c_str()));
  png.format = PNG_FORMAT_RGBA;
  std::vector<uint8_t> raw(PNG_IMAGE_SIZE(png));
  ASSERT_TRUE(png_image_finish_read(&png, nullptr, raw.data(), 0, nullptr));
  int wrong = 0;
  for (int a = 0; a < 256; ++a)
    for (int v = 0; v < 256; ++v) {
      const uint8_t* p = &raw[4 * (size_t(a) * 256 + v)];
      // 255 v / a rounded half up, computed exactly in long double (v, a < 256).
      const int expect = a == 0 ? 0 : (int)std::min<long double>(255, std::floor(255.0L * v / a + 0.5L));
      wrong += p[0] != expect || p[3] != a;
    }
  EXPECT_EQ(wrong, 0);
}

// Over a background the rows come from a table built per background: for every (alpha,
// value) pair and two backgrounds in turn (the table must follow the background), each byte
// is the direct computation, round(255 * (v + (1 - a) * bg)) in double, ties up.
TEST(ImageIo, OverABackgroundEveryPairIsTheDirectComputation) {
  Image8 img(256, 256);
  for (int a = 0; a < 256; ++a)
    for (int v = 0; v < 256; ++v) {
      uint8_t* p = img.at(v, a);
      p[0] = (uint8_t)v, p[1] = (uint8_t)(255 - v), p[2] = (uint8_t)(v / 2);
      p[3] = (uint8_t)a;
    }
  for (const std::array<double, 3> bg : {std::array<double, 3>{0.2, 0.5, 1.0}, {1.0, 0.0, 0.125}}) {
    const std::vector<uint8_t> rows = pngPixels(img, bg);
    int wrong = 0;
    for (size_t i = 0; i < img.px.size(); i += 4) {
      for (int k = 0; k < 3; ++k) {
        const double v = std::floor(255.0 * (img.px[i + k] / 255.0 + (1 - img.px[i + 3] / 255.0) * bg[k]) + 0.5);
        wrong += rows[i + k] != (uint8_t)std::clamp(v, 0.0, 255.0);
      }
      wrong += rows[i + 3] != 255;
    }
    EXPECT_EQ(wrong, 0) << bg[0];
  }
}

TEST(ImageIo, BackgroundMakesOpaque) {
  TempDir t("image_io");
  ImageF img(2, 1);
  img.px = {0, 0, 0, 0, 0.25f, 0.25f, 0.25f, 0.5f};
  writePng(t.file("c.png"), img, std::array<double, 3>{1.0, 0.0, 0.5});
  Image8 back = readPng(t.file("c.png"));
  // transparent -> background; 0.25 + 0.5 * bg, rounded.
  const uint8_t want[8] = {255, 0, 128, 255, 191, 64, 128, 255};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(back.px[i], want[i]) << "byte " << i;
}

TEST(ImageIo, RawF32Layout) {
  TempDir t("image_io");
  ImageF img(3, 2);
  img.px[5] = 0.75f;
  writeRawF32(t.file("d.raw"), img);
  std::ifstream in(t.file("d.raw"), std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  ASSERT_EQ(bytes.size(), 16u + 3 * 2 * 16);
  EXPECT_EQ(std::string(bytes.data(), 8), "TSRAWF32");
  EXPECT_EQ(bytes[8], 3);
  EXPECT_EQ(bytes[12], 2);
  float v;
  std::memcpy(&v, &bytes[16 + 5 * 4], 4);
  EXPECT_EQ(v, 0.75f);
}

TEST(ImageIo, ErrorsNameTheFile) {
  TempDir t("image_io");
  try {
    readPng(t.file("missing.png"));
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos) << e.what();
  }
  std::ofstream(t.file("junk.png")) << "not a png at all";
  EXPECT_THROW(readPng(t.file("junk.png")), std::runtime_error);
}

TEST(ImageIo, TruncatedOrDamagedPngIsAnErrorNamingTheFile) {
  TempDir t("image_io");
  Image8 img(64, 48);
  for (size_t i = 0; i < img.px.size(); ++i) img.px[i] = (uint8_t)(i * 31 % 251);
  for (size_t i = 3; i < img.px.size(); i += 4) img.px[i] = 255;
  writePng(t.file("whole.png"), img);
  std::ifstream in(t.file("whole.png"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  ASSERT_GT(bytes.size(), 100u);
  auto expectError = [&](const std::string& name, const std::string& content) {
    std::ofstream(t.file(name), std::ios::binary) << content;
    try {
      readPng(t.file(name));
      ADD_FAILURE() << name << ": read without an error";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not a valid PNG"), std::string::npos) << e.what();
    }
  };
  expectError("cut.png", bytes.substr(0, bytes.size() / 2));  // the image data ends early
  std::string damaged = bytes;
  damaged[damaged.size() / 2] ^= 0x5a;  // a flipped byte in the compressed data: CRC mismatch
  expectError("flipped.png", damaged);
}

TEST(ImageIo, PremultipliedPamRoundTripIsExact) {
  // Translucent pixels whose colour <= alpha: a PNG could not keep them exactly, a PAM must.
  TempDir t("image_io");
  Image8 img(7, 5);
  for (size_t i = 0; i < img.px.size(); i += 4) {
    img.px[i + 3] = (uint8_t)(i * 13 % 256);
    for (int k = 0; k < 3; ++k) img.px[i + k] = (uint8_t)(img.px[i + 3] * (k + 1) / 4);
  }
  writePam(t.file("a.pam"), img);
  EXPECT_EQ(readPam(t.file("a.pam")), img);
}

TEST(ImageIo, PamOfAnotherTupleTypeIsRefused) {
  TempDir t("image_io");
  std::ofstream(t.file("s.pam"), std::ios::binary) << "P7\nWIDTH 1\nHEIGHT 1\nDEPTH 4\nMAXVAL 255\nTUPLTYPE RGB_ALPHA\nENDHDR\n"
                                                   << std::string(4, '\x10');
  try {
    readPam(t.file("s.pam"));
    FAIL() << "straight-alpha PAM accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("RGB_ALPHA_PREMULTIPLIED"), std::string::npos) << e.what();
  }
}

TEST(ImageIo, AFailingComparisonLeavesExpectedActualAndDiffPngs) {
  TempDir t("image_mismatch");
  Image8 expected(3, 2);
  for (size_t i = 3; i < expected.px.size(); i += 4) expected.px[i] = 255;  // opaque: PNG keeps it exactly
  Image8 actual = expected;
  actual.px[4 * 4 + 1] = 5;  // pixel (1, 1), green: 5 levels off
  const std::string named = test::writeImageMismatch(t.path, "frame_7", expected, actual);
  EXPECT_NE(named.find("frame_7_{expected,actual,diff}.png"), std::string::npos) << named;
  EXPECT_EQ(readPng(t.file("frame_7_expected.png")), expected);
  EXPECT_EQ(readPng(t.file("frame_7_actual.png")), actual);
  const Image8 diff = readPng(t.file("frame_7_diff.png"));
  EXPECT_EQ(diff.at(1, 1)[0], 80);  // 5 levels x 16
  EXPECT_EQ(diff.at(0, 0)[0], 0);
  EXPECT_EQ(diff.at(0, 0)[3], 255);
}
