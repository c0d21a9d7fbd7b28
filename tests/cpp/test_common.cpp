// cpp/common: vector maths used by the soil model's hot loop.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "ernest/common/vector_math.hpp"

using namespace ernest;

namespace {
double ulps(double got, double want) {
  if (got == want) return 0.0;
  const double spacing = std::abs(std::nextafter(want, 2.0 * want + 1.0) - want);
  return std::abs(got - want) / spacing;
}

// Every length 0..13 (full vectors and every tail), over the ranges the soil model uses (exp of
// -40..0: shear laws, power law; log of 1e-300..2: the power law's base) and beyond; in place;
// the edge values the model can hit.
void check_exp_and_log() {
  for (int n = 0; n <= 13; ++n) {
    std::vector<double> x(n), y(n, -1.0), l(n), z(n, -1.0);
    for (int i = 0; i < n; ++i) {
      x[i] = -40.0 + 45.0 * i / 13.0;  // up to e^5
      l[i] = std::pow(10.0, -300.0 + 300.3 * i / 13.0);
    }
    exp_n(x.data(), y.data(), n);
    log_n(l.data(), z.data(), n);
    for (int i = 0; i < n; ++i) {
      EXPECT_LE(ulps(y[i], std::exp(x[i])), 4.0) << "exp(" << x[i] << "), n = " << n;
      EXPECT_LE(ulps(z[i], std::log(l[i])), 4.0) << "log(" << l[i] << "), n = " << n;
    }
  }
  std::vector<double> v = {0.0, -800.0, 1.0, 1e-300};
  exp_n(v.data(), v.data(), 2);
  EXPECT_EQ(v[0], 1.0);
  EXPECT_EQ(v[1], 0.0);  // underflows to zero, as std::exp does
  log_n(v.data() + 2, v.data() + 2, 2);
  EXPECT_EQ(v[2], 0.0);
  EXPECT_NEAR(v[3], std::log(1e-300), 1e-12);
}
}  // namespace

TEST(VectorMath, EveryBackendMatchesTheScalarLibraryWithinFourUlp) {
  const std::string best = vector_math_backend();
  EXPECT_TRUE(best == "avx2" || best == "sse2" || best == "scalar") << best;
  EXPECT_FALSE(set_vector_math_backend("avx512"));
  EXPECT_EQ(vector_math_backend(), best);
  int checked = 0;
  for (const char* backend : {"avx2", "sse2", "scalar"}) {
    if (!set_vector_math_backend(backend)) continue;  // not on this machine / build
    SCOPED_TRACE(backend);
    check_exp_and_log();
    ++checked;
  }
  EXPECT_GE(checked, 1);
  ASSERT_TRUE(set_vector_math_backend(best.c_str()));
}
