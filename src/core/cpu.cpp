#include "cpu.hpp"

#include <cstdlib>
#include <cstring>

#if LIMN_X86_SIMD
#include <cpuid.h>
#endif

namespace limn::cpu {

Features probe() {
  Features f;
  const char* off = std::getenv("LIMN_NO_SIMD");
  if (off && *off && std::strcmp(off, "0") != 0) return f;
#if LIMN_X86_SIMD
  __builtin_cpu_init();
  f.avx2 = __builtin_cpu_supports("avx2");
  f.avx2_fma = f.avx2 && __builtin_cpu_supports("fma");
  // LZCNT (ABM) is CPUID 0x80000001 ECX bit 5; clang's __builtin_cpu_supports has no name for it.
  unsigned a = 0, b = 0, c = 0, d = 0;
  const bool lzcnt = __get_cpuid(0x80000001u, &a, &b, &c, &d) && (c >> 5 & 1u);
  f.avx2_bits = f.avx2 && __builtin_cpu_supports("popcnt") && __builtin_cpu_supports("bmi") &&
                __builtin_cpu_supports("bmi2") && lzcnt;
#endif
  return f;
}

}  // namespace limn::cpu
