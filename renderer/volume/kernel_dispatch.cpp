// Picks the fast kernel compiled for the best instruction set this CPU has (common/cpu.h):
// fast_kernel.cpp is built once per set, each copy in its own namespace.
#include <spdlog/spdlog.h>

#include "common/cpu.h"
#include "renderer/volume/kernel_isas.h"

namespace tessera::renderer {
namespace {

struct Kernel {
  decltype(&scalar::castFast) single;
  decltype(&scalar::castFastBatch) batch;
  decltype(&scalar::raySpans) spans;
};

const Kernel& kernel() {
  static const Kernel k = [] {
    const Isa isa = cpuIsa();
    spdlog::debug("ray casting kernel: {}", isaName(isa));
    switch (isa) {
#if TESSERA_X86_KERNELS
      case Isa::Avx512: return Kernel{avx512::castFast, avx512::castFastBatch, avx512::raySpans};
      case Isa::Avx2: return Kernel{avx2::castFast, avx2::castFastBatch, avx2::raySpans};
#endif
      default: return Kernel{scalar::castFast, scalar::castFastBatch, scalar::raySpans};
    }
  }();
  return k;
}

}  // namespace

bool castFast(const FastContext& c, const RaySpan& span, float out[4], SampleCounts& counts) {
  return kernel().single(c, span, out, counts);
}

void castFastBatch(const FastContext& c, const RaySpan* spans, float* const* out, int n, SampleCounts& counts,
                   bool* terminated) {
  kernel().batch(c, spans, out, n, counts, terminated);
}

unsigned raySpans(const SpanRow& row, int px0, int py, int n, const double* t_lo, const double* t_hi, RaySpan* spans) {
  return kernel().spans(row, px0, py, n, t_lo, t_hi, spans);
}

}  // namespace tessera::renderer
