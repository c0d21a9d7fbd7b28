// ernest_runtime: the onboard runtime against the C++ simulator, no Python (seed 004 §5).
//   ernest_runtime --policy FILE --scenario NAME --seed N --duration S [--telemetry out.csv]
//                  [--mode env|onboard] [--soil NAME] [--passive] [--actions out.csv] [--quiet]
//                  [--terrain-source truth|stereo]   (stereo: elevation samples from the map the
//                  loop fuses from ray-cast stereo pairs, seed 004 §2.4)
//   ernest_runtime --policy FILE --replay observations.csv --actions out.csv
// (--replay: run the policy on logged normalised observations, one row of 45 per line, and write
// the actions; the open-loop check of "same observations, same actions".)
// --mode env (default) steps envs::RoverEnv exactly as the Python environment does (one
// telemetry row per policy step); --mode onboard runs the 400 Hz ControlLoop on the simulator
// interface (telemetry at 50 Hz). Prints progress along the path, travel reduction and cost of
// transport (Table 6). Exit status: 0 done, 1 runtime error, 2 usage error, 3 diverged.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/envs/rover_env.hpp"
#include "ernest/envs/scenarios.hpp"
#include "ernest/runtime/policy.hpp"
#include "ernest/runtime/sim_in_the_loop.hpp"
#include "ernest/runtime/telemetry.hpp"
#include "ernest/soil/soil_parameters.hpp"

namespace {

// Exit codes (also in --help and the README): 0 done, 1 a runtime error (policy file, I/O,
// simulator), 2 a usage error (the command line itself), 3 the simulation diverged.
constexpr int kExitError = 1, kExitUsage = 2, kExitDiverged = 3;

// One error report for every command: policy errors name their kind; exit code 1.
int report_error(const std::exception& e) {
  if (const auto* p = dynamic_cast<const ernest::runtime::PolicyError*>(&e)) {
    std::fprintf(stderr, "ernest_runtime: policy error (%s): %s\n", ernest::runtime::to_string(p->kind()), e.what());
  } else {
    std::fprintf(stderr, "ernest_runtime: %s\n", e.what());
  }
  return kExitError;
}

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: ernest_runtime --policy FILE --scenario NAME --seed N --duration S\n"
               "                      [--telemetry out.csv] [--actions out.csv] [--mode env|onboard]\n"
               "                      [--soil m90|dry_sand|wet_sand] [--passive] [--quiet]\n"
               "                      [--terrain-source truth|stereo]\n"
               "       ernest_runtime --policy FILE --replay observations.csv --actions out.csv\n"
               "       ernest_runtime --help\n"
               "scenarios:");
  for (const auto& n : ernest::envs::scenario_names()) std::fprintf(out, " %s", n.c_str());
  std::fprintf(out,
               "\nexit status: 0 done, 1 runtime error (policy file, I/O, simulator), 2 usage error,\n"
               "             3 the simulation diverged\n");
}

// A usage error: its own message, a pointer to --help, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The whole of `text` as a number (std::stod alone accepts "3abc" and "inf").
double parse_double(const std::string& option, const std::string& text) {
  size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v))
    throw UsageError(option + " '" + text + "' is not a finite number");
  return v;
}

long long parse_integer(const std::string& option, const std::string& text) {
  size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) throw UsageError(option + " '" + text + "' is not an integer");
  return v;
}

