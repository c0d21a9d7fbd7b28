// Uses the installed ernest::core: one soil evaluation on M90 must give a positive normal force
// and a positive driving torque for a wheel spinning faster than it travels.
#include <cstdio>
#include <ernest/soil/bekker_wong.hpp>

int main() {
  using namespace ernest::soil;
  const BekkerWongModel model(SoilParameters::m90(), WheelGeometry{});
  const WheelSoilForce f = model.evaluate(ContactState{0.01, 0.1, 0.0, -0.02, 0.0});
  std::printf("consumer: M90, sinkage 10 mm, driving: fx=%.2f N fz=%.2f N torque=%.3f N m\n",
              f.fx, f.fz, f.axle_torque);
  return (f.fz > 0.0 && f.axle_torque > 0.0) ? 0 : 1;
}
