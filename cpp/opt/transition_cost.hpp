// The cost and constraints of the optimised gait transitions (seed 000 §4; internal to cpp/opt,
// used by transition_optimise.cpp): the decision vector (T, the end phase, interior waypoints),
// the curve through it (Bezier eqs 9–13, Linear/Spline waypoints), the kinematics integrated
// along it, cost eq 8 normalised with its analytic gradient, and the exact joint-limit rows
// (eqs 16–17) with their Jacobian.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "ernest/common/validation.hpp"
#include "ernest/opt/ode.hpp"
#include "ernest/opt/transition.hpp"

namespace ernest::opt::detail {


// Decision vector x = [T, sigma, interior waypoints joint-major], sigma = t1 + T - phi (the end
// phase of g2). With two waypoints (Bezier) x = [T, sigma] and the curve is eqs 9–13:
//   p0 = g1(t1), p3 = g2(sigma), p1 = p0 + (T/3) g1'(t1), p2 = p3 - (T/3) g2'(sigma).
// Eq 9 as printed has an exponent typo in its third term: the cubic Bernstein basis is
// 3 (1-s) s^2, not 3 (1-s)^3 s^2. Eqs 11–12 print 1/(3T): with q(t) = B(s), s = (t - t1)/T,
// dq/dt(t1) = B'(0)/T = 3 (p1 - p0)/T, so matching the gait velocity (eq 4) needs
// p1 - p0 = (T/3) g1'(t1) — the dimensions of 1/(3T) (rad s^-2) cannot even be a joint angle.
class TransitionCost {
 public:
  TransitionCost(const TransitionProblem& pb, Strategy strategy, const CostWeights& w,
                 const TransitionOptions& o, int waypoints)
      : pb_(pb), kin_(pb.rover), strategy_(strategy), w_(w), o_(o), nj_(pb.joints()),
        n_(waypoints), ds_(1.0 / (waypoints - 1)) {
    dim_ = 2 + nj_ * (n_ - 2);
    W_ = Eigen::MatrixXd::Zero(nj_, n_);
    gW_ = Eigen::MatrixXd::Zero(nj_, n_);
    m0_ = m1_ = v1_ = g2v_ = g2a_ = gm0_ = gm1_ = Eigen::VectorXd::Zero(nj_);
    for (int j = 0; j < nj_; ++j) {
      double q, dq, ddq;
      pb.from.evaluate(j, pb.t1, q, dq, ddq);
      W_(j, 0) = q;
      v1_[j] = dq;
    }
    seg_.resize(2 * (n_ - 1));
    for (int k = 0; k < n_ - 1; ++k) {
      spline_stencil(n_, k, 0.0, seg_[2 * k]);
      spline_stencil(n_, k, 1.0, seg_[2 * k + 1]);
    }
    // Two exact-limit rows per joint (position, velocity); Linear/Spline add eq 17's two rows per
    // pair of consecutive waypoints.
    m_ = 2 * nj_ + (strategy_ == Strategy::Bezier ? 0 : 2 * nj_ * (n_ - 1));
    const int P = n_ + 3;
    y_.assign(3 + 3 * P, 0.0);
  }

  int dimension() const { return dim_; }
  int constraint_count() const { return m_; }
  int index(int j, int i) const { return 2 + j * (n_ - 2) + (i - 1); }

  // x from (T, sigma) with the interior waypoints on the two-point Bezier through the gaits.
  std::vector<double> bezier_guess(double T, double sigma) {
    std::vector<double> x(dim_, 0.0);
    x[0] = T;
    x[1] = sigma;
    SplineStencil st;
    for (int j = 0; j < nj_; ++j) {
      double q2, v2, a2;
      pb_.to.evaluate(j, sigma, q2, v2, a2);
      for (int i = 1; i < n_ - 1; ++i) {
        spline_stencil(2, 0, i * ds_, st);
        x[index(j, i)] = st.w[0][1] * W_(j, 0) + st.w[0][2] * q2 +
                         st.start_tangent[0] * T * v1_[j] + st.end_tangent[0] * T * v2;
      }
    }
    return x;
  }

  void unpack(const double* x) {
    T_ = x[0];
    sigma_ = x[1];
    for (int j = 0; j < nj_; ++j) {
      double q, dq, ddq;
      pb_.to.evaluate(j, sigma_, q, dq, ddq);
      W_(j, n_ - 1) = q;
      g2v_[j] = dq;
      g2a_[j] = ddq;
      m0_[j] = T_ * v1_[j];
      m1_[j] = T_ * dq;
      for (int i = 1; i < n_ - 1; ++i) W_(j, i) = x[index(j, i)];
    }
  }

