// Internal to cpp/dynamics: the ODE model behind RoverSim, as a model (RoverModel: built once,
// never re-created) and its data (RoverData: what a step reads and writes). rover_sim.cpp builds
// and places it, rover_step.cpp and obstacle_contacts.cpp advance it, rover_sim_api.cpp is
// RoverSim's API over it. Not part of the embedding API (no stability promise).
#pragma once

#include <ode/ode.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <atomic>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

// The constraint solver (cpp/solver) as the rover uses it: ODE's set-up and its error scope
// (init_ode_once, OdeCallScope, OdeInternalError, ode_lcp_messages), the solves' workspace
// (LcpWorkspace: its switches enabled / exact_friction / coulomb_friction, its counters, and
// clear / save / load for a Snapshot), the hook's scope and probe (LcpScope, sparse_lcp_active),
// our own island step (IslandStep) and canonicalise_quaternion.
#include "ernest/solver/island_step.hpp"
#include "ernest/solver/ode_init.hpp"  // init_ode_once, OdeInternalError, OdeCallScope
#include "ernest/solver/ode_lcp.hpp"
#include "ernest/solver/ode_quaternion.hpp"  // canonicalise_quaternion
#include "ernest/dynamics/row_guess.hpp"
#include "ernest/dynamics/rover_sim.hpp"
#include "ernest/soil/bekker_wong.hpp"

namespace ernest::dynamics {

namespace detail {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

constexpr int kChassis = 0, kBogie = 1;
constexpr int kMaxObstacleContacts = 64;
constexpr int kMaxContactsPerPair = 4;
// World CFM (build()); the drives' rows use it, so checking a drive at its bound needs it too.
constexpr double kWorldCfm = 1e-9;
extern const char* const kBodyNames[6];

inline Vec3 to_vec(const dReal* v) { return {v[0], v[1], v[2]}; }
inline Mat3 to_mat(const dReal* r) {  // ODE stores 3x4 row-major
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = r[4 * i + j];
  return m;
}

struct DeepestPoint {
  Vec3 point;    // reference contact point on the tyre (deepest into the terrain)
  Vec3 normal;   // terrain normal at it
  double depth;  // penetration along the normal (> 0 in contact) [m]
};
DeepestPoint deepest_point(const HeightMap& hm, const Vec3& centre, const Vec3& axle, double r,
                           double tube);

// Bounded constraint rows whose active set is guessed from the previous step (rover_step.cpp).
// Per wheel i, row 5 i + k with k: shear x, shear y, compaction, drive, soil normal force (>= 0);
// then the gimbal's yaw and roll drives.
enum RowKind : int { kShearX = 0, kShearY = 1, kCompaction = 2, kWheelMotor = 3, kNormal = 4 };
constexpr int kRowsPerWheel = 5;
constexpr int kYawMotor = 4 * kRowsPerWheel, kRollMotor = kYawMotor + 1;
static_assert(kGuessedRowCount == kRollMotor + 1, "Snapshot::row_mode covers every guessed row");
// (a guess per row: RowState, rover_sim.hpp; the guesser: row_guess.hpp)
// Below 1 mN a soil row is dropped: a CFM of eps / F would overflow the LCP as F -> 0.
constexpr double kMinRowBound = 1e-3;
constexpr double kSlackSpeed = 100.0;  // [m/s] a normal row aiming at -100 m/s never engages
// Implicit slip (rover_step.cpp): at most kMaxSlipSolves solves of a step for its slip.
constexpr int kMaxSlipSolves = 12;
constexpr double kSlipTolerance = 2e-3;  // slips this close to eq 12's end value: accepted

inline double clamp_unit(double v) { return std::min(1.0, std::max(-1.0, v)); }

// A force at a point: added to a body's force and, about its centre of mass (arm from it), its
// torque.
inline void add_at(Vec3& f, Vec3& t, const Vec3& force, const Vec3& arm) {
  f += force;
  t += arm.cross(force);
}

// Per-wheel ground contact of the current step (configuration at the start of the step).
struct GroundContact {
  bool active = false;
  Vec3 point = Vec3::Zero(), arm = Vec3::Zero();  // arm = point - wheel centre
  Vec3 n = Vec3::UnitZ(), fx = Vec3::UnitX(), fy = Vec3::UnitY(), axle = Vec3::UnitY();
  double depth = 0.0;
  // soft soil: bounds of the implicit rows and the explicit normal force (eqs 28–32), and the
  // explicit share of the soil's axle torque (about `axle`), all at the slip of the attempt
  double ax = 0.0, ay = 0.0, comp = 0.0, fz = 0.0, axle_torque = 0.0;
  double fz_pressure = 0.0;  // eq 32's pressure part at the slip of the attempt [N]
  // the normal row's damper [N s/m]: the soil's plus h dF_z/dz (eq 32's pressure spring at the
  // end of the step, linearised in the sinkage)
  double normal_damping = 0.0;
  soil::ContactState cs{};  // eq 12–32 inputs at the start of the step (Fig. 7 frame)
  // soil.split(cs, slip) at the last two slips asked for this step (soil_split): the step's
  // first attempt and the implicit-slip check after it ask for the same slip, and the same
  // state and slip give the same split. Cleared with the contact every step.
  std::array<double, 2> memo_slip{std::nan(""), std::nan("")};
  std::array<soil::SoilSplit, 2> memo_split{};
  int memo_next = 0;
};

// One bounded velocity row of a motor: drive the relative rate to `target` with |torque| <= bound
// (bound 0: no row).
struct MotorRow {
  double target = 0.0, bound = 0.0;
};

// The model (pinocchio's Model): what RoverSim is built from and what build() creates once. The
// values are const. The ODE objects are mutable by nature (ODE's API takes them non-const, a step
// moves the bodies and sets the drives' parameters), but the model is their set: build() creates
// every body, geom and joint, and no step creates or destroys one (a step's contact joints live in
// `contacts`, a joint group emptied after every attempt, never re-created). Destroyed with it.
struct RoverModel {
  RoverModel(const RoverParameters& params, const HeightMap& terrain,
             const std::vector<BoxObstacle>& obstacles, const SimOptions& options);
  ~RoverModel();
  RoverModel(const RoverModel&) = delete;
  RoverModel& operator=(const RoverModel&) = delete;

