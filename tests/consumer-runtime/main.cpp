// A minimal onboard application on the installed ernest::runtime: writes a TorchScript policy that
// always commands 0.1 m/s straight ahead (with the metadata the runtime checks), loads it, and
// runs the 400 Hz control loop for 3 s against the simulator interface on flat M90. Succeeds if
// the rover moved forward along the path and the watchdog never tripped.
#include <torch/script.h>

#include <cstdio>
#include <sstream>
#include <string>

#include <ernest/envs/rover_env.hpp>
#include <ernest/runtime/control_loop.hpp>
#include <ernest/runtime/policy.hpp>
#include <ernest/runtime/sim_interface.hpp>

namespace {
std::string array(const Eigen::VectorXd& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) os << (i ? "," : "") << v[i];
  return os.str() + "]";
}
}  // namespace

int main(int argc, char** argv) {
  using namespace ernest;
  const std::string path = argc > 1 ? argv[1] : "onboard_policy.pt";
  const sensing::ActionLimits l;
  std::ostringstream meta;
  meta << "{\"format\":\"ernest-policy-v1\",\"layout_version\":\"ernest-obs-v"
       << sensing::kObservationLayoutVersion << "\",\"obs_dim\":45,\"act_dim\":3,\"policy_rate_hz\":2.0,"
       << "\"obs_offset\":" << array(Eigen::VectorXd::Zero(45))
       << ",\"obs_scale\":" << array(sensing::ObservationScales{}.divisors())
       << ",\"action_low\":" << array(Eigen::Vector3d(0, -l.yaw_rate_max, -l.roll_rate_max))
       << ",\"action_high\":" << array(Eigen::Vector3d(l.vx_max, l.yaw_rate_max, l.roll_rate_max)) << "}";
  torch::jit::Module m("__torch__.OnboardConstant");
  m.register_buffer("c", torch::tensor({0.1f, 0.0f, 0.0f}));
  m.define("def forward(self, x):\n  return self.c + 0.0 * x[0:3]\n");
  m.save(path, {{"ernest_metadata.json", meta.str()}});

  runtime::Policy policy(path);
  envs::EnvOptions eo;
  eo.scenario.kind = envs::ScenarioKind::Flat;
  envs::RoverEnv env(dynamics::RoverParameters{}, eo);
  env.reset(1);
  runtime::SimRoverInterface io(env);
  runtime::ControlLoop loop(io, policy, env.parameters(), env.scenario().path,
                            runtime::LoopOptions::from_env(env));
  loop.set_fts_bias(env.fts_bias());
  loop.run(3.0);
  const auto& s = env.sim().state();
  const double progress = env.scenario().path.arc_length(s.position.x(), s.position.y()) -
                          env.scenario().path.arc_length(env.scenario().start_x, env.scenario().start_y);
  const runtime::LatencyStats lat = policy.latency();
  std::printf("onboard_app: %ld ticks, %ld policy steps, progress %.3f m, watchdog trips %d, "
              "inference median %.1f us\n",
              loop.ticks(), loop.policy_steps(), progress, loop.watchdog().trips(), lat.median_us);
  return (loop.ticks() == 1200 && loop.policy_steps() == 6 && progress > 0.1 &&
          loop.watchdog().trips() == 0)
             ? 0
             : 1;
}
