// Dijkstra–bisection smoothing for the smallest peak joint torque (seed 003 §7.1, §3.4.2); see
// torque_smoothing.hpp.
#include "ernest/footfall/torque_smoothing.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"
#include "ernest/footfall/leg_planner.hpp"

namespace ernest::footfall {

namespace {

enum : char { kUnchecked = 0, kFree = 1, kBlocked = 2 };

// What is known of the edge a < b: collision state and exact peak (NaN: not evaluated).
struct Edges {
  int n = 0;
  std::vector<char> state;
  std::vector<double> peak;
  explicit Edges(int nodes) : n(nodes), state(std::size_t(nodes) * nodes, kUnchecked),
                              peak(std::size_t(nodes) * nodes, std::numeric_limits<double>::quiet_NaN()) {}
  std::size_t at(int a, int b) const { return std::size_t(std::min(a, b)) * n + std::max(a, b); }
};

struct Label {
  double peak = std::numeric_limits<double>::infinity(), length = std::numeric_limits<double>::infinity();
};

class Search {
 public:
  Search(LegCollisionChecker& checker, StanceTorques& torques, const SmoothingOptions& o)
      : checker_(checker), torques_(torques), o_(o) {}
  long checks = 0, evaluations = 0;

  bool better(const Label& a, const Label& b) const {
    if (a.peak < b.peak - o_.torque_tolerance) return true;
    if (a.peak > b.peak + o_.torque_tolerance) return false;
    return a.length < b.length;
  }

  // Lexicographic (bottleneck, length) Dijkstra over every unblocked shortcut, dense O(n^2).
  std::vector<int> dijkstra(const Eigen::MatrixXd& nodes, const std::vector<double>& node_peak, const Edges& e,
                            Label& best) const {
    const int n = static_cast<int>(nodes.cols());
    std::vector<Label> label(n);
    std::vector<int> pred(n, -1);
    std::vector<char> done(n, 0);
    label[0] = {node_peak[0], 0.0};
    for (int it = 0; it < n; ++it) {
      int u = -1;
      for (int v = 0; v < n; ++v)
        if (!done[v] && std::isfinite(label[v].length) && (u < 0 || better(label[v], label[u]))) u = v;
      if (u < 0 || u == n - 1) break;
      done[u] = 1;
      for (int v = 0; v < n; ++v) {
        if (done[v] || v == u || e.state[e.at(u, v)] == kBlocked) continue;
        const double exact = e.peak[e.at(u, v)];
        const double edge_peak = std::isnan(exact) ? std::max(node_peak[u], node_peak[v]) : exact;
        const Label cand{std::max(label[u].peak, edge_peak), label[u].length + (nodes.col(v) - nodes.col(u)).norm()};
        if (better(cand, label[v])) label[v] = cand, pred[v] = u;
      }
    }
    best = label[n - 1];
    std::vector<int> route{n - 1};
    while (route.back() != 0) route.push_back(pred[route.back()]);
    std::reverse(route.begin(), route.end());
    return route;
  }

  // Dijkstra until every edge of its answer is collision-free and exactly evaluated.
  std::vector<int> shortest(const Eigen::MatrixXd& nodes, const std::vector<double>& node_peak, Edges& e, Label& best) {
    for (;;) {
      const std::vector<int> route = dijkstra(nodes, node_peak, e, best);
      bool settled = true;
      for (std::size_t k = 0; k + 1 < route.size() && settled; ++k) {
        const int a = route[k], b = route[k + 1];
        const std::size_t i = e.at(a, b);
        if (e.state[i] == kUnchecked) {
          ++checks;
          e.state[i] = checker_.motion_valid(nodes.col(std::min(a, b)), nodes.col(std::max(a, b)), o_.epsilon) ? kFree : kBlocked;
          if (e.state[i] == kBlocked) settled = false;
        }
        if (settled && std::isnan(e.peak[i])) {
          ++evaluations;
          e.peak[i] = torques_.lifted_segment(nodes.col(std::min(a, b)), nodes.col(std::max(a, b)), o_.torque_resolution).saturation;
          if (e.peak[i] > std::max(node_peak[a], node_peak[b])) settled = false;  // the bound was low
        }
      }
      if (settled) return route;
    }
  }

