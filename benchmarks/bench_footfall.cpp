// FootFall benchmark: on the SDM-B standard stance among rocks (footfall::rock_field),
//  * the stability map of leg 0 with 2 cm cells over its full reach (target ≤ 0.5 s),
//  * SBL (OMPL) on random feasible queries between compliance waypoints above random stable cells
//    (target ≤ 50 ms median), success rate, and OMPL's RRT-Connect on the same queries as the
//    same-run reference,
//  * the Dijkstra–bisection smoother (§3.4.2, target ≤ 50 ms median, shorter paths) against OMPL's
//    PathSimplifier::simplifyMax on the same plans (length, time),
//  * a dense re-check (1e-3 rad, zero clearance) of every returned path,
//  * the torque-aware map (§7.1: every cell's peak joint torque, target ≤ 0.5 s as the plain map)
//    and the peak-torque smoother against the length smoother on the same plans (peak |tau| /
//    limit along the path with the leg in the air, length, time).
// Medians; `./run bench footfall` (then benchmarks/bench_footfall.py, the Python-side timings).
// Arguments: [queries (60)] [SBL range, rad (PlannerOptions' default)]; FOOTFALL_VERBOSE=1 prints
// every hard query (wall and CPU times, nodes, rounds, checks), FOOTFALL_ONLY=k runs query k only.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <vector>

#include "bench_util.hpp"
#include "ernest/footfall/leg_planner.hpp"
#include "ernest/footfall/path_smoothing.hpp"
#include "ernest/footfall/scenario.hpp"
#include "ernest/footfall/stability_map.hpp"
#include "ernest/footfall/stance_torque.hpp"
#include "ernest/footfall/torque_smoothing.hpp"

using namespace ernest::footfall;
using ernest::bench::Clock;

namespace {
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
double max_of(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }
// CPU time of this thread [s]: on the shared, loaded machine the wall figures include the time
// other processes hold the core; the CPU time is what the planner itself costs.
double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
}  // namespace

