// Tests of the sparse solver's symbolic analysis (LdltPlan::analyse: minimum degree on row sets of
// up to 64 rows in one word, more in two) and of the plans a simulation remembers
// (LcpWorkspace::find/adopt/clear/save/load in cpp/solver/lcp_workspace.cpp), as SolverStats
// counts them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include "ernest/solver/ode_lcp.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/solver/sparse_ldlt.hpp"

using namespace ernest::dynamics;
using namespace ernest::solver;
using Mask = LdltPlan::Mask;

namespace {

Mask bit(int i) { return Mask{1} << i; }

// A random tree on n rows (each row below the first coupled to one earlier row), lower pattern.
std::vector<Mask> random_tree(int n, std::mt19937_64& rng) {
  std::vector<Mask> p(n);
  for (int i = 0; i < n; ++i) p[i] = bit(i);
  for (int i = 1; i < n; ++i) {
    const int parent = static_cast<int>(rng() % i);
    p[i] |= bit(parent);
  }
  return p;
}

// Ascending rows of A with gaps (as the solved rows among ODE's bounded ones), and A's stride.
std::vector<unsigned> rows_with_gaps(int n, std::mt19937_64& rng, int& stride) {
  std::vector<unsigned> rows(n);
  unsigned r = 0;
  for (int i = 0; i < n; ++i) {
    rows[i] = r;
    r += rng() % 3 == 0 ? 2 : 1;
  }
  stride = static_cast<int>(r + 3) & ~3;
  return rows;
}

}  // namespace

// A tree has an elimination order without fill (a leaf, degree 1, first: its one neighbour
// gains no edge), and minimum degree always picks a leaf: L's pattern is A's, so every entry
// outside it is refused. Both representations of the row sets: 40 rows (one word), 100 (two).
TEST(LdltPlan, MinimumDegreeEliminatesTreesWithoutFill) {
  std::mt19937_64 rng(3);
  for (const int n : {2, 40, 64, 65, 100, LdltPlan::kMaxRows}) {
    SCOPED_TRACE(n);
    const std::vector<Mask> tree = random_tree(n, rng);
    int stride = 0;
    const std::vector<unsigned> rows = rows_with_gaps(n, rng, stride);
    LdltPlan plan;
    plan.analyse(tree.data(), rows.data(), n, stride);
    ASSERT_TRUE(plan.covers(tree.data()));
    EXPECT_GE(plan.dense_from(), n - 2);  // the last two rows at most are the dense tail
    int refused = 0, tried = 0;
    for (int t = 0; t < 200; ++t) {
      const int i = 1 + static_cast<int>(rng() % (n - 1)), j = static_cast<int>(rng() % i);
      if (tree[i] & bit(j)) continue;
      std::vector<Mask> more = tree;
      more[i] |= bit(j);
      ++tried;
      refused += plan.covers(more.data()) ? 0 : 1;
    }
    EXPECT_EQ(refused, tried);
  }
}

