// ernest_runtime: the onboard runtime against the C++ simulator, no Python (seed 004 §5).
//   ernest_runtime --policy FILE --scenario NAME --seed N --duration S [--telemetry out.csv]
//                  [--mode env|onboard] [--soil NAME] [--passive] [--actions out.csv] [--quiet]
//                  (--soil: the scenario's default soil, envs::default_soil, unless given)
//                  [--terrain-source truth|stereo]   (stereo: elevation samples from the map the
//                  loop fuses from ray-cast stereo pairs, seed 004 §2.4)
//   ernest_runtime --policy FILE --replay observations.csv --actions out.csv
// (--replay: run the policy on logged normalised observations, one row of 45 per line, and write
// the actions; the open-loop check of "same observations, same actions". A first line whose first
// field is not a number is a header; any other field that is not a finite number is refused,
// naming the file, line and column.) An output that is the same file as an input (or as the
// other output) is a usage error; an output that cannot be written is a runtime error.
// --mode env (default) steps envs::RoverEnv exactly as the Python environment does (one
// telemetry row per policy step); --mode onboard runs the 400 Hz ControlLoop on the simulator
// interface (telemetry at 50 Hz). Prints progress along the path, travel reduction and cost of
// transport (Table 6). Exit status: 0 done, 1 runtime error, 2 usage error, 3 diverged.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
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

// Standard output flushed; exit code 1 (with a message on stderr) if it could not be written.
int finish_stdout() {
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout) != 0) {
    std::fprintf(stderr, "ernest_runtime: cannot write standard output: %s\n",
                 std::strerror(errno != 0 ? errno : EIO));
    return kExitError;
  }
  return 0;
}

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: ernest_runtime --policy FILE --scenario NAME --seed N --duration S\n"
               "                      [--telemetry out.csv] [--actions out.csv] [--mode env|onboard]\n"
               "                      [--soil m90|dry_sand|wet_sand] [--passive] [--quiet]\n"
               "                      (--soil default: the scenario's, as its Gymnasium id:\n"
               "                      dry_sand for bickler, m90 otherwise)\n"
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

// Whether two paths name one file: the same inode (hard links, symbolic links, "./x" and "x"), or,
// for a file not created yet, the same normalised absolute path. Devices and pipes (/dev/null)
// are never "the same file": writing one twice loses nothing.
bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(a, ec);
  if (!ec && fs::exists(st) && !fs::is_regular_file(st)) return false;
  ec.clear();
  if (fs::equivalent(a, b, ec) && !ec) return true;
  ec.clear();
  const fs::path ca = fs::weakly_canonical(a, ec);
  if (ec) return false;
  const fs::path cb = fs::weakly_canonical(b, ec);
  return !ec && ca == cb;
}

// An output must not be an input (it would be truncated before it is read) nor another output.
void require_distinct(const std::vector<std::pair<std::string, std::string>>& outputs,
                      const std::vector<std::pair<std::string, std::string>>& inputs) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    const auto& [option, path] = outputs[i];
    if (path.empty()) continue;
    for (const auto& [in_option, in_path] : inputs)
      if (!in_path.empty() && same_file(path, in_path))
        throw UsageError(option + " " + path + " is the same file as " + in_option + " " + in_path +
                         ": an output never overwrites an input");
    for (size_t j = 0; j < i; ++j)
      if (!outputs[j].second.empty() && same_file(path, outputs[j].second))
        throw UsageError(option + " " + path + " is the same file as " + outputs[j].first + " " +
                         outputs[j].second + ": each output needs its own file");
  }
}

