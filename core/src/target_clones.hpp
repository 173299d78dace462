#pragma once
// HANDTRACK_TARGET_CLONES: a hot kernel compiled three times, for x86-64-v4 (AVX-512), x86-64-v3
// (AVX2, FMA) and the baseline, the loader picking one per machine through an ifunc resolver
// (measured in docs/BENCHMARKS.md "Kernels").
//
// ThreadSanitizer builds get the baseline only: the resolver runs while the dynamic loader
// relocates the program, before the TSan runtime is initialised, and its instrumented code
// crashes there (seen with gcc 12). CMake defines HANDTRACK_NO_TARGET_CLONES for them.
#if defined(HANDTRACK_NO_TARGET_CLONES)
#define HANDTRACK_TARGET_CLONES
#else
#define HANDTRACK_TARGET_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif
