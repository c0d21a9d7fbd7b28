// cpp/common: vector maths used by the soil model's hot loop; cooperative interruption.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <string>
#include <vector>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/thread_pool.hpp"
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

// ---- interrupt.hpp ---------------------------------------------------------------------------

namespace {
std::atomic<int> g_checks{0};
std::atomic<bool> g_stop{false};
bool count_and_answer() {
  ++g_checks;
  return g_stop.load();
}
}  // namespace

TEST(Interrupt, PollingOutsideAScopeDoesNothing) {
  EXPECT_EQ(InterruptScope::current(), nullptr);
  for (int i = 0; i < 1000; ++i) poll_interrupt();
}

TEST(Interrupt, TheCheckRunsOncePerIntervalAndStopsEveryPollAfter) {
  g_checks = 0;
  g_stop = false;
  InterruptScope scope(&count_and_answer, std::chrono::milliseconds(20));
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(110)) poll_interrupt();
  EXPECT_GE(g_checks.load(), 1);  // ~5 intervals of 20 ms (fewer on a loaded machine), never more
  EXPECT_LE(g_checks.load(), 6);
  g_stop = true;
  std::this_thread::sleep_for(std::chrono::milliseconds(25));
  EXPECT_THROW(poll_interrupt(), Interrupted);
  EXPECT_TRUE(scope.stopped());
  const int checks = g_checks.load();
  EXPECT_THROW(poll_interrupt(), Interrupted);  // stays stopped, without asking again
  EXPECT_EQ(g_checks.load(), checks);
}

TEST(Interrupt, NestedScopesRestoreTheOuterOne) {
  InterruptScope outer(&count_and_answer);
  {
    InterruptScope inner(&count_and_answer);
    EXPECT_EQ(InterruptScope::current(), &inner);
  }
  EXPECT_EQ(InterruptScope::current(), &outer);
}

TEST(Interrupt, ThreadPoolWorkersStopWithTheirCaller) {
  // the caller's check says stop after ~30 ms: every task polls in a loop, so every worker must
  // leave through Interrupted (only the caller asks; the workers see the flag)
  g_checks = 0;
  g_stop = false;
  ThreadPool pool(3);
  InterruptScope scope(&count_and_answer, std::chrono::milliseconds(5));
  std::atomic<int> started{0}, stopped{0};
  const auto t0 = std::chrono::steady_clock::now();
  std::thread stopper([&] {
    // stop once all three tasks run (or after 10 s, which fails the test below)
    while (started.load() < 3 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10))
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    g_stop = true;
  });
  EXPECT_THROW(pool.parallel_for(3, [&](int) {
    ++started;
    try {
      for (;;) poll_interrupt();
    } catch (const Interrupted&) {
      ++stopped;
      throw;
    }
  }), Interrupted);
  stopper.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(stopped.load(), 3);
  EXPECT_LT(seconds, 9.0);
  // the pool is usable afterwards, with or without a scope
  std::atomic<int> sum{0};
  g_stop = false;
  InterruptScope fresh(&count_and_answer);
  pool.parallel_for(8, [&](int i) { sum += i; });
  EXPECT_EQ(sum.load(), 28);
}
