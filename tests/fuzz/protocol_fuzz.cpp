// Feeds arbitrary bytes to every protocol decoder. Byte 0 picks the mode: even = the input
// as a raw message; odd = the input as type/codec/payload, framed with a valid header and
// checksum so the fuzzer reaches the payload parsers and decompressors. Anything that
// decodes must re-encode to a message that decodes to the same value.
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "common/wire/protocol.h"

using namespace tessera;
using namespace tessera::proto;

namespace {

// The pixel decoders without a receiver's bound, as values (the bound is a defaulted argument).
Result<Piece> anyPiece(std::span<const std::byte> m) { return decodePiece(m); }
Result<Strips> anyStrips(std::span<const std::byte> m) { return decodeStrips(m); }
Result<Framebuffer> anyFramebuffer(std::span<const std::byte> m) { return decodeFramebuffer(m); }


uint32_t adler(const std::vector<std::byte>& m, size_t from) {
  uint32_t a = 1, b = 0;
  for (size_t i = from; i < m.size(); ++i) {
    a = (a + uint8_t(m[i])) % 65521;
    b = (b + a) % 65521;
  }
  return (b << 16) | a;
}

void put(std::vector<std::byte>& m, size_t off, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) m[off + i] = std::byte(uint8_t(v >> (8 * i)));
}

// data: [type][codec][raw_size u32][payload...] -> a correctly framed message.
std::vector<std::byte> frame(const uint8_t* data, size_t size) {
  std::vector<std::byte> m(kHeaderSize);
  if (size < 6) return m;
  const uint8_t type = 1 + data[0] % kTypeCount, codec = data[1] % kCodecCount;
  const uint32_t raw = data[2] | data[3] << 8 | data[4] << 16 | uint32_t(data[5] & 0x0F) << 24;
  const auto* p = reinterpret_cast<const std::byte*>(data + 6);
  m.insert(m.end(), p, p + (size - 6));
  put(m, 0, kMagic, 4);
  put(m, 4, kVersion, 2);
  put(m, 6, type, 2);
  put(m, 20, codec, 1);
  put(m, 24, codec == 0 ? size - 6 : raw, 4);
  put(m, 28, size - 6, 4);
  put(m, 32, adler(m, kHeaderSize), 4);
  return m;
}

template <class T, class Dec, class Enc>
void check(std::span<const std::byte> msg, Dec dec, Enc enc) {
  Result<T> r = dec(msg);
  if (!r) {
    if (r.error().empty()) std::abort();  // every failure carries a reason
    return;
  }
  Result<T> again = dec(enc(*r));
  if (!again || !(*again == *r)) std::abort();
}

void writeSeed(const std::string& dir, int& n, const std::vector<std::byte>& msg) {
  std::ofstream f(dir + "/seed" + std::to_string(n++), std::ios::binary);
  const char mode = 0;  // even first byte: the rest is a raw message
  f.write(&mode, 1);
  f.write(reinterpret_cast<const char*>(msg.data()), std::streamsize(msg.size()));
}