  double value(const SplineStencil& st, int d, int j) const {
    double acc = st.start_tangent[d] * m0_[j] + st.end_tangent[d] * m1_[j];
    for (int i = 0; i < 4; ++i) {
      const int idx = st.first + i;
      if (idx >= 0 && idx < n_) acc += st.w[d][i] * W_(j, idx);
    }
    return acc;
  }

  void add_grad(const SplineStencil& st, int d, int j, double g) {
    gm0_[j] += g * st.start_tangent[d];
    gm1_[j] += g * st.end_tangent[d];
    for (int i = 0; i < 4; ++i) {
      const int idx = st.first + i;
      if (idx >= 0 && idx < n_) gW_(j, idx) += g * st.w[d][i];
    }
  }

  void clear_grad() {
    gW_.setZero();
    gm0_.setZero();
    gm1_.setZero();
    gT_ = gSigma_ = 0.0;
  }

  // Chain rule from the sources (waypoints, end tangents, explicit T and sigma) to x.
  void chain(double* grad) const {
    double gT = gT_, gS = gSigma_;
    for (int j = 0; j < nj_; ++j) {
      gT += gm0_[j] * v1_[j] + gm1_[j] * g2v_[j];                   // m0 = T g1', m1 = T g2'
      gS += gW_(j, n_ - 1) * g2v_[j] + gm1_[j] * T_ * g2a_[j];     // W_{N-1} = g2(sigma)
      for (int i = 1; i < n_ - 1; ++i) grad[index(j, i)] = gW_(j, i);
    }
    grad[0] = gT;
    grad[1] = gS;
  }

  // Relative pose of the transition end w.r.t. its start, with sensitivities (dim 3 x (N+3):
  // explicit T, m0, m1, W_0..W_{N-1} of the steering joint) when `sens`.
  void integrate_transition(bool sens) {
    const int P = n_ + 3;
    const std::size_t size = sens ? 3 + 3 * P : 3;
    std::vector<double>& y = y_;
    y.assign(size, 0.0);
    const double V = pb_.rover.forward_speed, l = pb_.rover.l_x;
    auto rhs = [&](const std::vector<double>& s, std::vector<double>& dy, double t) {
      SplineStencil st;
      spline_stencil_at(n_, t, st);
      const double th = value(st, 0, kSteering), thp = value(st, 1, kSteering);
      const double h = 0.5 * th, tn = std::tan(h), sh = std::sin(h), ch = std::cos(h);
      const double psi = s[2], c = std::cos(psi), sn = std::sin(psi);
      // Reference-point velocity (asterix_model.hpp) in normalised time: d/ds = T d/dt.
      const double F = T_ * V * ch, L = 0.5 * l * thp * tn * sh;
      const double dX = F * c - L * sn, dY = F * sn + L * c;
      dy[0] = dX;
      dy[1] = dY;
      dy[2] = -T_ * V / l * tn;  // eq 22 averaged
      if (!sens) return;
      const double sec2 = 1.0 + tn * tn;
      const double dpsi_dth = -0.5 * T_ * V / l * sec2;
      const double dF_dth = -0.5 * T_ * V * sh;
      const double dL_dth = 0.25 * l * thp * sh * (sec2 + 1.0);
      const double dL_dthp = 0.5 * l * tn * sh;
      for (int p = 0; p < P; ++p) {
        const double spsi = s[3 + 3 * p + 2];
        dy[3 + 3 * p + 0] = -dY * spsi;  // dX'/dpsi = -Y'
        dy[3 + 3 * p + 1] = dX * spsi;   // dY'/dpsi = X'
        dy[3 + 3 * p + 2] = 0.0;
      }
      auto add = [&](int p, double dth, double dthp) {
        const double dF = dF_dth * dth, dL = dL_dth * dth + dL_dthp * dthp;
        dy[3 + 3 * p + 0] += dF * c - dL * sn;
        dy[3 + 3 * p + 1] += dF * sn + dL * c;
        dy[3 + 3 * p + 2] += dpsi_dth * dth;
      };
      // Explicit T (the V_r terms).
      dy[3 + 0] += V * ch * c;
      dy[3 + 1] += V * ch * sn;
      dy[3 + 2] += -V / l * tn;
      add(1, st.start_tangent[0], st.start_tangent[1]);
      add(2, st.end_tangent[0], st.end_tangent[1]);
      for (int i = 0; i < 4; ++i) {
        const int idx = st.first + i;
        if (idx >= 0 && idx < n_) add(3 + idx, st.w[0][i], st.w[1][i]);
      }
    };
    detail::integrate_checked(rhs, y, 0.0, 1.0, o_.integration, "transition kinematics", n_ - 1);
  }

