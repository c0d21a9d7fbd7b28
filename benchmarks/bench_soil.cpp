// Soil benchmark: microseconds per wheel evaluation (single and batched) for each quadrature
// size, with the accuracy of that size (convergence study) and, as the same-run reference, the
// naive scalar evaluation of the same equations (std:: maths, adaptive Gauss–Kronrod).
// Medians over repeats, since these machines are noisy.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bench_util.hpp"
#include "ernest/soil/bekker_wong.hpp"
#include "reference_bekker_wong.hpp"

using namespace ernest::soil;
using ernest::bench::Clock;
using ernest::bench::cpu_model;
using ernest::bench::median_us;

namespace {
using States = Eigen::Matrix<double, Eigen::Dynamic, 5, Eigen::RowMajor>;
using Forces = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;

// Realistic rover states: sinkage 2–80 mm, speeds up to 0.3 m/s, every sign combination.
States make_states(int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> h(2e-3, 0.08), v(-0.3, 0.3);
  States s(n, 5);
  for (int i = 0; i < n; ++i) s.row(i) << h(rng), v(rng), v(rng), v(rng), v(rng);
  return s;
}

}  // namespace

int main() {
  std::printf("machine: %s, %u hardware threads\n", cpu_model().c_str(),
              std::thread::hardware_concurrency());
  const WheelGeometry wheel{0.17, 0.13};
  const SoilParameters soil = SoilParameters::m90();
  const int kWheels = 4096;
  const States states = make_states(kWheels, 42);
  Forces forces(kWheels, 4);
  volatile double sink = 0;

  // Accuracy reference: 32 points per panel.
  const BekkerWongModel fine(soil, wheel, 32);
  Forces exact(kWheels, 4);
  fine.evaluate_batch(states, exact);

  // Same-run baseline: the plain scalar formulation (std:: maths, one node at a time) at the
  // default number of nodes, i.e. what a straightforward implementation would cost.
  const int kRef = 1024;
  const double ref_us = median_us(
      [&] {
        for (int i = 0; i < kRef; ++i) {
          const auto f = reference::evaluate(soil, wheel,
              {states(i, 0), states(i, 1), states(i, 2), states(i, 3), states(i, 4)}, 0,
              BekkerWongModel::kDefaultPointsPerPanel);
          sink = sink + f[2];
        }
      },
      kRef, 11);

  std::printf("\nM90, ERNEST wheel, %d random states (sinkage 2-80 mm, |v| <= 0.3 m/s)\n", kWheels);
  std::printf("naive scalar baseline (std:: maths, %d points per panel): %.3f us/wheel\n\n",
              BekkerWongModel::kDefaultPointsPerPanel, ref_us);
  std::printf("%8s %8s %13s %13s %14s %14s %12s\n", "pts/pan", "nodes", "single us", "batch us",
              "median relerr", "max relerr", "naive/ours");
  for (int n : {2, 3, 4, 5, 6, 8, 12, 16}) {
    const BekkerWongModel m(soil, wheel, n);
    const double single_us = median_us(
        [&] {
          for (int i = 0; i < kWheels; ++i) {
            const WheelSoilForce f = m.evaluate(
                {states(i, 0), states(i, 1), states(i, 2), states(i, 3), states(i, 4)});
            sink = sink + f.fz;
          }
        },
        kWheels, 21);
    const double batch_us = median_us([&] { m.evaluate_batch(states, forces); },
                                                kWheels, 21);
    m.evaluate_batch(states, forces);
    std::vector<double> err(kWheels);
    for (int i = 0; i < kWheels; ++i) {
      const double scale = exact.row(i).head<3>().cwiseAbs().maxCoeff() + 1e-12;
      err[i] = (forces.row(i).head<3>() - exact.row(i).head<3>()).cwiseAbs().maxCoeff() / scale;
    }
    std::sort(err.begin(), err.end());
    std::printf("%8d %8d %13.3f %13.3f %14.1e %14.1e %11.1fx%s\n", n, 3 * n, single_us, batch_us,
                err[kWheels / 2], err.back(), ref_us / batch_us,
                n == BekkerWongModel::kDefaultPointsPerPanel ? "  <- default" : "");
  }
  std::printf("\ntarget: <= 0.5 us per wheel at the default quadrature\n");
  return sink == 12345.678 ? 1 : 0;
}
