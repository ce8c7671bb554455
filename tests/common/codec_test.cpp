// Codec round trips and failure modes: every decoder must reject bad input cleanly.
#include "common/wire/codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tests/common/random_bytes.h"

namespace tessera {
namespace {

// rgba8 with a smooth disc of colour in a transparent field, like a volume rendering.
std::vector<std::byte> imageLike(int w, int h) {
  std::vector<std::byte> v(size_t(4) * w * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double dx = x - w / 2.0, dy = y - h / 2.0, r = std::sqrt(dx * dx + dy * dy) / (w / 3.0);
      if (r >= 1) continue;
      auto* p = &v[4 * (size_t(y) * w + x)];
      double a = 1 - r;
      p[0] = std::byte(uint8_t(255 * a * (0.5 + 0.5 * std::sin(x * 0.05))));
      p[1] = std::byte(uint8_t(255 * a * 0.6));
      p[2] = std::byte(uint8_t(255 * a * (0.5 + 0.5 * std::cos(y * 0.03))));
      p[3] = std::byte(uint8_t(255 * a));
    }
  }
  return v;
}

const Codec kAll[] = {Codec::None, Codec::Lzo, Codec::Lz4, Codec::Zstd};

class CodecTest : public ::testing::TestWithParam<Codec> {};

TEST_P(CodecTest, RoundTripsRandomZeroAndImageData) {
  const Codec c = GetParam();
  const std::vector<std::vector<std::byte>> inputs = {
      {}, randomBytes(1, 1), randomBytes(100000, 2), std::vector<std::byte>(1 << 20), imageLike(256, 256)};
  for (const auto& raw : inputs) {
    auto enc = compress(c, raw);
    auto dec = decompress(c, enc, raw.size());
    ASSERT_TRUE(dec) << codecName(c) << " size " << raw.size() << ": " << dec.error();
    EXPECT_EQ(*dec, raw) << codecName(c) << " size " << raw.size();
  }
}

TEST_P(CodecTest, CompressesZerosAndImagesButNotNone) {
  const Codec c = GetParam();
  std::vector<std::byte> zeros(1 << 20);
  auto img = imageLike(256, 256);
  if (c == Codec::None) {
    EXPECT_EQ(compress(c, zeros).size(), zeros.size());
    return;
  }
  // Runs of zeros compress at least 100:1 with every real codec (LZO is the weakest, ~250:1).
  EXPECT_LT(compress(c, zeros).size(), zeros.size() / 100) << codecName(c);
  // A smooth image with a transparent border compresses to well under half.
  EXPECT_LT(compress(c, img).size(), img.size() / 2) << codecName(c);
}

TEST_P(CodecTest, WrongRawSizeFails) {
  const Codec c = GetParam();
  auto raw = imageLike(64, 64);
  auto enc = compress(c, raw);
  EXPECT_FALSE(decompress(c, enc, raw.size() - 1)) << codecName(c);
  EXPECT_FALSE(decompress(c, enc, raw.size() + 1)) << codecName(c);
  EXPECT_FALSE(decompress(c, enc, 0)) << codecName(c);
}

TEST_P(CodecTest, TruncatedInputFailsAtEveryLength) {
  const Codec c = GetParam();
  auto raw = imageLike(32, 32);
  auto enc = compress(c, raw);
  for (size_t n = 0; n < enc.size(); ++n) {
    auto dec = decompress(c, std::span(enc).first(n), raw.size());
    EXPECT_FALSE(dec) << codecName(c) << " truncated to " << n << " of " << enc.size();
  }
}

TEST_P(CodecTest, CorruptInputNeverCrashesAndNeverLies) {
  const Codec c = GetParam();
  auto raw = imageLike(64, 64);
  auto enc = compress(c, raw);
  std::mt19937 rng(7);
  int failures = 0;
  for (int trial = 0; trial < 300; ++trial) {
    auto bad = enc;
    for (int k = 0; k < 3; ++k) bad[rng() % bad.size()] ^= std::byte(1 + rng() % 255);
    auto dec = decompress(c, bad, raw.size());
    if (!dec) {
      ++failures;
      EXPECT_FALSE(dec.error().empty());
    } else {
      EXPECT_EQ(dec->size(), raw.size());  // success is only ever the exact size
    }
  }
  if (c != Codec::None) {
    EXPECT_GT(failures, 0) << codecName(c) << ": no corruption was ever detected";
    // Pure garbage is rejected by every compressed format.
    EXPECT_FALSE(decompress(c, randomBytes(4096, 9), raw.size())) << codecName(c);
  }
}

TEST_P(CodecTest, ImpossibleRawSizeFailsBeforeAllocating) {
  const Codec c = GetParam();
  auto raw = imageLike(32, 32);
  auto enc = compress(c, raw);
  EXPECT_TRUE(plausibleRawSize(c, enc, raw.size())) << codecName(c);
  // 1 TiB from a few KiB: allocating it would throw bad_alloc; it must be a clean failure.
  const size_t huge = size_t(1) << 40;
  EXPECT_FALSE(plausibleRawSize(c, enc, huge)) << codecName(c);
  auto r = decompress(c, enc, huge);
  ASSERT_FALSE(r) << codecName(c);
  EXPECT_NE(r.error().find(codecName(c)), std::string::npos) << r.error();
}

INSTANTIATE_TEST_SUITE_P(Codecs, CodecTest, ::testing::ValuesIn(kAll),
                         [](const auto& p) { return std::string(codecName(p.param)); });

TEST(CodecNames, ParseRoundTripsAndRejectsUnknown) {
  for (Codec c : kAll) EXPECT_EQ(parseCodec(codecName(c)), c);
  try {
    parseCodec("gzip");
    FAIL() << "parseCodec accepted gzip";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lzo"), std::string::npos) << e.what();
  }
}

TEST(CodecNames, UnknownCodecValueFailsToDecompress) {
  EXPECT_FALSE(decompress(static_cast<Codec>(9), std::vector<std::byte>(4), 4));
}

TEST(Codec, CompressAppendKeepsPrefixAndDecompressIntoFillsExactly) {
  auto raw = imageLike(32, 32);
  std::vector<std::byte> out(5, std::byte{0x42});
  compressAppend(Codec::Lz4, raw, out);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(out[i], std::byte{0x42});
  std::vector<std::byte> back(raw.size());
  auto r = decompressInto(Codec::Lz4, std::span(out).subspan(5), back);
  ASSERT_TRUE(r) << r.error();
  EXPECT_EQ(back, raw);
}

}  // namespace
}  // namespace tessera
