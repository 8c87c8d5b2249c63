#pragma once
// PIEZO_SIMD_CLONES: a function compiled twice, for the baseline x86-64
// (SSE2) and for AVX2, the loader choosing by the CPU (GCC's target_clones,
// an ifunc). For the forward models' element-wise loops over frequency bins
// (issue 43): four doubles per instruction where SSE2 has two. The results
// are bit for bit the same on either clone: AVX2 does not bring FMA (no
// contraction of a·b + c), each element's +, −, ×, ÷ and √ are correctly
// rounded whatever the vector width, and GCC vectorises no reduction of
// doubles without -ffast-math (a sum keeps its order). So a loop marked
// here must be element-wise; a sum over elements stays scalar anyway.
// Off for other compilers and architectures, and with PIEZO_NO_SIMD_CLONES.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(PIEZO_NO_SIMD_CLONES)
#define PIEZO_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PIEZO_SIMD_CLONES
#endif
