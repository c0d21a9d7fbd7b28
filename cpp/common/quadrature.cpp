#include "ernest/common/quadrature.hpp"

#include <cmath>

#include "ernest/common/validation.hpp"

namespace ernest {

void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
  require_in_range("gauss_legendre", "n", n, 1, 1000);
  nodes.assign(n, 0.0);
  weights.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    // Newton on P_n from the asymptotic guess for the i-th root.
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) p0 = 1.0;
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-15) break;
    }
    nodes[i] = z;
    weights[i] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

}  // namespace ernest
