// Our own step of the rover's island: what ODE 0.16's dWorldStep (ode/src/step.cpp, dxStepIsland)
// computes for the rover's six bodies and the joint types it uses, built for this structure and
// solved through the sparse solver (solve_sparse, sparse_lcp.hpp) directly (used by cpp/dynamics).
//
// Why (benchmarks/RESULTS.md, "Where a step goes"): a time profile put ODE's own
// part of dWorldStep at ~45 % of a step on flat soil, of which forming A = J M⁻¹ Jᵀ joint pair by
// joint pair in scalar code alone was 15 %; ODE also rebuilds J, A and the right-hand side for
// every attempt of a step (implicit-slip re-solves, guess retries) though J and M are the same.
// Here A is formed body by body (the rows touching a body, M⁻¹ Jᵀ once per row and side), and the
// attempt's joints are recorded instead of created as ODE joints.
//
// ODE stays the source of truth: bodies, masses, the permanent joints' anchors, axes and stops
// (public getters), and dWorldStep is the reference and the fallback. The angular motors'
// parameters, which RoverSim sets every step, are the exception: set through set_amotor_param(),
// which sets ODE's and keeps a copy that step() reads (hinges' stops and motor: read once).
// Anything this step does not reproduce exactly (another joint type, a joint option it does not know, a body
// outside the rover, a problem the sparse solver refuses) makes step() return false without
// touching ODE: the caller then materialises the recorded joints and calls dWorldStep.
#pragma once

#include <ode/ode.h>

#include <array>
#include <cstdint>
#include <limits>

#include "ernest/solver/lcp_workspace.hpp"
#include "ernest/solver/sparse_lcp.hpp"
#include "ernest/solver/sparse_ldlt.hpp"

namespace ernest::solver {

class IslandStep {
 public:
  static constexpr int kBodies = 6;
  static constexpr int kMaxRows = LdltPlan::kMaxRows;
  static constexpr int kMaxAttemptJoints = 96;  // contacts and linear motors of one attempt
  static constexpr int kMaxPermanent = 16;  // hinges, universals, angular motors
  static constexpr int kMaxJoints = kMaxPermanent + kMaxAttemptJoints;
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();

  /// The bodies (all of the world's) and the permanent joints between them. Hinges' second
  /// axes are captured in body 2's frame as dJointSetHingeAxis stored them (ODE has no getter):
  /// call right after the hinges are set up, with the bodies where they were then.
  void bind(const std::array<dBodyID, kBodies>& bodies);
  void add_hinge(dJointID j, const dReal axis_world[3]);
  void add_universal(dJointID j);
  void add_amotor(dJointID j);
  /// dJointSetAMotorParam for a permanent angular motor, which must go through here: step() reads
  /// the motors' parameters from a copy kept at add_amotor() and updated here (28 calls into ODE
  /// a step otherwise, 1.4 % of a flat step's instructions). Also forget()s: a parameter changed.
  void set_amotor_param(dJointID j, int parameter, double value);

  /// This attempt's own joints: recorded here instead of created in ODE (clear: none). While
  /// resolve() may follow, the other of two buffers: the stepped attempt's joints stay to compare.
  void clear_attempt() {
    if (kept_) {
      if (cur_ == kept_buf_) cur_ ^= 1;
      else kept_ = false;  // a second attempt recorded since the kept one
    }
    n_attempt_ = 0;
  }
  /// A contact as dJointCreateContact + dJointAttach(b1, b2) + dJointSetFeedback(fb) would make.
  void add_contact(const dContact& c, dBodyID b1, dBodyID b2, dJointFeedback* fb);
  /// A one-axis linear motor (axis global, rel 0) on body b alone, as dJointCreateLMotor with
  /// dParamVel, dParamFMax, dParamCFM would make.
  void add_lmotor(dBodyID b, const double axis[3], double vel, double fmax, double cfm);
  /// Creates the recorded joints in ODE (in `group`), for dWorldStep to take this attempt.
  void materialise(dWorldID world, dJointGroupID group) const;