int main(int argc, char** argv) {
  const int queries = argc > 1 ? std::atoi(argv[1]) : 60;
  const ernest::walker::WalkerModel model(ernest::walker::sdm_b_parameters());
  const Eigen::Isometry3d body = model.standard_body_pose();
  const Eigen::MatrixXd q = model.standard_configuration();
  const Eigen::Matrix3Xd feet = model.contact_points(body, q);
  RockFieldOptions rocks;  // a dense field: about six rocks within the leg's reach
  rocks.rocks = 40;
  rocks.max_height = 0.5;
  const auto terrain = rock_field(rocks, feet.topRows<2>());
  const int leg = 0;
  std::printf("FootFall on SDM-B, %d rocks (%.2f-%.2f m high) on a %.0f m field, leg %d; %s\n", rocks.rocks,
              rocks.min_height, rocks.max_height, rocks.length, leg, ernest::bench::cpu_model().c_str());

  // 1. Stability map (§3.3).
  StabilityMapOptions mo;
  std::vector<double> tm;
  StabilityMap map;
  for (int r = 0; r < 5; ++r) {
    const auto t0 = Clock::now();
    StabilityMapper mapper(model, terrain, body, q, leg, mo);
    map = mapper.map();
    tm.push_back(seconds_since(t0));
  }
  std::printf("stability map, %.0f cm cells, %ld x %ld, reach %.2f m: %.3f s median  (target <= 0.5 s)\n",
              100 * mo.cell, long(map.status.rows()), long(map.status.cols()), map.reach, median(tm));
  std::printf("  stable %d, unstable %d, unreachable %d cells, %ld IK solves, criterion %s\n",
              map.count(CellStatus::kStable), map.count(CellStatus::kUnstable), map.count(CellStatus::kUnreachable),
              map.ik_solves, map.nesm ? "NESM" : "SSM");

  // 1b. The torque-aware map (§7.1): the same map with every reachable cell's peak joint torque.
  StabilityMapOptions to = mo;
  to.torques = true;
  to.max_saturation = 0.85;
  std::vector<double> tt;
  StabilityMap tmap;
  for (int r = 0; r < 5; ++r) {
    const auto t0 = Clock::now();
    StabilityMapper mapper(model, terrain, body, q, leg, to);
    tmap = mapper.map();
    tt.push_back(seconds_since(t0));
  }
  std::printf("torque-aware map (peak joint torque per cell, max_saturation %.2f): %.3f s median  (target <= 0.5 s;"
              " plain map %.3f s)\n", to.max_saturation, median(tt), median(tm));
  std::printf("  stable %d, overloaded %d, unstable %d cells; leg lifted above its foot: %.3f of a limit\n",
              tmap.count(CellStatus::kStable), tmap.count(CellStatus::kOverloaded), tmap.count(CellStatus::kUnstable),
              tmap.lift_saturation);

  // 2. Random feasible queries (§3.4.1).
  StabilityMapper mapper(model, terrain, body, q, leg, mo);
  LegCollisionChecker checker(model, terrain, body, q, leg);
  CollisionOptions exact;
  exact.environment_clearance = exact.own_leg_clearance = 0.0;
  exact.clearance_table = Eigen::MatrixXd::Zero(model.joints_per_leg() + 1, model.joints_per_leg() + 2);
  LegCollisionChecker dense(model, terrain, body, q, leg, exact);
  const Eigen::MatrixXd ends = sample_waypoints(mapper, map, checker, 2 * queries, 7);
  PlannerOptions po;
  po.time_limit = 1.0;
  if (argc > 2) po.range = std::atof(argv[2]);
  StanceTorques torques(model, body, q, leg);
  std::vector<double> tq_len_peak, tq_peak, tq_len_len, tq_len, tq_len_t, tq_t, tq_gain;
  int tq_lower = 0, tq_higher = 0;
  std::vector<double> h_sbl, h_rrt, h_ours, h_ratio, hc_sbl, hc_ours, h_len, c_sbl, c_rrt, t_sbl, t_rrt, t_ours, t_ompl, l_raw, l_smooth, r_ours, r_ompl;
  int ok_sbl = 0, ok_rrt = 0, shorter = 0, dirty = 0, straight = 0;
  const int only = std::getenv("FOOTFALL_ONLY") ? std::atoi(std::getenv("FOOTFALL_ONLY")) : -1;
  for (int k = 0; k < queries; ++k) {
    if (only >= 0 && k != only) continue;
    const bool free_edge = checker.motion_valid(ends.col(2 * k), ends.col(2 * k + 1), po.epsilon);
    straight += free_edge;
    po.seed = 100 + k;
    po.planner = PlannerType::kSbl;
    LegPlanner sbl(checker, po);
    const double c0 = cpu_now();
    const PlanResult r = sbl.plan(ends.col(2 * k), ends.col(2 * k + 1));
    const double cpu_sbl = cpu_now() - c0;
    po.planner = PlannerType::kRrtConnect;
    PlannerOptions ro = po;
    ro.range.reset();  // the reference at OMPL's default range
    LegPlanner rrt(checker, ro);
    const PlanResult c = rrt.plan(ends.col(2 * k), ends.col(2 * k + 1));
    if (c.status == PlanStatus::kSolved) ++ok_rrt, t_rrt.push_back(c.seconds), c_rrt.push_back(double(c.checks));
    if (r.status != PlanStatus::kSolved) continue;
    ++ok_sbl;
    t_sbl.push_back(r.seconds);
    if (!free_edge) h_sbl.push_back(r.seconds), h_rrt.push_back(c.seconds), hc_sbl.push_back(cpu_sbl);
    c_sbl.push_back(double(r.checks));
    // 3. Smoothing (§3.4.2) against OMPL's simplifier, same plan.
    const long checks0 = checker.checks();
    const double c1 = cpu_now();
    const SmoothingResult s = smooth_path(checker, r.path);
    const double cpu_smooth = cpu_now() - c1;
    if (!free_edge) hc_ours.push_back(cpu_smooth), h_len.push_back(s.length);
    if (std::getenv("FOOTFALL_VERBOSE") && !free_edge)
      std::printf("  hard query %d: SBL %.1f ms (CPU %.1f), %ld nodes, %.2f rad; smoothing %.1f ms (CPU %.1f), %d rounds, %ld edges, %ld configs, %.2f rad\n",
                  k, 1e3 * r.seconds, 1e3 * cpu_sbl, long(r.path.cols()), r.length, 1e3 * s.seconds, 1e3 * cpu_smooth, s.iterations, s.edge_checks,
                  checker.checks() - checks0, s.length);
    t_ours.push_back(s.seconds);
    if (!free_edge) h_ours.push_back(s.seconds), h_ratio.push_back(s.length / r.length);
    const auto t0 = Clock::now();
    const Eigen::MatrixXd o = sbl.simplify_with_ompl(r.path);
    t_ompl.push_back(seconds_since(t0));
    l_raw.push_back(r.length);
    l_smooth.push_back(s.length);
    r_ours.push_back(s.length / r.length);
    r_ompl.push_back(path_length(o) / r.length);
    shorter += s.length < r.length - 1e-9 || r.path.cols() == 2;
    dirty += first_colliding_edge(dense, r.path, 1e-3) >= 0;
    dirty += first_colliding_edge(dense, s.path, 1e-3) >= 0;
    // 4. The peak-torque smoother (§7.1) on the same plan.
    const SmoothingResult ts = smooth_path_for_torque(checker, torques, r.path);
    const double len_peak = torques.lifted_path(s.path, 0.05).saturation;
    tq_len_peak.push_back(len_peak);
    tq_peak.push_back(ts.peak_saturation);
    tq_gain.push_back(len_peak - ts.peak_saturation);
    tq_len_len.push_back(s.length);
    tq_len.push_back(ts.length);
    tq_len_t.push_back(s.seconds);
    tq_t.push_back(ts.seconds);
    tq_lower += ts.peak_saturation < len_peak - 1e-3;
    tq_higher += ts.peak_saturation > len_peak + 1e-3;
    dirty += first_colliding_edge(dense, ts.path, 1e-3) >= 0;
  }
  std::printf("planning, %d random feasible queries (waypoints above random stable cells), 1 s budget;\n"
              "  %d of them have a free straight edge (the rest must go round or over rocks):\n", queries, straight);
  std::printf("  SBL:         %5.1f ms median, success %d/%d  (target <= 50 ms)\n", 1e3 * median(t_sbl), ok_sbl, queries);
  std::printf("  RRT-Connect: %5.1f ms median, success %d/%d  (OMPL reference, same queries)\n", 1e3 * median(t_rrt),
              ok_rrt, queries);
  std::printf("  the %zu queries without a free straight edge: SBL %.1f ms median (max %.1f; CPU %.1f ms median, max %.1f),"
              " RRT-Connect %.1f ms median\n",
              h_sbl.size(), 1e3 * median(h_sbl), 1e3 * max_of(h_sbl), 1e3 * median(hc_sbl), 1e3 * max_of(hc_sbl),
              1e3 * median(h_rrt));
  std::printf("  configurations checked per query (median): SBL %.0f, RRT-Connect %.0f\n", median(c_sbl), median(c_rrt));
  std::printf("  ratio SBL / RRT-Connect: %.2f\n", median(t_sbl) / std::max(1e-12, median(t_rrt)));
  std::printf("smoothing the %d SBL plans (median raw length %.2f rad, smoothed %.2f rad):\n", ok_sbl, median(l_raw),
              median(l_smooth));
  std::printf("  Dijkstra-bisection (ours): %5.1f ms median, length x %.3f median, shorter %d/%d (target <= 50 ms)\n",
              1e3 * median(t_ours), median(r_ours), shorter, ok_sbl);
  std::printf("  ours on the queries without a free straight edge: %.1f ms median, %.1f ms max (CPU %.1f ms median, %.1f max),"
              " length x %.3f, %.2f rad median\n",
              1e3 * median(h_ours), 1e3 * max_of(h_ours), 1e3 * median(hc_ours), 1e3 * max_of(hc_ours), median(h_ratio),
              median(h_len));
  std::printf("  OMPL simplifyMax:          %5.1f ms median, length x %.3f median\n", 1e3 * median(t_ompl),
              median(r_ompl));
  std::printf("  time ratio ours / OMPL: %.2f\n", median(t_ours) / std::max(1e-12, median(t_ompl)));
  std::printf("peak-torque smoothing (§7.1) vs length smoothing, same %d plans (peak |tau|/limit with the leg in the air):\n"
              "  peak: length-smoothed %.3f median (max %.3f), torque-smoothed %.3f median (max %.3f);"
              " lower on %d, higher on %d, largest gain %.3f\n"
              "  length: %.2f rad vs %.2f rad median; time: %.1f ms vs %.1f ms median (max %.1f ms)\n",
              ok_sbl, median(tq_len_peak), max_of(tq_len_peak), median(tq_peak), max_of(tq_peak), tq_lower, tq_higher,
              max_of(tq_gain), median(tq_len_len), median(tq_len), 1e3 * median(tq_len_t), 1e3 * median(tq_t),
              1e3 * max_of(tq_t));
  std::printf("dense re-check (1e-3 rad, zero clearance) of %d raw + length- and torque-smoothed paths: %d in collision\n",
              3 * ok_sbl, dirty);
  return 0;
}
