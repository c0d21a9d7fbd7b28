// Compliance (sag) model, seed 003 §5.1.1 eqs 1–12, solved with Eigen's (unsupported)
// Levenberg–Marquardt. See sag.hpp for the formulation.
#include "ernest/statics/sag.hpp"
#include "ernest/common/interrupt.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>
#include <unsupported/Eigen/NonLinearOptimization>

#include "ernest/common/validation.hpp"
#include "ernest/statics/stability.hpp"

namespace ernest::statics {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

void require_rotation(const char* field, const Eigen::Matrix3d& r) {
  const bool ok = r.allFinite() &&
                  (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 &&
                  r.determinant() > 0.0;
  if (!ok) {
    throw std::invalid_argument(std::string("SagProblem.") + field +
                                " must be a rotation matrix (orthonormal, det +1)");
  }
}

void require_all_finite(const char* field, const Eigen::Ref<const Eigen::MatrixXd>& m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
      if (!std::isfinite(m(i, j))) {
        std::ostringstream os;
        os << "SagProblem." << field << "(" << i << ", " << j << ") = " << m(i, j)
           << " is not finite";
        throw std::invalid_argument(os.str());
      }
    }
  }
}

// The residuals of eqs 4–8 and their Jacobian, for Eigen's LevenbergMarquardt. Unknowns
// x = [Δr_0 .. Δr_{N-1}, Δr_CG]. Scales: forces over W = m|g|, moments over W L, distances over
// the typical deflection δ, so every block is O(1) per unit of error.
struct SagFunctor {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;

  const SagProblem& p;
  Eigen::VectorXd lift;                        // Δh_i, eq 9
  std::vector<std::pair<int, int>> pairs;      // eqs 6 and 7: successive and alternate feet
  std::vector<double> pair_d0, cg_d0;          // unsagged distances
  Eigen::Vector3d o, weight;                   // moment origin (r_0,CG), m g
  std::vector<char> active;                    // the contact set inside one LM solve
  double W = 1.0, L = 1.0, delta = 1.0;
  int n = 0;

  explicit SagFunctor(const SagProblem& problem) : p(problem) {
    n = static_cast<int>(p.feet.cols());
    lift = p.lift.size() == n ? p.lift : Eigen::VectorXd::Zero(n);
    active.assign(n, 0);
    o = p.cg;
    weight = p.mass * p.gravity;
    W = weight.norm();
    for (int step = 1; step <= 2; ++step) {
      for (int i = 0; i < n; ++i) {
        std::pair<int, int> e{std::min(i, (i + step) % n), std::max(i, (i + step) % n)};
        if (e.first != e.second && std::find(pairs.begin(), pairs.end(), e) == pairs.end()) {
          pairs.push_back(e);
        }
      }
    }
    for (const auto& [i, j] : pairs) pair_d0.push_back((p.feet.col(i) - p.feet.col(j)).norm());
    L = 0.0;
    for (int i = 0; i < n; ++i) {
      cg_d0.push_back((p.cg - p.feet.col(i)).norm());
      L = std::max(L, cg_d0.back());
    }
    L = std::max(L, 1e-9);
    delta = W / p.stiffness.row(2).sum();
  }

  int inputs() const { return 3 * n + 3; }
  int values() const { return 6 + static_cast<int>(pairs.size()) + n; }

  // Eqs 10–12 in the spring frame F: d = F^T Δr, compression c = -(d_z + Δh); loaded iff c > 0.
  // Inside the LM the contact set is held fixed (`active`: a bilateral spring, c of any sign),
  // so the residuals are smooth; solve_sag switches the set until it is consistent with eqs
  // 10–12. Writes f and, if J is given, ∂f/∂Δr. Returns whether the foot carries force.
  bool spring(int i, const Eigen::Vector3d& dr, Eigen::Vector3d& f,
              Eigen::Matrix3d* J = nullptr) const {
    if (!active[i]) {
      f.setZero();
      return false;
    }
    const Eigen::Matrix3d& F = p.spring_frame;
    const Eigen::Vector3d d = F.transpose() * dr;
    const double c = -(d.z() + lift(i));
    f = F * Eigen::Vector3d(-p.stiffness(0, i) * d.x(), -p.stiffness(1, i) * d.y(),
                            p.stiffness(2, i) * c);
    if (J) *J = -F * p.stiffness.col(i).asDiagonal() * F.transpose();
    return true;
  }
  double compression(int i, const Eigen::Vector3d& dr) const {
    return -((p.spring_frame.transpose() * dr).z() + lift(i));
  }

