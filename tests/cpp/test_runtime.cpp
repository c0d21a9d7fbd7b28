// Onboard runtime (cpp/runtime): policy loading errors, inference mapping, the watchdog on
// injected stale / non-finite data and failed inference, and the equivalence of the 400 Hz
// onboard loop on the simulator with the environments' episode core. Policies are built here
// with libtorch's TorchScript compiler, so these tests need no Python.
#include <gtest/gtest.h>
#include <torch/script.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ernest/envs/rover_env.hpp"
#include "ernest/runtime/control_loop.hpp"
#include "ernest/runtime/policy.hpp"
#include "ernest/runtime/safety.hpp"
#include "ernest/runtime/sim_in_the_loop.hpp"
#include "ernest/runtime/sim_interface.hpp"
#include "ernest/runtime/telemetry.hpp"
#include "runtime_policies.hpp"

using namespace ernest;
using runtime::PolicyError;
using namespace ernest::testing_policies;
namespace fs = std::filesystem;

namespace {

// A random 45-64-3 tanh MLP on the normalised observation, mapped to the action ranges like
// rl/export.py's ExportedPolicy: a policy whose commands depend on every input.
std::string mlp_policy(const std::string& name, int seed) {
  torch::manual_seed(seed);
  const sensing::ObservationScales sc;
  const sensing::ActionLimits l;
  const Eigen::VectorXd d = sc.divisors();
  torch::Tensor s = torch::empty({45});
  for (int i = 0; i < 45; ++i) s[i] = d[i];
  return save_module(
      name,
      "def forward(self, x):\n"
      "  h = torch.relu(torch.mv(self.w1, x / self.s) + self.b1)\n"
      "  u = torch.tanh(torch.mv(self.w2, h) + self.b2)\n"
      "  return self.lo + (u + 1.0) * 0.5 * (self.hi - self.lo)\n",
      {{"w1", torch::randn({64, 45}) * 0.3},
       {"b1", torch::randn({64}) * 0.1},
       {"w2", torch::randn({3, 64}) * 0.3},
       {"b2", torch::randn({3}) * 0.1},
       {"s", s},
       {"lo", torch::tensor({0.0f, float(-l.yaw_rate_max), float(-l.roll_rate_max)})},
       {"hi", torch::tensor({float(l.vx_max), float(l.yaw_rate_max), float(l.roll_rate_max)})}});
}

PolicyError::Kind load_error(const std::string& path, std::string* message = nullptr) {
  try {
    runtime::Policy p(path);
  } catch (const PolicyError& e) {
    if (message) *message = e.what();
    return e.kind();
  }
  ADD_FAILURE() << path << " loaded without error";
  return PolicyError::Kind::Inference;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Loading errors
TEST(PolicyLoad, MissingFile) {
  std::string msg;
  EXPECT_EQ(load_error((tmpdir() / "does_not_exist.pt").string(), &msg), PolicyError::Kind::MissingFile);
  EXPECT_TRUE(contains(msg, "does_not_exist.pt")) << msg;
  EXPECT_TRUE(contains(msg, "no such policy file")) << msg;
}

TEST(PolicyLoad, CorruptFile) {
  const std::string garbage = (tmpdir() / "garbage.pt").string();
  std::ofstream(garbage) << "this is not a TorchScript archive";
  std::string msg;
  EXPECT_EQ(load_error(garbage, &msg), PolicyError::Kind::CorruptFile);
  EXPECT_TRUE(contains(msg, "not a loadable TorchScript archive")) << msg;
  // A truncated (half-written) real archive.
  const std::string good = identity_policy("to_truncate");
  const auto size = fs::file_size(good);
  fs::resize_file(good, size / 2);
  EXPECT_EQ(load_error(good, &msg), PolicyError::Kind::CorruptFile);
}

TEST(PolicyLoad, MissingOrInvalidMetadata) {
  const std::string none;
  std::string msg;
  EXPECT_EQ(load_error(identity_policy("no_meta", &none), &msg), PolicyError::Kind::MissingMetadata);
  EXPECT_TRUE(contains(msg, "ernest_metadata.json")) << msg;
  const std::string broken = "{\"format\": \"ernest-policy-v1\", ";
  EXPECT_EQ(load_error(identity_policy("bad_json", &broken), &msg), PolicyError::Kind::MissingMetadata);
  EXPECT_TRUE(contains(msg, "not valid JSON")) << msg;
}

// The weights digest: the known answer for one float32 buffer c = (0.1, 0.2, 0.3) is
// sha256("c\n3\n" + its 12 little-endian bytes), computed with Python's hashlib; a file whose
// weights differ from its metadata's digest is refused, one without a digest loads (warning).
TEST(PolicyLoad, WeightsChecksum) {
  const std::string src = "def forward(self, x):\n  return self.c + 0.0 * x[0:3]\n";
  const std::string known = "06bdb1e753abcc68a8548dfa26a17aba4cdde8d42e31087c1d4771de208c628f";
  const torch::Tensor c = torch::tensor({0.1f, 0.2f, 0.3f});
  const std::string meta = metadata_json("weights_sha256", "\"" + known + "\"");
  const std::string good = save_module("hashed", src, {{"c", c}}, &meta);
  EXPECT_EQ(runtime::weights_sha256(torch::jit::load(good)), known);
  runtime::Policy p(good);
  EXPECT_TRUE(p.metadata().weights_verified);
  EXPECT_EQ(p.metadata().weights_sha256, known);
  // One weight altered (as flipped bytes in the file would), the digest kept.
  const std::string altered = save_module("altered", src, {{"c", torch::tensor({0.1f, 0.2f, 0.31f})}}, &meta);
  std::string msg;
  EXPECT_EQ(load_error(altered, &msg), PolicyError::Kind::ChecksumMismatch);
  EXPECT_TRUE(contains(msg, "altered.pt") && contains(msg, "weights_sha256")) << msg;
  // Malformed digest: refused as a metadata mismatch.
  const std::string short_meta = metadata_json("weights_sha256", "\"abc\"");
  EXPECT_EQ(load_error(save_module("short_hash", src, {{"c", c}}, &short_meta)),
            PolicyError::Kind::LayoutMismatch);
  // No digest (exported before it existed): loads, not verified.
  runtime::Policy legacy(save_module("legacy", src, {{"c", c}}));
  EXPECT_FALSE(legacy.metadata().weights_verified);
  EXPECT_TRUE(legacy.metadata().weights_sha256.empty());
}

// The archive digest (policy_sha256: code, constants, weights, metadata): a file stamped with it
// loads verified; the same weights under an edited forward(), or an edited metadata member that
// every other check accepts, are refused.
TEST(PolicyLoad, ArchiveChecksum) {
  const std::string zeros(64, '0');
  auto module = [](const std::string& name, const std::string& src) {
    torch::jit::Module m("__torch__.TestPolicy_" + name);
    m.register_buffer("c", torch::tensor({0.01f, 0.02f, 0.03f}));
    m.define(src);
    return m;
  };
  auto save = [](torch::jit::Module& m, const std::string& name, const std::string& meta) {
    const std::string path = (tmpdir() / (name + ".pt")).string();
    m.save(path, {{runtime::Policy::kMetadataFile, meta}});
    return path;
  };
  torch::jit::Module good = module("archive_good", "def forward(self, x):\n  return self.c + 0.0 * x[0:3]\n");
  // Written with the placeholder, digested, written again (one module saves the same records).
  const std::string path = save(good, "archive_good", metadata_json("policy_sha256", "\"" + zeros + "\""));
  const std::string digest = runtime::policy_sha256(path, zeros);
  const std::string meta = metadata_json("policy_sha256", "\"" + digest + "\"");
  save(good, "archive_good", meta);
  runtime::Policy p(path);
  EXPECT_TRUE(p.metadata().policy_verified);
  EXPECT_EQ(p.metadata().policy_sha256, digest);
  std::string msg;
  torch::jit::Module times10 = module("archive_x10", "def forward(self, x):\n  return 10.0 * self.c + 0.0 * x[0:3]\n");
  EXPECT_EQ(load_error(save(times10, "archive_x10", meta), &msg), PolicyError::Kind::ChecksumMismatch);
  EXPECT_TRUE(contains(msg, "archive_x10.pt") && contains(msg, "policy_sha256")) << msg;
  std::string renamed = meta;
  renamed.replace(renamed.find("heading_deviation"), 17, "heading_deviatio2");
  EXPECT_EQ(load_error(save(good, "archive_meta", renamed), &msg), PolicyError::Kind::ChecksumMismatch);
}

TEST(PolicyLoad, MetadataLayoutMismatch) {
  struct Case {
    std::string field, value, expect_in_message;
  };
  sensing::ObservationScales other;
  other.force = 100.0;  // a policy trained with another scaling table
  const std::vector<Case> cases = {
      {"layout_version", "\"ernest-obs-v99\"", "layout_version 'ernest-obs-v99'"},
      {"obs_dim", "44", "obs_dim 44"},
      {"act_dim", "2", "act_dim 2"},
      {"policy_rate_hz", "10.0", "policy_rate_hz 10"},
      {"obs_scale", vec_json(other.divisors()), "obs_scale[6] = 100, expected 200 (fts_FL_Fx)"},
      {"obs_offset", vec_json(Eigen::VectorXd::Constant(45, 0.5)), "obs_offset[0]"},
      {"action_high", "[0.5, 0.349, 0.1745]", "action_high[0] = 0.5"},
      {"format", "\"something-else\"", "format 'something-else'"},
      {"obs_scale", "", "'obs_scale' is missing"},
  };
  for (const auto& c : cases) {
    const std::string meta = metadata_json(c.field, c.value);
    std::string msg;
    EXPECT_EQ(load_error(identity_policy("mismatch_" + c.field, &meta), &msg),
              PolicyError::Kind::LayoutMismatch)
        << c.field;
    EXPECT_TRUE(contains(msg, "does not match the runtime's observation layout")) << msg;
    EXPECT_TRUE(contains(msg, c.expect_in_message)) << c.field << ": " << msg;
  }
}

TEST(PolicyLoad, LegacyLayoutVersionOnlyWithTheSameTable) {
  // Version 1 files carry one of two tables: the runtime's one loads, the other (torque 50 N m,
  // elevation 0.3 m, lateral 1 m) is refused naming the first entry that differs.
  const std::string v1 = metadata_json("layout_version", "\"ernest-obs-v1\"");
  runtime::Policy p(identity_policy("legacy_v1", &v1));
  EXPECT_EQ(p.metadata().layout_version, "ernest-obs-v1");
  sensing::ObservationScales python_v1;
  python_v1.torque = 50.0, python_v1.elevation = 0.3, python_v1.lateral = 1.0;
  std::string text = metadata_json("obs_scale", vec_json(python_v1.divisors()));
  text.replace(text.find("ernest-obs-v2"), 13, "ernest-obs-v1");
  std::string msg;
  EXPECT_EQ(load_error(identity_policy("legacy_v1_other", &text), &msg), PolicyError::Kind::LayoutMismatch);
  EXPECT_TRUE(contains(msg, "obs_scale[1] = 1, expected 2 (lateral_deviation): the policy was trained "
                            "with another observation scale table")) << msg;
}

TEST(PolicyLoad, WrongInputSize) {
  // Metadata claims 45 inputs but the network takes 40.
  const std::string path = save_module("in40", "def forward(self, x):\n  return torch.mv(self.w, x)\n",
                                       {{"w", torch::ones({3, 40})}});
  std::string msg;
  EXPECT_EQ(load_error(path, &msg), PolicyError::Kind::InputSize);
  EXPECT_TRUE(contains(msg, "does not accept a 45-value observation")) << msg;
}

TEST(PolicyLoad, WrongOutputSize) {
  const std::string path = save_module("out4", "def forward(self, x):\n  return x[0:4] * 1.0\n", {});
  std::string msg;
  EXPECT_EQ(load_error(path, &msg), PolicyError::Kind::OutputSize);
  EXPECT_TRUE(contains(msg, "returns 4 values")) << msg;
}

TEST(PolicyLoad, MetadataIsStrictJson) {
  // conformant RFC 8259 (nlohmann::json): escapes and exponents read, everything else refused
  // with the file named; a repeated member name is refused too (it would hide a second table)
  const runtime::PolicyExpectations expect;
  std::string text = metadata_json("observation_names", R"(["x\"\u00e9", "\ud83d\ude00"])");
  const runtime::PolicyMetadata m = runtime::check_metadata(text, expect, "p.pt");
  ASSERT_EQ(m.observation_names.size(), 2u);
  EXPECT_EQ(m.observation_names[0], "x\"\xc3\xa9");
  EXPECT_EQ(m.observation_names[1], "\xf0\x9f\x98\x80");
  EXPECT_EQ(runtime::check_metadata(metadata_json("policy_rate_hz", "2e0"), expect, "p.pt").policy_rate_hz, 2.0);
  const std::vector<std::string> bad = {
      metadata_json("policy_rate_hz", "NaN"), metadata_json("policy_rate_hz", "-inf"),
      metadata_json("policy_rate_hz", "0x2"), metadata_json("policy_rate_hz", "+2"),
      metadata_json("observation_names", R"(["\udc00"])"),  // lone low surrogate
      metadata_json().substr(0, 40), metadata_json() + " x",
      metadata_json("act_dim", "3, \"act_dim\": 4")};  // duplicate member
  for (const std::string& b : bad) {
    try {
      runtime::check_metadata(b, expect, "p.pt");
      ADD_FAILURE() << "accepted: " << b.substr(0, 200);
    } catch (const PolicyError& e) {
      EXPECT_EQ(e.kind(), PolicyError::Kind::MissingMetadata) << e.what();
      EXPECT_TRUE(contains(e.what(), "p.pt: ernest_metadata.json is not valid JSON")) << e.what();
    }
  }
  std::string msg;
  try {
    runtime::check_metadata(bad.back(), expect, "p.pt");
  } catch (const PolicyError& e) {
    msg = e.what();
  }
  EXPECT_TRUE(contains(msg, "duplicate member name \"act_dim\"")) << msg;
}

// ---------------------------------------------------------------------------------------------
// Inference
TEST(PolicyInference, FeedsPhysicalObservationAndReturnsCommand) {
  runtime::Policy p(identity_policy());
  EXPECT_EQ(p.metadata().layout_version, "ernest-obs-v2");
  sensing::ObservationVector obs = sensing::ObservationVector::Zero();
  obs[0] = 0.25;   // heading deviation / pi
  obs[1] = -0.5;   // lateral / 2 m
  obs[2] = 0.125;  // roll / 30 deg
  const Eigen::Vector3d c = p.command(obs);
  // The module sees obs * maximum expected value (§4.2 table of observation.hpp), in float32.
  EXPECT_NEAR(c[0], 0.25 * M_PI, 1e-6);
  EXPECT_NEAR(c[1], -1.0, 1e-7);
  EXPECT_NEAR(c[2], 0.125 * M_PI / 6.0, 1e-7);
  // action(): the inverse of action_to_command.
  const sensing::ActionVector a = p.action(obs);
  EXPECT_NEAR(sensing::action_to_command(a)[1], c[1] < -0.349 ? -0.3490658504 : c[1], 1e-9);
  const runtime::LatencyStats s = p.latency();
  EXPECT_EQ(s.count, 2);
  EXPECT_GT(s.median_us, 0.0);
  EXPECT_GE(s.p99_us, s.median_us);
}

TEST(PolicyInference, FailedForwardAndNonFiniteAreReported) {
  // Raises once the current-action entry says "standing" (x[42] < -0.5); loads fine (zero input).
  const std::string raising = save_module(
      "raising",
      "def forward(self, x):\n"
      "  i = 0\n"
      "  if float(x[42]) < -0.5:\n"
      "    i = 1000  # an out-of-range index: the forward pass throws\n"
      "  return x[0:3] * 0.0 + x[i] * 0.0\n",
      {});
  runtime::Policy p(raising);
  sensing::ObservationVector obs = sensing::ObservationVector::Zero();
  obs[42] = -1.0;
  try {
    p.command(obs);
    FAIL() << "no error";
  } catch (const PolicyError& e) {
    EXPECT_EQ(e.kind(), PolicyError::Kind::Inference);
    EXPECT_TRUE(contains(e.what(), "forward pass failed")) << e.what();
    EXPECT_TRUE(contains(e.what(), "index 1000 out of range")) << e.what();
  }
  const std::string nan_path = save_module(
      "nan_later", "def forward(self, x):\n  return x[0:3] * 0.0 + x[1] * 1e38 * 1e38 * 0.0\n", {});
  runtime::Policy q(nan_path);  // zero input: 0 * inf... is NaN only when x[1] != 0
  obs.setZero();
  obs[1] = 0.5;
  try {
    q.command(obs);
    FAIL() << "no error";
  } catch (const PolicyError& e) {
    EXPECT_EQ(e.kind(), PolicyError::Kind::Inference);
    EXPECT_TRUE(contains(e.what(), "non-finite")) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Limits
TEST(Safety, VelocityAndJointLimits) {
  const dynamics::RoverParameters p;
  runtime::LimitOptions o;
  // Velocity bounds of §4.2.
  Eigen::Vector3d c = runtime::limit_command({0.5, -1.0, 1.0}, 0.0, 0.0, p, o);
  EXPECT_DOUBLE_EQ(c[0], 0.2);
  EXPECT_DOUBLE_EQ(c[1], -o.velocity.yaw_rate_max);
  EXPECT_DOUBLE_EQ(c[2], o.velocity.roll_rate_max);
  EXPECT_DOUBLE_EQ(runtime::limit_command({-0.1, 0, 0}, 0, 0, p, o)[0], 0.0);  // no reversing
  // At the yaw stop, further yaw is cut, moving away is allowed.
  c = runtime::limit_command({0.1, 0.2, 0.1}, p.yaw_limit - 0.01, 0.0, p, o);
  EXPECT_EQ(c[1], 0.0);
  EXPECT_EQ(c[2], 0.1);
  EXPECT_EQ(runtime::limit_command({0.1, -0.2, 0.0}, p.yaw_limit - 0.01, 0.0, p, o)[1], -0.2);
  c = runtime::limit_command({0.1, 0.0, -0.1}, 0.0, -p.roll_limit, p, o);
  EXPECT_EQ(c[2], 0.0);
  EXPECT_TRUE(runtime::limit_command({NAN, 0, 0}, 0, 0, p, o).isZero());
  // No joint limiting is the unset margin; a negative one is refused, naming the field.
  o.joint_margin.reset();
  EXPECT_EQ(runtime::limit_command({0.1, 0.2, 0.0}, p.yaw_limit, 0.0, p, o)[1], 0.2);
  o.validate();
  o.joint_margin = -1.0;
  try {
    o.validate();
    ADD_FAILURE() << "a negative joint_margin was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("LimitOptions.joint_margin = -1"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// The onboard loop on the simulator

namespace {

envs::EnvOptions flat_options(double duration) {
  envs::EnvOptions o;
  o.scenario.kind = envs::ScenarioKind::Flat;
  o.episode_duration = duration;
  return o;
}

// Wraps the simulator interface and corrupts the frames in [t0, t1).
class FaultInjector : public runtime::RoverInterface {
 public:
  enum class Mode { StaleFts, NanFts, NanPose };
  FaultInjector(runtime::RoverInterface& inner, Mode mode, double t0, double t1)
      : inner_(inner), mode_(mode), t0_(t0), t1_(t1) {}
  double now() const override { return inner_.now(); }
  const runtime::SensorFrame& read() override {
    frame_ = inner_.read();
    const double t = now();
    if (t >= t0_ && t < t1_) {
      if (mode_ == Mode::StaleFts) {
        if (!frozen_) frozen_fts_ = frame_.fts, frozen_stamp_ = frame_.fts_stamp, frozen_ = true;
        frame_.fts = frozen_fts_;  // a dead bus segment: the last samples repeated, old stamp
        frame_.fts_stamp = frozen_stamp_;
      } else if (mode_ == Mode::NanFts) {
        frame_.fts(2, 1) = std::nan("");
      } else {
        frame_.position.x() = std::nan("");
      }
    }
    return frame_;
  }
  void command(const runtime::ActuatorCommand& c) override {
    last_ = c;
    inner_.command(c);
  }
  void wait_next_tick() override { inner_.wait_next_tick(); }
  const sensing::HeightSource& heights() const override { return inner_.heights(); }
  runtime::ActuatorCommand last_{};

 private:
  runtime::RoverInterface& inner_;
  Mode mode_;
  double t0_, t1_;
  runtime::SensorFrame frame_;
  sensing::Wrenches frozen_fts_;
  double frozen_stamp_ = 0.0;
  bool frozen_ = false;
};

struct FaultRun {
  double trip_time = -1.0, resume_time = -1.0;
  std::vector<std::string> log;
  double speed_before = 0.0, speed_stopped = 0.0, speed_after = 0.0;
  double max_wheel_cmd_stopped = 0.0;
  long ticks = 0, policy_steps_during = 0;
  runtime::Fault fault = runtime::Fault::None;
};

FaultRun run_with_fault(FaultInjector::Mode mode) {
  envs::RoverEnv env(dynamics::RoverParameters{}, flat_options(30.0));
  env.reset(3);
  runtime::Policy policy(constant_policy("forward", {0.15, 0.0, 0.0}));
  runtime::SimRoverInterface sim(env);
  const double t0 = 3.0, t1 = 5.0;
  FaultInjector io(sim, mode, t0, t1);
  runtime::LoopOptions lo = runtime::LoopOptions::from_env(env);
  runtime::ControlLoop loop(io, policy, env.parameters(), env.scenario().path, lo);
  loop.set_fts_bias(env.fts_bias());
  FaultRun r;
  loop.set_logger([&](double t, const std::string& m) {
    r.log.push_back(m);
    if (contains(m, "zero velocities") && r.trip_time < 0) r.trip_time = t;
    if (contains(m, "resumes")) r.resume_time = t;
  });
  auto speed = [&] { return env.sim().state().linear_velocity.head<2>().norm(); };
  long steps_at_trip = -1;
  while (io.now() < 9.0 - 1e-9) {
    loop.tick();
    const double t = io.now();
    if (std::abs(t - 2.9) < 1e-9) r.speed_before = speed();
    if (loop.watchdog().tripped()) {
      r.fault = loop.watchdog().fault() != runtime::Fault::None ? loop.watchdog().fault() : r.fault;
      if (steps_at_trip < 0) steps_at_trip = loop.policy_steps();
      for (double w : io.last_.wheel_speed) r.max_wheel_cmd_stopped = std::max(r.max_wheel_cmd_stopped, std::abs(w));
    }
    if (std::abs(t - 4.9) < 1e-9) {
      r.speed_stopped = speed();
      r.policy_steps_during = loop.policy_steps() - steps_at_trip;
    }
    if (std::abs(t - 9.0) < 1e-9) r.speed_after = speed();
  }
  r.ticks = loop.ticks();
  return r;
}

void expect_stop_and_recovery(const FaultRun& r, runtime::Fault fault, const char* reason) {
  ASSERT_FALSE(r.log.empty());
  EXPECT_TRUE(contains(r.log.front(), reason)) << r.log.front();
  EXPECT_EQ(r.fault, fault);
  EXPECT_GT(r.speed_before, 0.08) << "the rover was not driving before the fault";
  EXPECT_LT(r.speed_stopped, 0.01) << "the rover did not stop";
  EXPECT_EQ(r.max_wheel_cmd_stopped, 0.0);
  EXPECT_EQ(r.policy_steps_during, 0);
  EXPECT_EQ(r.ticks, 9 * 400) << "the loop must keep running";
  EXPECT_GE(r.resume_time, 5.0 + 0.5 - 1e-9);  // recovery_time after the fault clears
  EXPECT_GT(r.speed_after, 0.08) << "the rover did not drive again after recovery";
}

}  // namespace

TEST(Watchdog, StaleForceTorqueDataStopsTheRover) {
  const FaultRun r = run_with_fault(FaultInjector::Mode::StaleFts);
  expect_stop_and_recovery(r, runtime::Fault::StaleFts, "stale force-torque data");
  // Trips once the samples are older than max_age (50 ms) plus at most one physics step (the
  // simulator's stamps advance every 25 ms).
  EXPECT_GT(r.trip_time, 3.0 + 0.05 - 1e-9);
  EXPECT_LE(r.trip_time, 3.0 + 0.05 + 0.025 + 1e-9);
}

TEST(Watchdog, NonFiniteForceTorqueStopsTheRover) {
  const FaultRun r = run_with_fault(FaultInjector::Mode::NanFts);
  expect_stop_and_recovery(r, runtime::Fault::NonFinite, "non-finite force-torque sample");
  EXPECT_NEAR(r.trip_time, 3.0, 1e-9);  // the same tick
}

TEST(Watchdog, NonFinitePoseStopsTheRover) {
  const FaultRun r = run_with_fault(FaultInjector::Mode::NanPose);
  expect_stop_and_recovery(r, runtime::Fault::NonFinite, "non-finite position");
}

TEST(Watchdog, FailedInferenceCommandsZeroAndTheLoopKeepsRunning) {
  envs::RoverEnv env(dynamics::RoverParameters{}, flat_options(30.0));
  env.reset(3);
  // Fails whenever the current action says "standing" — i.e. at the first policy step and every
  // retry after the watchdog has stopped the rover.
  const std::string path = save_module(
      "raising_loop",
      "def forward(self, x):\n"
      "  i = 0\n"
      "  if float(x[42]) < -0.5:\n"
      "    i = 1000  # an out-of-range index: the forward pass throws\n"
      "  return x[0:3] * 0.0 + x[i] * 0.0 + 0.1\n",
      {});
  runtime::Policy policy(path);
  runtime::SimRoverInterface io(env);
  runtime::ControlLoop loop(io, policy, env.parameters(), env.scenario().path,
                            runtime::LoopOptions::from_env(env));
  std::vector<std::string> log;
  loop.set_logger([&](double, const std::string& m) { log.push_back(m); });
  loop.run(3.0);
  EXPECT_EQ(loop.ticks(), 1200);
  EXPECT_EQ(loop.policy_steps(), 0);
  EXPECT_GE(loop.watchdog().trips(), 2);  // tripped, re-armed, tripped again
  ASSERT_FALSE(log.empty());
  EXPECT_TRUE(contains(log.front(), "inference failed")) << log.front();
  EXPECT_TRUE(contains(log.front(), "index 1000 out of range")) << log.front();
  EXPECT_TRUE(loop.command().isZero());
  EXPECT_LT(env.sim().state().linear_velocity.head<2>().norm(), 0.01);
}

// Joint limits inside the loop: a policy that keeps commanding +15 deg/s of gimbal yaw drives the
// joint to its 45 deg stop (RoverParameters::yaw_limit) when limiting is off, and stops it one
// margin short of the stop when it is on; the observation then reports the cut rate as the
// action in force.
TEST(OnboardLoop, JointLimitsStopTheGimbalShortOfItsStop) {
  const dynamics::RoverParameters params;
  auto run = [&](std::optional<double> margin, Eigen::Vector3d* last_command, sensing::ActionVector* last_action) {
    envs::RoverEnv env(params, flat_options(30.0));
    env.reset(2);
    runtime::Policy policy(constant_policy("yawing", {0.05, 0.2618, 0.0}));
    runtime::SimRoverInterface io(env);
    runtime::LoopOptions lo = runtime::LoopOptions::from_env(env);
    lo.limits.joint_margin = margin;
    runtime::ControlLoop loop(io, policy, params, env.scenario().path, lo);
    loop.set_fts_bias(env.fts_bias());
    double max_psi = 0.0;
    for (int k = 0; k < 5 * 400; ++k) {
      loop.tick();
      max_psi = std::max(max_psi, env.sim().state().gimbal_yaw);
    }
    if (last_command) *last_command = loop.command();
    if (last_action) *last_action = loop.action();
    return max_psi;
  };
  const double free_psi = run(std::nullopt, nullptr, nullptr);
  EXPECT_GT(free_psi, params.yaw_limit - 0.01) << "without limiting the joint reaches its stop";
  Eigen::Vector3d cmd;
  sensing::ActionVector act;
  const double margin = 0.035;
  const double limited_psi = run(margin, &cmd, &act);
  EXPECT_LT(limited_psi, params.yaw_limit - margin + 0.2618 * 0.025 + 1e-3);  // <= one physics step late
  EXPECT_GT(limited_psi, params.yaw_limit - margin - 0.01);
  EXPECT_EQ(cmd[1], 0.0);
  EXPECT_NEAR(cmd[0], 0.05, 1e-9);  // driving continues
  EXPECT_NEAR(act[1], 0.0, 1e-12);  // the observation reports the rate actually applied
}

// The onboard loop (400 Hz sensor ticks, FTS filter per sample, policy at 2 Hz, synchroniser)
// on the simulator makes exactly the decisions of the environments' episode core for the same
// seed and policy: the same filter, observation and synchroniser code, in the same order.
TEST(OnboardLoop, ReproducesTheEnvironmentEpisode) {
  for (const auto& [kind, seed] : {std::pair{envs::ScenarioKind::RockField, 11},
                                   std::pair{envs::ScenarioKind::Ripples, 5}}) {
    envs::EnvOptions eo;
    eo.scenario.kind = kind;
    eo.episode_duration = 8.0;
    envs::RoverEnv env(dynamics::RoverParameters{}, eo);
    runtime::Policy policy(mlp_policy("mlp", 7));
    const runtime::EpisodeReport a = runtime::run_env_episode(env, policy, seed);
    runtime::LoopOptions lo;
    env.reset(seed);
    lo = runtime::LoopOptions::from_env(env);
    lo.limits.joint_margin.reset();      // the environment has no joint limiting
    lo.limits.max_wheel_speed = 1e3;     // nor a wheel-speed clamp
    const runtime::EpisodeReport b = runtime::run_onboard_episode(env, policy, seed, &lo);
    ASSERT_EQ(a.actions.size(), 16u);
    ASSERT_EQ(b.actions.size(), a.actions.size());
    double spread = 0.0;
    for (size_t k = 0; k < a.actions.size(); ++k) {
      EXPECT_LE((a.actions[k] - b.actions[k]).cwiseAbs().maxCoeff(), 1e-12) << "policy step " << k;
      spread = std::max(spread, (a.actions[k] - a.actions[0]).cwiseAbs().maxCoeff());
    }
    EXPECT_GT(spread, 1e-3) << "the policy's actions must vary for the comparison to mean something";
    EXPECT_NEAR(a.metrics.progress, b.metrics.progress, 1e-9);
    EXPECT_NEAR(a.metrics.energy, b.metrics.energy, 1e-6);
  }
}

// With terrain_source "stereo" the loop builds its own elevation map from the pairs the
// interface delivers (onboard: the masthead cameras; here ray-cast from the simulator), with the
// environments' matcher and map code, and still makes the environment's decisions exactly.
TEST(OnboardLoop, ReproducesTheStereoEnvironmentEpisode) {
  envs::EnvOptions eo;
  eo.scenario.kind = envs::ScenarioKind::RockField;
  eo.episode_duration = 5.0;
  eo.terrain_source = "stereo";
  eo.stereo.camera.width = 320;  // smaller frames keep the test fast
  eo.stereo.camera.height = 240;
  envs::RoverEnv env(dynamics::RoverParameters{}, eo);
  runtime::Policy policy(mlp_policy("mlp", 7));
  const runtime::EpisodeReport a = runtime::run_env_episode(env, policy, 11);
  env.reset(11);
  runtime::LoopOptions lo = runtime::LoopOptions::from_env(env);
  EXPECT_TRUE(lo.stereo_map);
  lo.limits.joint_margin.reset();
  lo.limits.max_wheel_speed = 1e3;
  const runtime::EpisodeReport b = runtime::run_onboard_episode(env, policy, 11, &lo);
  ASSERT_EQ(a.actions.size(), 10u);
  ASSERT_EQ(b.actions.size(), a.actions.size());
  for (size_t k = 0; k < a.actions.size(); ++k)
    EXPECT_LE((a.actions[k] - b.actions[k]).cwiseAbs().maxCoeff(), 1e-12) << "policy step " << k;
  // and the map matters: the ground-truth episode of the same seed acts differently
  eo.terrain_source = "truth";
  envs::RoverEnv truth(dynamics::RoverParameters{}, eo);
  const runtime::EpisodeReport c = runtime::run_env_episode(truth, policy, 11);
  double diff = 0.0;
  for (size_t k = 0; k < c.actions.size(); ++k)
    diff = std::max(diff, (c.actions[k] - a.actions[k]).cwiseAbs().maxCoeff());
  EXPECT_GT(diff, 1e-6);
}

TEST(Telemetry, WritesOneRowPerRecordWithHeader) {
  envs::RoverEnv env(dynamics::RoverParameters{}, flat_options(2.0));
  runtime::Policy policy(constant_policy("forward_tel", {0.1, 0.05, 0.0}));
  const std::string path = (tmpdir() / "telemetry.csv").string();
  {
    runtime::Telemetry tel(path);
    env.reset(1);
    runtime::SimRoverInterface io(env);
    runtime::ControlLoop loop(io, policy, env.parameters(), env.scenario().path,
                              runtime::LoopOptions::from_env(env));
    loop.set_telemetry(&tel);
    loop.run(1.0);
    EXPECT_EQ(tel.rows(), 50);  // 50 Hz
  }
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, runtime::Telemetry::header());
  int rows = 0, cols = 0;
  std::string last;
  while (std::getline(in, line)) ++rows, last = line;
  for (char ch : last) cols += ch == ',';
  EXPECT_EQ(rows, 50);
  EXPECT_EQ(cols, 21);
  EXPECT_THROW(runtime::Telemetry("/nonexistent_dir/x.csv"), std::runtime_error);
}

TEST(Telemetry, CloseReportsAFailedWriteNamingThePath) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "/dev/full does not exist here";
  runtime::Telemetry tel("/dev/full");
  runtime::TelemetryRow row;
  for (int k = 0; k < 100; ++k) tel.record(row);  // more than a stdio buffer: record never throws
  EXPECT_EQ(tel.rows(), 100);
  try {
    tel.close();
    FAIL() << "close() did not report the failed writes";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot write /dev/full"), std::string::npos) << e.what();
  }
  EXPECT_NE(tel.write_error(), 0);
  EXPECT_THROW(tel.close(), std::runtime_error);  // reported again, not forgotten
  // A file that takes every write closes cleanly.
  const std::string path = (tmpdir() / "telemetry_ok.csv").string();
  runtime::Telemetry ok(path);
  ok.record(row);
  EXPECT_NO_THROW(ok.close());
  EXPECT_EQ(ok.write_error(), 0);
}
