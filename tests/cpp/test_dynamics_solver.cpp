// Tests of the sparse constraint solver (cpp/solver/sparse_ldlt, sparse_lcp, ode_lcp) against
// dense linear algebra (Eigen) and against ODE's own Dantzig solver.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <ode/ode.h>

#include "ernest/solver/ode_lcp.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "lcp_matrix.hpp"
#include "snapshot_gap.hpp"
#include "ernest/solver/sparse_ldlt.hpp"

using namespace ernest::dynamics;
using namespace ernest::solver;
using Mask = LdltPlan::Mask;

namespace {

// J M⁻¹ Jᵀ + CFM of a random tree of bodies, as ODE builds it: each row acts on one body or on a
// body and its parent, so rows meet only through a shared body and every other entry is an
// exact zero. Stored as ODE stores A: lower triangle, row-major, stride dPAD(n).
using TreeSystem = ernest::testing::LcpMatrix;

TreeSystem tree_system(int bodies, int rows, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd minv = Eigen::MatrixXd::Zero(6 * bodies, 6 * bodies);
  for (int b = 0; b < bodies; ++b) {
    Eigen::Matrix<double, 6, 6> r;
    for (int i = 0; i < 36; ++i) r(i) = u(rng);
    minv.block<6, 6>(6 * b, 6 * b) = r * r.transpose() + 0.1 * Eigen::Matrix<double, 6, 6>::Identity();
  }
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(rows, 6 * bodies);
  for (int i = 0; i < rows; ++i) {
    const int b = static_cast<int>(rng() % bodies);
    for (int k = 0; k < 6; ++k) j(i, 6 * b + k) = u(rng);
    if (b > 0 && rng() % 4 != 0) {
      const int parent = static_cast<int>(rng() % b);
      for (int k = 0; k < 6; ++k) j(i, 6 * parent + k) = u(rng);
    }
  }
  TreeSystem s;
  s.n = rows;
  s.stride = rows > 1 ? (rows + 3) & ~3 : rows;
  s.dense = j * minv * j.transpose();
  for (int i = 0; i < rows; ++i) s.dense(i, i) += std::pow(10.0, -4.0 + 2.0 * (u(rng) + 1.0) / 2.0);
  s.a.assign(static_cast<std::size_t>(s.n) * s.stride, std::nan(""));  // the upper part is junk
  for (int i = 0; i < rows; ++i)
    for (int k = 0; k <= i; ++k) s.a[i * s.stride + k] = s.dense(i, k);
  return s;
}

// Pattern of the rows `rows` (a subset of the system's, ascending) as LdltPlan::analyse wants it.
std::vector<Mask> pattern_of(const TreeSystem& s, const std::vector<unsigned>& rows) {
  std::vector<Mask> p(rows.size(), 0);
  for (std::size_t a = 0; a < rows.size(); ++a)
    for (std::size_t b = 0; b <= a; ++b)
      if (s.a[rows[a] * s.stride + rows[b]] != 0.0) p[a] |= Mask{1} << b;
  return p;
}

}  // namespace

TEST(SparseLdlt, SolvesTreeSystemsLikeADenseFactorisation) {
  std::mt19937_64 rng(42);
  for (int trial = 0; trial < 60; ++trial) {
    const int bodies = 2 + trial % 9;
    const int n = 1 + static_cast<int>(rng() % LdltPlan::kMaxRows);
    const TreeSystem s = tree_system(bodies, n, rng);
    // Every third trial solves only some of the rows (ODE's bounded rows are left out).
    std::vector<unsigned> rows;
    for (int i = 0; i < n; ++i)
      if (trial % 3 != 0 || i % 5 != 2) rows.push_back(static_cast<unsigned>(i));
    const int m = static_cast<int>(rows.size());
    const std::vector<Mask> pattern = pattern_of(s, rows);
    LdltPlan plan;
    plan.analyse(pattern.data(), rows.data(), m, s.stride);
    ASSERT_TRUE(plan.covers(pattern.data()));
    SparseLdlt ldlt;
    ASSERT_TRUE(ldlt.factor(plan, s.a.data())) << trial;
    Eigen::MatrixXd sub(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) sub(a, b) = s.dense(rows[a], rows[b]);
    Eigen::VectorXd rhs = Eigen::VectorXd::NullaryExpr(m, [&] { return std::sin(double(rng() % 1000)); });
    const Eigen::VectorXd expected = sub.ldlt().solve(rhs);
    Eigen::VectorXd x = rhs;
    ldlt.solve(x.data());
    EXPECT_LE((x - expected).norm(), 1e-9 * expected.norm()) << "trial " << trial << ", n " << m;
    EXPECT_LE((sub * x - rhs).norm(), 1e-10 * rhs.norm() * sub.norm()) << trial;
  }
}