  Eigen::Vector3d foot(const Eigen::VectorXd& x, int i) const {
    return p.feet.col(i) + x.segment<3>(3 * i);
  }
  Eigen::Vector3d cg(const Eigen::VectorXd& x) const { return p.cg + x.segment<3>(3 * n); }

  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    poll_interrupt();  // Ctrl-C in a long fit (common/interrupt.hpp): the exception ends the solve
    Eigen::Vector3d sum_f = weight, sum_m = (cg(x) - o).cross(weight), f;
    for (int i = 0; i < n; ++i) {
      spring(i, x.segment<3>(3 * i), f);
      sum_f += f;                              // eq 4
      sum_m += (foot(x, i) - o).cross(f);      // eq 5
    }
    r.segment<3>(0) = sum_f / W;
    r.segment<3>(3) = sum_m / (W * L);
    int row = 6;
    for (std::size_t k = 0; k < pairs.size(); ++k) {  // eqs 6, 7
      const auto [i, j] = pairs[k];
      r(row++) = (pair_d0[k] - (foot(x, i) - foot(x, j)).norm()) / delta;
    }
    for (int i = 0; i < n; ++i) r(row++) = (cg_d0[i] - (cg(x) - foot(x, i)).norm()) / delta;  // 8
    return 0;
  }

  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& J) const {
    J.setZero();
    Eigen::Vector3d f;
    for (int i = 0; i < n; ++i) {
      Eigen::Matrix3d Jf;  // ∂f_i/∂Δr_i
      if (!spring(i, x.segment<3>(3 * i), f, &Jf)) continue;
      J.block<3, 3>(0, 3 * i) = Jf / W;
      J.block<3, 3>(3, 3 * i) = (-skew(f) + skew(foot(x, i) - o) * Jf) / (W * L);
    }
    J.block<3, 3>(3, 3 * n) = -skew(weight) / (W * L);
    int row = 6;
    for (const auto& [i, j] : pairs) {
      const Eigen::Vector3d d = foot(x, i) - foot(x, j);
      const Eigen::Vector3d u = d / std::max(d.norm(), 1e-300);
      J.block<1, 3>(row, 3 * i) = -u.transpose() / delta;
      J.block<1, 3>(row, 3 * j) = u.transpose() / delta;
      ++row;
    }
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d d = cg(x) - foot(x, i);
      const Eigen::Vector3d u = d / std::max(d.norm(), 1e-300);
      J.block<1, 3>(row, 3 * n) = -u.transpose() / delta;
      J.block<1, 3>(row, 3 * i) = u.transpose() / delta;
      ++row;
    }
    return 0;
  }
};

}  // namespace

void SagProblem::validate() const {
  const Eigen::Index n = feet.cols();
  require_all_finite("feet", feet);
  if (stiffness.cols() != n) {
    throw std::invalid_argument("SagProblem.stiffness has " + std::to_string(stiffness.cols()) +
                                " columns; it needs one per foot (" + std::to_string(n) + ")");
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    for (int i = 0; i < 3; ++i) {
      const double k = stiffness(i, j);
      if (!(std::isfinite(k) && k > 0.0)) {
        std::ostringstream os;
        os << "SagProblem.stiffness(" << i << ", " << j << ") = " << k
           << " must be finite and > 0";
        throw std::invalid_argument(os.str());
      }
    }
  }
  if (lift.size() != 0 && lift.size() != n) {
    throw std::invalid_argument("SagProblem.lift has " + std::to_string(lift.size()) +
                                " entries; it needs 0 or one per foot (" + std::to_string(n) +
                                ")");
  }
  for (Eigen::Index i = 0; i < lift.size(); ++i) {
    if (std::isnan(lift(i)) || lift(i) == -std::numeric_limits<double>::infinity()) {
      std::ostringstream os;
      os << "SagProblem.lift(" << i << ") = " << lift(i) << " must be finite or +inf";
      throw std::invalid_argument(os.str());
    }
  }
  require_all_finite("cg", cg);
  require_positive("SagProblem", "mass", mass);
  require_all_finite("gravity", gravity);
  require(gravity.norm() > 0.0, "SagProblem.gravity must be non-zero");
  require_rotation("spring_frame", spring_frame);
  require_all_finite("chassis_position", chassis_position);
  require_rotation("chassis_rotation", chassis_rotation);
  require_all_finite("body_points", body_points);
}

void SagOptions::validate() const {
  require_in_range("SagOptions", "max_evaluations", max_evaluations, 10, 1e7);
  require_in_range("SagOptions", "tolerance", tolerance, 1e-300, 1e-3);
  require_in_range("SagOptions", "equilibrium_tolerance", equilibrium_tolerance, 1e-300, 1.0);
  require_in_range("SagOptions", "contact_tolerance", contact_tolerance, 0.0, 1.0);
}

