// The 400 Hz onboard loop does not allocate. This binary replaces the C heap
// allocator (malloc and friends) with counting versions (a separate executable so that no other
// test is affected) and counts heap allocations across many ticks of ControlLoop after a warm-up.
//
// What is counted: every sensor tick that is not a policy tick (read, watchdog check, FTS filter,
// synchroniser, limits, command), i.e. 199 of every 200 ticks at 2 Hz. A policy tick runs
// libtorch's forward pass, which allocates its tensors (outside our control); the part of it that
// is ours (elevation samples and the observation) is counted separately.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <vector>

#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/runtime/control_loop.hpp"
#include "ernest/runtime/policy.hpp"
#include "runtime_policies.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};

inline void count() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}

// Allocations made between construction and destruction.
struct CountAllocations {
  CountAllocations() {
    g_allocations = 0;
    g_counting = true;
  }
  ~CountAllocations() { g_counting = false; }
  long count() const { return g_allocations.load(); }
};
}  // namespace

// The C allocator itself is replaced (glibc supports this; the replacements forward to glibc's own
// entry points), so that every heap allocation is counted: operator new (libstdc++ calls malloc),
// Eigen's dynamic matrices (aligned malloc), OpenCV, libtorch.
extern "C" {
void* __libc_malloc(std::size_t) noexcept;
void* __libc_calloc(std::size_t, std::size_t) noexcept;
void* __libc_realloc(void*, std::size_t) noexcept;
void* __libc_memalign(std::size_t, std::size_t) noexcept;
void __libc_free(void*) noexcept;

void* malloc(std::size_t n) noexcept {
  count();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) noexcept {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) noexcept {
  count();
  return __libc_realloc(p, n);
}
void* memalign(std::size_t alignment, std::size_t n) noexcept {
  count();
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) noexcept {
  count();
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t n) noexcept {
  count();
  void* p = __libc_memalign(alignment, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
void free(void* p) noexcept { __libc_free(p); }
}

using namespace ernest;

namespace {

// A rover standing on a 2 m x 2 m plane with fresh, slowly varying sensor data: everything the
// loop does per tick happens (filter, synchroniser, limits, command), nothing else is simulated.
class StandingRover : public runtime::RoverInterface {
 public:
  StandingRover() : ground_(Eigen::MatrixXd::Zero(21, 21), 0.1, -1.0, -1.0) {}
  double now() const override { return t_; }
  const runtime::SensorFrame& read() override {
    frame_.fts_stamp = frame_.pose_stamp = frame_.joint_stamp = t_;
    frame_.fts.setConstant(std::sin(t_));
    frame_.fts.col(2).array() += 184.0;
    frame_.body_angular_velocity.x() = 0.01 * std::cos(t_);
    return frame_;
  }
  void command(const runtime::ActuatorCommand& c) override { last_ = c; }
  void wait_next_tick() override { t_ += 1.0 / 400.0; }
  const sensing::HeightSource& heights() const override { return ground_; }
  runtime::ActuatorCommand last_{};

 private:
  double t_ = 0.0;
  runtime::SensorFrame frame_;
  sensing::GridHeightSource ground_;
};

TEST(RuntimeAllocations, SensorTicksDoNotAllocate) {
  runtime::Policy policy(testing_policies::constant_policy("alloc_forward", {0.15, 0.05, 0.02}));
  StandingRover io;
  const sensing::PathLine path;
  runtime::ControlLoop loop(io, policy, dynamics::RoverParameters{}, path, runtime::LoopOptions{});
  loop.set_logger([](double, const std::string&) {});
  loop.run(2.0);  // warm-up: four policy periods
  ASSERT_EQ(loop.policy_steps(), 4);
  ASSERT_FALSE(loop.watchdog().tripped());

  long sensor_ticks = 0, allocations = 0;
  for (int period = 0; period < 5; ++period) {
    loop.tick();  // the policy tick (libtorch allocates)
    CountAllocations counter;
    for (int i = 1; i < 200; ++i, ++sensor_ticks) loop.tick();
    allocations += counter.count();
  }
  EXPECT_EQ(sensor_ticks, 5 * 199);
  EXPECT_EQ(loop.policy_steps(), 4 + 5);
  EXPECT_EQ(allocations, 0) << "heap allocations in " << sensor_ticks << " sensor ticks";
  EXPECT_GT(io.last_.wheel_speed[0], 0.0) << "the loop did drive";
}

TEST(RuntimeAllocations, ObservationAndFilterDoNotAllocate) {
  // the policy tick's own part: elevation samples, the observation, the FTS filter update
  sensing::ElevationSampler sampler{sensing::ElevationSamplingOptions{}};
  const sensing::GridHeightSource ground(Eigen::MatrixXd::Zero(41, 41), 0.1, -2.0, -2.0);
  sensing::FtsProcessor fts{sensing::FtsFilterOptions{}};
  sensing::Wrenches raw = sensing::Wrenches::Constant(3.0);
  fts.reset(raw);
  sensing::ObservationInputs in;
  double sum = 0.0;
  CountAllocations counter;
  for (int i = 0; i < 1000; ++i) {
    raw(0, 0) = i;
    fts.update(raw);
    in.fts = fts.processed();
    in.elevation = sampler.sample(Eigen::Vector3d(0.001 * i, 0.0, 0.3), Eigen::Matrix3d::Identity(),
                                  ground).values;
    sum += sensing::build_observation(in).sum();
  }
  EXPECT_EQ(counter.count(), 0);
  EXPECT_TRUE(std::isfinite(sum));
}

TEST(RuntimeAllocations, TheCounterSeesAllocations) {
  // the counting allocator is really in use (else the tests above could not fail): operator new
  // and an Eigen dynamic vector each allocate once
  static std::vector<double>* volatile sink = nullptr;  // volatile: the pair cannot be elided
  static double volatile total = 0.0;
  {
    CountAllocations counter;
    sink = new std::vector<double>;
    EXPECT_EQ(counter.count(), 1);
    Eigen::VectorXd v = Eigen::VectorXd::Constant(100, 1.0);
    total = v.sum();
    EXPECT_EQ(counter.count(), 2);
  }
  delete sink;
  EXPECT_EQ(total, 100.0);
}

}  // namespace