// A file written with printf; every write checked. close() flushes and closes it and throws
// std::runtime_error naming the path if anything failed (a full disk, /dev/full, a /proc file).
class OutputFile {
 public:
  explicit OutputFile(std::string path) : path_(std::move(path)) {
    file_ = std::fopen(path_.c_str(), "w");
    if (!file_) throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(errno));
  }
  ~OutputFile() {
    if (file_) std::fclose(file_);
  }
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  [[gnu::format(printf, 2, 3)]] void printf(const char* format, ...) {
    if (!file_) return;
    std::va_list args;
    va_start(args, format);
    const int n = std::vfprintf(file_, format, args);
    va_end(args);
    note(n < 0);
  }

  void close() {
    if (file_) {
      note(std::fflush(file_) != 0 || std::ferror(file_) != 0);
      note(std::fclose(file_) != 0);
      file_ = nullptr;
    }
    if (error_ != 0) throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(error_));
  }

 private:
  void note(bool failed) {
    if (failed && error_ == 0) error_ = errno != 0 ? errno : EIO;
  }
  std::string path_;
  std::FILE* file_ = nullptr;
  int error_ = 0;
};

// Logged observations (--replay): one row of kObservationSize comma-separated decimal numbers a
// line; blank lines are skipped, and so is a first line whose first field is not a number (a
// header). Anything else that is not a finite number is refused, naming the file, the line, the
// column (1-based) and the text.
class ObservationReader {
 public:
  explicit ObservationReader(std::string path) : path_(std::move(path)) {
    std::error_code ec;
    if (std::filesystem::is_directory(path_, ec))
      throw std::runtime_error("cannot read " + path_ + ": is a directory, expected a CSV file");
    in_.open(path_);
    if (!in_) throw std::runtime_error("cannot read " + path_ + ": " + std::strerror(errno));
  }

  // The next row into `obs`; false at the end of the file.
  bool next(ernest::sensing::ObservationVector& obs) {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_no_;
      if (line_no_ == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 BOM
      std::vector<std::string_view> fields = split(line);
      if (fields.size() == 1 && fields[0].empty()) continue;  // blank line
      const bool first = !seen_line_;
      seen_line_ = true;
      if (first && !starts_number(fields[0])) continue;  // a header
      const size_t n = static_cast<size_t>(ernest::sensing::kObservationSize);
      for (size_t c = 0; c < fields.size(); ++c) {
        const double v = parse(fields[c], c);
        if (c < n) obs[static_cast<int>(c)] = v;
      }
      if (fields.size() != n)
        fail(": expected " + std::to_string(n) + " values, found " + std::to_string(fields.size()));
      return true;
    }
    if (in_.bad()) throw std::runtime_error("cannot read " + path_ + ": read error after line " +
                                            std::to_string(line_no_));
    return false;
  }

  long line() const { return line_no_; }

 private:
  static std::string_view trim(std::string_view v) {
    const auto space = [](char ch) { return ch == ' ' || ch == '\t' || ch == '\r'; };
    while (!v.empty() && space(v.front())) v.remove_prefix(1);
    while (!v.empty() && space(v.back())) v.remove_suffix(1);
    return v;
  }

