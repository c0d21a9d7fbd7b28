// SparseLdlt's numeric part (cpp/solver/sparse_ldlt_numeric.cpp: its own dense kernel for
// supernodes and the dense tail) against Eigen's dense LDLᵀ on random symmetric positive definite
// matrices: every dense size up to 48 and the rover's own flat-step pattern. (Tree-shaped
// systems and the agreement with ODE's solver: test_dynamics_solver.cpp.)
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "ernest/solver/sparse_ldlt.hpp"
#include "lcp_matrix.hpp"

using namespace ernest::solver;
using Mask = LdltPlan::Mask;

namespace {

using System = ernest::testing::LcpMatrix;

// A random symmetric positive definite matrix with the lower-triangle pattern `pattern` (bit j of
// row i: entry (i, j), diagonal included), diagonally dominant then scaled by a random diagonal
// (entries spanning two orders of magnitude), as ODE stores it (NaN above the diagonal).
System spd_with_pattern(const std::vector<Mask>& pattern, std::mt19937_64& rng) {
  const int n = static_cast<int>(pattern.size());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < i; ++j)
      if (pattern[i] >> j & 1) b(i, j) = b(j, i) = u(rng);
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) {
    b(i, i) = b.row(i).cwiseAbs().sum() + 0.1 + (u(rng) + 1.0);
    scale[i] = std::pow(10.0, u(rng));
  }
  System s;
  s.n = n;
  s.stride = n > 1 ? (n + 3) & ~3 : n;
  s.dense = scale.asDiagonal() * b * scale.asDiagonal();
  s.a.assign(static_cast<std::size_t>(n) * s.stride, std::nan(""));
  for (int i = 0; i < n; ++i)
    for (int k = 0; k <= i; ++k) s.a[i * s.stride + k] = s.dense(i, k);
  return s;
}

// Factorises s with a plan of its own pattern and solves; compares with Eigen's dense LDLᵀ.
void expect_solves_like_eigen(const System& s, const std::vector<Mask>& pattern,
                              std::mt19937_64& rng, const char* what) {
  std::vector<unsigned> rows(s.n);
  for (int i = 0; i < s.n; ++i) rows[i] = static_cast<unsigned>(i);
  LdltPlan plan;
  plan.analyse(pattern.data(), rows.data(), s.n, s.stride);
  ASSERT_TRUE(plan.covers(s.a.data())) << what;
  SparseLdlt ldlt;
  ASSERT_TRUE(ldlt.factor(plan, s.a.data())) << what;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::VectorXd rhs = Eigen::VectorXd::NullaryExpr(s.n, [&] { return u(rng); });
  const Eigen::VectorXd expected = s.dense.ldlt().solve(rhs);
  Eigen::VectorXd x = rhs;
  ldlt.solve(x.data());
  EXPECT_LE((x - expected).norm(), 1e-10 * expected.norm()) << what;
  EXPECT_LE((s.dense * x - rhs).norm(), 1e-13 * s.dense.norm() * x.norm()) << what;
}

}  // namespace

// The dense kernel (sparse_ldlt.cpp dense_ldlt) on every size up to 48: a full pattern is one
// dense clique (the whole matrix is the dense tail), so each block width and remainder is met.
TEST(SparseLdlt, DenseMatricesSolveLikeEigen) {
  std::mt19937_64 rng(3);
  for (int n = 1; n <= 48; ++n) {
    std::vector<Mask> full(n);
    for (int i = 0; i < n; ++i) full[i] = (Mask{2} << i) - 1;
    const System s = spd_with_pattern(full, rng);
    expect_solves_like_eigen(s, full, rng, ("dense n " + std::to_string(n)).c_str());
  }
}

// The 37 solved rows of a flat M90 step (the rover on soil, profile_rocks with no rocks): lone
// columns, a supernode of 12 columns with 5 rows below it, and a dense tail of 17 rows; random
// values in that pattern.
TEST(SparseLdlt, TheRoversFlatPatternSolvesLikeEigen) {
  const std::vector<Mask> rover = {
      0x1, 0x3, 0x7, 0xf, 0x1f, 0x3f, 0x7f, 0xff, 0x1ff, 0x3ff, 0x7ff, 0xfff, 0x1fff, 0x3fff,
      0x400f, 0xc00f, 0x1c00f, 0x3c00f, 0x7c00f, 0xfc00f, 0x1fc00f, 0x3fc00f, 0x7fc00f, 0xffc00f,
      0x1000040, 0x20001b0, 0x4200000, 0x8d80000, 0x10010000, 0x2006c000, 0x40000800, 0x80003600,
      0x180003fff, 0x302003fff, 0x700ffffff, 0xc08ffc00f, 0x1c20ffc00f};
  LdltPlan plan;
  std::vector<unsigned> rows(rover.size());
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<unsigned>(i);
  plan.analyse(rover.data(), rows.data(), static_cast<int>(rover.size()), 40);
  EXPECT_EQ(plan.dense_from(), 20);  // (the shape described above)
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const System s = spd_with_pattern(rover, rng);
    expect_solves_like_eigen(s, rover, rng, ("rover trial " + std::to_string(trial)).c_str());
  }
}

// solve_many (several right-hand sides interleaved: solve_clamped's columns in sparse_lcp.cpp) gives
// the bits of one solve() per column, for every count up to 9 (two blocks of four and a
// remainder), on the rover's pattern and on dense matrices; and the answers solve the system.
TEST(SparseLdlt, SolveManyGivesTheBitsOfSeparateSolves) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n : {5, 23, 37}) {
    std::vector<Mask> pattern(n);
    for (int i = 0; i < n; ++i)  // a band plus a dense tail: lone columns, supernodes, a clique
      pattern[i] = ((Mask{2} << i) - 1) & ~((Mask{1} << std::max(0, i - 3)) - 1) |
                   (i >= n - 6 ? (Mask{2} << i) - 1 : Mask{0});
    const System s = spd_with_pattern(pattern, rng);
    std::vector<unsigned> rows(n);
    for (int i = 0; i < n; ++i) rows[i] = static_cast<unsigned>(i);
    LdltPlan plan;
    plan.analyse(pattern.data(), rows.data(), n, s.stride);
    SparseLdlt ldlt;
    ASSERT_TRUE(ldlt.factor(plan, s.a.data()));
    for (int k = 1; k <= 9; ++k) {
      const int stride = n + 3;  // columns apart, not packed
      std::vector<double> many(static_cast<std::size_t>(k) * stride, 0.0), one(many.size());
      for (auto& v : many) v = u(rng);
      one = many;
      ldlt.solve_many(many.data(), k, stride);
      for (int c = 0; c < k; ++c) {
        Eigen::Map<const Eigen::VectorXd> rhs(one.data() + c * stride, n);
        const Eigen::VectorXd b = rhs;
        ldlt.solve(one.data() + c * stride);
        for (int i = 0; i < n; ++i)
          ASSERT_EQ(many[c * stride + i], one[c * stride + i]) << "n " << n << " k " << k << " column " << c;
        Eigen::Map<const Eigen::VectorXd> x(many.data() + c * stride, n);
        EXPECT_LE((s.dense * x - b).norm(), 1e-12 * s.dense.norm() * x.norm());
        for (int i = n; i < stride; ++i) EXPECT_EQ(many[c * stride + i], one[c * stride + i]);
      }
    }
  }
}
