#include "ernest/footfall/leg_planner.hpp"
#include "ernest/common/interrupt.hpp"

#include <ompl/base/MotionValidator.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateProjections.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/sbl/SBL.h>
#include <ompl/util/Console.h>

#include <chrono>
#include <cmath>

#include "ernest/common/validation.hpp"

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace ernest::footfall {

const char* to_string(PlanStatus status) { return status == PlanStatus::kSolved ? "solved" : "no plan"; }

void PlannerOptions::validate() const {
  const char* o = "PlannerOptions";
  require_in_range(o, "time_limit", time_limit, 1e-4, 3600.0);
  require_in_range(o, "epsilon", epsilon, 1e-5, 1.0);
  if (range) {
    require_in_range(o, "range", *range, 0.0, 100.0);
    require_positive(o, "range", *range);  // no 0 for "OMPL's default": unset the field
  }
}

double path_length(const Eigen::Ref<const Eigen::MatrixXd>& path) {
  require(path.allFinite(), "path_length: path must be finite");
  double l = 0.0;
  for (Eigen::Index k = 1; k < path.cols(); ++k) l += (path.col(k) - path.col(k - 1)).norm();
  require(std::isfinite(l), "path_length: the length of path overflows");
  return l;
}

namespace {

Eigen::Map<const Eigen::VectorXd> as_vector(const ob::State* s, int n) {
  return {s->as<ob::RealVectorStateSpace::StateType>()->values, n};
}

// §3.4.1 lazy edge check: recursive bisection to ε, through the leg's checker.
class BisectionValidator : public ob::MotionValidator {
 public:
  BisectionValidator(const ob::SpaceInformationPtr& si, LegCollisionChecker& checker, double epsilon)
      : ob::MotionValidator(si), checker_(checker), epsilon_(epsilon),
        n_(checker.model().joints_per_leg()), x_(n_) {}
  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    const bool ok = checker_.motion_valid(as_vector(s1, n_), as_vector(s2, n_), epsilon_);
    ok ? ++valid_ : ++invalid_;
    return ok;
  }
  // Variant that reports the last valid point: walk the edge at resolution ε from s1.
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    const auto a = as_vector(s1, n_), b = as_vector(s2, n_);
    const int steps = std::max(1, int(std::ceil((b - a).cwiseAbs().maxCoeff() / epsilon_)));
    for (int k = 1; k <= steps; ++k) {
      x_ = a + (double(k) / steps) * (b - a);
      if (!checker_.valid(x_)) {
        const double t = double(k - 1) / steps;
        if (last_valid.first) si_->getStateSpace()->interpolate(s1, s2, t, last_valid.first);
        last_valid.second = t;
        ++invalid_;
        return false;
      }
    }
    ++valid_;
    return true;
  }

 private:
  LegCollisionChecker& checker_;
  double epsilon_;
  int n_;
  mutable Eigen::VectorXd x_;
};

// Uniform sampler with its own seeded stream (OMPL's RNG::setSeed is global and once only).
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, std::uint32_t seed) : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(seed);
  }
};

class SeededSbl : public og::SBL {
 public:
  SeededSbl(const ob::SpaceInformationPtr& si, std::uint32_t seed) : og::SBL(si) { rng_.setLocalSeed(seed); }
};

}  // namespace

struct LegPlanner::Impl {
  std::shared_ptr<ob::RealVectorStateSpace> space;
  ob::SpaceInformationPtr si;
  std::uint32_t sampler_seed = 0;  // next sampler's seed (advanced per allocation)
};

LegPlanner::LegPlanner(LegCollisionChecker& checker, const PlannerOptions& options)
    : checker_(checker), options_(options), impl_(std::make_unique<Impl>()) {
  options.validate();
  ompl::msg::setLogLevel(ompl::msg::LOG_NONE);  // OMPL would print to stderr on every query
  const walker::WalkerModel& model = checker.model();
  const int n = model.joints_per_leg();
  Impl& s = *impl_;
  s.space = std::make_shared<ob::RealVectorStateSpace>(n);
  ob::RealVectorBounds bounds(n);
  for (int i = 0; i < n; ++i) bounds.setLow(i, model.lower_limits()[i]), bounds.setHigh(i, model.upper_limits()[i]);
  s.space->setBounds(bounds);
  // SBL grids its trees in a projection: the first three joints (hip yaw, hip pitch, knee), not
  // the default random linear projection (drawn from OMPL's global seed: not reproducible).
  // Explicit cell sizes (a twentieth of each range, OMPL's default) mark it user-configured, so
  // the space's setup keeps it.
  std::vector<unsigned int> components;
  std::vector<double> cells;
  for (int i = 0; i < std::min(n, 3); ++i) {
    components.push_back(i);
    cells.push_back((model.upper_limits()[i] - model.lower_limits()[i]) / 20.0);
  }
  s.space->registerDefaultProjection(
      std::make_shared<ob::RealVectorOrthogonalProjectionEvaluator>(s.space.get(), cells, components));
  Impl* raw = &s;
  s.space->setStateSamplerAllocator([raw](const ob::StateSpace* sp) -> ob::StateSamplerPtr {
    return std::make_shared<SeededSampler>(sp, raw->sampler_seed++);
  });
  s.si = std::make_shared<ob::SpaceInformation>(s.space);
  LegCollisionChecker* c = &checker;
  s.si->setStateValidityChecker([c, n](const ob::State* st) { return c->valid(as_vector(st, n)); });
  s.si->setMotionValidator(std::make_shared<BisectionValidator>(s.si, checker, options.epsilon));
  s.si->setup();
}