TEST(SparseLdlt, MinimumDegreeEliminatesAStarWithoutFill) {
  // A hub row coupled to every other row, the others to nothing else: eliminating the leaves
  // first creates no fill, and the last two rows form the dense tail.
  const int n = 20;
  std::vector<Mask> star(n);
  std::vector<unsigned> rows(n);
  for (int i = 0; i < n; ++i) {
    rows[i] = static_cast<unsigned>(i);
    star[i] = (Mask{1} << i) | 1u;
  }
  LdltPlan plan;
  plan.analyse(star.data(), rows.data(), n, n);
  EXPECT_EQ(plan.dense_from(), n - 2);
  EXPECT_TRUE(plan.covers(star.data()));
  std::vector<Mask> leaves_coupled = star;
  leaves_coupled[7] |= Mask{1} << 3;  // an entry between two leaves is not in the factor
  EXPECT_FALSE(plan.covers(leaves_coupled.data()));
  std::vector<Mask> fewer = star;
  fewer[9] = Mask{1} << 9;  // a subset of the pattern is
  EXPECT_TRUE(plan.covers(fewer.data()));
  // The same asked of the values (only the entries outside the factor are read).
  std::vector<double> a(n * n, std::nan(""));  // junk above the diagonal
  for (int i = 0; i < n; ++i)
    for (int j = 0; j <= i; ++j) a[i * n + j] = i == j ? 2.0 : (j == 0 ? 0.1 : 0.0);
  EXPECT_TRUE(plan.covers(a.data()));
  a[7 * n + 3] = 1e-300;
  EXPECT_FALSE(plan.covers(a.data()));
  a[7 * n + 3] = -0.0;  // a zero all the same
  a[9 * n + 0] = 0.0;
  EXPECT_TRUE(plan.covers(a.data()));
  // The zero entries are listed on the first check after each analysis: the plan analysed again
  // with the leaves' entry in its factor accepts a non-zero there.
  plan.analyse(leaves_coupled.data(), rows.data(), n, n);
  a[7 * n + 3] = 1.0;
  EXPECT_TRUE(plan.covers(a.data()));
  a[8 * n + 3] = 1.0;  // (row 8 couples to nothing but the hub)
  EXPECT_FALSE(plan.covers(a.data()));
}

TEST(SparseLdlt, RefusesAMatrixThatIsNotPositiveDefinite) {
  std::mt19937_64 rng(7);
  for (const double bad : {-1.0, 0.0, std::nan("")}) {
    TreeSystem s = tree_system(3, 12, rng);
    std::vector<unsigned> rows(12);
    for (int i = 0; i < 12; ++i) rows[i] = static_cast<unsigned>(i);
    const std::vector<Mask> pattern = pattern_of(s, rows);
    LdltPlan plan;
    plan.analyse(pattern.data(), rows.data(), 12, s.stride);
    SparseLdlt ldlt;
    EXPECT_TRUE(ldlt.factor(plan, s.a.data()));
    s.a[5 * s.stride + 5] = bad;  // (pattern unchanged: the diagonal is always in it)
    EXPECT_FALSE(ldlt.factor(plan, s.a.data())) << bad;
  }
}