  const RoverParameters p;
  const HeightMap hm;
  const std::vector<BoxObstacle> boxes;
  const SimOptions opt;
  const soil::BekkerWongModel soil;  // eq 12 with exact sign(v_x); the shear levels: ODE's rows
  // Coulomb friction of the obstacles and of rigid ground: opt.friction, or drawn once from
  // opt.rigid with opt.seed.
  const double mu;

  // ODE objects, created by RoverSim::Impl::build() (the joints' feedback buffers are data)
  dWorldID world = nullptr;
  dThreadingImplementationID threading = nullptr;
  dSpaceID rover_space = nullptr, obstacle_space = nullptr;
  dJointGroupID contacts = nullptr;
  std::array<dBodyID, 6> body{};
  std::array<dGeomID, 6> geom{};
  std::array<dJointID, 4> hinge{};
  std::array<dJointID, 4> wheel_motor{};  // one-axis AMotors (outside the hinges: see build())
  dJointID gimbal = nullptr;        // universal joint with the stops
  dJointID gimbal_motor = nullptr;  // two-axis AMotor: yaw (chassis z), roll (bogie x)
  std::vector<dGeomID> obstacle_geoms;
  std::vector<std::array<double, 6>> obstacle_aabb;  // their bounding boxes (ODE's order)
  std::vector<int> obstacle_by_x;   // their indices by the boxes' lowest x (prepare_obstacles)
  double obstacle_max_width = 0.0;  // the widest box along x
};

// The data (pinocchio's Data): everything a step reads and writes. The state a Snapshot carries
// (commands, sensors, the soil rows' levels, the guesses, the tyres' deflections, the solver's
// orderings), caches of what was last set in ODE, and the step's working arrays (preallocated:
// the hot loop never allocates).
struct RoverData {
  using Vec3 = detail::Vec3;
  static std::array<double, 4> no_slip_offset() {
    const double n = std::nan("");
    return {n, n, n, n};
  }

