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
// transport (Table 6).
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <exception>
#include <memory>
#include <string>

#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/envs/rover_env.hpp"
#include "ernest/envs/scenarios.hpp"
#include "ernest/runtime/policy.hpp"
#include "ernest/runtime/sim_in_the_loop.hpp"
#include "ernest/runtime/telemetry.hpp"

namespace {

// One error report for every command: policy errors name their kind; exit code 1.
int report_error(const std::exception& e) {
  if (const auto* p = dynamic_cast<const ernest::runtime::PolicyError*>(&e)) {
    std::fprintf(stderr, "ernest_runtime: policy error (%s): %s\n", ernest::runtime::to_string(p->kind()), e.what());
  } else {
    std::fprintf(stderr, "ernest_runtime: %s\n", e.what());
  }
  return 1;
}

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: ernest_runtime --policy FILE --scenario NAME --seed N --duration S\n"
               "                      [--telemetry out.csv] [--actions out.csv] [--mode env|onboard]\n"
               "                      [--soil m90|dry_sand|wet_sand] [--passive] [--quiet]\n"
               "                      [--terrain-source truth|stereo]\n"
               "       ernest_runtime --policy FILE --replay observations.csv --actions out.csv\n"
               "scenarios:");
  for (const auto& n : ernest::envs::scenario_names()) std::fprintf(out, " %s", n.c_str());
  std::fprintf(out, "\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ernest;
  std::string policy_path, scenario, telemetry_path, actions_path, replay_path, mode = "env", soil = "m90",
              terrain_source = "truth";
  long long seed = -1;
  double duration = -1.0;
  bool passive = false, quiet = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* name) -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "ernest_runtime: %s needs a value\n", name);
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--policy") policy_path = value("--policy");
      else if (a == "--scenario") scenario = value("--scenario");
      else if (a == "--seed") seed = std::stoll(value("--seed"));
      else if (a == "--duration") duration = std::stod(value("--duration"));
      else if (a == "--telemetry") telemetry_path = value("--telemetry");
      else if (a == "--actions") actions_path = value("--actions");
      else if (a == "--replay") replay_path = value("--replay");
      else if (a == "--mode") mode = value("--mode");
      else if (a == "--soil") soil = value("--soil");
      else if (a == "--terrain-source") terrain_source = value("--terrain-source");
      else if (a == "--passive") passive = true;
      else if (a == "--quiet") quiet = true;
      else if (a == "-h" || a == "--help") { usage(stdout); return 0; }
      else { std::fprintf(stderr, "ernest_runtime: unknown argument %s\n", a.c_str()); usage(stderr); return 2; }
    } catch (const std::exception&) {
      std::fprintf(stderr, "ernest_runtime: invalid number for %s\n", a.c_str());
      return 2;
    }
  }
  if (!replay_path.empty()) {
    if (policy_path.empty() || actions_path.empty()) {
      std::fprintf(stderr, "ernest_runtime: --replay needs --policy and --actions\n");
      return 2;
    }
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
  if (policy_path.empty() || scenario.empty() || seed < 0 || duration <= 0.0 ||
      (mode != "env" && mode != "onboard")) {
    std::fprintf(stderr, "ernest_runtime: --policy, --scenario, --seed >= 0 and --duration > 0 are required; "
                         "--mode is env or onboard\n");
    usage(stderr);
    return 2;
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
    return rep.diverged ? 3 : 0;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}
