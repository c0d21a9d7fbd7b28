// Gauss–Legendre rules, shared by the soil model, its tests and benchmarks.
#pragma once

#include <vector>

namespace ernest {

/// n-point Gauss–Legendre nodes and weights on [-1, 1] (exact for polynomials of degree 2n - 1).
void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights);

}  // namespace ernest