  static std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> out;
    size_t start = 0;
    for (;;) {
      const size_t comma = line.find(',', start);
      out.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos
                                                                             : comma - start)));
      if (comma == std::string_view::npos) return out;
      start = comma + 1;
    }
  }

  // Whether `text` begins like a decimal number (a header's first field does not); "nan" and
  // "inf" do, so that such a row is refused rather than skipped.
  static bool starts_number(std::string_view text) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    double v = 0.0;
    return std::from_chars(text.data(), text.data() + text.size(), v).ptr != text.data();
  }

  double parse(std::string_view text, size_t column) const {
    std::string_view digits = text;
    if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-') digits.remove_prefix(1);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (ptr != digits.data() + digits.size() || digits.empty())
      fail(", column " + std::to_string(column + 1) + ": '" + std::string(text) + "' is not a number");
    if (ec == std::errc::result_out_of_range) {
      // from_chars leaves `v` alone then: an underflow reads as strtod's (tiny or zero) value,
      // an overflow is refused below.
      const std::string copy(digits);
      v = std::strtod(copy.c_str(), nullptr);
    }
    if (!std::isfinite(v))
      fail(", column " + std::to_string(column + 1) + ": '" + std::string(text) +
           "' is not a finite number");
    return v;
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(path_ + ": line " + std::to_string(line_no_) + what);
  }

  std::string path_;
  std::ifstream in_;
  long line_no_ = 0;
  bool seen_line_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace ernest;
  std::string policy_path, scenario, telemetry_path, actions_path, replay_path, mode = "env", soil,
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
      if (soil.empty()) soil = envs::default_soil(envs::scenario_kind(scenario));
      try {
        soil::SoilParameters::preset(soil);
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--soil: ") + e.what());
      }
      require_choice("--terrain-source", terrain_source, {"truth", "stereo"});
    }
    require_distinct({{"--actions", actions_path}, {"--telemetry", telemetry_path}},
                     {{"--policy", policy_path}, {"--replay", replay_path}});
  } catch (const UsageError& e) {
    std::fprintf(stderr, "ernest_runtime: error: %s\n(see ernest_runtime --help)\n", e.what());
    return kExitUsage;
  }
  if (!replay_path.empty()) {
    try {
      runtime::Policy policy(policy_path);
      // Every row is read and checked before the actions file is opened: a malformed input
      // leaves no partial output.
      ObservationReader in(replay_path);
      std::vector<sensing::ObservationVector> rows;
      for (sensing::ObservationVector obs; in.next(obs);) rows.push_back(obs);
      if (rows.empty())
        throw std::runtime_error(replay_path + ": no observations (" + std::to_string(in.line()) +
                                 " lines, expected rows of " +
                                 std::to_string(sensing::kObservationSize) + " values)");
      OutputFile out(actions_path);
      out.printf("step [-],a_vx [-],a_yaw [-],a_roll [-]\n");
      long step = 0;
      for (const sensing::ObservationVector& obs : rows) {
        const sensing::ActionVector act = policy.action(obs);
        out.printf("%ld,%.17g,%.17g,%.17g\n", step++, act[0], act[1], act[2]);
      }
      out.close();
      std::printf("replayed %ld observations through %s\n", step, policy_path.c_str());
      return finish_stdout();
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

    // Both outputs are opened before the episode: one that cannot be written fails at once.
    std::unique_ptr<OutputFile> actions_out;
    if (!actions_path.empty()) actions_out = std::make_unique<OutputFile>(actions_path);
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
    if (actions_out) {
      actions_out->printf("step [-],a_vx [-],a_yaw [-],a_roll [-]\n");
      for (size_t k = 0; k < rep.actions.size(); ++k)
        actions_out->printf("%zu,%.17g,%.17g,%.17g\n", k, rep.actions[k][0], rep.actions[k][1],
                            rep.actions[k][2]);
      actions_out->close();
    }
    if (telemetry) telemetry->close();
    const runtime::LatencyStats lat = policy.latency();
    std::printf("scenario %s on %s seed %lld mode %s: %s after %.1f s (%zu policy steps)\n",
                scenario.c_str(), soil.c_str(), seed, mode.c_str(), rep.end.c_str(), rep.metrics.time,
                rep.actions.size());
    std::printf("progress along the path  %.3f m\n", rep.metrics.progress);
    std::printf("travel reduction         %.3f (fraction: 1 - progress / no-slip travel)\n", rep.travel_reduction);
    std::printf("cost of transport        %.3f (dimensionless: energy / (m g progress))\n", rep.cost_of_transport);
    std::printf("energy                   %.1f J\n", rep.metrics.energy);
    std::printf("inference latency        median %.1f us, p99 %.1f us (%lld calls)\n", lat.median_us, lat.p99_us,
                static_cast<long long>(lat.count));
    if (mode == "onboard") std::printf("watchdog trips           %ld\n", rep.watchdog_trips);
    const int status = finish_stdout();
    return status != 0 ? status : rep.diverged ? kExitDiverged : 0;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}
