// Reliability in C++: commands with physical ranges, ODE's internal errors as exceptions
// instead of a process abort, and one RoverSim used from two threads refused, not raced.
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <array>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "ernest/common/exclusive_use.hpp"
#include "ernest/dynamics/batch_stepper.hpp"
#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;

namespace {

// The message of the std::invalid_argument that f throws ("" if none).
template <class F>
std::string invalid_argument_message(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::shared_ptr<RoverSim> make_sim() {
  auto sim = std::make_shared<RoverSim>(RoverParameters{}, HeightMap::flat(8, 8, 0.25));
  sim->reset(0.0, 0.0, 0.0);
  return sim;
}

}  // namespace

TEST(DynamicsReliability, CommandsHavePhysicalRanges) {
  Commands c;
  c.yaw_rate = 1e306;  // finite: passed validate() and made ODE abort the process
  const std::string m = invalid_argument_message([&] { c.validate(); });
  EXPECT_NE(m.find("Commands.yaw_rate"), std::string::npos) << m;
  EXPECT_NE(m.find("[-100, 100]"), std::string::npos) << m;
  c = Commands{};
  c.wheel_speed[2] = 1e307;
  const std::string w = invalid_argument_message([&] { c.validate(); });
  EXPECT_NE(w.find("Commands.wheel_speed[2]"), std::string::npos) << w;
  c = Commands{};
  c.roll_torque = -2e5;
  EXPECT_NE(invalid_argument_message([&] { c.validate(); }).find("roll_torque"), std::string::npos);
  c = Commands{};
  c.yaw_rate = 100.0;  // the bound itself is allowed
  EXPECT_NO_THROW(c.validate());
}

TEST(DynamicsReliability, BatchCommandsAreChecked) {
  BatchStepper b({make_sim()}, 1);
  std::array<double, RoverSim::kCommandSize> c{0, 0, 0, 0, 1e306, 0, 1, 0};
  EXPECT_NE(invalid_argument_message([&] { b.step(c.data(), 1, nullptr); }).find("yaw_rate"),
            std::string::npos);
  c = {0, 0, 0, 0, 0, 0, std::nan(""), 0};  // NaN != 0 used to read as "gimbal on"
  EXPECT_NE(invalid_argument_message([&] { b.step(c.data(), 1, nullptr); }).find("gimbal_enabled"),
            std::string::npos);
  c = {0, 0, 0, 0, 0, 0, 1, INFINITY};
  EXPECT_NE(invalid_argument_message([&] { b.step(c.data(), 1, nullptr); }).find("clutch_engage"),
            std::string::npos);
  c = {0, 0, 0, 0, 0, 0, 1, 0};
  EXPECT_NO_THROW(b.step(c.data(), 1, nullptr));
}

TEST(DynamicsReliability, OdeInternalErrorsThrowInsteadOfAborting) {
  make_sim();  // installs the handlers
  // ODE calls these on internal failures and aborts the process if the handler returns.
  EXPECT_ANY_THROW(dDebug(1, "assertion \"%s\" failed", "!bSafeNormalize4Fault"));
  EXPECT_ANY_THROW(dError(2, "error %d", 2));
  try {
    dDebug(1, "assertion \"%s\" failed", "x");
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("assertion \"x\" failed"), std::string::npos) << e.what();
  }
  // Stepping still works afterwards (only a simulator whose step failed is retired).
  auto sim = make_sim();
  EXPECT_NO_THROW(sim->step_n(4));
}

TEST(DynamicsReliability, ConcurrentUseOfOneSimulatorIsRefused) {
  auto sim = make_sim();
  const Snapshot snap = sim->snapshot();
  std::atomic<bool> stop{false};
  std::atomic<int> refused{0}, done{0};
  std::thread stepper([&] {  // steps until the main thread has been refused a few times
    while (!stop) {
      try {
        sim->step_n(50);
        ++done;
      } catch (const ernest::ConcurrentUse&) {
        ++refused;
      }
    }
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  int main_refused = 0;
  while (main_refused < 5 && std::chrono::steady_clock::now() < deadline) {
    try {
      sim->restore(snap);
    } catch (const ernest::ConcurrentUse& e) {
      ++main_refused;
      EXPECT_NE(std::string(e.what()).find("in use by another thread"), std::string::npos);
    }
  }
  stop = true;
  stepper.join();
  // Every call either ran alone or was refused; nothing crashed and the state is sound.
  EXPECT_EQ(main_refused, 5);
  EXPECT_GT(done.load(), 0);
  EXPECT_TRUE(sim->state().position.allFinite());
  EXPECT_NO_THROW(sim->step_n(2));  // the guard is released after each call
}