 private:
  LegCollisionChecker& checker_;
  StanceTorques& torques_;
  const SmoothingOptions& o_;
};

}  // namespace

SmoothingResult smooth_path_for_torque(LegCollisionChecker& checker, StanceTorques& torques,
                                       const Eigen::Ref<const Eigen::MatrixXd>& path, const SmoothingOptions& options) {
  options.validate();
  require(path.rows() == checker.model().joints_per_leg() && path.cols() >= 2 && path.allFinite(),
          "smooth_path_for_torque: path must be finite, joints x waypoints (at least two)");
  require(checker.leg() == torques.leg(), "smooth_path_for_torque: the checker and the torques are for different legs");
  const auto t0 = std::chrono::steady_clock::now();
  SmoothingResult r;
  r.initial_length = path_length(path);
  r.initial_peak_saturation = torques.lifted_path(path, options.torque_resolution).saturation;
  Eigen::MatrixXd nodes = path;
  std::vector<double> node_peak(nodes.cols());
  for (Eigen::Index i = 0; i < nodes.cols(); ++i) node_peak[i] = torques.lifted(nodes.col(i)).saturation;
  Edges e(static_cast<int>(nodes.cols()));
  for (int i = 0; i + 1 < e.n; ++i) e.state[e.at(i, i + 1)] = kFree;  // the plan's edges
  Search search(checker, torques, options);
  Label current{r.initial_peak_saturation, r.initial_length};
  for (r.iterations = 1; r.iterations <= options.max_iterations; ++r.iterations) {
    poll_interrupt();  // Ctrl-C between iterations (common/interrupt.hpp)
    Label best;
    const std::vector<int> route = search.shortest(nodes, node_peak, e, best);
    const int m = static_cast<int>(route.size());
    Eigen::MatrixXd simplified(nodes.rows(), m);
    std::vector<double> simplified_peak(m);
    for (int k = 0; k < m; ++k) simplified.col(k) = nodes.col(route[k]), simplified_peak[k] = node_peak[route[k]];
    const bool done = current.peak - best.peak <= options.torque_tolerance &&
                      current.length - best.length < options.min_improvement * current.length;
    current = best;
    nodes = std::move(simplified);
    node_peak = std::move(simplified_peak);
    if (done || 2 * m - 1 > options.max_nodes) break;
    // Fig. 4 step 3: bisect every edge; old node k is new node 2k, the states and peaks carry over.
    const int b = 2 * m - 1;
    Eigen::MatrixXd bisected(nodes.rows(), b);
    std::vector<double> bisected_peak(b);
    Edges next(b);
    for (int k = 0; k < m; ++k) {
      bisected.col(2 * k) = nodes.col(k);
      bisected_peak[2 * k] = node_peak[k];
      if (k + 1 < m) {
        bisected.col(2 * k + 1) = 0.5 * (nodes.col(k) + nodes.col(k + 1));
        bisected_peak[2 * k + 1] = torques.lifted(bisected.col(2 * k + 1)).saturation;
        next.state[next.at(2 * k, 2 * k + 1)] = next.state[next.at(2 * k + 1, 2 * k + 2)] = kFree;
      }
      for (int l = k + 1; l < m; ++l) {
        next.state[next.at(2 * k, 2 * l)] = e.state[e.at(route[k], route[l])];
        next.peak[next.at(2 * k, 2 * l)] = e.peak[e.at(route[k], route[l])];
      }
    }
    nodes = std::move(bisected);
    node_peak = std::move(bisected_peak);
    e = std::move(next);
  }
  r.iterations = std::min(r.iterations, options.max_iterations);
  r.edge_checks = search.checks;
  r.path = std::move(nodes);
  r.length = path_length(r.path);
  r.peak_saturation = torques.lifted_path(r.path, options.torque_resolution).saturation;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace ernest::footfall