  /// One step of length h of the island. Anything but Stepped: nothing in ODE changed, and
  /// dWorldStep must take the step (after materialise()); SolveRefused: solve_sparse was tried
  /// on this very problem and refused it (ODE's Dantzig solver must solve it).
  /// Resolved: resolve() took the last step's rows and factor; ResolvedCaps: its rows with new
  /// bounds and CFMs (A's diagonal), factorised again.
  enum class Outcome { Stepped, Resolved, ResolvedCaps, Unsupported, SolveRefused };
  Outcome step(dWorldID world, double h, LcpWorkspace& ws);
  /// Another attempt at the last step()'s problem, which differs from it only in the attempt's
  /// targets (contacts' motion velocities, linear motors' speeds) and the forces on the bodies:
  /// the implicit slip's re-solves that only move the soil rows' levels (rover_step.cpp). Then
  /// J, A and the rows stay, and only the right-hand side is formed again (ODE's rhs = c / h -
  /// J (v / h + M⁻¹ f_ext)) and solved with the kept LDLᵀ factor: the bits step() would give.
  /// Checked: the bodies' state (bit for bit, as restored), the world's parameters, h, the
  /// attempt's joints but for their targets, and that the workspace still holds the factor.
  /// Where only the attempt's caps changed too (contacts' mu and slip, linear motors' fmax and
  /// CFM: the rows' bounds and A's diagonal), the rows, J and A off the diagonal stay, the
  /// diagonal is summed again as build_a sums it, and A is factorised (ResolvedCaps).
  /// Not checked (the caller's part): the permanent joints' parameters are those of the last
  /// step(); forget() when they change. Anything else is a step().
  Outcome resolve(dWorldID world, double h, LcpWorkspace& ws);
  /// The permanent joints' parameters may have changed: the next resolve() is a step().
  void forget() { kept_ = false; }
  /// Whether the last step() or resolve() that stepped the bodies left every body's quaternion
  /// at a fixed point of ODE's normalisation (ode_quaternion.hpp): nothing to canonicalise.
  bool quaternions_fixed() const { return quaternions_fixed_; }

 private:
  enum class Kind : std::int8_t { Hinge, Universal, AMotor, Contact, LMotor };
  struct Joint {
    Kind kind = Kind::Hinge;
    dJointID id = nullptr;        // permanent joints
    int a = -1, b = -1;           // body indices (b = -1: the world)
    dJointFeedback* fb = nullptr;
    dReal axis2[4]{};             // hinge: axis in body b's frame (ODE's axis2)
    dContact contact{};           // contact
    double lm_axis[3]{}, lm_vel = 0.0, lm_fmax = 0.0, lm_cfm = 0.0;  // linear motor
    int first = 0, rows = 0;      // this step's rows
    int row_a = -1, row_b = -1;   // this step's bodies of the rows (a contact on (0, b): b first)
  };
  // A permanent angular motor's mode and each axis' parameters, as ODE holds them (add_amotor,
  // set_amotor_param); a hinge's stops and motor (never set after build: read at add_hinge).
  struct MotorParams {
    int mode = 0, num_axes = 0;
    std::array<double, 3> lo{}, hi{}, fmax{}, vel{}, cfm{};
  };
  struct HingeParams {
    double lo = 0.0, hi = 0.0, fmax = 0.0;
  };
  std::array<MotorParams, kMaxPermanent> motor_params_{};  // by permanent joint
  std::array<HingeParams, kMaxPermanent> hinge_params_{};
  struct BodyState {
    const dReal *pos, *R, *q, *lvel, *avel, *facc, *tacc;
    dReal invI[12];      // world frame (3x4, ODE's layout)
    dReal facc_g[3];     // force accumulator plus gravity
    dReal tacc_g[3];     // torque accumulator plus the gyroscopic torque
    double inv_mass;
  };
  int body_index(dBodyID b) const;
  bool bodies_supported() const;
  void load_forces(int i, const dVector3 gravity);
  template <bool kWithJm>
  void form_rhs(int m, double fps);
  bool solve(LcpWorkspace& ws, std::uint64_t kept_factor);
  void apply(double h);
  enum class Match { Different, Caps, Same };
  Match same_problem(dWorldID world, double h, const LcpWorkspace& ws);
  void attempt_caps(const Joint& jt, double fps);
  int attempt_targets(const Joint& jt, double fps, double erp, double* c) const;
  Joint& add_permanent(dJointID j, Kind kind);
  bool add_rows(Joint& jt, double fps, double erp);
  bool hinge_rows(Joint& jt, double fps, double erp);
  bool universal_rows(Joint& jt, double fps, double erp);
  bool ball_rows(Joint& jt, const dReal* w1, const dReal* w2, double k);
  int angular_row(Joint& jt, const dReal* d);
  bool amotor_rows(Joint& jt);
  bool contact_rows(Joint& jt, double fps, double erp);
  bool lmotor_rows(Joint& jt);
  // A new row of joint jt, as dxStepIsland_Stage2a initialises it: J zero, rhs 0, the world's
  // CFM, no bounds, no friction index; listed under its bodies (build_a). -1: too many rows.
  int new_row(Joint& jt, double world_cfm) {
    if (m_ >= kMaxRows) return -1;
    const int r = m_++;
    j_[r].fill(0.0);
    ra_[r] = jt.row_a;
    rb_[r] = jt.row_b;
    body_rows_[jt.row_a][n_body_rows_[jt.row_a]++] = static_cast<std::int16_t>(2 * r);
    if (jt.row_b >= 0)
      body_rows_[jt.row_b][n_body_rows_[jt.row_b]++] = static_cast<std::int16_t>(2 * r + 1);
    bx_[2 * r] = 0.0;
    cfm_[r] = world_cfm;
    lh_[2 * r] = -kInfinity;
    lh_[2 * r + 1] = kInfinity;
    findex_[r] = -1;
    ++jt.rows;
    return r;
  }
  void build_a(int m, double h);
  void integrate(double h);

