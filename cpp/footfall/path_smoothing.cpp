#include "ernest/footfall/path_smoothing.hpp"

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
}

namespace {

using Graph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property,
                                    boost::property<boost::edge_weight_t, double>>;

// Lazy Dijkstra over every shortcut between the nodes (Fig. 4, steps 2 and 4): returns the node
// indices of the shortest collision-free path from the first node to the last.
std::vector<int> shortest(LegCollisionChecker& checker, const Eigen::MatrixXd& nodes, double epsilon,
                          long& checks) {
  const int n = static_cast<int>(nodes.cols());
  Graph g(n);
  std::vector<char> known(std::size_t(n) * n, 0);  // 0 unchecked, 1 free (checked or a path edge)
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) boost::add_edge(i, j, (nodes.col(j) - nodes.col(i)).norm(), g);
  for (int i = 0; i + 1 < n; ++i) known[std::size_t(i) * n + i + 1] = 1;  // the path's own edges
  std::vector<std::size_t> pred(n);
  std::vector<double> dist(n);
  for (;;) {
    boost::dijkstra_shortest_paths(g, 0, boost::predecessor_map(pred.data()).distance_map(dist.data()));
    std::vector<int> route{n - 1};
    while (route.back() != 0) route.push_back(static_cast<int>(pred[route.back()]));
    std::reverse(route.begin(), route.end());
    bool free = true;
    for (std::size_t k = 0; k + 1 < route.size(); ++k) {
      const int a = std::min(route[k], route[k + 1]), b = std::max(route[k], route[k + 1]);
      char& state = known[std::size_t(a) * n + b];
      if (state) continue;
      ++checks;
      if (checker.motion_valid(nodes.col(a), nodes.col(b), epsilon)) {
        state = 1;
      } else {
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
  for (r.iterations = 1; r.iterations <= options.max_iterations; ++r.iterations) {
    const std::vector<int> route = shortest(checker, nodes, options.epsilon, r.edge_checks);
    Eigen::MatrixXd simplified(nodes.rows(), static_cast<Eigen::Index>(route.size()));
    for (std::size_t k = 0; k < route.size(); ++k) simplified.col(Eigen::Index(k)) = nodes.col(route[k]);
    const double shorter = path_length(simplified);
    const bool done = length - shorter < options.min_improvement * length;
    nodes = std::move(simplified);
    length = shorter;
    if (done || 2 * nodes.cols() - 1 > options.max_nodes) break;
    // Fig. 4 step 3: bisect every edge (its midpoint lies on a checked edge).
    Eigen::MatrixXd bisected(nodes.rows(), 2 * nodes.cols() - 1);
    for (Eigen::Index k = 0; k + 1 < nodes.cols(); ++k) {
      bisected.col(2 * k) = nodes.col(k);
      bisected.col(2 * k + 1) = 0.5 * (nodes.col(k) + nodes.col(k + 1));
    }
    bisected.col(bisected.cols() - 1) = nodes.col(nodes.cols() - 1);
    nodes = std::move(bisected);
  }
  r.iterations = std::min(r.iterations, options.max_iterations);
  r.path = std::move(nodes);
  r.length = length;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace ernest::footfall
