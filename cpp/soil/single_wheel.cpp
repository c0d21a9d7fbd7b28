#include "ernest/soil/single_wheel.hpp"

#include <boost/math/tools/roots.hpp>
#include <cstdint>

#include "ernest/common/validation.hpp"

namespace ernest::soil {

void RigOptions::validate() const {
  require_in_range("RigOptions", "carriage_speed", carriage_speed, 1e-4, 100.0);
  require_in_range("RigOptions", "sinkage_tolerance", sinkage_tolerance, 1e-15, 1e-2);
  require_in_range("RigOptions", "max_iterations", max_iterations, 1, 10000);
}

ContactState rig_state(double sinkage, double slip, double carriage_speed, double wheel_radius) {
  // Carriage at v_x = V; the wheel spins at r w = V / (1 - s) when driving (s >= 0) and
  // r w = V (1 + s) when braking (s < 0), so v_cx = v_x - r w reproduces s through eq 12.
  (void)wheel_radius;
  ContactState st;
  st.sinkage = sinkage;
  st.vx = carriage_speed;
  const double rw = slip >= 0.0 ? carriage_speed / (1.0 - slip) : carriage_speed * (1.0 + slip);
  st.vcx = st.vx - rw;
  return st;
}

RigResult solve_equilibrium(const BekkerWongModel& model, double load, double slip,
                            const RigOptions& options) {
  options.validate();
  require_in_range("solve_equilibrium", "load", load, 1e-3, 1e5);
  require_in_range("solve_equilibrium", "slip", slip, -1.0, 0.99);
  const double r = model.wheel().radius;
  auto eval = [&](double h) {
    return model.evaluate(rig_state(h, slip, options.carriage_speed, r));
  };
  RigResult res;
  res.slip = slip;
  double h = r;
  WheelSoilForce f = eval(r);
  if (f.fz >= load) {
    // F_z(0) = 0 < load <= F_z(r): a sign change brackets the root; TOMS 748 converges fast.
    std::uintmax_t iters = static_cast<std::uintmax_t>(options.max_iterations);
    const double tol = options.sinkage_tolerance;
    auto [a, bnd] = boost::math::tools::toms748_solve(
        [&](double x) { return eval(x).fz - load; }, 0.0, r, -load, f.fz - load,
        [tol](double lo, double hi) { return hi - lo <= tol; }, iters);
    h = 0.5 * (a + bnd);
    res.iterations = static_cast<int>(iters);
    res.converged = (bnd - a) <= tol;
    f = eval(h);
  }
  res.model_slip = f.slip;
  res.sinkage = h;
  res.drawbar_pull = f.fx;
  res.lateral_force = f.fy;
  res.normal_force = f.fz;
  res.torque = f.axle_torque;
  res.theta_f = f.theta_f;
  res.theta_m = f.theta_m;
  res.theta_r = f.theta_r;
  return res;
}

Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> slip_sweep(
    const BekkerWongModel& model, double load, const Eigen::Ref<const Eigen::VectorXd>& slips,
    const RigOptions& options) {
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> out(slips.size(), 7);
  for (Eigen::Index i = 0; i < slips.size(); ++i) {
    const RigResult r = solve_equilibrium(model, load, slips[i], options);
    out.row(i) << r.slip, r.model_slip, r.sinkage, r.drawbar_pull, r.normal_force, r.torque,
        r.converged ? 1.0 : 0.0;
  }
  return out;
}

}  // namespace ernest::soil
