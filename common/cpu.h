// The instruction sets Tessera's hot loops are built for, chosen at run time from the CPU,
// so one binary (the Docker image, a distribution package) runs the fastest code this
// machine has and still runs on an x86-64 without AVX2.
#pragma once
#include <cstdint>
#include <string>

// For loops the compiler vectorizes by itself: a baseline copy and an x86-64-v3 (AVX2, FMA)
// copy, chosen by the dynamic loader from the CPU (GNU IFUNC). With -ffp-contract=off (set
// for the whole build) both copies compute the same values.
#if defined(__x86_64__) && defined(__ELF__) && !defined(__SANITIZE_ADDRESS__)
#define TESSERA_CLONES __attribute__((target_clones("default", "arch=x86-64-v3")))
#else
#define TESSERA_CLONES
#endif

namespace tessera {

// x86-64 baseline (SSE2); x86-64-v3 (AVX2, FMA, F16C, BMI2); x86-64-v4 (AVX-512 F/BW/CD/DQ/VL).
enum class Isa : uint8_t { Scalar, Avx2, Avx512 };

// The best level this CPU supports, lowered by TESSERA_SIMD=scalar|avx2|avx512 (to test or
// compare the slower paths). Read once; a TESSERA_SIMD above what the CPU has, or an unknown
// word, throws std::invalid_argument naming the variable, its value and what the CPU has.
Isa cpuIsa();
const char* isaName(Isa isa);
// The level TESSERA_SIMD asks for given what the CPU supports (what cpuIsa() uses; tested).
Isa chooseIsa(const std::string& requested, Isa supported);

// How the SIMD ray caster reads a packet's eight scattered voxels: by the CPU's gather
// instructions or one lane at a time (scalar loads put into the vector). Which is faster
// depends on the core, not on the instruction set: on an Intel Xeon (Emerald Rapids) the
// AVX-512 gathers took 0.955x the time of a hollow-shell frame, on an AMD EPYC (Zen 4) the
// lane reads 0.95x. So Intel CPUs gather and the others read lanes, except an Intel CPU whose
// kernel reports the microcode fix for Gather Data Sampling ("Downfall": Skylake to Ice Lake
// and Tiger Lake), which makes gathers several times slower (not measured here: no such CPU).
// TESSERA_GATHER=hardware|lanes overrides (to test or compare both; an unknown word throws
// std::invalid_argument). The image is the same either way: the same values, read differently.
enum class Gathers : uint8_t { Lanes, Hardware };
Gathers cpuGathers();
const char* gathersName(Gathers g);
// What TESSERA_GATHER asks for given the CPU's own choice (what cpuGathers() uses; tested).
Gathers chooseGathers(const std::string& requested, Gathers own);
// The CPU's own choice from its vendor and the kernel's report on Gather Data Sampling (the
// contents of /sys/devices/system/cpu/vulnerabilities/gather_data_sampling, "" if none; tested).
Gathers gathersFor(bool intel, const std::string& gds_report);

}  // namespace tessera