LegPlanner::~LegPlanner() = default;

PlanResult LegPlanner::plan(const Eigen::Ref<const Eigen::VectorXd>& start, const Eigen::Ref<const Eigen::VectorXd>& goal) {
  const walker::WalkerModel& model = checker_.model();
  model.check_q(start, "start");
  model.check_q(goal, "goal");
  const auto t0 = std::chrono::steady_clock::now();
  const long checks0 = checker_.checks();
  PlanResult r;
  auto finish = [&](PlanStatus status, std::string reason) {
    r.status = status;
    r.reason = std::move(reason);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.checks = checker_.checks() - checks0;
    if (status == PlanStatus::kSolved) r.length = path_length(r.path);
    return r;
  };
  if (!model.within_limits(start)) return finish(PlanStatus::kNoPlan, "start outside the joint limits");
  if (!model.within_limits(goal)) return finish(PlanStatus::kNoPlan, "goal outside the joint limits");
  if (!checker_.valid(start)) return finish(PlanStatus::kNoPlan, "start in collision");
  if (!checker_.valid(goal)) return finish(PlanStatus::kNoPlan, "goal in collision");
  Impl& s = *impl_;
  const int n = model.joints_per_leg();
  // Every query restarts the seeded streams, so the same seed gives the same plan.
  s.sampler_seed = options_.seed * 7919u + 1u;
  ob::ScopedState<ob::RealVectorStateSpace> a(s.space), b(s.space);
  for (int i = 0; i < n; ++i) a[i] = start[i], b[i] = goal[i];
  auto pdef = std::make_shared<ob::ProblemDefinition>(s.si);
  pdef->setStartAndGoalStates(a, b, 1e-9);
  ob::PlannerPtr planner;
  if (options_.planner == PlannerType::kSbl) {
    auto sbl = std::make_shared<SeededSbl>(s.si, options_.seed);
    if (options_.range) sbl->setRange(*options_.range);
    planner = sbl;
  } else {
    auto rrt = std::make_shared<og::RRTConnect>(s.si);
    if (options_.range) rrt->setRange(*options_.range);
    planner = rrt;
  }
  planner->setProblemDefinition(pdef);
  planner->setup();
  // Ctrl-C (common/interrupt.hpp) ends the query like the time limit; the exception is raised
  // after OMPL returns (throwing through OMPL's solve loop is not safe).
  bool interrupted = false;
  const ob::PlannerTerminationCondition on_interrupt([&interrupted] {
    try {
      poll_interrupt();
    } catch (const Interrupted&) {
      interrupted = true;
    }
    return interrupted;
  });
  const ob::PlannerStatus status = planner->solve(
      ob::plannerOrTerminationCondition(ob::timedPlannerTerminationCondition(options_.time_limit), on_interrupt));
  if (interrupted) throw Interrupted("interrupted");
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    return finish(PlanStatus::kNoPlan, status == ob::PlannerStatus::TIMEOUT || status == ob::PlannerStatus::APPROXIMATE_SOLUTION
                                           ? "no path found within the time limit"
                                           : std::string("planner: ") + status.asString());
  }
  const auto& path = *pdef->getSolutionPath()->as<og::PathGeometric>();
  r.path.resize(n, static_cast<Eigen::Index>(path.getStateCount()));
  for (std::size_t k = 0; k < path.getStateCount(); ++k) r.path.col(Eigen::Index(k)) = as_vector(path.getState(k), n);
  return finish(PlanStatus::kSolved, "");
}

Eigen::MatrixXd LegPlanner::simplify_with_ompl(const Eigen::Ref<const Eigen::MatrixXd>& path) {
  const int n = checker_.model().joints_per_leg();
  require(path.rows() == n && path.cols() >= 2 && path.allFinite(),
          "simplify_with_ompl: path must be finite, joints x waypoints (at least two)");
  og::PathGeometric p(impl_->si);
  ob::ScopedState<ob::RealVectorStateSpace> x(impl_->space);
  for (Eigen::Index k = 0; k < path.cols(); ++k) {
    for (int i = 0; i < n; ++i) x[i] = path(i, k);
    p.append(x.get());
  }
  og::PathSimplifier simplifier(impl_->si);
  simplifier.simplifyMax(p);
  Eigen::MatrixXd out(n, static_cast<Eigen::Index>(p.getStateCount()));
  for (std::size_t k = 0; k < p.getStateCount(); ++k) out.col(Eigen::Index(k)) = as_vector(p.getState(k), n);
  return out;
}

}  // namespace ernest::footfall
