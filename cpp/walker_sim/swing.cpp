#include "ernest/walker_sim/swing.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/walker/leg_ik.hpp"

namespace ernest::walker_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Wheel centre and axle of one leg in the world for body pose `body`.
void wheel_in_world(const walker::WalkerModel& model, const Eigen::Isometry3d& body, int leg,
                    const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Vector3d& centre, Eigen::Vector3d& axle) {
  const Eigen::Isometry3d f = body * model.foot_pose(leg, q);
  centre = f.translation();
  axle = f.linear().col(1);
}

}  // namespace

std::vector<Eigen::VectorXd> swing_path(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                                        int leg, const Eigen::Ref<const Eigen::VectorXd>& q_start,
                                        const Eigen::Vector3d& goal, double lift_height) {
  model.check_leg(leg);
  model.check_q(q_start, "q_start");
  require(body.matrix().allFinite(), "swing_path: body pose is not finite");
  require(goal.allFinite(), "swing_path: goal is not finite");
  require_in_range("swing_path", "lift_height", lift_height, 0.0, 2.0);
  walker::LegIk ik(model);
  const Eigen::Isometry3d inv = body.inverse();
  const Eigen::Vector3d up_body = inv.linear() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d start = body * model.contact_point(leg, q_start);
  const double heading = 2.0 * kPi * leg / model.legs();
  std::vector<Eigen::VectorXd> path{q_start};
  const Eigen::Vector3d lift(0.0, 0.0, lift_height);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(start + lift), Eigen::Vector3d(goal + lift), goal}) {
    const Eigen::Isometry3d target = walker::upright_foot_pose(model, inv * p, heading, up_body);
    const walker::IkResult r = ik.solve(leg, target, path.back());
    require(r.status == walker::IkStatus::kSolved,
            "swing_path: leg " + std::to_string(leg) + " cannot reach (" + std::to_string(p.x()) + ", " +
                std::to_string(p.y()) + ", " + std::to_string(p.z()) + ")");
    path.push_back(r.solutions.front());  // the branch nearest the previous waypoint
  }
  return path;
}

double planned_clearance(const walker::WalkerModel& model, const Eigen::Isometry3d& body, int leg,
                         const std::vector<Eigen::VectorXd>& path, const std::vector<Rock>& rocks,
                         int samples) {
  model.check_leg(leg);
  require(!path.empty(), "planned_clearance: the path is empty");
  require(samples >= 1 && samples <= 100000, "planned_clearance: samples = " + std::to_string(samples) +
                                                 " is outside [1, 100000]");
  for (const auto& q : path) model.check_q(q, "path");
  for (const Rock& r : rocks) r.validate();
  const walker::WalkerParameters& p = model.params();
  double c = kInf;
  Eigen::Vector3d centre, axle;
  Eigen::VectorXd q;
  for (std::size_t s = 0; s + 1 < std::max<std::size_t>(path.size(), 2); ++s)
    for (int i = 0; i <= samples; ++i) {
      const double u = static_cast<double>(i) / samples;
      q = path.size() == 1 ? path[0] : Eigen::VectorXd((1.0 - u) * path[s] + u * path[s + 1]);
      wheel_in_world(model, body, leg, q, centre, axle);
      for (const Rock& r : rocks)
        c = std::min(c, wheel_rock_clearance(centre, axle, p.wheel_radius, p.wheel_width, r));
    }
  return c;
}

void ExecutionOptions::validate() const {
  require_in_range("ExecutionOptions", "joint_speed", joint_speed, 1e-6, 10.0);
  require_in_range("ExecutionOptions", "pause", pause, 0.0, 60.0);
  if (frame_interval) {
    require_in_range("ExecutionOptions", "frame_interval", *frame_interval, 0.0, 60.0);
    require_positive("ExecutionOptions", "frame_interval", *frame_interval);  // unset: no frames
  }
}