namespace {

using ernest::testing::body_gap;

Commands varied(int k, double base, double yaw = 0.2) {
  Commands c;
  for (int i = 0; i < 4; ++i) c.wheel_speed[i] = base + 0.3 * std::sin(0.05 * k + (yaw > 0 ? i : 0));
  c.yaw_rate = yaw * std::sin(0.03 * k);
  c.roll_rate = 0.1 * std::cos(0.04 * k);
  c.clutch_engage = (k / 60) % 2 == 1;
  return c;
}

// From the same state, one step with the sparse solver and one with ODE's Dantzig solver.
void expect_sparse_matches_ode(SimOptions o, const HeightMap& hm, int steps, double base,
                               double yaw = 0.2) {
  o.sparse_lcp = true;
  RoverSim sparse(RoverParameters{}, hm, {}, o);
  o.sparse_lcp = false;
  RoverSim dense(RoverParameters{}, hm, {}, o);
  sparse.reset(0.0, 0.0, 0.2, 0.0, 0.0, 0.1);
  for (int k = 0; k < steps; ++k) {
    sparse.set_commands(varied(k, base, yaw));
    dense.restore(sparse.snapshot());
    dense.set_commands(varied(k, base, yaw));
    sparse.step();
    dense.step();
    ASSERT_LE(body_gap(sparse.snapshot(), dense.snapshot()), 1e-9) << "step " << k;
    ASSERT_NEAR(sparse.state().wheel_load[2], dense.state().wheel_load[2], 1e-6) << k;
    ASSERT_NEAR(sparse.state().yaw_torque, dense.state().yaw_torque, 1e-6) << k;
  }
  const SolverStats& s = sparse.solver_stats();
  // Guessed steps are solved sparsely; only steps that pivot go to ODE. (A step may be solved
  // more than once, for its implicit slip: the share is of all solves.)
  EXPECT_GE(s.sparse_solves, static_cast<std::uint64_t>(0.9 * steps));
  EXPECT_LE(s.dense_solves, 0.1 * (s.sparse_solves + s.dense_solves));
  EXPECT_EQ(dense.solver_stats().sparse_solves, 0u);
  EXPECT_GE(dense.solver_stats().dense_solves, static_cast<std::uint64_t>(steps));
}

}  // namespace

TEST(SparseLcp, StepsMatchOdesSolverOnSoil) {
  expect_sparse_matches_ode(SimOptions{}, HeightMap::flat(10, 10, 0.25), 300, 1.0);
}

TEST(SparseLcp, StepsMatchOdesSolverOnRigidGround) {
  SimOptions o;
  o.ground = GroundType::Rigid;
  o.friction = 0.8;
  // (no yaw and one speed for all wheels: otherwise wheels slide, and sliding rigid contacts,
  // bounded by mu times a normal force, always go to ODE)
  expect_sparse_matches_ode(o, HeightMap::flat(10, 10, 0.25), 300, 0.8, 0.0);
}

TEST(SparseLcp, StepsMatchOdesSolverOnRoughSoil) {
  Eigen::MatrixXd h(41, 41);
  for (int r = 0; r < h.rows(); ++r)
    for (int c = 0; c < h.cols(); ++c) h(r, c) = 0.05 * std::sin(0.7 * r) * std::cos(0.5 * c);
  expect_sparse_matches_ode(SimOptions{}, HeightMap(h, 0.1, -2.0, -2.0), 200, 1.5);
}

TEST(SparseLcp, RestoreIntoAFreshSimulationIsBitExact) {
  // The solver's orderings depend on the sparsity patterns seen so far; the snapshot carries
  // them, so a simulation with another history continues bit for bit.
  const HeightMap hm = HeightMap::flat(10, 10, 0.25);
  RoverSim a(RoverParameters{}, hm);
  a.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.1);
  for (int k = 0; k < 150; ++k) {
    a.set_commands(varied(k, 1.0));
    a.step();
  }
  const Snapshot s = a.snapshot();
  EXPECT_FALSE(s.solver_patterns.empty());
  for (int k = 150; k < 300; ++k) {
    a.set_commands(varied(k, 1.0));
    a.step();
  }
  RoverSim b(RoverParameters{}, hm);
  b.restore(s);
  for (int k = 150; k < 300; ++k) {
    b.set_commands(varied(k, 1.0));
    b.step();
  }
  const Snapshot fa = a.snapshot(), fb = b.snapshot();
  EXPECT_EQ(std::memcmp(fa.bodies.data(), fb.bodies.data(), sizeof(fa.bodies)), 0);
}