// The same coupling of rows analysed among 40 rows and among 100 (60 uncoupled rows after
// them): the uncoupled rows go first (degree 0) and add nothing, so the plans factorise the same
// rows alike; both solve a tree-coupled system exactly as a dense solve does.
TEST(LdltPlan, OneAndTwoWordRowSetsGiveTheSamePlanForTheSameCoupling) {
  std::mt19937_64 rng(11);
  std::vector<Mask> small = random_tree(40, rng);
  for (int e = 0; e < 30; ++e) {  // and some cycles (fill)
    const int i = 1 + static_cast<int>(rng() % 39);
    small[i] |= bit(static_cast<int>(rng() % i));
  }
  std::vector<Mask> big(small);
  for (int i = 40; i < 100; ++i) big.push_back(bit(i));
  std::vector<unsigned> rows(100);
  for (int i = 0; i < 100; ++i) rows[i] = static_cast<unsigned>(i);
  LdltPlan a, b;
  a.analyse(small.data(), rows.data(), 40, 40);
  b.analyse(big.data(), rows.data(), 100, 100);
  // A in each layout: diagonally dominant, the coupling's entries 0.3.
  std::vector<double> ma(40 * 40, 0.0), mb(100 * 100, 0.0);
  for (int i = 0; i < 100; ++i) {
    mb[i * 100 + i] = 20.0 + i;
    if (i < 40) ma[i * 40 + i] = mb[i * 100 + i];
    for (int j = 0; j < i && i < 40; ++j)
      if (small[i] & bit(j)) ma[i * 40 + j] = mb[i * 100 + j] = 0.3 * (1 + (i + j) % 3);
  }
  SparseLdlt la, lb;
  ASSERT_TRUE(la.factor(a, ma.data()));
  ASSERT_TRUE(lb.factor(b, mb.data()));
  std::vector<double> xa(40), xb(100, 0.0);
  for (int i = 0; i < 40; ++i) xa[i] = xb[i] = std::sin(1.0 + i);
  la.solve(xa.data());
  lb.solve(xb.data());
  for (int i = 0; i < 40; ++i) EXPECT_EQ(xa[i], xb[i]) << i;  // the same arithmetic, bit for bit
  for (int i = 40; i < 100; ++i) EXPECT_EQ(xb[i], 0.0);
  // and they solve A x = b: the residual of the small system
  for (int i = 0; i < 40; ++i) {
    double s = 0.0;
    for (int j = 0; j < 40; ++j) s += (j <= i ? ma[i * 40 + j] : ma[j * 40 + i]) * xa[j];
    EXPECT_NEAR(s, std::sin(1.0 + i), 1e-12);
  }
}

namespace {

// Row set number k (k + 1 rows from row k, stride 64) with a tridiagonal pattern.
struct RowSet {
  std::vector<unsigned> rows;
  std::vector<Mask> pattern;
};
RowSet row_set(int k) {
  RowSet s;
  for (int i = 0; i <= k; ++i) {
    s.rows.push_back(static_cast<unsigned>(k + i));
    s.pattern.push_back(bit(i) | (i > 0 ? bit(i - 1) : 0));
  }
  return s;
}
LdltPlan* find(LcpWorkspace& ws, const RowSet& s) {
  LdltPlan* p = ws.find(s.rows.data(), static_cast<int>(s.rows.size()), 64);
  Mask set = 0;
  for (const unsigned r : s.rows) set |= bit(static_cast<int>(r));
  EXPECT_EQ(ws.find(set, static_cast<int>(s.rows.size()), 64), p);  // the same as a row set
  return p;
}
const LdltPlan& adopt(LcpWorkspace& ws, const RowSet& s, const std::vector<Mask>& p) {
  return ws.adopt(find(ws, s), p.data(), s.rows.data(), static_cast<int>(s.rows.size()), 64);
}

}  // namespace