  Commands cmd{};
  RoverState st{};
  // The soil rows' levels (shear used / shear cap, compaction force) that the soil's remaining
  // terms (eq 32's shear part, the axle torque) are evaluated at: the step's own, solved with the
  // slip (rover_step.cpp); and the row guesses (the last two steps' outcomes, row_guess.hpp).
  std::array<double, 4> shear_x{}, shear_y{}, compaction{};
  detail::RowGuesser guesser;
  // Rigid ground (rover_rigid.cpp): each tyre's tangential deflection (world, in the contact's
  // tangent plane) at the start of the step (Snapshot) and at the end of the current attempt.
  std::array<Vec3, 4> rigid_deflection{}, rigid_deflection_end{};
  // Caches of what was last set in ODE's joints (set again only when it changes).
  std::array<bool, 2> stop_set{};  // the gimbal's yaw / roll stop is set (prepare_actuators)
  // The drives' AMotor parameters as last set (target rate, torque bound), NaN = never (emit()).
  std::array<std::array<double, 2>, 6> motor_set = [] {
    std::array<std::array<double, 2>, 6> a{};
    for (auto& v : a) v = {std::nan(""), std::nan("")};
    return a;
  }();
  Vec3 pending_force = Vec3::Zero();
  bool diverged = false;
  // ODE failed internally (OdeInternalError): its world may be inconsistent (an exception left
  // dWorldStep half way), so it is never stepped, reset or restored again.
  std::string ode_failure;

  // The step being taken: its length and the §3.4 spring–dampers as ERP / CFM at it.
  double h = 0.0;  // length of the step being taken: opt.dt, or a substep of it (step())
  // The last attempt's own step left every quaternion canonical (IslandStep::quaternions_fixed):
  // read_outputs() need not canonicalise them (six tests with a square root and a division).
  bool quaternions_fixed = false;
  bool obstacles_collected = false;  // step() found this step's obstacle contacts already
  // §3.4 spring–damper as ERP / CFM at h, implicit (rigid ground; obstacles: set_obstacle_rows)
  double contact_erp = 0.0, contact_cfm = 0.0;
  // The tyre's along x and y on rigid ground (rover_rigid.cpp).
  std::array<double, 2> tangential_erp{}, tangential_cfm{};
  // Buffers ODE writes the joints' forces into (registered with the joints by build()).
  std::array<dJointFeedback, 4> hinge_fb{};
  std::array<dJointFeedback, 4> wheel_motor_fb{};
  dJointFeedback gimbal_fb{}, gimbal_motor_fb{};
  // Ground feedback: each wheel's contact with the terrain (rover_rows.cpp).
  std::array<dJointFeedback, 4> ground_fb{};

