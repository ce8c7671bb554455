// Membership messages on the wire: Hello, Welcome, Heartbeat, Probe, Shutdown and Roster
// (see protocol.h for what each carries).
#include <cmath>
#include <string>
#include <vector>

#include "common/wire/protocol.h"
#include "common/wire/protocol_internal.h"

namespace tessera::proto {

using detail::ByteReader;
using detail::ByteWriter;
using detail::decodeStructured;
using detail::encodeStructured;
using detail::readRole;

std::vector<std::byte> encode(const Hello& m, uint32_t sender) {
  return encodeStructured(Type::Hello, 0, sender, [&](ByteWriter& w) {
    w.u8(static_cast<uint8_t>(m.role));
    w.u32(m.pid);
    w.str(m.endpoint);
    w.str(m.run);
    w.str(m.scene);
  });
}
Result<Hello> decodeHello(std::span<const std::byte> msg) {
  return decodeStructured<Hello>(msg, Type::Hello, [](ByteReader& r, const Header&, Hello& m) {
    m.role = readRole(r);
    m.pid = r.u32("pid");
    m.endpoint = r.str("endpoint");
    m.run = r.str("run");
    m.scene = r.str("scene");
  });
}

std::vector<std::byte> encode(const Welcome& m, uint32_t sender) {
  return encodeStructured(Type::Welcome, 0, sender, [&](ByteWriter& w) {
    w.u8(static_cast<uint8_t>(m.role));
    w.u32(m.rank);
    w.f64(m.volume_range[0]);
    w.f64(m.volume_range[1]);
  });
}
Result<Welcome> decodeWelcome(std::span<const std::byte> msg) {
  return decodeStructured<Welcome>(msg, Type::Welcome, [](ByteReader& r, const Header&, Welcome& m) {
    m.role = readRole(r);
    m.rank = r.u32("rank");
    m.volume_range[0] = detail::readFinite(r, "volume_range.lo");
    m.volume_range[1] = detail::readFinite(r, "volume_range.hi");
    const auto [lo, hi] = m.volume_range;
    if (r.ok() && !(lo < hi) && !(lo == 0 && hi == 0))
      r.fail("volume_range [" + std::to_string(lo) + ", " + std::to_string(hi) + "] is neither none nor lo < hi");
  });
}

std::vector<std::byte> encode(const Heartbeat& m, uint32_t sender) {
  return encodeStructured(Type::Heartbeat, 0, sender, [&](ByteWriter& w) {
    w.u8(static_cast<uint8_t>(m.role));
    w.u32(m.rank);
    w.u64(m.waiting_frame);
    w.u32(m.waiting_for);
  });
}
Result<Heartbeat> decodeHeartbeat(std::span<const std::byte> msg) {
  return decodeStructured<Heartbeat>(msg, Type::Heartbeat, [](ByteReader& r, const Header&, Heartbeat& m) {
    m.role = readRole(r);
    m.rank = r.u32("rank");
    m.waiting_frame = r.u64("waiting_frame");
    m.waiting_for = r.u32("waiting_for");
  });
}

std::vector<std::byte> encode(const Probe&, uint32_t sender) {
  return encodeStructured(Type::Probe, 0, sender, [](ByteWriter&) {});
}
Result<Probe> decodeProbe(std::span<const std::byte> msg) {
  return decodeStructured<Probe>(msg, Type::Probe, [](ByteReader&, const Header&, Probe&) {});
}

std::vector<std::byte> encode(const Shutdown& m, uint32_t sender) {
  return encodeStructured(Type::Shutdown, 0, sender, [&](ByteWriter& w) {
    w.str(m.reason);
    w.str(m.run);
  });
}
Result<Shutdown> decodeShutdown(std::span<const std::byte> msg) {
  return decodeStructured<Shutdown>(msg, Type::Shutdown,
                                    [](ByteReader& r, const Header&, Shutdown& m) {
    m.reason = r.str("reason");
    m.run = r.str("run");
  });
}

std::vector<std::byte> encode(const Roster& m, uint32_t sender) {
  return encodeStructured(Type::Roster, 0, sender, [&](ByteWriter& w) {
    w.u32(m.epoch);
    w.u32(static_cast<uint32_t>(m.members.size()));
    for (const RosterEntry& e : m.members) {
      w.u8(static_cast<uint8_t>(e.role));
      w.u32(e.rank);
      w.str(e.identity);
    }
  });
}
Result<Roster> decodeRoster(std::span<const std::byte> msg) {
  return decodeStructured<Roster>(msg, Type::Roster, [](ByteReader& r, const Header&, Roster& m) {
    m.epoch = r.u32("epoch");
    m.members.resize(r.count("members", 1u << 16, 1 + 4 + 4));
    for (RosterEntry& e : m.members) {
      e.role = readRole(r);
      e.rank = r.u32("members.rank");
      e.identity = r.str("members.identity");
      if (r.ok() && (e.identity.empty() || e.identity.size() > 255))
        r.fail("members.identity: " + std::to_string(e.identity.size()) + " bytes, not 1..255 (a ZeroMQ routing id)");
    }
  });
}

const char* roleName(Role r) {
  switch (r) {
    case Role::Renderer: return "renderer";
    case Role::Compositor: return "compositor";
    case Role::Display: return "display";
  }
  return "?";
}

}  // namespace tessera::proto
