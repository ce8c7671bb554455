// TESSERA_SIMD may lower the instruction set the CPU supports, never raise it; TESSERA_GATHER
// picks either way of reading voxels, whatever the CPU's own choice.
#include "common/cpu.h"

#include <gtest/gtest.h>

namespace tessera {
namespace {

TEST(Cpu, UnsetMeansWhatTheCpuSupports) {
  EXPECT_EQ(chooseIsa("", Isa::Avx512), Isa::Avx512);
  EXPECT_EQ(chooseIsa("", Isa::Scalar), Isa::Scalar);
}

TEST(Cpu, LowerLevelsCanBeForced) {
  EXPECT_EQ(chooseIsa("scalar", Isa::Avx512), Isa::Scalar);
  EXPECT_EQ(chooseIsa("avx2", Isa::Avx512), Isa::Avx2);
  EXPECT_EQ(chooseIsa("avx512", Isa::Avx512), Isa::Avx512);
}

TEST(Cpu, HigherOrUnknownLevelsAreRefusedByName) {
  try {
    chooseIsa("avx512", Isa::Avx2);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "TESSERA_SIMD=avx512: this CPU supports at most avx2");
  }
  try {
    chooseIsa("sse9", Isa::Avx512);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "TESSERA_SIMD=sse9: expected scalar, avx2 or avx512");
  }
}

TEST(Cpu, NamesRoundTrip) {
  for (Isa isa : {Isa::Scalar, Isa::Avx2, Isa::Avx512}) EXPECT_EQ(chooseIsa(isaName(isa), Isa::Avx512), isa);
}

TEST(Cpu, IntelGathersUnlessTheKernelReportsTheDownfallMicrocodeFix) {
  EXPECT_EQ(gathersFor(true, "Not affected"), Gathers::Hardware);  // Emerald Rapids, Sapphire Rapids
  EXPECT_EQ(gathersFor(true, ""), Gathers::Hardware);              // an older kernel without the report
  EXPECT_EQ(gathersFor(true, "Vulnerable"), Gathers::Hardware);
  EXPECT_EQ(gathersFor(true, "Mitigation: Microcode"), Gathers::Lanes);
  EXPECT_EQ(gathersFor(false, "Not affected"), Gathers::Lanes);  // AMD
}

TEST(Cpu, EitherWayOfReadingVoxelsCanBeForced) {
  for (Gathers own : {Gathers::Lanes, Gathers::Hardware}) {
    EXPECT_EQ(chooseGathers("", own), own);
    EXPECT_EQ(chooseGathers("lanes", own), Gathers::Lanes);
    EXPECT_EQ(chooseGathers("hardware", own), Gathers::Hardware);
  }
  try {
    chooseGathers("avx512", Gathers::Lanes);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "TESSERA_GATHER=avx512: expected hardware or lanes");
  }
}

}  // namespace
}  // namespace tessera
