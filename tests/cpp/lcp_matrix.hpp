// A symmetric matrix as ODE's LCP solver receives it, and the same densely, shared by the sparse
// LDLᵀ tests (test_dynamics_solver.cpp, test_dynamics_ldlt.cpp).
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace ernest::testing {

/// a: the lower triangle, row-major, row stride `stride` (ODE's dPAD(n)), junk above the
/// diagonal; dense: the whole matrix.
struct LcpMatrix {
  int n = 0, stride = 0;
  std::vector<double> a;
  Eigen::MatrixXd dense;
};

}  // namespace ernest::testing
