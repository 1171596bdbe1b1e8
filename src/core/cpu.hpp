// The processor features limn's SIMD kernels need, probed in one place.
//
// Every kernel written with x86 intrinsics or compiled for an x86 target is inside
// `#if LIMN_X86_SIMD` (or uses LIMN_TARGET), so limn compiles on any processor; where it runs,
// `cpu::features()` says which kernels this process may use. Every dispatch site asks it, and
// every kernel has a scalar path with the same results (to the rounding of a fused multiply-add
// where the kernel uses one): LIMN_NO_SIMD=1 in the environment forces those paths (the test
// suite runs a second time so), and -DLIMN_SIMD=OFF in CMake compiles the kernels out.
#pragma once

#if (defined(__x86_64__) || defined(__i386__)) && defined(__GNUC__) && !defined(LIMN_NO_SIMD_BUILD)
#define LIMN_X86_SIMD 1
/// Compiles one function for an instruction set beyond the build's baseline ("avx2,fma").
#define LIMN_TARGET(isa) __attribute__((target(isa)))
#else
#define LIMN_X86_SIMD 0
#define LIMN_TARGET(isa)
#endif

namespace limn::cpu {

struct Features {
  bool avx2 = false;      ///< AVX2 (paint's box tests)
  bool avx2_fma = false;  ///< AVX2 and FMA (subdiv's stencil and patch evaluation kernels)
  /// AVX2 with BMI1/2, POPCNT and LZCNT (paint's lookup walk, compiled for those bit tricks).
  bool avx2_bits = false;
};

/// Reads the processor and LIMN_NO_SIMD; features() asks it once and keeps the answer.
Features probe();

/// The kernels this process may use. Probed at the first call, not in a static initialiser (which
/// may run before the compiler runtime's own CPU probe), and kept; all false when LIMN_NO_SIMD is
/// set to anything but "" or "0", or when the kernels are not compiled in. Thread-safe; O(1),
/// inline (hot loops ask it: one load and a branch once probed).
inline const Features& features() {
  static const Features f = probe();
  return f;
}

}  // namespace limn::cpu