  double objective(const double* x, double* grad) {
    unpack(x);
    if (grad) clear_grad();
    const bool g = grad != nullptr;
    // Duration term.
    c_T_ = T_ / o_.duration_scale;
    if (g) gT_ += w_.duration / o_.duration_scale;
    // Acceleration term: (1/T) ∫ sum_j (q̈_j / a)^2 dt = ∫_0^1 sum_j (q''_j / (T^2 a))^2 ds, exact
    // for piecewise-linear q'' (cubic segments).
    const double a2 = o_.acceleration_scale * o_.acceleration_scale;
    const double scale = 1.0 / (T_ * T_ * T_ * T_ * a2);
    double sum = 0.0;
    for (int j = 0; j < nj_; ++j) {
      for (int k = 0; k < n_ - 1; ++k) {
        const SplineStencil& s0 = seg_[2 * k];
        const SplineStencil& s1 = seg_[2 * k + 1];
        const double a0 = value(s0, 2, j), a1 = value(s1, 2, j);
        sum += ds_ / 3.0 * (a0 * a0 + a0 * a1 + a1 * a1);
        if (g) {
          add_grad(s0, 2, j, w_.acceleration * scale * ds_ / 3.0 * (2.0 * a0 + a1));
          add_grad(s1, 2, j, w_.acceleration * scale * ds_ / 3.0 * (a0 + 2.0 * a1));
        }
      }
    }
    c_A_ = sum * scale;
    if (g) gT_ += -4.0 * w_.acceleration * c_A_ / T_;
    // Workspace deviation (eqs 6–7, 20–23).
    integrate_transition(g);
    const Pose2 dq{y_[0], y_[1], y_[2]};
    const double a = sigma_ - T_, b = sigma_;
    const Pose2 dg = gait_pose(kin_, pb_.to, a, b, Pose2{}, o_.integration);
    const double ex = dq.x - dg.x, ey = dq.y - dg.y, ep = dq.heading - dg.heading;
    const double L2 = o_.position_scale * o_.position_scale;
    const double H2 = o_.heading_scale * o_.heading_scale;
    c_D_ = (ex * ex + ey * ey) / L2 + ep * ep / H2;
    if (g) {
      const double de[3] = {2.0 * ex / L2, 2.0 * ey / L2, 2.0 * ep / H2};
      const int P = n_ + 3;
      auto sens = [&](int p) {
        return w_.deviation * (de[0] * y_[3 + 3 * p] + de[1] * y_[3 + 3 * p + 1] +
                               de[2] * y_[3 + 3 * p + 2]);
      };
      gT_ += sens(0);
      gm0_[kSteering] += sens(1);
      gm1_[kSteering] += sens(2);
      for (int i = 0; i < P - 3; ++i) gW_(kSteering, i) += sens(3 + i);
      // Target D_g(a, b): dD/db = pose rate at b (in a's frame), dD/da = -v_a - w_a J p, -w_a.
      double ta, ra, aa, tb, rb, ab;
      pb_.to.evaluate(kSteering, a, ta, ra, aa);
      pb_.to.evaluate(kSteering, b, tb, rb, ab);
      double vxa, vya, wa, vxb, vyb, wb;
      kin_.pose_rate(0.0, ta, ra, vxa, vya, wa);
      kin_.pose_rate(dg.heading, tb, rb, vxb, vyb, wb);
      const double dDa[3] = {-vxa + wa * dg.y, -vya - wa * dg.x, -wa};
      const double dDb[3] = {vxb, vyb, wb};
      for (int c = 0; c < 3; ++c) {
        gT_ -= w_.deviation * de[c] * (-dDa[c]);
        gSigma_ -= w_.deviation * de[c] * (dDa[c] + dDb[c]);
      }
    }
    // Linear cost (eqs 18–19), Linear strategy only.
    c_L_ = 0.0;
    if (strategy_ == Strategy::Linear) {
      const double norm = 1.0 / (n_ * o_.linear_scale * o_.linear_scale);
      for (int j = 0; j < nj_; ++j) {
        const double start = W_(j, 0), span = W_(j, n_ - 1) - start;
        double g_end = 0.0;
        for (int i = 1; i < n_ - 1; ++i) {
          const double si = i * ds_;
          const double r = W_(j, i) - (start + span * si);
          c_L_ += norm * r * r;
          if (g) {
            gW_(j, i) += w_.linear * 2.0 * norm * r;
            g_end -= w_.linear * 2.0 * norm * r * si;
          }
        }
        if (g) gW_(j, n_ - 1) += g_end;
      }
    }
    const double f = w_.duration * c_T_ + w_.acceleration * c_A_ + w_.deviation * c_D_ +
                     (strategy_ == Strategy::Linear ? w_.linear * c_L_ : 0.0);
    if (g) chain(grad);
    return f;
  }

