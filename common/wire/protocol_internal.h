// Private to protocol*.cpp: message framing shared by structured and pixel messages.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "common/wire/bytes.h"
#include "common/wire/protocol.h"

namespace tessera::proto::detail {

inline constexpr int kMaxDimension = 16384;  // image sizes and rect extents, pixels

// A message buffer with room for the header; append the payload after it.
std::vector<std::byte> beginMessage();
// Writes the header over the reserved space; raw_size is the decoded payload size.
void finishMessage(std::vector<std::byte>& msg, Type type, uint64_t frame, uint32_t sender, Codec codec,
                   size_t raw_size);

struct Opened {
  Header header;
  std::span<const std::byte> payload;
};
// decodeHeader, then checks the type; structured (non-pixel) messages must use codec none.
Result<Opened> openMessage(std::span<const std::byte> msg, Type expected, bool pixels);

void writeRect(ByteWriter& w, const Rect& r);
Rect readRect(ByteReader& r, const char* field);
std::string rectText(const Rect& r);  // "x,y wxh"
// Fails the reader unless 0 <= x, y, w, h and x + w, y + h <= kMaxDimension.
void checkSaneRect(ByteReader& r, const Rect& rect, const char* field);
double readFinite(ByteReader& r, const char* field);

template <class F>
std::vector<std::byte> encodeStructured(Type type, uint64_t frame, uint32_t sender, F&& body) {
  auto msg = beginMessage();
  ByteWriter w(msg);
  body(w);
  finishMessage(msg, type, frame, sender, Codec::None, msg.size() - kHeaderSize);
  return msg;
}

// Opens the message, runs body(reader, header, value), requires the payload fully used.
template <class T, class F>
Result<T> decodeStructured(std::span<const std::byte> msg, Type type, F&& body) {
  auto m = openMessage(msg, type, false);
  if (!m) return Result<T>::fail(m.error());
  ByteReader r(m->payload);
  T v{};
  body(r, m->header, v);
  if (r.ok() && r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " trailing bytes");
  if (!r.ok()) return Result<T>::fail(std::string(typeName(type)) + ": " + r.error());
  return v;
}

inline Role readRole(ByteReader& r) {
  uint8_t v = r.u8("role");
  if (r.ok() && !validRole(v)) r.fail("role " + std::to_string(v) + " unknown");
  return static_cast<Role>(v);
}

}  // namespace tessera::proto::detail