const char* to_string(SagStatus status) {
  switch (status) {
    case SagStatus::Converged: return "converged";
    case SagStatus::Unstable: return "unstable";
    case SagStatus::NotConverged: return "not_converged";
  }
  return "unknown";
}

SagResult solve_sag(const SagProblem& problem, const SagOptions& options) {
  problem.validate();
  options.validate();
  const int n = static_cast<int>(problem.feet.cols());
  SagResult res;
  res.forces = Eigen::Matrix3Xd::Zero(3, n);
  res.deflections = Eigen::Matrix3Xd::Zero(3, n);
  res.compression = Eigen::VectorXd::Zero(n);
  res.cg = problem.cg;
  res.chassis_position = problem.chassis_position;
  res.chassis_rotation = problem.chassis_rotation;
  res.body_points = problem.body_points;
  int touchable_feet = 0;
  for (int i = 0; i < n; ++i) {
    touchable_feet += problem.lift.size() == 0 || std::isfinite(problem.lift(i)) ? 1 : 0;
  }
  if (n < 3 || touchable_feet < 3) {  // two or fewer contacts cannot hold a rigid body
    if (problem.lift.size() == n) res.compression = -problem.lift;
    res.status = SagStatus::Unstable;
    res.equilibrium_residual = 1.0;
    return res;
  }

  SagFunctor fn(problem);
  // Start from a uniform sink along gravity that loads the feet already touching.
  const Eigen::Vector3d down = problem.gravity.normalized();
  double k_touching = 0.0;
  for (int i = 0; i < n; ++i) {
    if (fn.lift(i) <= 0.0) k_touching += problem.stiffness.col(i).dot(
        (problem.spring_frame.transpose() * down).cwiseAbs2());
  }
  const double sink = fn.W / (k_touching > 0.0 ? k_touching : problem.stiffness.row(2).sum());
  Eigen::VectorXd x(3 * n + 3);
  for (int i = 0; i <= n; ++i) x.segment<3>(3 * i) = sink * down;

  auto run_lm = [&](Eigen::VectorXd& y) {
    Eigen::LevenbergMarquardt<SagFunctor> lm(fn);
    lm.parameters.ftol = options.tolerance;
    lm.parameters.xtol = options.tolerance;
    lm.parameters.maxfev = options.max_evaluations;
    lm.minimize(y);
    res.evaluations += static_cast<int>(lm.nfev);
    Eigen::VectorXd r(fn.values());
    fn(y, r);
    return y.allFinite() && r.head<6>().norm() <= options.equilibrium_tolerance;
  };
  // Active set over the LM (eqs 10–12's "if in contact" exactly): start with the feet the
  // state x loads, solve with the set fixed, then switch one foot (below) until every foot obeys
  // eqs 10–12. A unilateral spring inside the LM instead stalls: a foot that an iterate lifts
  // has no gradient to come back. Returns whether a consistent set was found; `tips` whether it
  // failed because a foot that had to unload left feet that cannot hold the robot.
  auto active_set = [&](Eigen::VectorXd& x, bool& tips, bool keep_set) {
    if (!keep_set) {
      for (int i = 0; i < n; ++i) fn.active[i] = fn.compression(i, x.segment<3>(3 * i)) > 0.0;
    }
    // Never start on fewer than three feet (the LM would find a spurious equilibrium of a rigid
    // body on two bilateral springs): add the least lifted ones.
    while (std::count(fn.active.begin(), fn.active.end(), 1) < 3) {
      int best = -1;
      for (int i = 0; i < n; ++i) {
        if (fn.active[i] || !std::isfinite(fn.lift(i))) continue;
        if (best < 0 || fn.compression(i, x.segment<3>(3 * i)) >
                            fn.compression(best, x.segment<3>(3 * best))) {
          best = i;
        }
      }
      if (best < 0) break;
      fn.active[best] = 1;
    }
    tips = false;
    const int max_switches = 4 * n;
    bool consistent = false;
    int flipped = -1;
    auto unflip = [&] {
      tips = flipped >= 0 && fn.active[flipped] == 0;
      if (flipped >= 0) fn.active[flipped] = !fn.active[flipped];
    };
    for (int round = 0; round <= max_switches; ++round) {
      Eigen::VectorXd y = x;
      if (!run_lm(y)) {  // no equilibrium on this set: keep the last solved state and its set
        unflip();
        break;
      }
      x = y;
      // The next switch: the foot in the air that penetrates the ground deepest (beyond
      // contact_tolerance: see SagOptions for why a little is accepted), else the loaded foot in
      // the most tension (beyond rounding). Adding first never leaves too few feet to stand on.
      int worst = -1;
      double worst_depth = 0.0;
      for (int pass = 0; pass < 2 && worst < 0; ++pass) {
        for (int i = 0; i < n; ++i) {
          if (fn.active[i] != pass) continue;  // pass 0: feet in the air; 1: loaded feet
          const double c = fn.compression(i, x.segment<3>(3 * i));
          const double depth = pass == 0 ? c - options.contact_tolerance : -c - 1e-12 * fn.delta;
          if (depth > worst_depth) {
            worst_depth = depth;
            worst = i;
          }
        }
      }
      if (worst < 0) {
        consistent = true;
        break;
      }
      fn.active[worst] = !fn.active[worst];
      flipped = worst;
      if (std::count(fn.active.begin(), fn.active.end(), 1) < 3) {  // it cannot stand
        unflip();
        break;
      }
    }
    return consistent;
  };

  // If that fails (typically: a foot that must unload leaves feet that cannot hold the robot,
  // which then leans until a lifted foot comes down), a second start follows the quasi-static
  // path FootFall's legs take: the lifts grow from zero (every foot that can touch is loaded) to
  // their values in steps, each solved from the last, so a foot unloads gradually and the robot
  // settles on the feet that catch it.
  const Eigen::VectorXd final_lift = fn.lift;
  auto lift_path = [&](Eigen::VectorXd& x, bool& tips) {
    constexpr int kSteps = 8;
    bool ok = false;
    for (int step = 0; step <= kSteps; ++step) {
      const double s = double(step) / kSteps;
      for (int i = 0; i < n; ++i) {
        fn.lift(i) = std::isfinite(final_lift(i)) ? s * final_lift(i) : final_lift(i);
      }
      ok = active_set(x, tips, step > 0);  // each step starts on the last step's feet
      if (!ok) break;
    }
    fn.lift = final_lift;
    return ok;
  };

  const Eigen::VectorXd x0 = x;
  bool tips = false;
  bool consistent = active_set(x, tips, false);
  if (!consistent) {  // second start along the lift path; keep the first attempt if it fails
    const std::vector<char> first_set = fn.active;
    Eigen::VectorXd y = x0;
    bool tips2 = false;
    if (lift_path(y, tips2)) {
      x = y;
      consistent = true;
    } else {
      fn.active = first_set;
    }
  }
  if (!x.allFinite()) x.setZero();

  // Backtrack the forces, deflections and the rigid motion (eq 3 and §5.1.1's last paragraph).
  Eigen::Matrix3Xd src(3, n + 1), dst(3, n + 1);
  Eigen::Vector3d f;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d dr = x.segment<3>(3 * i);
    if (fn.spring(i, dr, f)) ++res.loaded;  // the consistent contact set
    res.forces.col(i) = f;
    res.deflections.col(i) = dr;
    res.compression(i) = fn.compression(i, dr);
    src.col(i) = problem.feet.col(i);
    dst.col(i) = fn.foot(x, i);
  }
  res.cg = fn.cg(x);
  src.col(n) = problem.cg;
  dst.col(n) = res.cg;
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, false);
  res.rotation = T.topLeftCorner<3, 3>();
  res.translation = T.topRightCorner<3, 1>();
  res.rigidity_residual =
      ((res.rotation * src).colwise() + res.translation - dst).colwise().norm().maxCoeff();
  res.chassis_position = res.rotation * problem.chassis_position + res.translation;
  res.chassis_rotation = res.rotation * problem.chassis_rotation;
  if (problem.body_points.cols() > 0) {
    res.body_points = (res.rotation * problem.body_points).colwise() + res.translation;
  }
  Eigen::VectorXd r(fn.values());
  fn(x, r);
  res.equilibrium_residual = r.segment<3>(0).norm() + r.segment<3>(3).norm();

  if (consistent && res.equilibrium_residual <= options.equilibrium_tolerance &&
      res.loaded >= 3) {
    res.status = SagStatus::Converged;
  } else {
    // No equilibrium: unstable if the CG is outside every foot's support, else LM's failure.
    // (feet with lift +inf never touch and do not count).
    const ProjectionFrame frame = ProjectionFrame::from_gravity(problem.gravity);
    Eigen::Matrix3Xd touchable(3, n);
    int m = 0;
    for (int i = 0; i < n; ++i) {
      if (std::isfinite(fn.lift(i))) touchable.col(m++) = problem.feet.col(i);
    }
    const bool outside =
        m < 3 || m > kMaxContacts ||
        static_stability_margin(support_polygon(touchable.leftCols(m), frame), problem.cg,
                                frame) < 0.0;
    res.status =
        (outside || tips || res.loaded < 3) ? SagStatus::Unstable : SagStatus::NotConverged;
  }
  return res;
}

}  // namespace ernest::statics
