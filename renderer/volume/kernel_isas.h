// The fast kernel's entry points in each instruction set's copy (fast_kernel.cpp and
// ray_spans.cpp are compiled once per set, each copy in its own namespace):
// kernel_dispatch.cpp picks one for the CPU; tests compare the copies with each other.
#pragma once
#include "renderer/volume/kernels.h"
#include "renderer/volume/ray_setup.h"

#define TESSERA_DECLARE_KERNEL(isa)                                                                       \
  namespace tessera::renderer::isa {                                                                      \
  bool castFast(const FastContext& c, const RaySpan& span, float out[4], SampleCounts& counts);           \
  void castFastBatch(const FastContext& c, const RaySpan* spans, float* const* out, int n,               \
                     SampleCounts& counts, bool* terminated);                                             \
  unsigned raySpans(const SpanRow& row, int px0, int py, int n, const double* t_lo, const double* t_hi,  \
                    RaySpan* spans);                                                                      \
  }
TESSERA_DECLARE_KERNEL(scalar)
#if defined(__x86_64__)  // built for x86-64 only (renderer/CMakeLists.txt)
TESSERA_DECLARE_KERNEL(avx2)
TESSERA_DECLARE_KERNEL(avx512)
#endif
#undef TESSERA_DECLARE_KERNEL