ExecutionTrace execute_configuration_path(WalkerSim& sim, std::optional<int> traced,
                                          const std::vector<Eigen::MatrixXd>& path,
                                          const ExecutionOptions& options) {
  options.validate();
  const walker::WalkerModel& model = sim.model();
  require(!traced || (*traced >= 0 && *traced < model.legs()),
          "execute_configuration_path: leg = " + std::to_string(traced.value_or(0)) +
              " is outside the allowed range [0, " + std::to_string(model.legs() - 1) +
              "] (None: no wheel traced)");
  const int leg = traced.value_or(-1);  // < 0 below: no wheel traced
  require(path.size() >= 2, "execute_configuration_path: the path needs at least two waypoints");
  for (const auto& q : path) model.check_configuration(q, "execute_configuration_path: a path waypoint");
  const auto t0 = std::chrono::steady_clock::now();
  const double dt = sim.options().dt, start = sim.time();
  const int last = static_cast<int>(path.size()) - 1;
  Eigen::MatrixXd target = path[0], rate = Eigen::MatrixXd::Zero(path[0].rows(), path[0].cols());
  std::vector<double> time, rock, ground, height, frame_time;
  std::vector<int> phase;
  std::vector<Eigen::Vector3d> wheel;
  ExecutionTrace out;
  out.min_rock_clearance = out.min_ground_clearance = out.min_any_rock_clearance = kInf;
  double next_frame = 0.0;
  // in_air: the transfer, from arriving at waypoint 1 to leaving waypoint last - 1
  auto record = [&](int seg, bool in_air) {
    time.push_back(sim.time() - start);
    rock.push_back(leg >= 0 ? sim.rock_clearance(leg) : kInf);
    ground.push_back(leg >= 0 ? sim.ground_clearance(leg) : kInf);
    height.push_back(sim.body_pose().translation().z());
    phase.push_back(seg);
    out.min_rock_clearance = std::min(out.min_rock_clearance, rock.back());
    for (int k = 0; k < model.legs(); ++k)
      out.min_any_rock_clearance = std::min(out.min_any_rock_clearance, k == leg ? rock.back() : sim.rock_clearance(k));
    if (leg >= 0) wheel.push_back(sim.wheel_centres().col(leg));
    if (options.frame_interval && time.back() >= next_frame - 1e-9) {
      frame_time.push_back(time.back());
      out.frame_body.push_back(sim.body_pose());
      out.frame_q.push_back(sim.joint_angles());
      next_frame += *options.frame_interval;
    }
    if (in_air) out.min_ground_clearance = std::min(out.min_ground_clearance, ground.back());
  };
  auto pause = [&](int waypoint) {
    target = path[waypoint];
    rate.setZero();
    for (int s = 0, steps = static_cast<int>(std::ceil(options.pause / dt - 1e-9)); s < steps; ++s) {
      sim.step(target, rate);
      record(waypoint - 1, waypoint >= 1 && waypoint <= last - 1);
    }
    out.waypoint_body.push_back(sim.body_pose());
  };
  pause(0);
  for (int w = 0; w < last; ++w) {
    const Eigen::MatrixXd delta = path[w + 1] - path[w];
    const double duration = std::max(dt, delta.cwiseAbs().maxCoeff() / options.joint_speed);
    const int steps = static_cast<int>(std::ceil(duration / dt - 1e-9));
    rate = delta / (steps * dt);
    for (int s = 1; s <= steps; ++s) {
      target = path[w] + (static_cast<double>(s) / steps) * delta;
      sim.step(target, rate);
      record(w, w >= 1 && w <= last - 2);
    }
    pause(w + 1);
  }
  const auto n = static_cast<Eigen::Index>(time.size());
  out.time = Eigen::Map<const Eigen::VectorXd>(time.data(), n);
  out.rock_clearance = Eigen::Map<const Eigen::VectorXd>(rock.data(), n);
  out.ground_clearance = Eigen::Map<const Eigen::VectorXd>(ground.data(), n);
  out.body_height = Eigen::Map<const Eigen::VectorXd>(height.data(), n);
  out.phase = Eigen::Map<const Eigen::VectorXi>(phase.data(), n);
  out.frame_time = Eigen::Map<const Eigen::VectorXd>(frame_time.data(), static_cast<Eigen::Index>(frame_time.size()));
  out.wheel_path.resize(3, static_cast<Eigen::Index>(wheel.size()));
  for (std::size_t i = 0; i < wheel.size(); ++i) out.wheel_path.col(static_cast<Eigen::Index>(i)) = wheel[i];
  out.final_q = sim.joint_angles();
  out.simulated_seconds = sim.time() - start;
  out.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

ExecutionTrace execute_joint_path(WalkerSim& sim, int leg, const Eigen::Ref<const Eigen::MatrixXd>& stance,
                                  const std::vector<Eigen::VectorXd>& path, const ExecutionOptions& options) {
  const walker::WalkerModel& model = sim.model();
  model.check_leg(leg);
  model.check_configuration(stance, "execute_joint_path: stance");
  std::vector<Eigen::MatrixXd> configs;
  for (const auto& q : path) {
    model.check_q(q, "path");
    configs.push_back(stance);
    configs.back().col(leg) = q;
  }
  return execute_configuration_path(sim, leg, configs, options);
}

}  // namespace ernest::walker_sim