  // Inequality constraints (<= 0).
  // Rows 0 .. 2 nj - 1, every strategy: eqs 16–17 EXACTLY along the whole curve, not at samples:
  //   max_t |q_j(t)| / P_j - 1 <= 0   and   max_t |q̇_j(t)| / V_j - 1 <= 0,
  // the maxima taken over the exact candidates of each cubic segment (its ends, the roots of its
  // quadratic q', the vertex of q'; cubic_extrema). A cubic Bezier (eqs 9–13) has a quadratic
  // velocity, so its peak between the ends is at the vertex; the position peaks where q' = 0.
  // At every candidate the derivative along s vanishes (or s is a segment end, fixed), so the
  // gradient of the maximum is the partial gradient at the fixed candidate s (envelope theorem);
  // the row is Lipschitz and smooth wherever one candidate is the strict maximum.
  // Linear/Spline then add eq 17 between consecutive waypoints, linear in (theta, T):
  //   ±(θ_t − θ_{t−1}) / (θ̇_max ds) − T <= 0   (ds = 1/(N−1), Δt = T ds),
  // implied by the exact rows (a chord's slope is the mean velocity over its segment) but kept as
  // the paper's linear constraints. Eq 16 also bounds the interior waypoints (box bounds).
  void constraints(const double* x, double* c, double* jac) {
    unpack(x);
    if (jac) std::fill(jac, jac + static_cast<std::size_t>(m_) * dim_, 0.0);
    int row = 0;
    for (int j = 0; j < nj_; ++j) {
      const Peak pos = peak(j, 0), vel = peak(j, 1);
      const double P = pb_.position_limit[j], V = pb_.velocity_limit[j];
      const double vq = std::abs(pos.value), vv = std::abs(vel.value);
      c[row] = vq / P - (1.0 - o_.limit_margin);
      c[row + 1] = vv / (V * T_) - (1.0 - o_.limit_margin);
      if (jac) {
        SplineStencil st;
        clear_grad();
        spline_stencil(n_, pos.segment, pos.u, st);
        add_grad(st, 0, j, std::copysign(1.0 / P, pos.value));
        chain(jac + static_cast<std::size_t>(row) * dim_);
        clear_grad();
        spline_stencil(n_, vel.segment, vel.u, st);
        add_grad(st, 1, j, std::copysign(1.0 / (V * T_), vel.value));
        gT_ += -vv / (V * T_ * T_);
        chain(jac + static_cast<std::size_t>(row + 1) * dim_);
      }
      row += 2;
    }
    if (strategy_ == Strategy::Bezier) return;
    for (int j = 0; j < nj_; ++j) {
      const double k = 1.0 / (pb_.velocity_limit[j] * ds_);
      for (int i = 1; i < n_; ++i) {
        const double d = W_(j, i) - W_(j, i - 1);
        for (int r = 0; r < 2; ++r) {
          const double sign = r == 0 ? 1.0 : -1.0;
          c[row] = sign * d * k - T_;
          if (jac) {
            double* J = jac + static_cast<std::size_t>(row) * dim_;
            J[0] = -1.0;
            if (i == n_ - 1)
              J[1] += sign * k * g2v_[j];
            else
              J[index(j, i)] += sign * k;
            if (i - 1 >= 1) J[index(j, i - 1)] -= sign * k;
          }
          ++row;
        }
      }
    }
  }