  // ---- per-step working data ----
  std::array<detail::GroundContact, 4> ground{};
  std::array<detail::MotorRow, 6> motor{};  // wheels FL..RR, yaw, roll
  Vec3 yaw_axis = Vec3::UnitZ(), roll_axis = Vec3::UnitX();
  // Gimbal angles and axes of the current bodies, from read_outputs(); step() uses them unless
  // restore() changed the bodies since (start_current false).
  double start_psi = 0.0, start_phi = 0.0;
  bool start_current = false;
  std::array<Vec3, 6> base_force{}, base_torque{};  // explicit forces of this step
  std::array<dContact, detail::kMaxObstacleContacts> obstacle_contact{};
  std::array<dBodyID, 2 * detail::kMaxObstacleContacts> obstacle_bodies{};
  int n_obstacle_contacts = 0;
  // Obstacle contacts' guesses (rover_rigid.cpp): each point's wheel (-1: not a wheel) and side
  // (the wheel is the joint's body 1 or 2), its feedback; per wheel whether its points are
  // emitted sticking (Free: friction rows unbounded, checked after the step) or bounded
  // (Bounded: ODE's friction bounded by mu times the normal force), for this step's attempts
  // (obstacle_try) and as the next step's guess (obstacle_mode, in the Snapshot; obstacle_next
  // equals it between steps: a step without contacts keeps it); points of a
  // sticking wheel found carrying no normal force, emitted without friction rows (obstacle_off).
  std::array<std::int8_t, detail::kMaxObstacleContacts> obstacle_wheel{};
  // Each contact's rover body (0-5), a lower bound of its effective mass along the normal
  // (contact_mass_bound; hinged: with the wheel's parent) and whether its §3.4 spring is explicit
  // at this step length (set_obstacle_rows; obstacle_contacts.hpp).
  std::array<std::int8_t, detail::kMaxObstacleContacts> obstacle_body{};
  std::array<double, detail::kMaxObstacleContacts> obstacle_mass{};
  std::array<bool, detail::kMaxObstacleContacts> obstacle_hinged{};
  std::array<bool, detail::kMaxObstacleContacts> obstacle_explicit{};
  std::array<bool, detail::kMaxObstacleContacts> obstacle_wheel_first{};
  std::array<dJointFeedback, detail::kMaxObstacleContacts> obstacle_fb{};
  std::array<RowState, 4> obstacle_mode{}, obstacle_try{}, obstacle_next{};
  // The largest growth rate lambda [1/s] of a wheel's slip estimated in the last step (the secant
  // d s_end / d sigma over h, step_once; 0 where none was measured); step() substeps an obstacle
  // step whose h lambda would reach 1/2 (in the Snapshot).
  double slip_rate = 0.0;
  // The implicit slip's first guesses (rover_step.cpp, warm_start_levels / warm_start_slips; in
  // the Snapshot): per wheel the soil rows' levels (shear_x, compaction) of the two steps before
  // the last, the steps the wheel has been on soil without a break (0-3), and the amount the last
  // step's accepted slip differed from eq 12 at its start (NaN: none, or the wheel drove).
  std::array<std::array<double, 4>, 2> shear_x_past{}, compaction_past{};
  std::array<int, 4> soil_steps{};
  std::array<double, 4> slip_offset = no_slip_offset();
  std::uint64_t obstacle_off = 0;
  bool rows_held = true;  // settle(): the guessed rows (not the obstacles) held
  std::array<dGeomID, detail::kMaxObstacleContacts> touched{};  // obstacles in the contacts
  int n_touched = 0;
  std::array<Snapshot::Body, 6> saved{};        // bodies at the start of the step (retries)
  std::array<double, kGuessedRowCount> row_force{};    // solved force of every guessed row
  std::array<double, 6> explicit_motor_torque{};  // Torque-mode set-points applied this step
  solver::LcpWorkspace lcp;  // the sparse constraint solves (lcp_workspace.hpp)
  // Our own step (SimOptions::stepper == Own): the bodies, permanent joints (bound by build())
  // and the attempt's contacts and linear motors, recorded instead of created in ODE.
  solver::IslandStep island;
  SolverStats stats{};
};

}  // namespace detail

/// The simulator: the model, its data, and the functions of a step (rover_*.cpp).
struct RoverSim::Impl : detail::RoverModel, detail::RoverData {
  using Vec3 = detail::Vec3;
  using Mat3 = detail::Mat3;

  // Held by every public method (cpp/common/exclusive_use.hpp): one thread at a time.
  mutable std::atomic<bool> in_use{false};

  /// Runs f (which calls into ODE); an ODE internal error becomes SimulationDiverged.
  template <class F>
  void run_ode(F&& f) {
    if (!ode_failure.empty())
      throw SimulationDiverged("RoverSim: ODE failed internally earlier (" + ode_failure +
                               "); this simulator cannot be used again, create a new RoverSim");
    try {
      const solver::OdeCallScope own;  // ODE's errors in here throw (ode_init.hpp)
      f();
    } catch (const solver::OdeInternalError& e) {
      ode_failure = e.what();
      diverged = true;
      throw SimulationDiverged(std::string("SimulationDiverged: ODE internal error (") + e.what() +
                               ") at t = " + std::to_string(st.time) +
                               " s; this simulator cannot be used again, create a new RoverSim");
    }
  }