// Round robin over kPlans: the oldest plan makes room; a pattern outside a remembered plan's
// factor grows it; clear() forgets every plan; save() and load() carry the plans and the next
// slot, and load refuses slots out of the order save() writes them in.
TEST(LcpWorkspace, RemembersPlansRoundRobinAndCarriesThemThroughSaveAndLoad) {
  constexpr int kPlans = LcpWorkspace::kPlans;
  LcpWorkspace ws;
  std::vector<std::uint64_t> empty;
  ws.save(empty);
  for (int k = 1; k <= kPlans + 1; ++k) adopt(ws, row_set(k), row_set(k).pattern);
  EXPECT_EQ(ws.plans_made, static_cast<std::uint64_t>(kPlans + 1));
  EXPECT_EQ(find(ws, row_set(1)), nullptr);  // the oldest made room
  for (int k = 2; k <= kPlans + 1; ++k) EXPECT_NE(find(ws, row_set(k)), nullptr) << k;
  // Row set 3 couples its first and last rows: outside the factor of a path, so it grows.
  const RowSet three = row_set(3);
  std::vector<Mask> cycle = three.pattern;
  cycle[3] |= bit(0);
  EXPECT_FALSE(find(ws, three)->covers(cycle.data()));
  EXPECT_TRUE(adopt(ws, three, cycle).covers(cycle.data()));
  EXPECT_EQ(ws.plans_grown, 1u);

  std::vector<std::uint64_t> saved;
  ws.save(saved);
  LcpWorkspace back;
  back.load(saved);
  EXPECT_EQ(find(back, row_set(1)), nullptr);
  for (int k = 2; k <= kPlans + 1; ++k) {
    const LdltPlan* p = find(back, row_set(k));
    ASSERT_NE(p, nullptr) << k;
    std::vector<Mask> closed = row_set(k).pattern;  // its last row coupled to its first
    closed[k] |= bit(0);
    EXPECT_EQ(p->covers(closed.data()), k == 3) << k;  // only the grown plan covers it
  }
  adopt(back, row_set(1), row_set(1).pattern);  // in the same slot as in ws: round robin goes on
  adopt(ws, row_set(1), row_set(1).pattern);
  std::vector<std::uint64_t> again_ws, again_back;
  ws.save(again_ws);
  back.save(again_back);
  EXPECT_EQ(again_ws, again_back);

  ws.clear();
  for (int k = 1; k <= kPlans + 1; ++k) EXPECT_EQ(find(ws, row_set(k)), nullptr) << k;
  std::vector<std::uint64_t> cleared;
  ws.save(cleared);
  EXPECT_EQ(cleared, empty);

  // One plan, in slot 0; the same data claiming slot 1 (after an empty slot 0) or a next slot
  // that round robin cannot have reached is refused.
  LcpWorkspace one;
  adopt(one, row_set(2), row_set(2).pattern);
  std::vector<std::uint64_t> good;
  one.save(good);
  EXPECT_NO_THROW(back.load(good));
  ASSERT_EQ(good[0], 1u);  // next_plan
  ASSERT_EQ(good[1], 3u);  // slot 0: 3 rows
  // Layout: next_plan, slot 0 (n = 3, stride, 3 rows, 3 masks of 2 words), slots 1.. (n = 0).
  std::vector<std::uint64_t> gap = good;
  gap.erase(gap.begin() + 12);      // one empty slot fewer after it,
  gap.insert(gap.begin() + 1, 0u);  // one before it: the plan in slot 1
  EXPECT_THROW(back.load(gap), std::invalid_argument);
  std::vector<std::uint64_t> skipped = good;
  skipped[0] = 2;
  EXPECT_THROW(back.load(skipped), std::invalid_argument);
  EXPECT_NO_THROW(back.load(good));
  EXPECT_NE(find(back, row_set(2)), nullptr);
}

// SolverStats::plans_made / plans_grown are the simulation's analyses: the first solve must make
// a plan, no solve analyses more than one plan per attempt at its active set (at most three
// attempts on soil without rocks), and the plans travel in the Snapshot, so that the same steps
// after restore() make and grow exactly as many plans again.
TEST(LcpWorkspace, SolverStatsCountTheSimulationsPlans) {
  SimOptions o;
  o.friction = 0.8;
  RoverSim sim(RoverParameters{}, HeightMap::flat(8, 8, 0.25, 0, -2, -2), {}, o);
  sim.reset(0, 0, 0, 0, 0, 0.15);
  Commands c;
  for (auto& w : c.wheel_speed) w = 0.15 / sim.parameters().wheel_radius;
  sim.set_commands(c);
  sim.step_n(20);
  const SolverStats first = sim.solver_stats();
  EXPECT_GE(first.plans_made, 1u);
  EXPECT_LE(first.plans_made + first.plans_grown, 3 * first.sparse_solves);
  const Snapshot start = sim.snapshot();
  c.wheel_speed[0] = c.wheel_speed[3] = 0.0;  // turning: rows change mode, new row sets
  sim.set_commands(c);
  sim.step_n(60);
  const SolverStats a = sim.solver_stats();
  EXPECT_GT(a.sparse_solves, first.sparse_solves);
  EXPECT_GT(a.plans_made + a.plans_grown, first.plans_made + first.plans_grown);
  sim.restore(start);
  sim.set_commands(c);
  sim.step_n(60);
  const SolverStats b = sim.solver_stats();
  EXPECT_EQ(b.plans_made - a.plans_made, a.plans_made - first.plans_made);
  EXPECT_EQ(b.plans_grown - a.plans_grown, a.plans_grown - first.plans_grown);
  EXPECT_EQ(b.sparse_solves - a.sparse_solves, a.sparse_solves - first.sparse_solves);
}
