// ERNEST multibody simulation on ODE (replaces the DARTS simulation of seed 004 §3): chassis with
// rear wheel assemblies, Active Gimbal Suspension (yaw then roll, collocated, §2.2) with roll
// clutch and yaw brake, front bogie with its wheel assemblies, four driven wheels; Bekker–Wong
// soft soil on a height map (§3.3) or rigid ground, rigid box obstacles (§3.4); DC motors with
// gearboxes (eq 40); force–torque sensors; snapshot/restore; divergence detection.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ernest/dynamics/rover_parameters.hpp"
#include "ernest/dynamics/terrain.hpp"
#include "ernest/soil/bekker_wong.hpp"
#include "ernest/soil/rigid_contact.hpp"
#include "ernest/soil/soil_parameters.hpp"

namespace ernest::dynamics {

/// Raised when the state becomes non-finite or absurd (see SimOptions::max_speed). The simulation
/// refuses to step again until restore() or reset().
class SimulationDiverged : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Who takes the step of the rover's bodies (SimOptions::stepper).
enum class Stepper : int {
  /// ODE's dWorldStep (the constraint solve through the solver hook, cpp/solver/ode_lcp.hpp)
  Ode = 0,
  Own = 1,  ///< our own island step (cpp/solver/island_step.hpp): the same step, faster
};

/// How a wheel's contact with a rock is found (SimOptions::wheel_obstacle_contact).
enum class WheelObstacleContact : int {
  Ode = 0,    ///< ODE's dCollideCylinderBox, its points merged into one contact
  Exact = 1,  ///< the exact penetration depth and normal (cpp/dynamics/cylinder_box.hpp)
};

struct SimOptions {
  /// Physics step [s]. Default from the step-independence study in benchmarks/RESULTS.md ("Step
  /// size and step independence"): every evaluation course with the passive bogie and the crawling
  /// gait within 2 pp of travel reduction and 5 % of cost of transport of a 4x smaller step. At
  /// 0.025 s (which passes straight driving) the soil's pressure-sinkage
  /// spring against its damper (time constant soil_normal_damping / (dF_z/dz) ~ 50 ms) is
  /// under-resolved: the crawling gait's first wheel lift on the 20 deg slope fails and the
  /// rocking on the mixed course's ripple moves by 5 %. Divides the 0.5 s policy period.
  double dt = 0.0125;
  std::uint64_t seed = 0;                 ///< seeds the friction draws (std::mt19937_64)
  GroundType ground = GroundType::Soil;   ///< soft soil or rigid ground on the whole height map
  soil::SoilParameters soil{};            ///< Bekker–Wong parameters (default M90, Table 2)
  /// Gauss–Legendre points per panel of the soil model.
  int soil_points_per_panel = soil::BekkerWongModel::kDefaultPointsPerPanel;
  /// Normal damping of the soil [N s/m per wheel] (assumption, ours: Bekker–Wong has no rate
  /// term, so a wheel would bounce forever on the pressure–sinkage spring, and eq 16's switch
  /// between rest and motion would pump energy into it). The normal force is
  /// F_n = max(0, F_z - c v_n): damped both ways, never pulling; solved implicitly by ODE, with
  /// F_z linearised in the sinkage (backward Euler: the damper grows by dt dF_z/dz).
  double soil_normal_damping = 1500.0;
  soil::RigidContactParameters rigid{};   ///< §3.4 spring–damper -> ODE ERP/CFM for dt
  /// Coulomb friction of the obstacles and of rigid ground, [0, 10]; nullopt draws it once from
  /// rigid.sample_friction(rng(seed)) ("per obstacle set").
  std::optional<double> friction;
  /// Tangential compliance of the tyre on rigid obstacles [(m/s)/N] (assumption, ours): ODE's
  /// force-dependent slip, so that wheels with slightly different rolling radii do not fight
  /// each other through perfectly sticking contacts. 1e-4 = 1 cm/s of creep at 100 N. Per
  /// wheel–obstacle pair, shared by its collision points like the §3.4 stiffness.
  double rigid_slip = 1e-4;
  /// Tangential stiffness of each tyre on rigid ground [N/m], along its rolling direction and
  /// along its axle, and the damping of both [N s/m] (assumptions, ours): a spring–damper per
  /// friction direction capped by Coulomb's law (seed 004 §3.4), so a parked rover holds where the
  /// friction cone allows and a constant force gives a constant deflection
  /// (cpp/dynamics/rover_rigid.cpp). Longitudinal: §3.4's radial 20 kN/m. Lateral: ERNEST's
  /// woven spring-mesh tyres (§2.1.1) give sideways; 1 kN/m lets the roll joint lift a wheel
  /// against held wheels on hard ground (§2.2), whose contacts must scrub sideways to do so.
  double rigid_tyre_stiffness_x = 20e3;
  double rigid_tyre_stiffness_y = 1e3;
  double rigid_tyre_damping = 1e3;
  /// Guess the active set of the bounded rows (motor limits, soil shear and compaction caps) from
  /// the previous step and verify it, instead of letting ODE's Dantzig solver pivot through it
  /// every step; a wrong guess is retried and finally solved by pivoting. The result is the same
  /// LCP solution either way (to rounding); false always pivots (tests, comparisons).
  bool guess_active_set = true;
  /// Guess each wheel's obstacle contacts sticking (friction rows unbounded, checked against
  /// mu F_n after the step, as rigid ground: cpp/dynamics/rover_rigid.cpp), so that a step on
  /// rocks is one linear system for the sparse solver; a wrong guess is retried with the
  /// friction bounded by mu times the normal force (ODE's pivoting). false: always bounded and
  /// pivoted by ODE (comparisons). Needs guess_active_set.
  bool guess_obstacle_contacts = true;
  /// Solve the step's constraint system with a sparse LDLᵀ (minimum-degree order,
  /// cpp/solver/sparse_ldlt.hpp) when every row is unbounded or has a zero bound (the contacts'
  /// normal rows, guessed pushing or not as they ended last time and checked), which the
  /// guessed active set makes the usual case, instead of ODE's dense Dantzig solver; other
  /// steps still go to ODE. The same solution to rounding; false: ODE's solver for every step.
  bool sparse_lcp = true;
  /// Implicit slip (cpp/dynamics/rover_step.cpp) [N]: a step on soil is solved again, with new
  /// slip ratios, until every wheel's slip agrees with eq 12 at the end of the step to 2e-3, or
  /// the soil's row bounds and explicit forces at that end slip are within this of those the
  /// step used (axle torques as forces at the wheel radius); at most 12 solves. Step
  /// independence at 0.1 N and its cost: benchmarks/RESULTS.md, "Step size and step independence". 1e9 takes
  /// the slip from the start of the step (explicit: a stalled wheel chatters at the step rate).
  double slip_force_tolerance = 0.1;
  /// Implicit slip's first guess: each wheel's soil-row levels predicted from its last three
  /// steps and its slip from the last step's offset over eq 12 (state: in the Snapshot), so that
  /// most steps are accepted after one solve; false: the last levels and eq 12 at the step's
  /// start. Either is accepted to slip_force_tolerance, so the two agree to it
  /// (benchmarks/RESULTS.md, "Where a step goes").
  bool slip_warm_start = true;
  /// A step in which a wheel touches an obstacle (a box or rock) is taken as this many substeps
  /// of dt / n. The §3.4 contact (20 kN/m, 20 N s/m on a 3 kg wheel assembly: 82 rad/s, damping
  /// ratio 0.04) is integrated with its spring explicit and its damper implicit where the
  /// contact's effective mass allows (cpp/dynamics/obstacle_contacts.hpp: no numerical damping),
  /// by ODE's implicit ERP/CFM elsewhere. The passive bogie spinning its wheels against a box
  /// face (the Bickler trap, the wheel-high step) climbs and falls back at fine steps; at coarse
  /// ones the implicit slip would hold the wheel at the stall, which the slip taken explicitly
  /// where it drives the motion avoids (rover_step.cpp). With 1 (the default) an
  /// obstacle step after one where a wheel's slip grew at a rate lambda
  /// with dt lambda >= 1/2 is split into ceil(2 dt lambda) <= 8 substeps (RoverSim::Impl::step):
  /// every obstacle row of bench_step_ladder.py is then within 3.1 % of dt / 16 at dt, dt/2, dt/4
  /// and dt/8 (benchmarks/RESULTS.md, "Step size and step independence"). n > 1 substeps every
  /// obstacle step (for comparisons).
  int obstacle_substeps = 1;
  /// Who steps the bodies: our own island step that reproduces ODE's dWorldStep for the rover's
  /// bodies and joints (cpp/solver/island_step.hpp; ~10 % faster a step, the same step to
  /// ~1e-15 m from the same state: benchmarks/RESULTS.md, "Where a step goes"), or
  /// dWorldStep itself. Own falls back to dWorldStep for any attempt it does not reproduce (a
  /// joint option it does not know, a solve the sparse path refuses), so the two differ by
  /// rounding only.
  Stepper stepper = Stepper::Own;
  /// A wheel against a rock (a box): one contact (seed 004 §3.4) from ODE's dCollideCylinderBox
  /// with its points merged (merge_contact_points; ODE's axis for a box edge against a wheel's rim
  /// is approximate), or with Exact the exact penetration depth and normal of the cylinder and
  /// the box by the separating-axis theorem over the complete candidate set, the point at the
  /// depth-weighted centre of the deepest features (cpp/dynamics/cylinder_box.hpp). The chassis
  /// and bogie boxes always use ODE's box-box. Exact is faster (2 % a step among 20 rocks, 7 %
  /// among 100) but it is not the default: where a rock's edge meets a rim it pushes the wheel
  /// sideways, and where the 20-rock drive's last stall ends moves with the step (median over 10
  /// start offsets 1.38 m at dt, 1.52 m at dt/8), where Ode's two outcomes do not
  /// (benchmarks/RESULTS.md, "Measured and not kept").
  WheelObstacleContact wheel_obstacle_contact = WheelObstacleContact::Ode;
  /// With the Own stepper: a re-solve of a step whose rows are the last attempt's (the implicit
  /// slip's solves that only move the soil rows' levels, rover_step.cpp: only the normal rows'
  /// targets and the explicit torques change) keeps that attempt's rows, A and LDLᵀ factor and
  /// solves a new right-hand side (cpp/solver/island_step.hpp, IslandStep::resolve); one whose
  /// slips moved the soil rows' caps keeps the rows, J and A but for its diagonal (the caps'
  /// CFMs) and factorises again. The same bits either way (SolverStats::rhs_resolves and
  /// cap_resolves count them); false rebuilds every attempt (tests, comparisons).
  bool resolve_rhs_only = true;
  double max_speed = 50.0;          ///< divergence: any body faster than this [m/s]
  double max_angular_speed = 500.0; ///< divergence: any body spinning faster [rad/s]
  void validate() const;
};

enum class ActuatorMode : int { Velocity = 0, Torque = 1, Off = 2 };
enum class ClutchState : int { Disengaged = 0, Aligning = 1, Engaged = 2 };

/// Actuator set-points, held until changed. Velocity mode = the servo drive's velocity loop,
/// modelled as ideal up to the current-limited torque (N eta K_tau I_max).
struct Commands {
  std::array<double, 4> wheel_speed{};    ///< [rad/s], positive rolls forward (Velocity mode)
  std::array<double, 4> wheel_torque{};   ///< [N m] output torque (Torque mode), clamped
  ActuatorMode wheel_mode = ActuatorMode::Velocity;
  double yaw_rate = 0.0, roll_rate = 0.0;      ///< gimbal psi_dot, phi_dot [rad/s]
  double yaw_torque = 0.0, roll_torque = 0.0;  ///< Torque mode [N m], clamped
  ActuatorMode yaw_mode = ActuatorMode::Velocity;
  ActuatorMode roll_mode = ActuatorMode::Velocity;
  /// false = AGS off: the yaw brake holds, the roll actuator is braked (passive bogie, §5 Table 6).
  bool gimbal_enabled = true;
  /// Request the roll clutch: the bogie frame first aligns with the bogie at bounded speed, then
  /// the pins engage (§2.2). false retracts the pins at once (bogie free on its bearing).
  bool clutch_engage = false;
  void validate() const;
};

using Wrench = Eigen::Matrix<double, 6, 1>;

/// Sensors and ground truth after the last step. Actuator arrays of six: FL, FR, RL, RR wheels,
/// yaw, roll.
struct RoverState {
  double time = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();         ///< chassis frame origin, world
  Eigen::Vector4d quaternion{1.0, 0.0, 0.0, 0.0};              ///< chassis (w, x, y, z)
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();   ///< of the origin, world
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  ///< world
  Eigen::Vector3d body_linear_velocity = Eigen::Vector3d::Zero();   ///< chassis frame
  Eigen::Vector3d body_angular_velocity = Eigen::Vector3d::Zero();  ///< chassis frame
  double roll = 0.0, pitch = 0.0, yaw = 0.0;  ///< chassis Z-Y-X Euler angles [rad]
  double gimbal_yaw = 0.0, gimbal_roll = 0.0;            ///< psi, phi [rad]
  double gimbal_yaw_rate = 0.0, gimbal_roll_rate = 0.0;  ///< [rad/s]
  double yaw_torque = 0.0, roll_torque = 0.0;  ///< actuator (or brake) torque on the bogie [N m]
  double bogie_frame_angle = 0.0;              ///< roll actuator output angle [rad]
  ClutchState clutch = ClutchState::Disengaged;
  std::array<double, 4> wheel_speed{};   ///< spin relative to the mount [rad/s]
  std::array<double, 4> wheel_torque{};  ///< drive output torque [N m]
  std::array<double, 4> wheel_load{};    ///< ground normal force on the wheel [N]
  std::array<double, 4> sinkage{};       ///< penetration of the reference contact point [m]
  std::array<double, 4> slip{};          ///< eq 12 slip (soil) [-]
  std::array<double, 4> contact_vx{};    ///< v_c,x of the contact point (Fig. 7 frame) [m/s]
  std::array<double, 4> contact_vy{};    ///< v_c,y lateral slip velocity [m/s]
  std::array<Eigen::Vector3d, 4> wheel_position{};  ///< wheel centres, world
  /// Force–torque sensors: wrench (Fx, Fy, Fz, Tx, Ty, Tz) exerted by the wheel assembly on its
  /// mount at the sensor point, in the sensor frame (Fz > 0 when the wheel carries load).
  std::array<Wrench, 4> fts{};
  std::array<double, 6> motor_current{};  ///< [A]
  std::array<double, 6> motor_power{};    ///< eq 40 [W]
  double energy = 0.0;  ///< integral of the positive electrical power of all six actuators [J]
};

/// Bounded constraint rows whose active set RoverSim guesses (see SimOptions::guess_active_set):
/// per wheel shear x, shear y, compaction, the drive and the soil's normal force; then the
/// gimbal's yaw and roll drives.
inline constexpr int kGuessedRowCount = 22;

/// Where a bounded row (or a wheel's obstacle contacts) was guessed or found to be: inside its
/// bounds (solved as an unbounded row: factorised with the joints instead of pivoted), at its
/// upper or lower bound (applied as the explicit force at that bound), or left to ODE with its
/// bounds (Bounded: ODE's pivoting solver places it). Obstacle contacts use Free (sticking,
/// friction rows unbounded) and Bounded (friction bounded by mu times the normal force).
enum class RowState : std::int8_t { Free = 0, AtHi = 1, AtLo = 2, Bounded = 3 };

/// How the constraint solver's active-set guesses fared (benchmarks, tests).
struct SolverStats {
  std::uint64_t steps = 0;         ///< physics steps taken since construction
  std::uint64_t first_guess = 0;   ///< steps whose first guess was right
  std::uint64_t later_guess = 0;   ///< steps right at the second or third guess (no row pivoted)
  std::uint64_t pivoted = 0;       ///< steps where ODE pivoted the rows whose guesses kept failing
  /// Steps on which ODE's pivoting solver reported an internal error ("LCP internal error, s <=
  /// 0"): it then stops early with a wrong answer. Guessed steps never pivot the guessed rows.
  std::uint64_t lcp_errors = 0;
  /// Constraint solves (one per attempt at a step) done by the sparse LDLᵀ (SimOptions::
  /// sparse_lcp), and those handed to ODE's Dantzig solver (friction bounded by a normal force,
  /// a bounded row without a zero bound, contact guesses that kept failing, or sparse_lcp off).
  std::uint64_t sparse_solves = 0;
  std::uint64_t dense_solves = 0;
  /// Extra solves of a step made to find the slip ratios that agree with eq 12 at the step's end
  /// (the implicit slip of cpp/dynamics/rover_step.cpp); 0 when the first slip already agreed.
  std::uint64_t slip_solves = 0;
  /// Steps (substeps) on soil with a wheel whose slip drove its motion (d s_end / d sigma >= 1:
  /// the slip taken from the step's start, not solved implicitly; cpp/dynamics/rover_step.cpp).
  std::uint64_t slip_driving = 0;
  /// Steps (substeps) with obstacle contacts whose every wheel was solved sticking (friction rows
  /// unbounded: a linear system for the sparse solver), and those with a wheel solved bounded
  /// (ODE's friction bounded by mu times the normal force: its pivoting solver).
  std::uint64_t obstacle_guessed = 0;
  std::uint64_t obstacle_bounded = 0;
  /// Obstacle contacts (one per rover body and obstacle touching, per step or substep) whose
  /// §3.4 spring was integrated explicitly (no numerical damping), and those integrated
  /// implicitly because a lower bound of their effective mass was too light for the explicit
  /// spring at the step (cpp/dynamics/obstacle_contacts.hpp).
  std::uint64_t obstacle_explicit = 0;
  std::uint64_t obstacle_implicit = 0;
  /// Attempts (solves) stepped by our own island step (SimOptions::stepper == Own), and those it
  /// handed to dWorldStep (a joint option it does not reproduce, or a solve the sparse path
  /// refused: then ODE's Dantzig solver).
  std::uint64_t own_steps = 0;
  std::uint64_t own_fallbacks = 0;
  /// Of the own steps, those solved as a new right-hand side of the last attempt's rows and
  /// factor (SimOptions::resolve_rhs_only).
  std::uint64_t rhs_resolves = 0;
  /// Of the own steps, those that kept the last attempt's rows (J, A but for its diagonal) with
  /// new bounds and CFMs (a slip re-solve that moved the soil rows' caps), factorised again.
  std::uint64_t cap_resolves = 0;
  /// Sparse solves' symbolic analyses (LdltPlan::analyse): plans made for row sets not
  /// remembered, and remembered plans analysed again grown by a pattern outside their factor.
  std::uint64_t plans_made = 0;
  std::uint64_t plans_grown = 0;
  /// Distinct obstacles in contact with the rover at the start of the last step (not a count).
  int obstacles_touched = 0;
  /// Solves can take the sparse path: SimOptions::sparse_lcp, and our own island step
  /// (SimOptions::stepper = Own, which calls the sparse solver itself) or the solver hook works in
  /// this process (solver::fast_lcp_active(), cpp/solver/ode_init.hpp). False: every solve is
  /// ODE's, friction bounded by its approximation (no solve_coulomb). With Own and the hook off,
  /// the attempts handed to dWorldStep (own_fallbacks) are ODE's solver's, without
  /// solve_coulomb.
  bool fast_lcp = false;
};

/// Complete simulation state; restore() reproduces the run bit for bit.
struct Snapshot {
  struct Body {
    std::array<double, 3> pos{}, lin{}, ang{};
    std::array<double, 4> quat{};
  };
  std::array<Body, 6> bodies{};
  RoverState state{};
  Commands commands{};
  std::array<double, 4> shear_x{}, shear_y{};  // implicit shear levels of the last step
  std::array<double, 4> compaction{};          // implicit compaction force of the last step
  // active-set outcomes of the last two steps (guesses for the next)
  std::array<RowState, kGuessedRowCount> row_mode{}, row_mode_before{};
  bool alternating = false;
  /// Tangential deflection of each tyre on rigid ground (world, m; cpp/dynamics/rover_rigid.cpp).
  std::array<std::array<double, 3>, 4> rigid_deflection{};
  /// Each wheel's obstacle contacts guessed sticking (Free) or bounded (rover_rigid.cpp).
  std::array<RowState, 4> obstacle_mode{};
  /// The largest growth rate of a wheel's slip estimated in the last step [1/s]; it decides the
  /// next obstacle step's substeps when SimOptions::obstacle_substeps is 1 (obstacle_contacts.cpp).
  double slip_rate = 0.0;
  /// The implicit slip's first guesses (cpp/dynamics/rover_step.cpp): per wheel the soil rows'
  /// levels of the two steps before the last (shear_x, compaction), the steps it has been on soil
  /// without a break (0-3), and its last accepted slip minus eq 12's at that step's start (NaN:
  /// none).
  std::array<std::array<double, 4>, 2> shear_x_past{}, compaction_past{};
  std::array<int, 4> soil_steps{};
  std::array<double, 4> slip_offset{};
  /// Sparsity patterns the constraint solver's orderings were made from (they set the rounding
  /// of the steps that follow; internal layout, see cpp/solver/lcp_workspace.hpp).
  std::vector<std::uint64_t> solver_patterns;
  bool valid = false;
};

/// One thread at a time: every public method that reads or changes the simulation refuses with
/// ConcurrentUse (std::runtime_error; RuntimeError in Python) while another thread is inside one
/// of them (e.g. step_n with the GIL released). Different RoverSims run in parallel freely.
/// After ODE fails internally (SimulationDiverged "ODE internal error") a RoverSim refuses every
/// further step, reset and restore: create a new one.
class RoverSim {
 public:
  /// The rover's state as a flat vector (state_vector()): kStateVectorSize values. Not the
  /// policy's observation (45 values, cpp/sensing/observation.hpp, layout ernest-obs-v2).
  static constexpr int kStateVectorSize = 65;
  static constexpr int kCommandSize = 8;

