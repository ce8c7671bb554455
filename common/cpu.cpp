#include "common/cpu.h"

#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace tessera {
namespace {

Isa supportedIsa() {
#if defined(__x86_64__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v4")) return Isa::Avx512;
  if (__builtin_cpu_supports("x86-64-v3")) return Isa::Avx2;
#endif
  return Isa::Scalar;
}

Gathers ownGathers() {
  bool intel = false;
#if defined(__x86_64__)
  __builtin_cpu_init();
  intel = __builtin_cpu_is("intel");
#endif
  std::string report;
  std::getline(std::ifstream("/sys/devices/system/cpu/vulnerabilities/gather_data_sampling"), report);
  return gathersFor(intel, report);
}

}  // namespace

const char* isaName(Isa isa) {
  switch (isa) {
    case Isa::Avx512: return "avx512";
    case Isa::Avx2: return "avx2";
    case Isa::Scalar: break;
  }
  return "scalar";
}

Isa chooseIsa(const std::string& requested, Isa supported) {
  if (requested.empty()) return supported;
  for (Isa isa : {Isa::Scalar, Isa::Avx2, Isa::Avx512}) {
    if (requested != isaName(isa)) continue;
    if (isa > supported) {
      throw std::invalid_argument("TESSERA_SIMD=" + requested + ": this CPU supports at most " + isaName(supported));
    }
    return isa;
  }
  throw std::invalid_argument("TESSERA_SIMD=" + requested + ": expected scalar, avx2 or avx512");
}

Isa cpuIsa() {
  static const Isa isa = [] {
    const char* env = std::getenv("TESSERA_SIMD");
    return chooseIsa(env ? env : "", supportedIsa());
  }();
  return isa;
}

Gathers gathersFor(bool intel, const std::string& gds_report) {
  // "Mitigation: Microcode" (or "...: AVX disabled, no microcode", where no gather runs at all).
  const bool mitigated = gds_report.rfind("Mitigation", 0) == 0;
  return intel && !mitigated ? Gathers::Hardware : Gathers::Lanes;
}

const char* gathersName(Gathers g) { return g == Gathers::Hardware ? "hardware" : "lanes"; }

Gathers chooseGathers(const std::string& requested, Gathers own) {
  if (requested.empty()) return own;
  for (Gathers g : {Gathers::Lanes, Gathers::Hardware})
    if (requested == gathersName(g)) return g;
  throw std::invalid_argument("TESSERA_GATHER=" + requested + ": expected hardware or lanes");
}

Gathers cpuGathers() {
  static const Gathers g = [] {
    const char* env = std::getenv("TESSERA_GATHER");
    return chooseGathers(env ? env : "", ownGathers());
  }();
  return g;
}

}  // namespace tessera
