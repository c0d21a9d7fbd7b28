// Quaternions as ODE stores them (ode_quaternion.hpp).
#include "ernest/solver/ode_quaternion.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace ernest::solver {

namespace {

// A quick test for that fixed point without the round trip through ODE: its normalisation as ODE
// 0.16 writes it (dxSafeNormalize4: (q0² + q1² + q2²) + q3², times 1 / sqrt). It is only trusted
// after it agreed with ODE on 4096 random unit quaternions at start-up, so a different ODE build
// just takes the slow path.
double sum_of_squares(const dReal* q) {
  return q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
}

// 1 / sqrt(s) for the sums of squares of unit quaternions as they come (within 16 doubles of 1:
// s = 1 + k 2^-53 below 1, 1 + k 2^-52 above), by s's bits: the same values, computed once, so
// that the test and its nudges (fixed_point_quaternion) spend no square root and no division.
constexpr int kNearOne = 16;
std::int64_t bits_of(double x) {
  std::int64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

double inverse_sqrt(double s) {
  static const auto table = [] {
    std::array<double, 2 * kNearOne + 1> t{};
    for (int k = -kNearOne; k <= kNearOne; ++k) {
      const std::int64_t b = bits_of(1.0) + k;
      double s_k;
      std::memcpy(&s_k, &b, sizeof s_k);
      t[k + kNearOne] = 1.0 / std::sqrt(s_k);
    }
    return t;
  }();
  const std::int64_t k = bits_of(s) - bits_of(1.0);
  if (k >= -kNearOne && k <= kNearOne) return table[k + kNearOne];
  return 1.0 / std::sqrt(s);
}

bool normalise_is_identity(const dReal* q) {
  const double l = inverse_sqrt(sum_of_squares(q));
  return q[0] * l == q[0] && q[1] * l == q[1] && q[2] * l == q[2] && q[3] * l == q[3];
}

bool quick_fixed_point_test_agrees_with_ode() {
  dWorldID w = dWorldCreate();
  dBodyID b = dBodyCreate(w);
  bool agree = true;
  std::uint64_t x = 0x9E3779B97F4A7C15ull;  // xorshift: a fixed, reproducible sample
  for (int k = 0; k < 4096 && agree; ++k) {
    dQuaternion q;
    for (double& c : q) {
      x ^= x << 13, x ^= x >> 7, x ^= x << 17;
      c = (static_cast<double>(x >> 11) * 0x1.0p-53 - 0.5) * (k % 3 == 0 ? 1e-3 : 1.0);
    }
    dBodySetQuaternion(b, q);  // normalised by ODE
    const dReal* n = dBodyGetQuaternion(b);
    dQuaternion c = {n[0], n[1], n[2], n[3]};
    // (fixed_point_quaternion's premise: ODE's normalisation of q is this)
    const double l = 1.0 / std::sqrt(sum_of_squares(q));
    for (int i = 0; i < 4 && agree; ++i) agree = q[i] * l == c[i];
    dBodySetQuaternion(b, c);  // a fixed point if and only if this returns it unchanged
    const bool ode_says = std::memcmp(c, dBodyGetQuaternion(b), sizeof c) == 0;
    agree = agree && ode_says == normalise_is_identity(c);
  }
  dBodyDestroy(b);
  dWorldDestroy(w);
  return agree;
}

bool quick_test_trusted() {
  static const bool quick = quick_fixed_point_test_agrees_with_ode();
  return quick;
}

constexpr int kNudge[] = {0, 1, -1, 2, -2, 3, -3, 4, -4};  // ulps of the largest component

int largest(const dReal* q) {
  int big = 0;
  for (int k = 1; k < 4; ++k)
    if (std::abs(q[k]) > std::abs(q[big])) big = k;
  return big;
}

// base with its largest component moved n ulps up (n > 0) or down: std::nextafter n times,
// here on the bits (|c[big]| >= 1/2 for a unit quaternion, so never zero, and the doubles of one
// sign are ordered as their bits, across binades too).
void nudge(const dReal* base, int big, int n, dReal* c) {
  for (int k = 0; k < 4; ++k) c[k] = base[k];
  if (n == 0) return;
  if (base[big] == 0.0 || !std::isfinite(base[big])) {  // (not from a normalised quaternion)
    for (int u = 0; u < std::abs(n); ++u) c[big] = std::nextafter(c[big], n > 0 ? 2.0 : -2.0);
    return;
  }
  std::uint64_t bits;
  std::memcpy(&bits, &base[big], sizeof bits);
  const bool away_from_zero = (base[big] > 0.0) == (n > 0);
  const auto steps = static_cast<std::uint64_t>(std::abs(n));
  bits = away_from_zero ? bits + steps : bits - steps;
  std::memcpy(&c[big], &bits, sizeof bits);
}

}  // namespace

void canonicalise_quaternion(dBodyID b) {
  const bool quick = quick_test_trusted();
  const dReal* q0 = dBodyGetQuaternion(b);
  if (quick && normalise_is_identity(q0)) return;  // already a fixed point: nothing to do
  const dQuaternion base = {q0[0], q0[1], q0[2], q0[3]};
  const int big = largest(base);
  for (int n : kNudge) {
    dQuaternion c;
    nudge(base, big, n, c);
    dBodySetQuaternion(b, c);
    const dReal* q = dBodyGetQuaternion(b);
    if (std::memcmp(c, q, sizeof(dQuaternion)) == 0) return;
  }
  // No fixed point within 4 ulps (never seen): keep ODE's normalised value.
}

bool fixed_point_quaternion(const dReal* q, dReal out[4]) {
  if (!quick_test_trusted()) return false;
  const double sum = sum_of_squares(q);
  if (!(sum > 0.0) || !std::isfinite(sum)) return false;  // ODE's fault path, or NaN: ODE decides
  const double l = 1.0 / std::sqrt(sum);
  const dQuaternion base = {q[0] * l, q[1] * l, q[2] * l, q[3] * l};  // dBodySetQuaternion's
  if (normalise_is_identity(base)) {
    for (int k = 0; k < 4; ++k) out[k] = base[k];
    return true;
  }
  const int big = largest(base);
  for (int n : kNudge) {
    if (n == 0) continue;  // (the base: just tested)
    nudge(base, big, n, out);
    if (normalise_is_identity(out)) return true;
  }
  return false;
}

}  // namespace ernest::solver
