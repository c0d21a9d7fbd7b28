#include "ernest/common/vector_math.hpp"

#include <cmath>
#include <cstring>

#if defined(ERNEST_HAVE_LIBMVEC)
#include <immintrin.h>

// glibc's vector function ABI (x86_64 vector function ABI, glibc >= 2.22): 'b' = SSE2, 2 lanes;
// 'd' = AVX2, 4 lanes.
extern "C" __m128d _ZGVbN2v_exp(__m128d);
extern "C" __m128d _ZGVbN2v_log(__m128d);
extern "C" __attribute__((target("avx2"))) __m256d _ZGVdN4v_exp(__m256d);
extern "C" __attribute__((target("avx2"))) __m256d _ZGVdN4v_log(__m256d);
#endif

namespace ernest {

namespace {

#if defined(ERNEST_HAVE_LIBMVEC)
// Full vectors straight from the arrays, the tail through a buffer padded with 1.0 (harmless for
// both functions). One function per ISA: the AVX2 ones are compiled for AVX2 only and called
// only when the CPU has it.
#define ERNEST_VECTOR_LOOP(W, LOAD, STORE, FN)                            \
  int i = 0;                                                             \
  for (; i + W <= n; i += W) STORE(y + i, FN(LOAD(x + i)));              \
  if (i < n) {                                                           \
    double in[W], out[W];                                                \
    for (int k = 0; k < W; ++k) in[k] = i + k < n ? x[i + k] : 1.0;      \
    STORE(out, FN(LOAD(in)));                                            \
    for (int k = 0; i + k < n; ++k) y[i + k] = out[k];                   \
  }

__attribute__((target("avx2"))) void exp_avx2(const double* x, double* y, int n) {
  ERNEST_VECTOR_LOOP(4, _mm256_loadu_pd, _mm256_storeu_pd, _ZGVdN4v_exp)
}
__attribute__((target("avx2"))) void log_avx2(const double* x, double* y, int n) {
  ERNEST_VECTOR_LOOP(4, _mm256_loadu_pd, _mm256_storeu_pd, _ZGVdN4v_log)
}
void exp_sse2(const double* x, double* y, int n) {
  ERNEST_VECTOR_LOOP(2, _mm_loadu_pd, _mm_storeu_pd, _ZGVbN2v_exp)
}
void log_sse2(const double* x, double* y, int n) {
  ERNEST_VECTOR_LOOP(2, _mm_loadu_pd, _mm_storeu_pd, _ZGVbN2v_log)
}
#undef ERNEST_VECTOR_LOOP
#endif
void exp_scalar(const double* x, double* y, int n) {
  for (int i = 0; i < n; ++i) y[i] = std::exp(x[i]);
}
void log_scalar(const double* x, double* y, int n) {
  for (int i = 0; i < n; ++i) y[i] = std::log(x[i]);
}

struct Backend {
  void (*exp)(const double*, double*, int);
  void (*log)(const double*, double*, int);
  const char* name;
};

bool available(const Backend& b) {
#if defined(ERNEST_HAVE_LIBMVEC)
  __builtin_cpu_init();
  return std::strcmp(b.name, "avx2") != 0 || __builtin_cpu_supports("avx2");
#else
  return std::strcmp(b.name, "scalar") == 0;
#endif
}

const Backend kBackends[] = {
#if defined(ERNEST_HAVE_LIBMVEC)
    {exp_avx2, log_avx2, "avx2"},
    {exp_sse2, log_sse2, "sse2"},
#endif
    {exp_scalar, log_scalar, "scalar"}};

const Backend* choose() {  // the first available, in order of speed
  for (const Backend& b : kBackends)
    if (available(b)) return &b;
  return &kBackends[0];
}

const Backend*& current() {  // a function-local static: safe from static-initialisation order
  static const Backend* b = choose();
  return b;
}

}  // namespace

void exp_n(const double* x, double* y, int n) { current()->exp(x, y, n); }
void log_n(const double* x, double* y, int n) { current()->log(x, y, n); }
const char* vector_math_backend() { return current()->name; }

bool set_vector_math_backend(const char* name) {
  for (const Backend& b : kBackends) {
    if (std::strcmp(b.name, name) == 0 && available(b)) {
      current() = &b;
      return true;
    }
  }
  return false;
}

}  // namespace ernest