void require_choice(const std::string& option, const std::string& value,
                    const std::vector<std::string>& choices) {
  if (std::find(choices.begin(), choices.end(), value) != choices.end()) return;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  throw UsageError(option + " '" + value + "' is not one of: " + list);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ernest;
  std::string policy_path, scenario, telemetry_path, actions_path, replay_path, mode = "env", soil = "m90",
              terrain_source = "truth";
  long long seed = -1;
  double duration = -1.0;
  bool passive = false, quiet = false, have_seed = false, have_duration = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw UsageError(a + " needs a value");
        return argv[++i];
      };
      if (a == "--policy") policy_path = value();
      else if (a == "--scenario") scenario = value();
      else if (a == "--seed") seed = parse_integer(a, value()), have_seed = true;
      else if (a == "--duration") duration = parse_double(a, value()), have_duration = true;
      else if (a == "--telemetry") telemetry_path = value();
      else if (a == "--actions") actions_path = value();
      else if (a == "--replay") replay_path = value();
      else if (a == "--mode") mode = value();
      else if (a == "--soil") soil = value();
      else if (a == "--terrain-source") terrain_source = value();
      else if (a == "--passive") passive = true;
      else if (a == "--quiet") quiet = true;
      else if (a == "-h" || a == "--help") { usage(stdout); return 0; }
      else throw UsageError("unknown argument '" + a + "'");
    }
    if (policy_path.empty()) throw UsageError("--policy FILE is required");
    if (!replay_path.empty()) {
      if (actions_path.empty()) throw UsageError("--replay needs --actions FILE (where the actions go)");
      if (!scenario.empty() || have_seed || have_duration)
        throw UsageError("--replay runs logged observations: --scenario, --seed and --duration do not apply");
    } else {
      if (scenario.empty()) throw UsageError("--scenario NAME is required");
      require_choice("--scenario", scenario, envs::scenario_names());
      if (!have_seed) throw UsageError("--seed N is required");
      if (seed < 0) throw UsageError("--seed " + std::to_string(seed) + " must be >= 0");
      if (!have_duration) throw UsageError("--duration S is required");
      if (duration <= 0.0) throw UsageError("--duration " + std::to_string(duration) + " must be > 0");
      require_choice("--mode", mode, {"env", "onboard"});
      try {
        soil::SoilParameters::preset(soil);
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--soil: ") + e.what());
      }
      require_choice("--terrain-source", terrain_source, {"truth", "stereo"});
    }
  } catch (const UsageError& e) {
    std::fprintf(stderr, "ernest_runtime: error: %s\n(see ernest_runtime --help)\n", e.what());
    return kExitUsage;
  }
  if (!replay_path.empty()) {
    try {
      runtime::Policy policy(policy_path);
      std::ifstream in(replay_path);
      if (!in) throw std::runtime_error("cannot read " + replay_path);
      std::FILE* out = std::fopen(actions_path.c_str(), "w");
      if (!out) throw std::runtime_error("cannot write " + actions_path);
      std::fprintf(out, "step,a_vx,a_yaw,a_roll\n");
      std::string line;
      long row = 0, step = 0;
      while (std::getline(in, line)) {
        ++row;
        if (line.empty() || !(std::isdigit(static_cast<unsigned char>(line[0])) || line[0] == '-' ||
                              line[0] == '+' || line[0] == '.'))
          continue;  // header or blank
        std::stringstream ss(line);
        sensing::ObservationVector obs;
        std::string cell;
        int n = 0;
        while (std::getline(ss, cell, ',')) {
          if (n >= sensing::kObservationSize) { n = -1; break; }
          obs[n++] = std::stod(cell);
        }
        if (n != sensing::kObservationSize)
          throw std::runtime_error(replay_path + ":" + std::to_string(row) + ": expected " +
                                   std::to_string(sensing::kObservationSize) + " values");
        const sensing::ActionVector act = policy.action(obs);
        std::fprintf(out, "%ld,%.17g,%.17g,%.17g\n", step++, act[0], act[1], act[2]);
      }
      std::fclose(out);
      std::printf("replayed %ld observations through %s\n", step, policy_path.c_str());
      return 0;
    } catch (const std::exception& e) {
      return report_error(e);
    }
  }
  try {
    envs::EnvOptions eo;
    eo.scenario.kind = envs::scenario_kind(scenario);
    eo.soil = soil;
    eo.terrain_source = terrain_source;
    eo.passive = passive;
    eo.episode_duration = duration;
    envs::RoverEnv env(dynamics::RoverParameters{}, eo);

    runtime::Policy policy(policy_path);
    std::printf("policy %s: %s, %d -> %d, %.3g Hz\n", policy_path.c_str(),
                policy.metadata().layout_version.c_str(), policy.metadata().obs_dim,
                policy.metadata().act_dim, policy.metadata().policy_rate_hz);

    std::unique_ptr<runtime::Telemetry> telemetry;
    if (!telemetry_path.empty()) telemetry = std::make_unique<runtime::Telemetry>(telemetry_path);
    int step = 0;
    auto progress = [&](double t, double s, const sensing::ActionVector& a) {
      ++step;
      if (!quiet && (step % 10 == 0))
        std::printf("t = %6.1f s  progress %7.3f m  action (%+.3f %+.3f %+.3f)\n", t, s, a[0], a[1], a[2]);
    };
    const runtime::EpisodeReport rep =
        mode == "env" ? runtime::run_env_episode(env, policy, static_cast<std::uint64_t>(seed), telemetry.get(), progress)
                      : runtime::run_onboard_episode(env, policy, static_cast<std::uint64_t>(seed), nullptr,
                                                     telemetry.get(), progress);
    if (telemetry) telemetry->flush();
    if (!actions_path.empty()) {
      std::FILE* f = std::fopen(actions_path.c_str(), "w");
      if (!f) throw std::runtime_error("cannot write " + actions_path);
      std::fprintf(f, "step,a_vx,a_yaw,a_roll\n");
      for (size_t k = 0; k < rep.actions.size(); ++k)
        std::fprintf(f, "%zu,%.17g,%.17g,%.17g\n", k, rep.actions[k][0], rep.actions[k][1], rep.actions[k][2]);
      std::fclose(f);
    }
    const runtime::LatencyStats lat = policy.latency();
    std::printf("scenario %s seed %lld mode %s: %s after %.1f s (%zu policy steps)\n", scenario.c_str(), seed,
                mode.c_str(), rep.end.c_str(), rep.metrics.time, rep.actions.size());
    std::printf("progress along the path  %.3f m\n", rep.metrics.progress);
    std::printf("travel reduction         %.3f\n", rep.travel_reduction);
    std::printf("cost of transport        %.3f\n", rep.cost_of_transport);
    std::printf("energy                   %.1f J\n", rep.metrics.energy);
    std::printf("inference latency        median %.1f us, p99 %.1f us (%lld calls)\n", lat.median_us, lat.p99_us,
                static_cast<long long>(lat.count));
    if (mode == "onboard") std::printf("watchdog trips           %ld\n", rep.watchdog_trips);
    return rep.diverged ? kExitDiverged : 0;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}