TEST(SparseLcp, CorruptSolverDataInASnapshotIsRejected) {
  RoverSim sim(RoverParameters{}, HeightMap::flat(10, 10, 0.25));
  sim.reset(0.0, 0.0, 0.0, 0.0, 0.0, 0.1);
  sim.step_n(5);
  Snapshot s = sim.snapshot();
  ASSERT_GT(s.solver_patterns.size(), 3u);
  Snapshot cut = s;
  cut.solver_patterns.pop_back();
  EXPECT_THROW(sim.restore(cut), std::invalid_argument);
  Snapshot junk = s;
  junk.solver_patterns[0] = 99;  // no such plan slot
  EXPECT_THROW(sim.restore(junk), std::invalid_argument);
  EXPECT_NO_THROW(sim.restore(s));
  EXPECT_NO_THROW(sim.step_n(5));
}

// The solver hook on a bare ODE world: a box on a frictionless contact (one row, bounded below
// by 0) and a distance row (unbounded). Separating, the contact row rests at its zero bound;
// pressed down by gravity it must push: the first guess (as last time, or at its bound) fails
// Dantzig's test and the second solves it. With Coulomb friction bounded by the normal force
// (findex) the step goes to ODE.
TEST(SparseLcp, SolvesContactsThatPushOrSeparateAndHandsFrictionBoundsToOde) {
  dInitODE2(0);
  struct Case {
    double vz;
    bool friction;
  };
  for (const Case k : {Case{2.0, false}, Case{0.0, false}, Case{0.0, true}}) {
    SCOPED_TRACE(testing::Message() << k.vz << " " << k.friction);
    dWorldID w = dWorldCreate();
    dWorldSetGravity(w, 0.0, 0.0, -9.81);
    dJointGroupID group = dJointGroupCreate(0);
    dBodyID b = dBodyCreate(w);
    dMass m;
    dMassSetBoxTotal(&m, 1.0, 0.2, 0.2, 0.2);
    dBodySetMass(b, &m);
    dBodySetPosition(b, 0.0, 0.0, 0.1);
    dBodySetLinearVel(b, 0.0, 0.0, k.vz);
    dContact c;
    std::memset(&c, 0, sizeof c);
    c.geom.pos[2] = 0.0;
    c.geom.normal[2] = 1.0;
    c.surface.mode = k.friction ? dContactApprox1 : 0;
    c.surface.mu = k.friction ? 0.5 : 0.0;
    dJointAttach(dJointCreateContact(w, group, &c), b, nullptr);
    dJointID ball = dJointCreateDBall(w, group);  // holds x: an unbounded row
    dJointAttach(ball, b, nullptr);
    dJointSetDBallAnchor1(ball, 0.0, 0.0, 0.1);
    dJointSetDBallAnchor2(ball, -1.0, 0.0, 0.1);
    LcpWorkspace ws;
    {
      const LcpScope scope(&ws);
      dWorldStep(w, 0.01);
    }
    const dReal* v = dBodyGetLinearVel(b);
    if (k.vz > 0.0) {
      EXPECT_NEAR(v[2], k.vz - 9.81 * 0.01, 1e-9);  // free flight
    } else {
      EXPECT_NEAR(v[2], 0.0, 1e-6);  // the contact holds it: no velocity into the ground
    }
    EXPECT_EQ(ws.sparse, k.friction ? 0u : 1u);
    EXPECT_EQ(ws.dense, k.friction ? 1u : 0u);
    if (k.vz == 0.0 && !k.friction) {
      // Thrown up now: the remembered guess (pushing) would pull; it must let go.
      dBodySetLinearVel(b, 0.0, 0.0, 2.0);
      {
        const LcpScope scope(&ws);
        dWorldStep(w, 0.01);
      }
      EXPECT_NEAR(dBodyGetLinearVel(b)[2], 2.0 - 9.81 * 0.01, 1e-9);
      EXPECT_EQ(ws.sparse, 2u);
    }
    dJointGroupDestroy(group);
    dWorldDestroy(w);
  }
}