  // Exact normalised violation of the joint limits (eqs 16–17) along the curve at x: the largest
  // of the exact rows of constraints() (<= 0 when feasible). This is what the result reports.
  double limit_violation(const std::vector<double>& x) {
    unpack(x.data());
    double worst = -kInf;
    for (int j = 0; j < nj_; ++j) {
      const double q = std::abs(peak(j, 0).value), v = std::abs(peak(j, 1).value);
      worst = std::max({worst, q / pb_.position_limit[j] - 1.0,
                        v / (pb_.velocity_limit[j] * T_) - 1.0});
    }
    return std::isfinite(worst) ? worst : kInf;
  }

  // Feasibility of x: the exact rows (with the margin), eq 17's rows (normalised by T), bounds.
  double max_violation(const std::vector<double>& x, const std::vector<double>& lo,
                       const std::vector<double>& hi) {
    std::vector<double> c(m_);
    constraints(x.data(), c.data(), nullptr);
    double worst = -kInf;
    for (int r = 0; r < 2 * nj_; ++r) worst = std::max(worst, std::isfinite(c[r]) ? c[r] : kInf);
    for (int r = 2 * nj_; r < m_; ++r) worst = std::max(worst, std::isfinite(c[r]) ? c[r] / T_ : kInf);
    for (int i = 0; i < dim_; ++i) {
      worst = std::max(worst, lo[i] - x[i]);
      worst = std::max(worst, x[i] - hi[i]);
    }
    return worst;
  }

  TransitionResult build(const std::vector<double>& x, double f) {
    unpack(x.data());
    TransitionResult r;
    r.requested = r.strategy = strategy_;
    r.weights = w_;
    r.t1 = pb_.t1;
    r.duration = T_;
    r.end_phase = sigma_;
    r.phase_shift = pb_.t1 + T_ - sigma_;  // sigma = t1 + T - phi (eq 3)
    r.spline = SplineTrajectory(W_, v1_, g2v_, T_);
    r.cost = f;
    r.cost_duration = c_T_;
    r.cost_acceleration = c_A_;
    r.cost_deviation = c_D_;
    r.cost_linear = c_L_;
    return r;
  }

  // Where |d-th derivative along s| of joint j peaks over the curve (d = 0 position, 1 velocity):
  // the candidate with the largest magnitude among every segment's ends and interior extrema.
  struct Peak {
    double value = 0.0;  ///< signed value at the peak (d/ds units for d = 1)
    int segment = 0;
    double u = 0.0;
  };
  Peak peak(int j, int d) const {
    Peak best;
    best.value = value(seg_[0], d, j);
    SplineStencil st;
    auto consider = [&](int k, double u, double v) {
      if (std::abs(v) > std::abs(best.value)) best = {v, k, u};
    };
    for (int k = 0; k < n_ - 1; ++k) {
      const SplineStencil& s0 = seg_[2 * k];
      const SplineStencil& s1 = seg_[2 * k + 1];
      consider(k, 1.0, value(s1, d, j));
      // Derivatives along the segment's local u are ds^d times those along s.
      const CubicExtrema e = cubic_extrema(ds_ * value(s0, 1, j), ds_ * ds_ * value(s0, 2, j),
                                           ds_ * ds_ * value(s1, 2, j));
      if (d == 0) {
        for (int r = 0; r < e.roots; ++r) {
          spline_stencil(n_, k, e.root[r], st);
          consider(k, e.root[r], value(st, 0, j));
        }
      } else if (e.has_vertex) {
        spline_stencil(n_, k, e.vertex, st);
        consider(k, e.vertex, value(st, 1, j));
      }
    }
    return best;
  }

 private:
  const TransitionProblem& pb_;
  AsterixKinematics kin_;
  Strategy strategy_;
  CostWeights w_;
  TransitionOptions o_;
  int nj_, n_, dim_ = 0, m_ = 0;
  double ds_;
  double T_ = 1.0, sigma_ = 0.0;
  Eigen::MatrixXd W_, gW_;
  Eigen::VectorXd m0_, m1_, v1_, g2v_, g2a_, gm0_, gm1_;
  double gT_ = 0.0, gSigma_ = 0.0;
  double c_T_ = 0.0, c_A_ = 0.0, c_D_ = 0.0, c_L_ = 0.0;
  std::vector<SplineStencil> seg_;
  std::vector<double> y_;
};

}  // namespace ernest::opt::detail