  std::array<dBodyID, kBodies> body_{};
  std::array<double, kBodies> mass_{};
  std::array<std::array<dReal, 12>, kBodies> inv_inertia_body_{};  // 3x4
  std::array<std::array<dReal, 12>, kBodies> inertia_body_{};
  std::array<Joint, kMaxPermanent> permanent_{};
  int n_permanent_ = 0;
  std::array<Joint, kMaxAttemptJoints> attempt_{};  // buffer 0 (clear_attempt; 1: attempt2_)
  int cur_ = 0;  // this attempt's buffer
  Joint* buffer(int i) { return i == 0 ? attempt_.data() : attempt2_.data(); }
  const Joint* buffer(int i) const { return i == 0 ? attempt_.data() : attempt2_.data(); }
  int n_attempt_ = 0;

  // ---- this step's working data (preallocated)
  std::array<BodyState, kBodies> bs_{};
  std::array<Joint*, kMaxJoints> order_{};
  int n_order_ = 0;
  int m_ = 0;
  double world_cfm_ = 0.0, min_depth_ = 0.0, max_vel_ = 0.0;  // dWorldGet*
  // Per row: the Jacobian for body a then body b (lin, ang each), M⁻¹ Jᵀ likewise, the body
  // indices, and the LCP data in ODE's interleaved layout (rhs, lambda) and (lo, hi).
  std::array<std::array<double, 12>, kMaxRows> j_{}, jm_{};
  std::array<int, kMaxRows> ra_{}, rb_{};
  // each body's rows in row order, as 2 r + side (side 1: the row's second body)
  std::array<std::array<std::int16_t, kMaxRows>, kBodies> body_rows_{};
  std::array<int, kBodies> n_body_rows_{};
  std::array<double, 2 * kMaxRows> bx_{}, lh_{};
  std::array<double, kMaxRows> cfm_{};
  std::array<int, kMaxRows> findex_{};
  std::array<double, kMaxRows * kMaxRows> a_{};
  // build_a's per-body gather: the Jacobians on the body, column by column, and their sides
  std::array<std::array<double, kMaxRows>, 6> jb_{};
  std::array<int, kMaxRows> side_{};
  std::array<std::array<double, 6>, kBodies> cforce_{};

  // ---- what resolve() keeps of the last step() (valid while kept_). Last: the step's working
  // data above keeps the offsets it had before (a time profile of flat ground's step moved by
  // ~2 % in code that did not change when they moved).
  std::array<Joint, kMaxAttemptJoints> attempt2_{};  // the other attempt buffer
  bool kept_ = false;
  mutable bool bodies_checked_ = false;  // bodies_supported() said yes since the last change
  bool quaternions_fixed_ = false;       // quaternions_fixed()
  int kept_buf_ = -1, kept_n_attempt_ = 0, kept_nub_ = 0, n_permanent_order_ = 0;
  std::uint64_t kept_factor_ = 0;  // LcpWorkspace::factors after the solve
  double kept_h_ = 0.0, kept_erp_ = 0.0;
  std::array<double, 3> kept_gravity_{};
  std::array<std::array<double, 25>, kBodies> kept_state_{};  // pos, q, R (3x4), v, w: bits
  std::array<std::array<double, 3>, kBodies> gyro_{};  // stage 0's gyroscopic torque
  std::array<bool, kBodies> has_gyro_{};
  std::array<double, kMaxRows> c_{};  // the rows' right-hand sides before stage 2a's 1 / h
  std::array<std::array<double, 2>, kMaxRows> diag_{};  // each body's product on A's diagonal
  std::array<int, kMaxRows> n_diag_{};
};

}  // namespace ernest::solver
