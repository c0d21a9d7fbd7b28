#include "ernest/walker/gait_planner.hpp"
#include "ernest/common/interrupt.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/statics/stability.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::walker {

namespace {

constexpr double kPi = 3.14159265358979323846;

class Planner {
 public:
  Planner(const WalkerModel& model, const GaitPlannerOptions& o)
      : m_(model), o_(o), ik_(model, ik_options(o)),
        d_(std::cos(o.heading), std::sin(o.heading), 0.0), gravity_(0.0, 0.0, -model.params().gravity) {}

  int tests() const { return tests_; }

  // IK of one leg putting its (upright) wheel on `contact` (world) with the body at `body`; the
  // local solve from `seed` first, the multi-start solve only when that fails.
  bool solve(int leg, const Eigen::Vector3d& body, const Eigen::Vector3d& contact,
             const Eigen::VectorXd& seed, Eigen::VectorXd& q) {
    ++tests_;
    const Eigen::Isometry3d target =
        upright_foot_pose(m_, contact - body, 2.0 * kPi * leg / m_.legs());  // body is level
    q.resize(m_.joints_per_leg());
    if (ik_.solve_from(leg, target, seed, q)) return true;
    const IkResult r = ik_.solve(leg, target, seed);
    if (r.status != IkStatus::kSolved) return false;
    q = r.solutions.front();
    return true;
  }

  // SSM of the CG over the feet other than `lifted` (-1: all feet).
  double margin(const Eigen::Vector3d& body, const Eigen::MatrixXd& q, const Eigen::Matrix3Xd& feet,
                int lifted) const {
    Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
    b.translation() = body;
    Eigen::Matrix3Xd loaded(3, m_.legs() - (lifted >= 0 ? 1 : 0));
    for (int k = 0, c = 0; k < m_.legs(); ++k)
      if (k != lifted) loaded.col(c++) = feet.col(k);
    return statics::stability_margins(loaded, m_.center_of_mass(b, q), gravity_).ssm;
  }

  // Largest s in [0, cap] with feasible(s), by tests every search_increment then bisection of
  // the last interval (feasibility assumed monotone in s, as reach is along a straight line).
  // feasible(0) must hold; the configuration of the accepted s is what feasible() stored last
  // when called with `commit` true.
  template <class F>
  double search(double cap, F&& feasible) {
    double lo = 0.0, hi = -1.0;
    for (double s = std::min(o_.search_increment, cap);; s = std::min(s + o_.search_increment, cap)) {
      if (!feasible(s, false)) {
        hi = s;
        break;
      }
      lo = s;
      if (s >= cap) break;
    }
    if (hi > 0.0)
      while (hi - lo > o_.search_tolerance) {
        const double mid = 0.5 * (lo + hi);
        (feasible(mid, false) ? lo : hi) = mid;
      }
    require(feasible(lo, true), "plan_gait: the accepted length is no longer feasible");
    return lo;
  }

  GaitEvent step(int cycle, int leg, const Eigen::Vector3d& body, Eigen::MatrixXd& q, Eigen::Matrix3Xd& feet) {
    GaitEvent e;
    e.kind = GaitEvent::kStep;
    e.cycle = cycle;
    e.leg = leg;
    e.body_before = e.body_after = body;
    e.feet_before = feet;
    e.q_before = q;
    const Eigen::Vector3d up(0.0, 0.0, o_.lift_height), start = feet.col(leg);
    Eigen::MatrixXd ql = q;
    Eigen::VectorXd lift_start;
    require(solve(leg, body, start + up, q.col(leg), lift_start),
            "plan_gait: leg " + std::to_string(leg) + " cannot lift " + std::to_string(o_.lift_height) +
                " m above its foot");
    ql.col(leg) = lift_start;
    const double m0 = margin(body, ql, feet, leg);
    require(m0 >= o_.min_support_margin, "plan_gait: lifting leg " + std::to_string(leg) +
                                             " is unstable (SSM " + std::to_string(m0) + " m)");
    Eigen::VectorXd seed_lift = lift_start, seed_goal = q.col(leg), lift_goal, goal;
    double m1 = m0;
    const auto feasible = [&](double s, bool commit) {
      const Eigen::Vector3d g = start + s * d_;
      Eigen::VectorXd a, b;
      if (!solve(leg, body, g + up, seed_lift, a) || !solve(leg, body, g, seed_goal, b)) return false;
      ql.col(leg) = a;
      const double mg = margin(body, ql, feet, leg);
      if (mg < o_.min_support_margin) return false;
      seed_lift = a;  // warm start the next test from the last feasible solution
      seed_goal = b;
      if (commit) lift_goal = a, goal = b, m1 = mg;
      return true;
    };
    e.length = search(o_.max_step, feasible);
    feet.col(leg) = start + e.length * d_;
    q.col(leg) = goal;
    e.q_lift_start = lift_start;
    e.q_lift_goal = lift_goal;
    e.support_margin = std::min(m0, m1);
    e.feet_after = feet;
    e.q_after = q;
    return e;
  }

