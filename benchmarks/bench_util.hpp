// Timing helpers shared by the C++ benchmarks: medians over repeats (these machines are noisy)
// and the machine's name for the printed header.
#pragma once

#include <algorithm>
#include <chrono>
#include <fstream>
#include <string>
#include <vector>

namespace ernest::bench {

using Clock = std::chrono::steady_clock;

/// Median over `repeats` runs of run(), in microseconds per unit (run() does `per` units).
template <class F>
double median_us(F&& run, int per, int repeats) {
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    run();
    t.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count() / per);
  }
  std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
  return t[t.size() / 2];
}

/// The processor's model name from /proc/cpuinfo ("unknown" elsewhere).
inline std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown";
}

}  // namespace ernest::bench
