// The CPU-feature module (src/core/cpu.hpp) against the environment switch it promises to honour
// and the processor's own answers (GCC's __builtin_cpu_supports).
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "core/cpu.hpp"

namespace limn {
namespace {

// Restores LIMN_NO_SIMD as the test found it.
struct EnvGuard {
  std::string old;
  bool had = false;
  EnvGuard() {
    if (const char* v = std::getenv("LIMN_NO_SIMD")) old = v, had = true;
  }
  ~EnvGuard() {
    if (had)
      setenv("LIMN_NO_SIMD", old.c_str(), 1);
    else
      unsetenv("LIMN_NO_SIMD");
  }
};

TEST(CoreCpu, NoSimdSwitchTurnsEveryKernelOff) {
  EnvGuard guard;
  for (const char* on : {"1", "yes"}) {
    setenv("LIMN_NO_SIMD", on, 1);
    const cpu::Features f = cpu::probe();
    EXPECT_FALSE(f.avx2 || f.avx2_fma || f.avx2_bits) << "LIMN_NO_SIMD=" << on;
  }
}

TEST(CoreCpu, WithoutTheSwitchTheProcessorDecides) {
  EnvGuard guard;
  for (const char* off : {"", "0"}) {
    setenv("LIMN_NO_SIMD", off, 1);
    const cpu::Features f = cpu::probe();
#if LIMN_X86_SIMD
    EXPECT_EQ(f.avx2, bool(__builtin_cpu_supports("avx2")));
    EXPECT_EQ(f.avx2_fma, f.avx2 && __builtin_cpu_supports("fma"));
    EXPECT_TRUE(!f.avx2_bits || (f.avx2 && __builtin_cpu_supports("bmi2")));
#else
    EXPECT_FALSE(f.avx2 || f.avx2_fma || f.avx2_bits) << "no kernels compiled in";
#endif
  }
}

// What the process's dispatch sites see is the probe of the environment it started with (the
// suite runs twice, once with LIMN_NO_SIMD=1).
TEST(CoreCpu, FeaturesAreTheStartingEnvironmentsProbe) {
  const cpu::Features f = cpu::probe(), g = cpu::features();
  EXPECT_EQ(f.avx2, g.avx2);
  EXPECT_EQ(f.avx2_fma, g.avx2_fma);
  EXPECT_EQ(f.avx2_bits, g.avx2_bits);
  if (const char* v = std::getenv("LIMN_NO_SIMD"); v && *v && std::string(v) != "0") {
    EXPECT_FALSE(g.avx2 || g.avx2_fma || g.avx2_bits);
  }
}

}  // namespace
}  // namespace limn