  RoverSim(const RoverParameters& params, const HeightMap& terrain,
           const std::vector<BoxObstacle>& obstacles = {}, const SimOptions& options = {});
  ~RoverSim();
  RoverSim(const RoverSim&) = delete;
  RoverSim& operator=(const RoverSim&) = delete;

  /// Place the rover at rest at (x, y) with heading [rad], the chassis tilted to the terrain
  /// under the wheels and lowered until the deepest wheel just touches; gimbal at (psi, phi).
  /// speed [m/s] gives a rolling start: every body moves forward at it and the wheels spin at
  /// speed / r (on soft soil eq 12's regularisation makes a standing start very hard).
  void reset(double x, double y, double heading, double psi = 0.0, double phi = 0.0,
             double speed = 0.0);

  void set_commands(const Commands& commands);
  const Commands& commands() const;
  /// Batch form: (w_FL, w_FR, w_RL, w_RR, psi_dot, phi_dot, gimbal_enabled, clutch_engage),
  /// velocity mode for all actuators.
  void set_command_vector(const double* c);

  /// Advance one physics step; throws SimulationDiverged on a non-finite or absurd state.
  void step();
  /// n steps. Interruptible (common/interrupt.hpp): stops between two whole steps, usable after.
  void step_n(int n);

  const RoverState& state() const;
  /// A copy of state(), taken under the one-thread-at-a-time rule (for the Python binding).
  RoverState state_copy() const;
  /// state() as kStateVectorSize values in a fixed layout; names from state_vector_names().
  void state_vector(double* out) const;
  static std::vector<std::string> state_vector_names();

  Snapshot snapshot() const;
  void restore(const Snapshot& s);

  /// Test/scenario hook: an external force [N] on the chassis at its CoM during the next step only.
  void apply_chassis_force(const Eigen::Vector3d& force);

  /// Kinetic energy of all bodies [J] and potential energy m g z [J] (world frame, z up).
  double kinetic_energy() const;
  double potential_energy() const;
  /// Counters of the active-set guesses (SimOptions::guess_active_set).
  const SolverStats& solver_stats() const;
  /// Friction coefficient in use for obstacles and rigid ground.
  double friction() const;

  const RoverParameters& parameters() const;
  const SimOptions& options() const;
  const HeightMap& terrain() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace ernest::dynamics
