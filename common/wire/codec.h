// Payload codecs for pixel messages. Compression never fails; decompression validates
// and requires the exact raw size (LZO uses the safe decompressor). Thread-safe.
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/result.h"

namespace tessera {

enum class Codec : uint8_t { None = 0, Lzo = 1, Lz4 = 2, Zstd = 3 };
inline constexpr uint8_t kCodecCount = 4;

const char* codecName(Codec c);
// Throws std::invalid_argument naming the accepted names ("none", "lzo", "lz4", "zstd").
Codec parseCodec(const std::string& name);

std::vector<std::byte> compress(Codec c, std::span<const std::byte> raw);
// Fails (never throws) on corrupt data or when the output is not exactly raw_size bytes.
Result<std::vector<std::byte>> decompress(Codec c, std::span<const std::byte> encoded, size_t raw_size);

// Zero-copy variants for the protocol: compressAppend appends the encoded bytes to `out`;
// decompressInto fills `out` and fails unless exactly out.size() bytes were decoded.
// Cheap check before allocating raw_size bytes for untrusted input: false when `encoded`
// cannot possibly decode to raw_size bytes (beyond the codec's maximum ratio, or a zstd
// frame that declares another size). True does not mean the data is valid.
bool plausibleRawSize(Codec c, std::span<const std::byte> encoded, size_t raw_size);
void compressAppend(Codec c, std::span<const std::byte> raw, std::vector<std::byte>& out);
Result<size_t> decompressInto(Codec c, std::span<const std::byte> encoded, std::span<std::byte> out);

}  // namespace tessera