// One valid message of every type, so mutations start from deep inside the decoders.
void writeSeeds(const std::string& dir) {
  int n = 0;
  writeSeed(dir, n, encode(Hello{Role::Compositor, 42, "ipc:///tmp/x", "run", "image: [64, 64]\n"}, 1));
  writeSeed(dir, n, encode(Welcome{Role::Renderer, 2}, 1));
  writeSeed(dir, n, encode(Heartbeat{Role::Display, 0}, 1));
  writeSeed(dir, n, encode(Probe{}, 1));
  writeSeed(dir, n, encode(Shutdown{"bye", "run-1"}, 1));
  writeSeed(dir, n, encode(Roster{3, {{Role::Renderer, 1, "0123456789abcdefd"}}}, 1));
  FrameParams fp;
  fp.width = 64;
  fp.height = 32;
  fp.work = SortLastWork{{{0, {{0, 0, 0}, {8, 8, 8}}}, {1, {{8, 0, 0}, {16, 8, 8}}}}, {1, 0}, {}};
  fp.regions = {{0, {0, 0, 64, 16}, "a"}, {1, {0, 16, 64, 16}, "b"}};
  fp.step = 3, fp.next_step = 4;
  writeSeed(dir, n, encode(fp, 1));
  std::get<SortLastWork>(fp.work).swap = {{0, "ipc:///tmp/r0"}, {1, "tcp://10.0.0.2:40001"}};  // binary swap
  writeSeed(dir, n, encode(fp, 1));
  fp.work = SortFirstWork{{{0, 1, {0, 0, 32, 32}}, {1, 0, {32, 0, 32, 32}}}};
  writeSeed(dir, n, encode(fp, 1));
  StageStats st;  // fields by name: a partial brace list warns (-Wmissing-field-initializers)
  st.rank = 1, st.frame = 3, st.work_ms = 1, st.encode_ms = 2, st.decode_ms = 0.5;
  st.bytes_raw = 3, st.bytes_encoded = 4, st.active_pixels = 5, st.active = {0, 0, 4, 4};
  st.step = 7, st.step_hits = 6, st.step_misses = 1, st.bytes_read = 4096, st.prefetch_ms = 2, st.wait_ms = 3;
  writeSeed(dir, n, encode(st, 1));
  writeSeed(dir, n, encode(FrameDone{3, 1, 2, 3, 4, 5}, 1));
  writeSeed(dir, n, encode(Input{3, 1, 2, 1.5, QualityName::Fast, true, 640, 480, TimeKey::Forward}, 1));
  writeSeed(dir, n, encode(Input{4, 0, 0, 1, std::nullopt, false, 0, 0, TimeKey::None, true}, 1));
  for (uint8_t c = 0; c < kCodecCount; ++c) {
    Piece p;
    p.region = {0, 0, 16, 16};
    p.active = {2, 3, 5, 4};
    p.pixels.resize(5 * 4 * 4);
    for (size_t i = 0; i < p.pixels.size(); ++i) p.pixels[i] = std::byte(uint8_t(i / 3));
    writeSeed(dir, n, encode(p, 1, Codec(c)));
    Strips s;
    s.stream.assign(200, 0);
    s.stream[5] = 9;
    writeSeed(dir, n, encode(s, 1, Codec(c)));
  }
}

}  // namespace

// With TESSERA_FUZZ_SEEDS=<dir> set, writes the seed corpus there first (run.sh does).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("TESSERA_FUZZ_SEEDS")) writeSeeds(dir);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  std::vector<std::byte> framed;
  std::span<const std::byte> msg;
  if (data[0] & 1) {
    framed = frame(data + 1, size - 1);
    msg = framed;
  } else {
    framed.assign(reinterpret_cast<const std::byte*>(data + 1), reinterpret_cast<const std::byte*>(data + size));
    msg = framed;  // own allocation: ASan catches any read past the end
  }
  auto h = decodeHeader(msg);
  const Codec codec = h ? h->codec : Codec::None;
  const uint32_t sender = h ? h->sender : 0;
  check<Hello>(msg, decodeHello, [&](const Hello& v) { return encode(v, sender); });
  check<Welcome>(msg, decodeWelcome, [&](const Welcome& v) { return encode(v, sender); });
  check<Heartbeat>(msg, decodeHeartbeat, [&](const Heartbeat& v) { return encode(v, sender); });
  check<Probe>(msg, decodeProbe, [&](const Probe& v) { return encode(v, sender); });
  check<Shutdown>(msg, decodeShutdown, [&](const Shutdown& v) { return encode(v, sender); });
  check<Roster>(msg, decodeRoster, [&](const Roster& v) { return encode(v, sender); });
  check<FrameParams>(msg, decodeFrameParams, [&](const FrameParams& v) { return encode(v, sender); });
  check<Piece>(msg, anyPiece, [&](const Piece& v) { return encode(v, sender, codec); });
  check<Strips>(msg, anyStrips, [&](const Strips& v) { return encode(v, sender, codec); });
  check<Framebuffer>(msg, anyFramebuffer, [&](const Framebuffer& v) { return encode(v, sender, codec); });
  check<StageStats>(msg, decodeStageStats, [&](const StageStats& v) { return encode(v, sender); });
  check<FrameDone>(msg, decodeFrameDone, [&](const FrameDone& v) { return encode(v, sender); });
  check<Input>(msg, decodeInput, [&](const Input& v) { return encode(v, sender); });
  return 0;
}
