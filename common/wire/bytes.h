// Private to the protocol: explicit little-endian writer and a bounds-checked reader.
// The reader never throws and never reads past its span; after any failure it stays
// failed, and `error()` names the first field that did not fit.
#pragma once
#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace tessera::proto::detail {

inline constexpr uint32_t kMaxString = 64 * 1024;  // endpoints, reasons, names, a Hello's scene

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::byte>& out) : out_(out) {}
  void u8(uint8_t v) { out_.push_back(std::byte{v}); }
  void u16(uint16_t v) { le(v, 2); }
  void u32(uint32_t v) { le(v, 4); }
  void u64(uint64_t v) { le(v, 8); }
  void i32(int32_t v) { le(static_cast<uint32_t>(v), 4); }
  void f64(double v) { le(std::bit_cast<uint64_t>(v), 8); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    const auto* p = reinterpret_cast<const std::byte*>(s.data());
    out_.insert(out_.end(), p, p + s.size());
  }

 private:
  void le(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out_.push_back(std::byte(static_cast<uint8_t>(v >> (8 * i))));
  }
  std::vector<std::byte>& out_;
};

class ByteReader {
 public:
  explicit ByteReader(std::span<const std::byte> in) : in_(in) {}
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  size_t pos() const { return pos_; }
  size_t remaining() const { return in_.size() - pos_; }
  std::span<const std::byte> rest() const { return in_.subspan(pos_); }

  uint8_t u8(const char* field) { return static_cast<uint8_t>(le(1, field)); }
  uint16_t u16(const char* field) { return static_cast<uint16_t>(le(2, field)); }
  uint32_t u32(const char* field) { return static_cast<uint32_t>(le(4, field)); }
  uint64_t u64(const char* field) { return le(8, field); }
  int32_t i32(const char* field) { return static_cast<int32_t>(static_cast<uint32_t>(le(4, field))); }
  double f64(const char* field) { return std::bit_cast<double>(le(8, field)); }
  bool boolean(const char* field) {
    uint8_t v = u8(field);
    if (v > 1) fail(std::string(field) + ": bool " + std::to_string(v) + " not 0 or 1");
    return v == 1;
  }
  std::string str(const char* field) {
    uint32_t n = u32(field);
    if (!ok()) return {};
    if (n > kMaxString) {
      fail(std::string(field) + ": string length " + std::to_string(n) + " too long");
      return {};
    }
    if (n > remaining()) {
      fail(std::string(field) + ": truncated");
      return {};
    }
    std::string s(reinterpret_cast<const char*>(in_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  // A count of elements each at least min_bytes long; fails before anything is allocated
  // when the remaining bytes cannot possibly hold that many.
  uint32_t count(const char* field, uint32_t max, size_t min_bytes) {
    uint32_t n = u32(field);
    if (!ok()) return 0;
    if (n > max || n * min_bytes > remaining()) {
      fail(std::string(field) + ": count " + std::to_string(n) + " too large");
      return 0;
    }
    return n;
  }
  void fail(std::string why) {
    if (ok()) error_ = std::move(why);
    pos_ = in_.size();
  }

 private:
  uint64_t le(int n, const char* field) {
    if (!ok()) return 0;
    if (remaining() < static_cast<size_t>(n)) {
      fail(std::string(field) + ": truncated");
      return 0;
    }
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(in_[pos_ + i]) << (8 * i);
    pos_ += n;
    return v;
  }
  std::span<const std::byte> in_;
  size_t pos_ = 0;
  std::string error_;
};

}  // namespace tessera::proto::detail
