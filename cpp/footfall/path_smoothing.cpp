#include "ernest/footfall/path_smoothing.hpp"
#include "ernest/common/interrupt.hpp"

#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/dijkstra_shortest_paths.hpp>

#include <algorithm>
#include <chrono>
#include <vector>

#include "ernest/common/validation.hpp"
#include "ernest/footfall/leg_planner.hpp"

namespace ernest::footfall {

void SmoothingOptions::validate() const {
  const char* o = "SmoothingOptions";
  require_in_range(o, "epsilon", epsilon, 1e-5, 1.0);
  require_in_range(o, "min_improvement", min_improvement, 0.0, 1.0);
  require_in_range(o, "max_iterations", max_iterations, 1, 1000);
  require_in_range(o, "max_nodes", max_nodes, 2, 100000);
  require_in_range(o, "torque_resolution", torque_resolution, 1e-3, 1.0);
  require_in_range(o, "torque_tolerance", torque_tolerance, 0.0, 1.0);
}

namespace {

using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property,
                                    boost::property<boost::edge_weight_t, double>>;

// What is known of the edge between nodes a < b, kept across the rounds (a node keeps its
// configuration when the path is simplified or bisected, so an edge checked in one round is not
// checked again in the next).
enum : char { kUnchecked = 0, kFree = 1, kBlocked = 2 };

// Lazy Dijkstra over every shortcut between the nodes (Fig. 4, steps 2 and 4): returns the node
// indices of the shortest collision-free path from the first node to the last. `known` (n × n,
// entry a * n + b for a < b) holds the edges' states; blocked edges stay out of the graph.
std::vector<int> shortest(LegCollisionChecker& checker, const Eigen::MatrixXd& nodes, double epsilon,
                          std::vector<char>& known, long& checks) {
  const int n = static_cast<int>(nodes.cols());
  Graph g(n);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (known[std::size_t(i) * n + j] != kBlocked) boost::add_edge(i, j, (nodes.col(j) - nodes.col(i)).norm(), g);
  std::vector<std::size_t> pred(n);
  std::vector<double> dist(n);
  for (;;) {
    boost::dijkstra_shortest_paths(g, 0, boost::predecessor_map(pred.data()).distance_map(dist.data()));
    std::vector<int> route{n - 1};
    while (route.back() != 0) route.push_back(static_cast<int>(pred[route.back()]));
    std::reverse(route.begin(), route.end());
    bool free = true;
    // Early exit: the first blocked edge of the answer ends this pass (Dijkstra then answers
    // without it); the edges after it may never be on a shortest path again.
    for (std::size_t k = 0; k + 1 < route.size() && free; ++k) {
      const int a = std::min(route[k], route[k + 1]), b = std::max(route[k], route[k + 1]);
      char& state = known[std::size_t(a) * n + b];
      if (state != kUnchecked) continue;
      ++checks;
      if (checker.motion_valid(nodes.col(a), nodes.col(b), epsilon)) {
        state = kFree;
      } else {
        state = kBlocked;
        boost::remove_edge(a, b, g);
        free = false;
      }
    }
    if (free) return route;
  }
}

}  // namespace

SmoothingResult smooth_path(LegCollisionChecker& checker, const Eigen::Ref<const Eigen::MatrixXd>& path,
                            const SmoothingOptions& options) {
  options.validate();
  require(path.rows() == checker.model().joints_per_leg() && path.cols() >= 2 && path.allFinite(),
          "smooth_path: path must be finite, joints x waypoints (at least two)");
  const auto t0 = std::chrono::steady_clock::now();
  SmoothingResult r;
  r.initial_length = path_length(path);
  Eigen::MatrixXd nodes = path;
  double length = r.initial_length;
  std::vector<char> known(std::size_t(nodes.cols()) * nodes.cols(), kUnchecked);
  for (Eigen::Index i = 0; i + 1 < nodes.cols(); ++i) known[std::size_t(i) * nodes.cols() + i + 1] = kFree;  // the plan's edges
  for (r.iterations = 1; r.iterations <= options.max_iterations; ++r.iterations) {
    poll_interrupt();  // Ctrl-C between iterations (common/interrupt.hpp)
    const std::vector<int> route = shortest(checker, nodes, options.epsilon, known, r.edge_checks);
    const Eigen::Index n = nodes.cols(), m = static_cast<Eigen::Index>(route.size());
    Eigen::MatrixXd simplified(nodes.rows(), m);
    for (Eigen::Index k = 0; k < m; ++k) simplified.col(k) = nodes.col(route[std::size_t(k)]);
    const double shorter = path_length(simplified);
    const bool done = length - shorter < options.min_improvement * length;
    nodes = std::move(simplified);
    length = shorter;
    if (done || 2 * m - 1 > options.max_nodes) break;
    // Fig. 4 step 3: bisect every edge (its midpoint lies on a checked edge). The states carry
    // over: old node k is new node 2k; the halves of a route edge are free.
    Eigen::MatrixXd bisected(nodes.rows(), 2 * m - 1);
    const Eigen::Index b = 2 * m - 1;
    std::vector<char> next(std::size_t(b) * b, kUnchecked);
    for (Eigen::Index k = 0; k < m; ++k) {
      bisected.col(2 * k) = nodes.col(k);
      if (k + 1 < m) {
        bisected.col(2 * k + 1) = 0.5 * (nodes.col(k) + nodes.col(k + 1));
        next[std::size_t(2 * k) * b + 2 * k + 1] = next[std::size_t(2 * k + 1) * b + 2 * k + 2] = kFree;
      }
      for (Eigen::Index l = k + 1; l < m; ++l) {
        const int i = std::min(route[std::size_t(k)], route[std::size_t(l)]), j = std::max(route[std::size_t(k)], route[std::size_t(l)]);
        next[std::size_t(2 * k) * b + 2 * l] = known[std::size_t(i) * n + j];
      }
    }
    nodes = std::move(bisected);
    known = std::move(next);
  }
  r.iterations = std::min(r.iterations, options.max_iterations);
  r.path = std::move(nodes);
  r.length = length;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace ernest::footfall
