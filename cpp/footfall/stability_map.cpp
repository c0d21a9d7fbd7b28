#include "ernest/footfall/stability_map.hpp"
#include "ernest/common/interrupt.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>

#include "ernest/common/validation.hpp"
#include "ernest/statics/stability.hpp"

namespace ernest::footfall {

void StabilityMapOptions::validate() const {
  const char* o = "StabilityMapOptions";
  require_in_range(o, "cell", cell, 1e-3, 1.0);
  require_in_range(o, "lift_height", lift_height, 0.0, 2.0);
  require_in_range(o, "min_margin", min_margin, -10.0, 10.0);
  require_in_range(o, "slope_threshold", slope_threshold, 0.0, 1.5);
  require_in_range(o, "ik_evaluations", ik_evaluations, 5, 10000);
  if (!(max_saturation >= 0.0))  // NaN and negative values
    throw std::invalid_argument("StabilityMapOptions.max_saturation = " + std::to_string(max_saturation) +
                                " is outside the allowed range [0, inf]");
}

int StabilityMap::count(CellStatus s) const {
  return static_cast<int>((status.array() == static_cast<std::uint8_t>(s)).count());
}

namespace {
walker::IkOptions map_ik_options(const StabilityMapOptions& o) {
  o.validate();
  walker::IkOptions ik;
  ik.max_evaluations = o.ik_evaluations;
  ik.seeds = 8;
  ik.position_tolerance = 1e-4;
  ik.orientation_tolerance = 1e-3;
  return ik;
}
}  // namespace

StabilityMapper::StabilityMapper(const walker::WalkerModel& model, const dynamics::HeightMap& terrain,
                                 const Eigen::Isometry3d& body, const Eigen::Ref<const Eigen::MatrixXd>& q,
                                 int leg, const StabilityMapOptions& options)
    : model_(model), terrain_(terrain), body_(body), q_(q), leg_(leg), options_(options),
      ik_(model, map_ik_options(options)), ws_(model) {
  model.check_leg(leg);
  model.check_configuration(q);
  require(body.matrix().allFinite(), "StabilityMapper: body pose is not finite");
  body_inv_ = body.inverse();
  const walker::WalkerParameters& p = model.params();
  gravity_ = Eigen::Vector3d(0.0, 0.0, -p.gravity);
  up_body_ = body_inv_.linear() * Eigen::Vector3d::UnitZ();
  hip_body_ = model.hip_mount(leg).translation();
  contacts_ = model.contact_points(body, q);
  // Mass moment of everything but the swing leg (world), as WalkerModel::center_of_mass sums it.
  total_mass_ = p.total_mass();
  model.forward(leg, q.col(leg), ws_);
  Eigen::Vector3d swing = Eigen::Vector3d::Zero();
  for (int i = 0; i < model.joints_per_leg(); ++i) {
    swing += p.joints[i].mass * (body * ws_.link_com.col(i));
    swing_mass_ += p.joints[i].mass;
  }
  rest_moment_ = total_mass_ * model.center_of_mass(body, q) - swing;
  // §3.3: NESM on sloped terrain — the slope of the plane through the stance's feet (the normal
  // is the eigenvector of the smallest eigenvalue of their scatter matrix).
  if (options.criterion == StabilityCriterion::kAuto) {
    const Eigen::Vector3d mean = contacts_.rowwise().mean();
    const Eigen::Matrix3Xd d = contacts_.colwise() - mean;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(d * d.transpose());
    const double cos_slope = std::abs(es.eigenvectors().col(0).z());
    nesm_ = std::acos(std::min(1.0, cos_slope)) > options.slope_threshold;
  } else {
    nesm_ = options.criterion == StabilityCriterion::kNesm;
  }
  // The compliance waypoint above the current foot must be reachable too (§3.3).
  q_start_above_ = q.col(leg);
  const Eigen::Vector3d c0 = contacts_.col(leg);
  start_ok_ = solve(target(c0, options.lift_height), q.col(leg), q_start_above_);
  if (options.evaluates_torques()) torques_ = std::make_unique<StanceTorques>(model, body, q, leg);
}

StabilityMapper::~StabilityMapper() = default;

Eigen::Isometry3d StabilityMapper::target(const Eigen::Vector3d& c, double lift) const {
  const Eigen::Vector3d cb = body_inv_ * (c + lift * Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d d = cb - hip_body_;
  return walker::upright_foot_pose(model_, cb, std::atan2(d.y(), d.x()), up_body_);
}

bool StabilityMapper::solve(const Eigen::Isometry3d& target, const Eigen::Ref<const Eigen::VectorXd>& seed,
                            Eigen::Ref<Eigen::VectorXd> q) {
  ++solves_;
  if (ik_.solve_from(leg_, target, seed, q)) return true;
  ++solves_;  // second start: the leg's current angles
  return ik_.solve_from(leg_, target, q_.col(leg_), q);
}

CellEvaluation StabilityMapper::evaluate(double x, double y, const Eigen::Ref<const Eigen::VectorXd>& seed) {
  require(std::isfinite(x) && std::isfinite(y), "StabilityMapper.evaluate: x, y must be finite");
  model_.check_q(seed, "seed");
  const int n = model_.joints_per_leg();
  CellEvaluation e;
  e.q.resize(n);
  // NaN until the waypoint is reached (Eigen's resize leaves the memory uninitialised)
  e.q_above.setConstant(n, std::numeric_limits<double>::quiet_NaN());
  const Eigen::Vector3d c(x, y, terrain_.height(x, y));
  if (!solve(target(c, 0.0), seed, e.q)) return e;
  e.ground_reachable = true;
  if (!solve(target(c, options_.lift_height), e.q, e.q_above)) return e;
  // New CG and CPS of the stance with the foot on c (§3.3).
  model_.forward(leg_, e.q, ws_);
  Eigen::Vector3d moment = rest_moment_;
  const walker::WalkerParameters& p = model_.params();
  for (int i = 0; i < n; ++i) moment += p.joints[i].mass * (body_ * ws_.link_com.col(i));
  e.cg = moment / total_mass_;
  contacts_.col(leg_) = body_ * ws_.contact;
  const statics::StabilityMargins m = statics::stability_margins(contacts_, e.cg, gravity_);
  e.margin = nesm_ ? m.nesm_cps : m.ssm_cps;
  e.status = e.margin > options_.min_margin ? CellStatus::kStable : CellStatus::kUnstable;
  if (torques_) {  // §7.1: the load-bearing workspace within the reachable one
    const TorquePeak down = torques_->down(e.q), lifted = torques_->lifted(e.q_above);
    e.saturation_down = down.saturation;
    e.saturation_lifted = lifted.saturation;
    const TorquePeak& peak = down.saturation >= lifted.saturation ? down : lifted;
    e.saturation = peak.saturation;
    e.peak_leg = peak.leg;
    e.peak_joint = peak.joint;
    if (e.status == CellStatus::kStable && e.saturation > options_.max_saturation) e.status = CellStatus::kOverloaded;
  }
  return e;
}

StabilityMap StabilityMapper::map() {
  const walker::WalkerParameters& p = model_.params();
  StabilityMap out;
  out.cell = options_.cell;
  out.nesm = nesm_;
  out.start_waypoint_reachable = start_ok_;
  out.hip = body_ * hip_body_;
  double reach = p.foot_offset.norm() + p.wheel_radius;
  for (const walker::JointSpec& j : p.joints) reach += j.offset.norm();
  out.reach = reach;
  const int half = static_cast<int>(std::ceil(reach / options_.cell));
  const int side = 2 * half + 1;
  out.origin_x = out.hip.x() - half * options_.cell;
  out.origin_y = out.hip.y() - half * options_.cell;
  out.status.setConstant(side, side, static_cast<std::uint8_t>(CellStatus::kUnreachable));
  out.margin.setConstant(side, side, std::numeric_limits<double>::quiet_NaN());
  out.saturation.setConstant(side, side, std::numeric_limits<double>::quiet_NaN());
  if (torques_ && start_ok_) out.lift_saturation = torques_->lifted(q_start_above_).saturation;
  const long solves0 = solves_;
  if (!start_ok_) return out;  // no step can leave the current foot (§3.3)
  // Breadth-first from the cell under the current foot: each cell's IK starts from a solved
  // neighbour's angles (continuation), so almost every local solve converges in a few steps.
  // Assumption: the reachable cells form one region with the current foot's (a region cut off
  // by unreachable cells is not searched).
  const int n = model_.joints_per_leg();
  Eigen::MatrixXd solution(n, std::size_t(side) * side);
  std::vector<char> state(std::size_t(side) * side, 0);  // 0 new, 1 queued, 2 solved, 3 failed
  const Eigen::Vector3d foot = body_ * model_.contact_point(leg_, q_.col(leg_));
  auto index = [&](int i, int j) { return std::size_t(i) * side + j; };
  auto in_reach = [&](int i, int j) {
    const double x = out.origin_x + i * options_.cell, y = out.origin_y + j * options_.cell;
    const Eigen::Vector3d c(x, y, terrain_.height(x, y));
    return (c - out.hip).norm() <= reach;
  };
  std::deque<std::array<int, 2>> queue;
  const int i0 = std::clamp(int(std::lround((foot.x() - out.origin_x) / options_.cell)), 0, side - 1);
  const int j0 = std::clamp(int(std::lround((foot.y() - out.origin_y) / options_.cell)), 0, side - 1);
  queue.push_back({i0, j0});
  state[index(i0, j0)] = 1;
  Eigen::VectorXd seed = q_.col(leg_);
  const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
  while (!queue.empty()) {
    poll_interrupt();  // Ctrl-C between cells (common/interrupt.hpp): the mapper is unchanged
    const auto [i, j] = queue.front();
    queue.pop_front();
    seed = q_.col(leg_);
    for (int k = 0; k < 4; ++k) {
      const int a = i + di[k], b = j + dj[k];
      if (a >= 0 && b >= 0 && a < side && b < side && state[index(a, b)] == 2) {
        seed = solution.col(index(a, b));
        break;
      }
    }
    const CellEvaluation e = evaluate(out.origin_x + i * options_.cell, out.origin_y + j * options_.cell, seed);
    state[index(i, j)] = e.ground_reachable ? 2 : 3;
    if (e.status != CellStatus::kUnreachable) {
      out.status(i, j) = static_cast<std::uint8_t>(e.status);
      out.margin(i, j) = e.margin;
      out.saturation(i, j) = e.saturation;
    }
    // Only cells with a ground solution seed and expand: the reachable region is connected
    // (continuous IK), so its unreachable border is evaluated once and nothing beyond it.
    if (!e.ground_reachable) continue;
    solution.col(index(i, j)) = e.q;
    for (int k = 0; k < 4; ++k) {
      const int a = i + di[k], b = j + dj[k];
      if (a < 0 || b < 0 || a >= side || b >= side || state[index(a, b)] != 0) continue;
      state[index(a, b)] = 1;
      if (in_reach(a, b)) queue.push_back({a, b});
    }
  }
  out.ik_solves = solves_ - solves0;
  return out;
}

}  // namespace ernest::footfall
