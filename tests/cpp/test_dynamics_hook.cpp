// The solver hook checked. The fast path is active in this build and says so
// (fast_lcp_active, SolverStats::fast_lcp); ODE's process-wide handlers that another ODE user
// installed before ours still get every message and error that is not ours.
#include <gtest/gtest.h>
#include <ode/ode.h>

#include <cstdarg>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "ernest/solver/ode_init.hpp"
#include "ernest/dynamics/rover_sim.hpp"

using namespace ernest::dynamics;
using namespace ernest::solver;

namespace {

// "Another ODE user": its handlers, installed before anything of ernest runs (a static
// initialiser, before main), record what reaches them. Its error and debug handlers must not
// return (ODE exits or aborts if they do), so they throw what they got.
struct Received {
  int num = -1;
  std::string text;
  int count = 0;
};
Received message_got, error_got, debug_got;

struct TheirError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void record(Received& r, int num, const char* msg, va_list ap) {
  char text[256];
  std::vsnprintf(text, sizeof text, msg, ap);
  r.num = num;
  r.text = text;
  ++r.count;
}

void their_message(int num, const char* msg, va_list ap) { record(message_got, num, msg, ap); }
void their_error(int num, const char* msg, va_list ap) {
  record(error_got, num, msg, ap);
  throw TheirError(error_got.text);
}
void their_debug(int num, const char* msg, va_list ap) {
  record(debug_got, num, msg, ap);
  throw TheirError(debug_got.text);
}

const bool installed_first = [] {
  dSetMessageHandler(their_message);
  dSetErrorHandler(their_error);
  dSetDebugHandler(their_debug);
  return true;
}();

std::unique_ptr<RoverSim> make_sim(bool sparse_lcp) {
  SimOptions o;
  o.ground = GroundType::Rigid;
  o.sparse_lcp = sparse_lcp;
  auto sim = std::make_unique<RoverSim>(RoverParameters{}, HeightMap::flat(8, 8, 0.25),
                                        std::vector<BoxObstacle>{}, o);
  sim->reset(0.0, 0.0, 0.0);
  return sim;
}

}  // namespace

TEST(SolverHook, FastPathIsActiveInThisBuildAndReported) {
  ASSERT_TRUE(installed_first);
  const int messages = message_got.count, errors = error_got.count, debugs = debug_got.count;
  EXPECT_TRUE(fast_lcp_active());
  EXPECT_EQ(fast_lcp_inactive_reason(), "");
  const auto fast = make_sim(true), dense = make_sim(false);
  EXPECT_TRUE(fast->solver_stats().fast_lcp);
  EXPECT_FALSE(dense->solver_stats().fast_lcp);  // switched off by SimOptions::sparse_lcp
  fast->step_n(8);
  dense->step_n(8);
  // the flag is what happens: sparse solves only where it is set
  EXPECT_GT(fast->solver_stats().sparse_solves, 0u);
  EXPECT_EQ(dense->solver_stats().sparse_solves, 0u);
  // the probe and the rover's steps sent nothing to the other user's handlers
  EXPECT_EQ(message_got.count, messages);
  EXPECT_EQ(error_got.count, errors);
  EXPECT_EQ(debug_got.count, debugs);
}

TEST(SolverHook, HandlersInstalledBeforeOursStillReceiveWhatIsNotOurs) {
  ASSERT_TRUE(installed_first);
  init_ode_once();
  // ours are installed, theirs are not lost
  EXPECT_NE(dGetMessageHandler(), &their_message);
  EXPECT_NE(dGetErrorHandler(), &their_error);
  EXPECT_NE(dGetDebugHandler(), &their_debug);
  const Received before = message_got;

  // Outside ernest's ODE calls everything is theirs, an LCP message included.
  dMessage(7, "their message %d", 1);
  EXPECT_EQ(message_got.count, before.count + 1);
  EXPECT_EQ(message_got.num, 7);
  EXPECT_EQ(message_got.text, "their message 1");
  const std::uint64_t counted = ode_lcp_message_count();
  dMessage(d_ERR_LCP, "LCP internal error, s <= 0 (s=%.4e)", -1.0);
  EXPECT_EQ(message_got.count, before.count + 2);
  EXPECT_EQ(message_got.num, d_ERR_LCP);
  EXPECT_EQ(ode_lcp_message_count(), counted);
  EXPECT_THROW(dError(2, "their error %d", 2), TheirError);
  EXPECT_EQ(error_got.text, "their error 2");
  EXPECT_THROW(dDebug(1, "assertion \"%s\" failed", "theirs"), TheirError);
  EXPECT_EQ(debug_got.text, "assertion \"theirs\" failed");

  // Inside one of ours (a RoverSim or WalkerSim step): LCP messages are counted, not passed on;
  // other messages are still theirs; errors throw OdeInternalError for our step to catch.
  {
    const OdeCallScope own;
    dMessage(d_ERR_LCP, "LCP internal error, s <= 0 (s=%.4e)", -1.0);
    EXPECT_EQ(ode_lcp_message_count(), counted + 1);
    EXPECT_EQ(message_got.count, before.count + 2);
    dMessage(8, "another message");
    EXPECT_EQ(message_got.count, before.count + 3);
    EXPECT_EQ(message_got.num, 8);
    const int errors = error_got.count, debugs = debug_got.count;
    EXPECT_THROW(dError(3, "ours %d", 3), OdeInternalError);
    EXPECT_THROW(dDebug(4, "ours"), OdeInternalError);
    EXPECT_EQ(error_got.count, errors);
    EXPECT_EQ(debug_got.count, debugs);
  }
  // the scope is over: theirs again
  EXPECT_THROW(dError(5, "theirs again"), TheirError);
}