  Impl(const RoverParameters& params, const HeightMap& terrain,
       const std::vector<BoxObstacle>& obstacles, const SimOptions& options);

  Vec3 axle_world(int i) const { return to_vec3(dBodyGetRotation(body[2 + i]), 1); }
  Mat3 rot(int b) const { return detail::to_mat(dBodyGetRotation(body[b])); }
  Vec3 pos(int b) const { return detail::to_vec(dBodyGetPosition(body[b])); }
  int parent_of(int wheel) const { return wheel < 2 ? detail::kBogie : detail::kChassis; }
  static Vec3 to_vec3(const dReal* r, int col) { return {r[col], r[4 + col], r[8 + col]}; }

  // rover_sim.cpp
  void build();
  void place(double x, double y, double heading, double psi, double phi, double speed);
  // obstacle_contacts.cpp: the step (substeps on obstacles), the obstacles' contacts, the bodies
  // saved for the attempts
  void step();
  void set_step_length(double length);
  bool touching_obstacles();
  void prepare_obstacles();
  void near(dGeomID a, dGeomID b);
  void add_obstacle_contact(dGeomID a, dGeomID b, const dContactGeom& merged);
  double contact_mass_bound(int body, const Vec3& point, const Vec3& normal, bool hinged) const;
  void set_obstacle_rows();
  void save_bodies();
  void restore_bodies();
  // rover_step.cpp
  void step_once();
  void gimbal_angles(double& psi, double& phi, double& psid, double& phid, Vec3& ez,
                     Vec3& ea) const;
  void prepare_actuators(double psi, double phi);
  void prepare_ground();
  void warm_start_levels();
  void warm_start_slips(Eigen::Vector4d& sigma);
  void record_warm_start(const std::array<double, 4>& start_x, const std::array<double, 4>& start_c,
                         const Eigen::Vector4d& sigma, const Eigen::Vector4d& start_sigma,
                         const std::array<bool, 4>& driving);
  struct SoilTerms {
    double slip = 0.0, ax = 0.0, ay = 0.0, comp = 0.0, fz = 0.0, axle_torque = 0.0;
    double fz_pressure = 0.0;  // eq 32 without the shear part, not floored
  };
  const soil::SoilSplit& soil_split(int wheel, double slip);
  SoilTerms soil_terms_at(int wheel, double slip);
  void soil_terms(int wheel, double slip);
  double soil_terms_gap(int wheel, double end_slip);
  void end_velocity(int wheel, double& vx, double& vcx) const;
  void soil_levels(int wheel);
  // The attempt's joints: recorded for our own step, or created in ODE (`contacts` group).
  void add_contact_joint(const dContact& c, dBodyID b1, dBodyID b2, dJointFeedback* fb);
  void add_lmotor_joint(dBodyID b, const Vec3& axis, double fmax, double cfm);
  void world_step();  // one attempt: our island step, or dWorldStep (and ODE's joints)
  bool solve_rows(detail::RowStates& guess, detail::RowStates& next, detail::RowStates& tried,
                  int& attempts);
  void emit_obstacles(detail::RowModes modes);
  bool settle_obstacles(detail::RowModes modes);
  struct DriveRow {
    int row;
    Vec3 axis;         // world, at the start of the step
    int body1, body2;  // the row drives (w_1 - w_2) . axis
  };
  DriveRow drive_row(int k) const;
  void emit(detail::RowModes modes);
  void emit_ground(int wheel, detail::RowModes modes, Vec3& wheel_force, Vec3& wheel_torque);
  bool settle(detail::RowModes modes, detail::RowStates& next);
  // rover_rigid.cpp: rigid ground under the wheels
  void prepare_rigid();
  bool rigid_sticking(detail::RowModes modes, int wheel) const;
  void emit_rigid(int wheel, detail::RowModes modes);
  bool settle_rigid(int wheel, detail::RowModes modes, const Vec3& patch_velocity,
                    detail::RowStates& next);
  void commit_rigid();
  void read_outputs(double dt_done);
  void check_divergence();
  void check_forces_before_step();
};

}  // namespace ernest::dynamics