// More than 64 rows (two or more wheels on rocks): row sets are 128-bit masks, so such a step
// stays on the sparse path and agrees with ODE's Dantzig solver; over 128 rows it
// goes to ODE. A row of boxes chained by ball joints (3 unbounded rows each), each on 4 contacts
// (a normal row bounded below by 0 and 2 unbounded friction rows, as emit_obstacles emits a
// sticking rock contact), pressed down and moving sideways: the contacts push and stop them.
namespace {
std::vector<double> step_box_row(int boxes, bool sparse, LcpWorkspace& ws) {
  dWorldID w = dWorldCreate();
  dWorldSetGravity(w, 0.0, 0.0, -9.81);
  dJointGroupID group = dJointGroupCreate(0);
  std::vector<dBodyID> body;
  for (int i = 0; i < boxes; ++i) {
    dBodyID b = dBodyCreate(w);
    dMass m;
    dMassSetBoxTotal(&m, 1.0 + 0.1 * i, 0.2, 0.2, 0.2);
    dBodySetMass(b, &m);
    dBodySetPosition(b, 0.3 * i, 0.0, 0.1);
    dBodySetLinearVel(b, 0.0, 0.01, -0.02);
    for (int k = 0; k < 4; ++k) {
      dContact c;
      std::memset(&c, 0, sizeof c);
      c.geom.pos[0] = 0.3 * i + (k % 2 ? 0.1 : -0.1);
      c.geom.pos[1] = k / 2 ? 0.1 : -0.1;
      c.geom.normal[2] = 1.0;
      c.geom.depth = 1e-3;
      c.surface.mode = dContactSoftCFM | dContactSoftERP;
      c.surface.mu = dInfinity;  // friction rows unbounded: the sticking guess (emit_obstacles)
      c.surface.soft_cfm = 1e-4;
      c.surface.soft_erp = 0.2;
      dJointAttach(dJointCreateContact(w, group, &c), b, nullptr);
    }
    if (i > 0) {
      dJointID ball = dJointCreateBall(w, group);
      dJointAttach(ball, body.back(), b);
      dJointSetBallAnchor(ball, 0.3 * i - 0.15, 0.0, 0.1);
    }
    body.push_back(b);
  }
  ws.enabled = sparse;
  ws.coulomb_friction = true;
  {
    const LcpScope scope(&ws);
    dWorldStep(w, 0.01);
  }
  std::vector<double> v;
  for (dBodyID b : body)
    for (int k = 0; k < 3; ++k) v.insert(v.end(), {dBodyGetLinearVel(b)[k], dBodyGetAngularVel(b)[k]});
  dJointGroupDestroy(group);
  dWorldDestroy(w);
  return v;
}
}  // namespace

TEST(SparseLcp, StepsOfMoreThan64RowsStayOnTheSparsePath) {
  dInitODE2(0);
  ASSERT_TRUE(sparse_lcp_active());
  for (const int boxes : {4, 5, 8, 9}) {  // 15 x boxes - 3 rows: 57, 72, 117, 132
    SCOPED_TRACE(boxes);
    LcpWorkspace sparse_ws, dense_ws;
    const std::vector<double> ours = step_box_row(boxes, true, sparse_ws);
    const std::vector<double> ode = step_box_row(boxes, false, dense_ws);
    const bool fits = 15 * boxes - 3 <= LdltPlan::kMaxRows;
    EXPECT_EQ(sparse_ws.sparse, fits ? 1u : 0u);
    EXPECT_EQ(sparse_ws.dense, fits ? 0u : 1u);
    EXPECT_EQ(dense_ws.dense, 1u);
    double scale = 0.0;
    for (double x : ode) scale = std::max(scale, std::abs(x));
    ASSERT_GT(scale, 1e-3);
    for (std::size_t k = 0; k < ode.size(); ++k) EXPECT_NEAR(ours[k], ode[k], 1e-9 * scale) << k;
    // the contacts held the boxes: the lateral velocity is gone
    for (int i = 0; i < boxes; ++i) EXPECT_LT(std::abs(ode[6 * i + 2]), 1e-3) << i;
  }
}
