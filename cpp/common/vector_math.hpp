// exp and log over arrays through glibc's vector math library (libmvec), for the hot loops of
// the soil model (eq 17's power law and the shear laws of eqs 19–22 cost 4 transcendentals per
// quadrature node). libmvec evaluates 4 values per call with AVX2 (chosen once at run time from
// the CPU) or 2 with SSE2, 2.5–4x faster than std::exp / std::log one by one and within 4 ulp
// of them (glibc documents its vector functions to 4 ulp). Without libmvec (not glibc on
// x86-64) the same calls fall back to std::exp / std::log.
#pragma once

// A function compiled twice, for AVX2 and for the baseline ISA, the copy chosen when the program
// loads (GCC's target_clones, an ifunc): for loops the compiler vectorises 4 wide on AVX2. AVX2
// without FMA and without reassociation does the same operations in the same order, so both
// copies give the same bits. Elsewhere than x86-64 with GCC/Clang: one plain copy.
#if defined(__x86_64__) && defined(__GNUC__) && defined(__linux__)
#define ERNEST_ALSO_AVX2 __attribute__((target_clones("avx2", "default")))
#else
#define ERNEST_ALSO_AVX2
#endif

namespace ernest {

/// y[i] = exp(x[i]) for 0 <= i < n. x and y may be the same array.
void exp_n(const double* x, double* y, int n);
/// y[i] = log(x[i]) for 0 <= i < n. x and y may be the same array.
void log_n(const double* x, double* y, int n);
/// Which implementation exp_n / log_n use: "avx2", "sse2" or "scalar" (the best this machine
/// has, chosen once at start-up).
const char* vector_math_backend();
/// Switch to another implementation (tests and benchmarks; not thread-safe). Returns false,
/// changing nothing, if this machine or build does not have it.
bool set_vector_math_backend(const char* name);

}  // namespace ernest