  GaitEvent shift(int cycle, Eigen::Vector3d& body, Eigen::MatrixXd& q, const Eigen::Matrix3Xd& feet) {
    GaitEvent e;
    e.kind = GaitEvent::kShift;
    e.cycle = cycle;
    e.body_before = body;
    e.feet_before = e.feet_after = feet;
    e.q_before = q;
    const Eigen::Vector3d centroid = feet.rowwise().mean();
    const double wanted = std::max(0.0, d_.dot(centroid - body));
    Eigen::MatrixXd seeds = q, trial = q, accepted = q;
    const auto feasible = [&](double s, bool commit) {
      const Eigen::Vector3d b = body + s * d_;
      for (int k = 0; k < m_.legs(); ++k) {
        Eigen::VectorXd qk;
        if (!solve(k, b, feet.col(k), seeds.col(k), qk)) return false;
        trial.col(k) = qk;
      }
      if (margin(b, trial, feet, -1) < o_.min_support_margin) return false;
      seeds = trial;
      if (commit) accepted = trial;
      return true;
    };
    e.length = search(wanted, feasible);
    body += e.length * d_;
    q = accepted;
    e.body_after = body;
    e.q_after = q;
    e.support_margin = std::min(margin(e.body_before, e.q_before, feet, -1), margin(body, q, feet, -1));
    return e;
  }

 private:
  static IkOptions ik_options(const GaitPlannerOptions& o) {
    IkOptions i;
    i.seeds = o.ik_seeds;
    i.max_solutions = 1;
    return i;
  }
  const WalkerModel& m_;
  const GaitPlannerOptions& o_;
  LegIk ik_;
  Eigen::Vector3d d_, gravity_;
  int tests_ = 0;
};

}  // namespace

void GaitPlannerOptions::validate(int legs) const {
  const char* o = "GaitPlannerOptions";
  require_finite(o, "heading", heading);
  require_in_range(o, "cycles", cycles, 1, 100);
  require_in_range(o, "max_step", max_step, 1e-6, 5.0);
  require_in_range(o, "lift_height", lift_height, 0.0, 2.0);
  require_in_range(o, "min_support_margin", min_support_margin, -10.0, 10.0);
  require_in_range(o, "search_increment", search_increment, 1e-6, 1.0);
  require_in_range(o, "search_tolerance", search_tolerance, 1e-9, 0.1);
  require_in_range(o, "ik_seeds", ik_seeds, 1, 256);
  if (sequence.empty()) return;
  require(static_cast<int>(sequence.size()) == legs,
          "GaitPlannerOptions.sequence must list each of the " + std::to_string(legs) + " legs once");
  std::vector<bool> seen(legs, false);
  for (int leg : sequence) {
    require(leg >= 0 && leg < legs && !seen[leg],
            "GaitPlannerOptions.sequence must list distinct legs in [0, " + std::to_string(legs - 1) + "]");
    seen[leg] = true;
  }
}

std::vector<int> reverse_wave_sequence(const WalkerModel& model, double heading) {
  require_finite("reverse_wave_sequence", "heading", heading);
  const Eigen::Vector2d d(std::cos(heading), std::sin(heading)), left(-d.y(), d.x());
  std::vector<int> order(model.legs());
  std::iota(order.begin(), order.end(), 0);
  std::vector<double> ahead(model.legs()), side(model.legs());
  for (int k = 0; k < model.legs(); ++k) {
    const Eigen::Vector2d h = model.hip_mount(k).translation().head<2>();
    ahead[k] = std::round(d.dot(h) * 1e6);  // micrometres: equal projections compare equal
    side[k] = left.dot(h);
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return ahead[a] != ahead[b] ? ahead[a] > ahead[b] : side[a] > side[b];
  });
  return order;
}

GaitPlan plan_gait(const WalkerModel& model, const Eigen::Vector3d& body_position,
                   const Eigen::Ref<const Eigen::MatrixXd>& q0, const GaitPlannerOptions& options) {
  options.validate(model.legs());
  model.check_configuration(q0);
  require(body_position.allFinite(), "plan_gait: body_position is not finite");
  const auto t0 = std::chrono::steady_clock::now();
  GaitPlan plan;
  plan.sequence = options.sequence.empty() ? reverse_wave_sequence(model, options.heading) : options.sequence;
  Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
  b.translation() = body_position;
  Eigen::Matrix3Xd feet = model.contact_points(b, q0);
  require(feet.row(2).cwiseAbs().maxCoeff() < 1e-3,
          "plan_gait: every wheel must start on the ground (z = 0), the highest is at z = " +
              std::to_string(feet.row(2).cwiseAbs().maxCoeff()) + " m");
  feet.row(2).setZero();
  Eigen::MatrixXd q = q0;
  Eigen::Vector3d body = body_position;
  const int legs = model.legs();
  plan.step_lengths.resize(options.cycles, legs);
  plan.shift_lengths.resize(options.cycles, legs);
  Planner p(model, options);
  for (int c = 0; c < options.cycles; ++c)
    for (int i = 0; i < legs; ++i) {
      poll_interrupt();  // Ctrl-C between steps of the plan (common/interrupt.hpp)
      plan.events.push_back(p.step(c, plan.sequence[i], body, q, feet));
      plan.step_lengths(c, i) = plan.events.back().length;
      plan.events.push_back(p.shift(c, body, q, feet));
      plan.shift_lengths(c, i) = plan.events.back().length;
    }
  plan.ik_tests = p.tests();
  plan.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return plan;
}

}  // namespace ernest::walker
