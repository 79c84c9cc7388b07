/// @file CpuClones.h
/// @brief VDBMATCH_X86_64_V3_CLONES: compiles a hot function twice, for the baseline x86-64 and
///        for x86-64-v3 (AVX2), and lets the dynamic loader pick one for the CPU it runs on
///        (GCC's target_clones, an ifunc). Empty where that is not available (clang, which
///        refuses it next to flatten; other architectures).
///
/// The library is built with -ffp-contract=off (CMakeLists.txt), so that the x86-64-v3 clone
/// does not fuse products and sums into FMA: both clones compute the same bits, and results do
/// not depend on the CPU (docs/performance.md).
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define VDBMATCH_X86_64_V3_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define VDBMATCH_X86_64_V3_CLONES
#endif
