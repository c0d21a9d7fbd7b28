// ERNEST on ODE. Equation numbers refer to seed 004.
#include "ernest/dynamics/rover_sim.hpp"

#include <ode/ode.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstring>
#include <exception>
#include <mutex>
#include <random>
#include <sstream>

#include "ernest/common/validation.hpp"
#include "ernest/soil/bekker_wong.hpp"

namespace ernest::dynamics {

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

constexpr int kChassis = 0, kBogie = 1;
constexpr int kMaxObstacleContacts = 64;
constexpr int kMaxContactsPerPair = 4;
const char* const kBodyNames[6] = {"chassis", "bogie", "wheel FL", "wheel FR", "wheel RL", "wheel RR"};

void init_ode_once() {
  static std::once_flag flag;
  std::call_once(flag, [] {
    dInitODE2(0);
    // ODE's Dantzig LCP reports recoverable pivoting issues on stderr; the divergence check
    // below is our error channel, so these messages are dropped.
    dSetMessageHandler([](int, const char*, va_list) {});
  });
  // Every thread that steps a world needs ODE's per-thread data (collision caches).
  thread_local bool allocated = false;
  if (!allocated) {
    dAllocateODEDataForThread(dAllocateMaskAll);
    allocated = true;
  }
}

Vec3 to_vec(const dReal* v) { return {v[0], v[1], v[2]}; }

Mat3 to_mat(const dReal* r) {  // ODE stores 3x4 row-major
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = r[4 * i + j];
  return m;
}

void to_ode_rot(const Mat3& m, dMatrix3 r) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r[4 * i + j] = m(i, j);
    r[4 * i + 3] = 0.0;
  }
}

Mat3 rot_zyx(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
          Eigen::AngleAxisd(roll, Vec3::UnitX()))
      .toRotationMatrix();
}

void set_body_pose(dBodyID b, const Vec3& p, const Mat3& r) {
  const Eigen::Quaterniond q(r);
  dQuaternion dq = {q.w(), q.x(), q.y(), q.z()};
  dBodySetPosition(b, p.x(), p.y(), p.z());
  dBodySetQuaternion(b, dq);
}

// ODE normalises a quaternion whenever it is set, so a restored state is only bit-identical if
// the stored quaternion is a fixed point of that normalisation (it need not be: normalisation can
// alternate between two neighbours). After each step we move every body's quaternion to a nearby
// fixed point by nudging its largest component by a few ulps (a 1e-16 change) until setting it
// returns it unchanged; the rotation matrix is then recomputed from exactly that quaternion.
void canonicalise_quaternion(dBodyID b) {
  const dReal* q0 = dBodyGetQuaternion(b);
  const dQuaternion base = {q0[0], q0[1], q0[2], q0[3]};
  int big = 0;
  for (int k = 1; k < 4; ++k)
    if (std::abs(base[k]) > std::abs(base[big])) big = k;
  static const int kNudge[] = {0, 1, -1, 2, -2, 3, -3, 4, -4};
  for (int nudge : kNudge) {
    dQuaternion c = {base[0], base[1], base[2], base[3]};
    for (int u = 0; u < std::abs(nudge); ++u)
      c[big] = std::nextafter(c[big], nudge > 0 ? 2.0 : -2.0);
    dBodySetQuaternion(b, c);
    const dReal* q = dBodyGetQuaternion(b);
    if (std::memcmp(c, q, sizeof(dQuaternion)) == 0) return;
  }
  // No fixed point within 4 ulps (never seen): keep ODE's normalised value.
}

struct DeepestPoint {
  Vec3 point;    // reference contact point on the tyre (deepest into the terrain)
  Vec3 normal;   // terrain normal at it
  double depth;  // penetration along the normal (> 0 in contact) [m]
};

// Reference contact point of a torus-shaped tyre (§3.3: DARTS accounts for the torus when locating
// the point penetrating farthest): centre-circle radius R0 = r - b/2 in the wheel plane, tube
// radius b/2. For a locally plane terrain of normal n the deepest tyre point is the centre-circle
// point farthest along -n plus the tube radius along -n. Two passes refine n at that point.
DeepestPoint deepest_point(const HeightMap& hm, const Vec3& centre, const Vec3& axle, double r,
                           double tube) {
  const double r0 = r - tube;
  DeepestPoint dp;
  Vec3 n = hm.normal(centre.x(), centre.y());
  Vec3 p = centre;
  for (int pass = 0; pass < 2; ++pass) {
    Vec3 d = n - n.dot(axle) * axle;  // in-plane direction of n
    const double dn = d.norm();
    d = dn > 1e-9 ? Vec3(d / dn) : Vec3::Zero();
    p = centre - r0 * d - tube * n;
    n = hm.normal(p.x(), p.y());
  }
  dp.point = p;
  dp.normal = n;
  dp.depth = (hm.height(p.x(), p.y()) - p.z()) * n.z();
  return dp;
}

inline double clamp_unit(double v) { return std::min(1.0, std::max(-1.0, v)); }

}  // namespace

void SimOptions::validate() const {
  const char* o = "SimOptions";
  require_in_range(o, "dt", dt, 1e-5, 0.05);
  soil.validate();
  require_in_range(o, "soil_points_per_panel", soil_points_per_panel, 1,
                   soil::BekkerWongModel::kMaxPointsPerPanel);
  require_in_range(o, "soil_normal_damping", soil_normal_damping, 1e-3, 1e7);
  rigid.validate();
  require(std::isfinite(friction) && friction <= 10.0,
          "SimOptions.friction = " + std::to_string(friction) +
              " must be finite and <= 10 (< 0 draws it from rigid)");
  require_in_range(o, "rigid_slip", rigid_slip, 0.0, 1.0);
  require_in_range(o, "max_speed", max_speed, 1e-3, 1e6);
  require_in_range(o, "max_angular_speed", max_angular_speed, 1e-3, 1e7);
}

void Commands::validate() const {
  const char* o = "Commands";
  for (int i = 0; i < 4; ++i) {
    require_finite(o, "wheel_speed", wheel_speed[i]);
    require_finite(o, "wheel_torque", wheel_torque[i]);
  }
  require_finite(o, "yaw_rate", yaw_rate);
  require_finite(o, "roll_rate", roll_rate);
  require_finite(o, "yaw_torque", yaw_torque);
  require_finite(o, "roll_torque", roll_torque);
}

struct RoverSim::Impl {
  RoverParameters p;
  HeightMap hm;
  std::vector<BoxObstacle> boxes;
  SimOptions opt;
  soil::BekkerWongModel soil_free;  // shear regularisation (eqs 28–29) -> 0: pressure terms only
  soil::BekkerWongModel soil_sat;   // shear saturated (|sign| = 1): pressure + unit shear
  double mu = 0.5;

  dWorldID world = nullptr;
  dThreadingImplementationID threading = nullptr;
  dSpaceID rover_space = nullptr, obstacle_space = nullptr;
  dJointGroupID contacts = nullptr;
  std::array<dBodyID, 6> body{};
  std::array<dGeomID, 6> geom{};
  std::array<dJointID, 4> hinge{};
  dJointID gimbal = nullptr;
  std::array<dJointFeedback, 4> hinge_fb{};
  dJointFeedback gimbal_fb{};
  std::array<dJointFeedback, 4> ground_fb{};
  std::array<dJointID, 4> ground_joint{};
  std::array<dJointID, 4> compaction_joint{};
  std::array<dJointFeedback, 4> compaction_fb{};
  std::array<double, 4> compaction{};  // last step's compaction resistance along x [N]
  std::vector<dGeomID> obstacle_geoms;
  int n_obstacle_contacts = 0;
  std::exception_ptr callback_error;

  Commands cmd{};
  RoverState st{};
  std::array<double, 4> shear_x{}, shear_y{};
  // per-step contact data
  std::array<double, 4> unit_shear_x{}, unit_shear_y{}, explicit_fz{};
  std::array<Vec3, 4> frame_x{}, frame_y{}, frame_n{};
  Vec3 pending_force = Vec3::Zero();
  bool diverged = false;
  double bogie_com_height_from_gimbal = 0.0;

  static soil::SoilParameters with_eps(soil::SoilParameters s, double eps) {
    s.eps_contact_x = eps;
    s.eps_contact_y = eps;
    s.eps_direction = 0.0;  // sign(v_x) exactly; its regularisation is applied implicitly below
    return s;
  }

  Impl(const RoverParameters& params, const HeightMap& terrain,
       const std::vector<BoxObstacle>& obstacles, const SimOptions& options)
      : p(params), hm(terrain), boxes(obstacles), opt(options),
        soil_free(with_eps(options.soil, 1e9),
                  soil::WheelGeometry{params.wheel_radius, params.wheel_width},
                  options.soil_points_per_panel),
        soil_sat(with_eps(options.soil, 1e-9),
                 soil::WheelGeometry{params.wheel_radius, params.wheel_width},
                 options.soil_points_per_panel) {}

  ~Impl() {
    if (contacts) dJointGroupDestroy(contacts);
    if (rover_space) dSpaceDestroy(rover_space);  // destroys its geoms (cleanup on by default)
    if (obstacle_space) dSpaceDestroy(obstacle_space);
    if (world) {
      dWorldSetStepThreadingImplementation(world, nullptr, nullptr);
      dWorldDestroy(world);
    }
    if (threading) dThreadingFreeImplementation(threading);
  }

  Vec3 axle_world(int i) const { return to_mat(dBodyGetRotation(body[2 + i])).col(1); }
  Mat3 rot(int b) const { return to_mat(dBodyGetRotation(body[b])); }
  Vec3 pos(int b) const { return to_vec(dBodyGetPosition(body[b])); }
  int parent_of(int wheel) const { return wheel < 2 ? kBogie : kChassis; }

  void build();
  void place(double x, double y, double heading, double psi, double phi, double speed);
  void gimbal_angles(double& psi, double& phi, double& psid, double& phid, Vec3& ez,
                     Vec3& ea) const;
  void apply_actuators(double psi, double phi, double psid, double phid, const Vec3& ez,
                       const Vec3& ea);
  void ground_contacts();
  void obstacle_contacts();
  void near(dGeomID a, dGeomID b);
  void read_outputs(double dt_done);
  void check_divergence();
  void check_forces_before_step();
  void step();
};

void RoverSim::Impl::build() {
  init_ode_once();
  world = dWorldCreate();
  // ODE's default step threading implementation is one object shared by every world and is not
  // thread-safe (ReleaseAJob assertions when two worlds step on two threads): each world gets
  // its own self-threaded implementation so that rovers can step concurrently.
  threading = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(world, dThreadingImplementationGetFunctions(threading),
                                       threading);
  dWorldSetGravity(world, 0.0, 0.0, -opt.soil.gravity);
  dWorldSetERP(world, 0.2);
  dWorldSetCFM(world, 1e-9);
  dWorldSetAutoDisableFlag(world, 0);
  rover_space = dSimpleSpaceCreate(nullptr);
  obstacle_space = dSimpleSpaceCreate(nullptr);
  contacts = dJointGroupCreate(0);

  std::mt19937_64 rng(opt.seed);
  mu = opt.friction >= 0.0 ? opt.friction : opt.rigid.sample_friction(rng);

  // Bodies in the nominal pose (rover frame = world, psi = phi = 0); reset() moves them.
  dMass m;
  const Vec3 g = p.gimbal_point();
  body[kChassis] = dBodyCreate(world);
  dMassSetZero(&m);
  dMassSetParameters(&m, p.chassis_mass, 0, 0, 0, p.chassis_inertia[0], p.chassis_inertia[1],
                     p.chassis_inertia[2], 0, 0, 0);
  dBodySetMass(body[kChassis], &m);
  body[kBogie] = dBodyCreate(world);
  dMassSetZero(&m);
  dMassSetParameters(&m, p.bogie_mass, 0, 0, 0, p.bogie_inertia[0], p.bogie_inertia[1],
                     p.bogie_inertia[2], 0, 0, 0);
  dBodySetMass(body[kBogie], &m);
  // Wheel assemblies (steering locked): spin inertia plus the rotor reflected through the gear.
  const double spin = p.wheel_spin_inertia + p.wheel_motor.rotor_inertia *
                                                 p.wheel_motor.gear_ratio * p.wheel_motor.gear_ratio;
  for (int i = 0; i < 4; ++i) {
    body[2 + i] = dBodyCreate(world);
    dMassSetZero(&m);
    dMassSetParameters(&m, p.wheel_assembly_mass, 0, 0, 0, p.wheel_transverse_inertia, spin,
                       p.wheel_transverse_inertia, 0, 0, 0);
    dBodySetMass(body[2 + i], &m);
  }
  for (auto b : body) dBodySetGyroscopicMode(b, 1);

  // Collision geometry vs rigid obstacles: chassis and bogie boxes, cylinders for the wheels.
  geom[kChassis] = dCreateBox(rover_space, p.chassis_box.x(), p.chassis_box.y(), p.chassis_box.z());
  dGeomSetBody(geom[kChassis], body[kChassis]);
  const Vec3 cbox = p.chassis_box_centre - p.chassis_com;
  dGeomSetOffsetPosition(geom[kChassis], cbox.x(), cbox.y(), cbox.z());
  geom[kBogie] = dCreateBox(rover_space, p.bogie_box.x(), p.bogie_box.y(), p.bogie_box.z());
  dGeomSetBody(geom[kBogie], body[kBogie]);
  dGeomSetOffsetPosition(geom[kBogie], 0.0, 0.0, p.bogie_box_height - p.bogie_com_height);
  dMatrix3 cyl;
  dRFromAxisAndAngle(cyl, 1.0, 0.0, 0.0, M_PI / 2.0);  // cylinder axis (local z) -> axle (y)
  for (int i = 0; i < 4; ++i) {
    geom[2 + i] = dCreateCylinder(rover_space, p.wheel_radius, p.wheel_width);
    dGeomSetBody(geom[2 + i], body[2 + i]);
    dGeomSetOffsetRotation(geom[2 + i], cyl);
  }
  for (const BoxObstacle& b : boxes) {
    dGeomID gb = dCreateBox(obstacle_space, b.size.x(), b.size.y(), b.size.z());
    dMatrix3 r;
    to_ode_rot(rot_zyx(b.yaw, b.pitch, b.roll), r);
    dGeomSetPosition(gb, b.centre.x(), b.centre.y(), b.centre.z());
    dGeomSetRotation(gb, r);
    obstacle_geoms.push_back(gb);
  }

  // Nominal placement so that joints are created in a consistent pose.
  place(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
  // Active Gimbal Suspension: yaw axis fixed in the chassis (z), roll axis fixed in the bogie (x),
  // collocated and intersecting (§2.2) — an ODE universal joint.
  const Vec3 gw = pos(kChassis) + rot(kChassis) * (g - p.chassis_com);
  gimbal = dJointCreateUniversal(world, nullptr);
  dJointAttach(gimbal, body[kChassis], body[kBogie]);
  dJointSetUniversalAnchor(gimbal, gw.x(), gw.y(), gw.z());
  dJointSetUniversalAxis1(gimbal, 0.0, 0.0, 1.0);
  dJointSetUniversalAxis2(gimbal, 1.0, 0.0, 0.0);
  dJointSetFeedback(gimbal, &gimbal_fb);
  for (int i = 0; i < 4; ++i) {
    hinge[i] = dJointCreateHinge(world, nullptr);
    dJointAttach(hinge[i], body[2 + i], body[parent_of(i)]);
    const Vec3 c = pos(2 + i);
    dJointSetHingeAnchor(hinge[i], c.x(), c.y(), c.z());
    dJointSetHingeAxis(hinge[i], 0.0, 1.0, 0.0);
    dJointSetFeedback(hinge[i], &hinge_fb[i]);
  }
}

void RoverSim::Impl::place(double x, double y, double heading, double psi, double phi,
                           double speed) {
  // Tilt the chassis to the plane through the terrain under the nominal wheel centres.
  const Mat3 rz = Eigen::AngleAxisd(heading, Vec3::UnitZ()).toRotationMatrix();
  std::array<double, 4> h{};
  for (int i = 0; i < 4; ++i) {
    const Vec3 w = Vec3(x, y, 0.0) + rz * p.wheel_centre(i);
    h[i] = hm.height(w.x(), w.y());
  }
  const double sx = ((h[kFL] + h[kFR]) - (h[kRL] + h[kRR])) / (2.0 * p.wheelbase);
  const double sy = ((h[kFL] + h[kRL]) - (h[kFR] + h[kRR])) / (2.0 * p.track);
  const Mat3 rc = rz * Eigen::AngleAxisd(-std::atan(sx), Vec3::UnitY()).toRotationMatrix() *
                  Eigen::AngleAxisd(std::atan(sy), Vec3::UnitX()).toRotationMatrix();
  const Mat3 rb_rel = (Eigen::AngleAxisd(psi, Vec3::UnitZ()) *
                       Eigen::AngleAxisd(phi, Vec3::UnitX())).toRotationMatrix();
  const Vec3 g = p.gimbal_point();
  auto wheel_rel = [&](int i) { return i < 2 ? Vec3(g + rb_rel * (p.wheel_centre(i) - g))
                                             : p.wheel_centre(i); };
  const double mean_h = 0.25 * (h[0] + h[1] + h[2] + h[3]);
  Vec3 origin(x, y, mean_h + p.wheel_radius);
  // Lower/raise until the deepest wheel just touches (1 mm above).
  double worst = -1e9;
  for (int i = 0; i < 4; ++i) {
    const Mat3 rw = i < 2 ? Mat3(rc * rb_rel) : rc;
    const DeepestPoint dp = deepest_point(hm, origin + rc * wheel_rel(i), rw.col(1),
                                          p.wheel_radius, p.tyre_tube_radius());
    worst = std::max(worst, dp.depth / std::max(dp.normal.z(), 1e-3));
  }
  origin.z() += worst + 1e-3;
  set_body_pose(body[kChassis], origin + rc * p.chassis_com, rc);
  const Vec3 bogie_com(0.5 * p.wheelbase, 0.0, p.bogie_com_height);
  set_body_pose(body[kBogie], origin + rc * (g + rb_rel * (bogie_com - g)), rc * rb_rel);
  for (int i = 0; i < 4; ++i)
    set_body_pose(body[2 + i], origin + rc * wheel_rel(i), i < 2 ? Mat3(rc * rb_rel) : rc);
  const Vec3 v0 = rc.col(0) * speed;
  for (int k = 0; k < 6; ++k) {
    const dBodyID b = body[k];
    dBodySetLinearVel(b, v0.x(), v0.y(), v0.z());
    const Vec3 w0 = k >= 2 ? Vec3(rot(k).col(1) * (speed / p.wheel_radius)) : Vec3::Zero();
    dBodySetAngularVel(b, w0.x(), w0.y(), w0.z());
    dBodySetForce(b, 0, 0, 0);
    dBodySetTorque(b, 0, 0, 0);
    canonicalise_quaternion(b);
  }
  st = RoverState{};
  st.gimbal_yaw = psi;
  st.gimbal_roll = phi;
  st.bogie_frame_angle = phi;
  shear_x.fill(0.0);
  shear_y.fill(0.0);
  compaction.fill(0.0);
  pending_force.setZero();
  diverged = false;
  callback_error = nullptr;
}

void RoverSim::Impl::gimbal_angles(double& psi, double& phi, double& psid, double& phid, Vec3& ez,
                                   Vec3& ea) const {
  // R_c^T R_b = R_z(psi) R_x(phi): yaw about the chassis z, then roll about the bogie x.
  const Mat3 rc = rot(kChassis), rb = rot(kBogie);
  const Mat3 rel = rc.transpose() * rb;
  psi = std::atan2(rel(1, 0), rel(0, 0));
  phi = std::atan2(rel(2, 1), rel(2, 2));
  ez = rc.col(2);
  ea = rb.col(0);
  const Vec3 wrel = to_vec(dBodyGetAngularVel(body[kBogie])) -
                    to_vec(dBodyGetAngularVel(body[kChassis]));
  psid = wrel.dot(ez);  // ez is orthogonal to ea, so the relative rate splits exactly
  phid = wrel.dot(ea);
}

void RoverSim::Impl::apply_actuators(double psi, double phi, double psid, double phid,
                                     const Vec3& ez, const Vec3& ea) {
  const double dt = opt.dt;
  // ---- wheels: hinge motors (ODE solves the velocity servo implicitly, |torque| <= limit) ----
  const double wheel_max = p.wheel_motor.max_output_torque();
  for (int i = 0; i < 4; ++i) {
    const dJointID j = hinge[i];
    if (cmd.wheel_mode == ActuatorMode::Velocity) {
      dJointSetHingeParam(j, dParamVel, cmd.wheel_speed[i]);
      dJointSetHingeParam(j, dParamFMax, wheel_max);
    } else {
      dJointSetHingeParam(j, dParamVel, 0.0);
      dJointSetHingeParam(j, dParamFMax, 0.0);
      if (cmd.wheel_mode == ActuatorMode::Torque) {
        const double t = std::clamp(cmd.wheel_torque[i], -wheel_max, wheel_max);
        const Vec3 a = axle_world(i) * t;
        dBodyAddTorque(body[2 + i], a.x(), a.y(), a.z());
        dBodyAddTorque(body[parent_of(i)], -a.x(), -a.y(), -a.z());
      }
    }
  }
  const double gimbal_max = p.gimbal_motor.max_output_torque();
  const auto add_pair_torque = [&](const Vec3& axis, double t) {
    const Vec3 v = axis * t;
    dBodyAddTorque(body[kBogie], v.x(), v.y(), v.z());
    dBodyAddTorque(body[kChassis], -v.x(), -v.y(), -v.z());
  };
  // ---- yaw: motor, or the brake when the AGS is off. ODE's universal motor drives the rate of
  // body1 (chassis) relative to body2 (bogie), hence the minus sign.
  if (!cmd.gimbal_enabled) {
    dJointSetUniversalParam(gimbal, dParamVel, 0.0);
    dJointSetUniversalParam(gimbal, dParamFMax, p.yaw_brake_torque);
  } else if (cmd.yaw_mode == ActuatorMode::Velocity) {
    dJointSetUniversalParam(gimbal, dParamVel, -cmd.yaw_rate);
    dJointSetUniversalParam(gimbal, dParamFMax, gimbal_max);
  } else {
    dJointSetUniversalParam(gimbal, dParamVel, 0.0);
    dJointSetUniversalParam(gimbal, dParamFMax, 0.0);
    if (cmd.yaw_mode == ActuatorMode::Torque)
      add_pair_torque(ez, std::clamp(cmd.yaw_torque, -gimbal_max, gimbal_max));
  }
  // ---- roll clutch (§2.2): align the bogie frame with the bogie at bounded speed, then engage.
  if (!cmd.clutch_engage) {
    st.clutch = ClutchState::Disengaged;
  } else if (st.clutch == ClutchState::Disengaged) {
    st.clutch = ClutchState::Aligning;
  }
  if (st.clutch == ClutchState::Aligning) {
    const double err = phi - st.bogie_frame_angle;
    const double v = std::clamp(p.clutch_align_gain * err, -p.clutch_align_speed,
                                p.clutch_align_speed);
    st.bogie_frame_angle += v * dt;
    if (std::abs(phi - st.bogie_frame_angle) <= p.clutch_align_tolerance) {
      st.clutch = ClutchState::Engaged;
    }
  } else if (st.clutch == ClutchState::Disengaged && cmd.gimbal_enabled) {
    // The unloaded frame follows the roll command (it can move with the clutch open).
    st.bogie_frame_angle = std::clamp(st.bogie_frame_angle + cmd.roll_rate * dt, -p.roll_limit,
                                      p.roll_limit);
  }
  if (st.clutch == ClutchState::Engaged) {
    st.bogie_frame_angle = phi;
    if (!cmd.gimbal_enabled) {  // roll actuator braked, pins in: bogie held
      dJointSetUniversalParam(gimbal, dParamVel2, 0.0);
      dJointSetUniversalParam(gimbal, dParamFMax2, p.yaw_brake_torque);
    } else if (cmd.roll_mode == ActuatorMode::Velocity) {
      dJointSetUniversalParam(gimbal, dParamVel2, -cmd.roll_rate);
      dJointSetUniversalParam(gimbal, dParamFMax2, gimbal_max);
    } else {
      dJointSetUniversalParam(gimbal, dParamVel2, 0.0);
      dJointSetUniversalParam(gimbal, dParamFMax2, 0.0);
      if (cmd.roll_mode == ActuatorMode::Torque)
        add_pair_torque(ea, std::clamp(cmd.roll_torque, -gimbal_max, gimbal_max));
    }
  } else {  // pins out: the bogie rolls freely on its bearing
    dJointSetUniversalParam(gimbal, dParamVel2, 0.0);
    dJointSetUniversalParam(gimbal, dParamFMax2, 0.0);
  }
  // ---- joint stops as stiff spring–dampers (§3.1): ODE's stops with the spring k and damper c
  // mapped to ERP = h k / (h k + c), CFM = 1 / (h k + c) so that they stay stable at large steps.
  const double kh = dt * p.stop_stiffness + p.stop_damping;
  for (int ax = 0; ax < 2; ++ax) {
    const double lim = ax == 0 ? p.yaw_limit : p.roll_limit;
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamLoStop : dParamLoStop2, -lim);
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamHiStop : dParamHiStop2, lim);
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamStopERP : dParamStopERP2,
                            dt * p.stop_stiffness / kh);
    dJointSetUniversalParam(gimbal, ax == 0 ? dParamStopCFM : dParamStopCFM2, 1.0 / kh);
  }
  (void)psi;
  (void)psid;
  (void)phid;
}

void RoverSim::Impl::ground_contacts() {
  const bool soil = opt.ground == GroundType::Soil;
  for (int i = 0; i < 4; ++i) {
    ground_joint[i] = nullptr;
    compaction_joint[i] = nullptr;
    unit_shear_x[i] = unit_shear_y[i] = explicit_fz[i] = 0.0;
    st.sinkage[i] = 0.0;
    st.slip[i] = 0.0;
    st.contact_vx[i] = st.contact_vy[i] = 0.0;
    const dBodyID wb = body[2 + i];
    const Vec3 c = pos(2 + i), a = axle_world(i);
    const DeepestPoint dp = deepest_point(hm, c, a, p.wheel_radius, p.tyre_tube_radius());
    // Contact frame of Fig. 7: x forward (yawed with the wheel, not tilted), y along the axle
    // projected on the terrain, z the terrain normal.
    const Vec3 n = dp.normal;
    Vec3 fx = a.cross(n);
    fx = fx.norm() > 1e-9 ? Vec3(fx.normalized()) : Vec3(rot(parent_of(i)).col(0));
    const Vec3 fy = n.cross(fx);
    frame_x[i] = fx;
    frame_y[i] = fy;
    frame_n[i] = n;
    if (!(dp.depth > 0.0)) continue;
    st.sinkage[i] = dp.depth;
    const Vec3 vc = to_vec(dBodyGetLinearVel(wb));
    dVector3 vp;
    dBodyGetPointVel(wb, dp.point.x(), dp.point.y(), dp.point.z(), vp);
    const Vec3 vpc = to_vec(vp);
    st.contact_vx[i] = vpc.dot(fx);
    st.contact_vy[i] = vpc.dot(fy);

    dContact ct;
    std::memset(&ct, 0, sizeof ct);
    ct.geom.pos[0] = dp.point.x();
    ct.geom.pos[1] = dp.point.y();
    ct.geom.pos[2] = dp.point.z();
    ct.geom.normal[0] = n.x();
    ct.geom.normal[1] = n.y();
    ct.geom.normal[2] = n.z();
    ct.fdir1[0] = fx.x();
    ct.fdir1[1] = fx.y();
    ct.fdir1[2] = fx.z();
    if (!soil) {
      // §3.4 spring–damper as ERP/CFM for this step; Coulomb friction mu (pyramid, dContactApprox1).
      ct.geom.depth = dp.depth;
      ct.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactSlip1 |
                        dContactSlip2 | dContactFDir1;
      ct.surface.mu = mu;
      ct.surface.slip1 = ct.surface.slip2 = opt.rigid_slip;
      ct.surface.soft_erp = opt.rigid.erp(opt.dt);
      ct.surface.soft_cfm = opt.rigid.cfm(opt.dt);
    } else {
      const double vx = vc.dot(fx);
      // The models use sign(v_x) exactly (eps_direction = 0); at v_x = 0 the sign is taken as +.
      soil::ContactState cs{dp.depth, vx != 0.0 ? vx : 1e-12, vc.dot(fy), st.contact_vx[i],
                            st.contact_vy[i]};
      // Bekker–Wong (eqs 12–32) is split into terms ODE can integrate implicitly and the rest:
      // (a) the shear, whose regularisation tau -> sign(-v_c) min(|v_c|/eps_contact, 1) tau
      //     (eqs 28–29) is a viscous law with a force cap: a friction row at the contact point
      //     with force-dependent slip (velocity = slip * force) and bounds +-F_sat;
      // (b) the compaction resistance -sign(v_x) rb int sigma sin (eq 30), whose regularised sign
      //     clamp(v_x / eps_direction) is the same kind of law on the wheel-centre velocity: a
      //     linear-motor row with CFM = eps_direction / F and bounds +-F;
      // (c) explicit forces: normal stress (eq 32), the shear's normal part and the share of the
      //     axle torque the rows do not produce, with the levels the rows reached last step.
      // Treated explicitly, (a) and (b) are stiff dampers (~1e4 N s/m) unstable at any useful step.
      const soil::WheelSoilForce free = soil_free.evaluate(cs);
      soil::ContactState sat_state = cs;
      if (std::abs(sat_state.vcx) < 1e-7) sat_state.vcx = -1e-7;
      if (std::abs(sat_state.vcy) < 1e-7) sat_state.vcy = -1e-7;
      const soil::WheelSoilForce sat = soil_sat.evaluate(sat_state);
      const double sgn_x = sat_state.vcx < 0.0 ? 1.0 : -1.0;  // eq 28 sign at saturation
      const double sgn_y = sat_state.vcy < 0.0 ? 1.0 : -1.0;  // eq 29
      const double ax = std::max((sat.fx - free.fx) * sgn_x, 0.0);  // eq 30 shear part, unit sign
      const double bz = (sat.fz - free.fz) * sgn_x;                  // eq 32 shear part
      const double cax = (sat.axle_torque - free.axle_torque) * sgn_x;
      const double ay = std::max((sat.fy - free.fy) * sgn_y, 0.0);  // eq 31
      const double sign_vx = cs.vx > 0.0 ? 1.0 : -1.0;
      // rb int sigma sin theta (eq 30); below 1 mN the row is dropped (a CFM of eps / F would
      // overflow ODE's LCP as F -> 0).
      double comp = std::max(-free.fx * sign_vx, 0.0);
      if (comp < 1e-3) comp = 0.0;
      unit_shear_x[i] = ax;
      unit_shear_y[i] = ay;
      st.slip[i] = free.slip;
      const double sx = shear_x[i];
      const double fz = free.fz + bz * sx;
      explicit_fz[i] = fz;
      const Vec3 f = fy * free.fy + n * fz;
      dBodyAddForceAtPos(wb, f.x(), f.y(), f.z(), dp.point.x(), dp.point.y(), dp.point.z());
      const double arm = (dp.point - c).cross(fx).dot(a);  // axle torque per unit x force at P
      const double row_torque = arm * ax * sx;
      const double soil_torque = -cax * sx;  // the soil applies -axle_torque (bekker_wong.hpp)
      // The compaction row acts at the wheel centre; its moment about the axle (at the patch) is
      // added with last step's level.
      const Vec3 tc = a * (soil_torque - row_torque + arm * compaction[i]);
      dBodyAddTorque(wb, tc.x(), tc.y(), tc.z());
      {
        // Row 0: compaction (b). Row 1: two-sided normal damping of the wheel centre, capped at
        // the soil's normal force so the net normal force never pulls the wheel down. Without it
        // the pressure law's jump between rest and motion (eq 16: t_rest switches within
        // eps_motion = 5e-5 m/s) pumps energy into vertical bouncing at rest.
        const double eps_dir = std::max(opt.soil.eps_direction, 1e-6);
        dJointID lm = dJointCreateLMotor(world, contacts);
        dJointAttach(lm, wb, nullptr);
        dJointSetLMotorNumAxes(lm, 2);
        dJointSetLMotorAxis(lm, 0, 0, fx.x(), fx.y(), fx.z());
        dJointSetLMotorAxis(lm, 1, 0, n.x(), n.y(), n.z());
        dJointSetLMotorParam(lm, dParamVel, 0.0);
        dJointSetLMotorParam(lm, dParamFMax, comp);
        dJointSetLMotorParam(lm, dParamCFM, comp > 0.0 ? eps_dir / comp : 1.0);
        dJointSetLMotorParam(lm, dParamVel2, 0.0);
        dJointSetLMotorParam(lm, dParamFMax2, std::max(fz, 0.0));
        dJointSetLMotorParam(lm, dParamCFM2, 1.0 / opt.soil_normal_damping);
        dJointSetFeedback(lm, &compaction_fb[i]);
        compaction_joint[i] = lm;
      }
      ct.geom.depth = 0.0;  // no position correction: the normal row is a one-sided damper
      ct.surface.mode = dContactMu2 | dContactFDir1 | dContactSlip1 | dContactSlip2 |
                        dContactSoftERP | dContactSoftCFM;
      ct.surface.mu = ax;
      ct.surface.mu2 = ay;
      ct.surface.slip1 = opt.soil.eps_contact_x / std::max(ax, 1e-3);
      ct.surface.slip2 = opt.soil.eps_contact_y / std::max(ay, 1e-3);
      ct.surface.soft_erp = 0.0;
      ct.surface.soft_cfm = 1.0 / opt.soil_normal_damping;
    }
    dJointID j = dJointCreateContact(world, contacts, &ct);
    dJointAttach(j, wb, nullptr);
    dJointSetFeedback(j, &ground_fb[i]);
    ground_joint[i] = j;
  }
}

void RoverSim::Impl::near(dGeomID a, dGeomID b) {
  dContact cs[kMaxContactsPerPair];
  std::memset(cs, 0, sizeof cs);
  const int n = dCollide(a, b, kMaxContactsPerPair, &cs[0].geom, sizeof(dContact));
  if (n <= 0) return;
  const double erp = opt.rigid.erp(opt.dt);
  // The §3.4 stiffness is per wheel–obstacle contact: n simultaneous points share it.
  const double cfm = opt.rigid.cfm(opt.dt) * n;
  for (int k = 0; k < n && n_obstacle_contacts < kMaxObstacleContacts; ++k) {
    cs[k].surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM | dContactSlip1 |
                         dContactSlip2;
    cs[k].surface.slip1 = cs[k].surface.slip2 = opt.rigid_slip;
    cs[k].surface.mu = mu;
    cs[k].surface.soft_erp = erp;
    cs[k].surface.soft_cfm = cfm;
    dJointID j = dJointCreateContact(world, contacts, &cs[k]);
    dJointAttach(j, dGeomGetBody(a), dGeomGetBody(b));
    ++n_obstacle_contacts;
  }
}

void RoverSim::Impl::obstacle_contacts() {
  n_obstacle_contacts = 0;
  if (obstacle_geoms.empty()) return;
  // Never let an exception cross ODE's C callback: capture it and rethrow after the collision.
  dSpaceCollide2(
      reinterpret_cast<dGeomID>(rover_space), reinterpret_cast<dGeomID>(obstacle_space), this,
      [](void* data, dGeomID a, dGeomID b) {
        auto* self = static_cast<Impl*>(data);
        if (self->callback_error) return;
        try {
          self->near(a, b);
        } catch (...) {
          self->callback_error = std::current_exception();
        }
      });
  if (callback_error) {
    std::exception_ptr e = callback_error;
    callback_error = nullptr;
    dJointGroupEmpty(contacts);
    std::rethrow_exception(e);
  }
}

void RoverSim::Impl::step() {
  if (diverged)
    throw SimulationDiverged("RoverSim: the simulation diverged earlier; restore() or reset() first");
  init_ode_once();
  double psi, phi, psid, phid;
  Vec3 ez, ea;
  gimbal_angles(psi, phi, psid, phid, ez, ea);
  apply_actuators(psi, phi, psid, phid, ez, ea);
  ground_contacts();
  obstacle_contacts();
  if (pending_force.squaredNorm() > 0.0) {
    dBodyAddForce(body[kChassis], pending_force.x(), pending_force.y(), pending_force.z());
    pending_force.setZero();
  }
  // ODE aborts the process (an assertion in its quaternion normalisation) when a step produces a
  // non-finite state, so absurd inputs are refused before the step: the divergence check after
  // it only has to catch finite but absurd states.
  check_forces_before_step();
  // dWorldStep (Dantzig LCP), not dWorldQuickStep: QuickStep reorders constraints with ODE's
  // process-wide random generator (runs are not reproducible) and at equal accuracy (~50
  // iterations) it is no faster for this 6-body rover (benchmarks/RESULTS.md).
  dWorldStep(world, opt.dt);
  read_outputs(opt.dt);
  dJointGroupEmpty(contacts);
  check_divergence();
}

void RoverSim::Impl::read_outputs(double dt) {
  for (auto b : body) canonicalise_quaternion(b);
  st.time += dt;
  const Mat3 rc = rot(kChassis);
  const Vec3 origin = pos(kChassis) - rc * p.chassis_com;
  st.position = origin;
  const dReal* q = dBodyGetQuaternion(body[kChassis]);
  st.quaternion = Eigen::Vector4d(q[0], q[1], q[2], q[3]);
  const Vec3 w = to_vec(dBodyGetAngularVel(body[kChassis]));
  dVector3 vo;
  dBodyGetPointVel(body[kChassis], origin.x(), origin.y(), origin.z(), vo);
  st.linear_velocity = to_vec(vo);
  st.angular_velocity = w;
  st.body_linear_velocity = rc.transpose() * st.linear_velocity;
  st.body_angular_velocity = rc.transpose() * w;
  st.yaw = std::atan2(rc(1, 0), rc(0, 0));
  st.pitch = std::asin(std::clamp(-rc(2, 0), -1.0, 1.0));
  st.roll = std::atan2(rc(2, 1), rc(2, 2));

  double psi, phi, psid, phid;
  Vec3 ez, ea;
  gimbal_angles(psi, phi, psid, phid, ez, ea);
  st.gimbal_yaw = psi;
  st.gimbal_roll = phi;
  st.gimbal_yaw_rate = psid;
  st.gimbal_roll_rate = phid;
  // Gimbal actuator torques on the bogie: the universal joint's feedback moved to the joint
  // centre and projected on each axis (the cross-axis constraint torque is orthogonal to both).
  const Vec3 gpt = pos(kChassis) + rc * (p.gimbal_point() - p.chassis_com);
  const Vec3 f2 = to_vec(gimbal_fb.f2), t2 = to_vec(gimbal_fb.t2);
  const Vec3 tg = t2 + (pos(kBogie) - gpt).cross(f2);
  const double gimbal_max = p.gimbal_motor.max_output_torque();
  double tyaw = tg.dot(ez), troll = tg.dot(ea);
  if (cmd.gimbal_enabled && cmd.yaw_mode == ActuatorMode::Torque)
    tyaw += std::clamp(cmd.yaw_torque, -gimbal_max, gimbal_max);
  if (st.clutch == ClutchState::Engaged && cmd.gimbal_enabled &&
      cmd.roll_mode == ActuatorMode::Torque)
    troll += std::clamp(cmd.roll_torque, -gimbal_max, gimbal_max);
  st.yaw_torque = tyaw;
  st.roll_torque = troll;

  const double wheel_max = p.wheel_motor.max_output_torque();
  for (int i = 0; i < 4; ++i) {
    const int par = parent_of(i);
    const Vec3 a = axle_world(i);
    const Vec3 c = pos(2 + i);
    st.wheel_position[i] = c;
    st.wheel_speed[i] = (to_vec(dBodyGetAngularVel(body[2 + i])) -
                         to_vec(dBodyGetAngularVel(body[par]))).dot(a);
    const Vec3 f1 = to_vec(hinge_fb[i].f1), t1 = to_vec(hinge_fb[i].t1);
    double tau = t1.dot(a);
    double explicit_tau = 0.0;
    if (cmd.wheel_mode == ActuatorMode::Torque)
      explicit_tau = std::clamp(cmd.wheel_torque[i], -wheel_max, wheel_max);
    tau += explicit_tau;
    st.wheel_torque[i] = tau;
    // FTS: wrench of the assembly on its mount = minus what the mount applies to the assembly
    // (hinge constraint + motor reaction), moved to the sensor point, in the mount's frame.
    const Mat3 rp = rot(par);
    const Vec3 force = -f1;
    const Vec3 torque_c = -(t1 + explicit_tau * a);
    const Vec3 s = c + rp.col(2) * p.fts_height;
    const Vec3 torque_s = torque_c + (c - s).cross(force);
    st.fts[i].head<3>() = rp.transpose() * force;
    st.fts[i].tail<3>() = rp.transpose() * torque_s;
    // Ground normal load and the implicit shear level for the next step's explicit terms.
    st.wheel_load[i] = 0.0;
    if (ground_joint[i]) {
      const Vec3 fc = to_vec(ground_fb[i].f1);
      const Vec3 fl = compaction_joint[i] ? to_vec(compaction_fb[i].f1) : Vec3::Zero();
      st.wheel_load[i] = (fc + fl).dot(frame_n[i]) + explicit_fz[i];
      if (opt.ground == GroundType::Soil) {
        compaction[i] =
            compaction_joint[i] ? to_vec(compaction_fb[i].f1).dot(frame_x[i]) : 0.0;
        shear_x[i] = unit_shear_x[i] > 1e-9 ? clamp_unit(fc.dot(frame_x[i]) / unit_shear_x[i]) : 0.0;
        shear_y[i] = unit_shear_y[i] > 1e-9 ? clamp_unit(fc.dot(frame_y[i]) / unit_shear_y[i]) : 0.0;
      }
    } else {
      shear_x[i] = shear_y[i] = compaction[i] = 0.0;
    }
  }
  // Electrical power (eq 40) and energy (positive power only: the drives do not regenerate).
  for (int i = 0; i < 4; ++i) {
    const MotorElectrical e = motor_electrical(p.wheel_motor, st.wheel_torque[i], st.wheel_speed[i]);
    st.motor_current[i] = e.current;
    st.motor_power[i] = e.power;
  }
  MotorElectrical ey{}, er{};
  if (cmd.gimbal_enabled) {  // AGS off: power-on-to-disengage brakes hold at zero power
    ey = motor_electrical(p.gimbal_motor, st.yaw_torque, psid);
    if (st.clutch == ClutchState::Engaged) er = motor_electrical(p.gimbal_motor, st.roll_torque, phid);
  }
  st.motor_current[4] = ey.current;
  st.motor_power[4] = ey.power;
  st.motor_current[5] = er.current;
  st.motor_power[5] = er.power;
  for (double pw : st.motor_power) st.energy += std::max(pw, 0.0) * dt;
}

void RoverSim::Impl::check_forces_before_step() {
  constexpr double kMaxForce = 1e8;  // [N] and [N m]; 1e6 x the rover's weight
  for (int b = 0; b < 6; ++b) {
    const Vec3 f = to_vec(dBodyGetForce(body[b])), t = to_vec(dBodyGetTorque(body[b]));
    if (f.allFinite() && t.allFinite() && f.norm() <= kMaxForce && t.norm() <= kMaxForce) continue;
    diverged = true;
    for (auto id : body) {
      dBodySetForce(id, 0, 0, 0);
      dBodySetTorque(id, 0, 0, 0);
    }
    dJointGroupEmpty(contacts);
    std::ostringstream os;
    os << "SimulationDiverged at t = " << st.time << " s: applied force " << f.norm()
       << " N / torque " << t.norm() << " N m on the " << kBodyNames[b] << " is non-finite or above "
       << kMaxForce << "; restore a snapshot or reset";
    throw SimulationDiverged(os.str());
  }
}

void RoverSim::Impl::check_divergence() {
  for (int b = 0; b < 6; ++b) {
    const Vec3 x = pos(b), v = to_vec(dBodyGetLinearVel(body[b])),
               w = to_vec(dBodyGetAngularVel(body[b]));
    std::string what;
    if (!x.allFinite() || !v.allFinite() || !w.allFinite()) {
      what = "non-finite state";
    } else if (v.norm() > opt.max_speed) {
      what = "speed " + std::to_string(v.norm()) + " m/s > max_speed " + std::to_string(opt.max_speed);
    } else if (w.norm() > opt.max_angular_speed) {
      what = "angular speed " + std::to_string(w.norm()) + " rad/s > max_angular_speed " +
             std::to_string(opt.max_angular_speed);
    } else if (x.norm() > 1e6) {
      what = "position beyond 1e6 m";
    }
    if (!what.empty()) {
      diverged = true;
      std::ostringstream os;
      os << "SimulationDiverged at t = " << st.time << " s: " << kBodyNames[b] << " " << what
         << " (dt = " << opt.dt << " s); restore a snapshot or reset";
      throw SimulationDiverged(os.str());
    }
  }
}

// ---------------------------------------------------------------------------------------------

RoverSim::RoverSim(const RoverParameters& params, const HeightMap& terrain,
                   const std::vector<BoxObstacle>& obstacles, const SimOptions& options) {
  params.validate();
  options.validate();
  for (const auto& b : obstacles) b.validate();
  impl_ = std::make_unique<Impl>(params, terrain, obstacles, options);
  impl_->build();
  reset(0.0, 0.0, 0.0);
}

RoverSim::~RoverSim() = default;

void RoverSim::reset(double x, double y, double heading, double psi, double phi, double speed) {
  require_finite("RoverSim.reset", "x", x);
  require_finite("RoverSim.reset", "y", y);
  require_finite("RoverSim.reset", "heading", heading);
  require_in_range("RoverSim.reset", "psi", psi, -impl_->p.yaw_limit, impl_->p.yaw_limit);
  require_in_range("RoverSim.reset", "phi", phi, -impl_->p.roll_limit, impl_->p.roll_limit);
  init_ode_once();
  require_in_range("RoverSim.reset", "speed", speed, -5.0, 5.0);
  impl_->place(x, y, heading, psi, phi, speed);
  impl_->read_outputs(0.0);
}

void RoverSim::set_commands(const Commands& c) {
  c.validate();
  impl_->cmd = c;
}

const Commands& RoverSim::commands() const { return impl_->cmd; }

void RoverSim::set_command_vector(const double* c) {
  Commands k = impl_->cmd;
  k.wheel_mode = k.yaw_mode = k.roll_mode = ActuatorMode::Velocity;
  for (int i = 0; i < 4; ++i) k.wheel_speed[i] = c[i];
  k.yaw_rate = c[4];
  k.roll_rate = c[5];
  k.gimbal_enabled = c[6] != 0.0;
  k.clutch_engage = c[7] != 0.0;
  set_commands(k);
}

void RoverSim::step() { impl_->step(); }

void RoverSim::step_n(int n) {
  require(n >= 0, "RoverSim.step_n: n must be >= 0");
  for (int k = 0; k < n; ++k) impl_->step();
}

const RoverState& RoverSim::state() const { return impl_->st; }

std::vector<std::string> RoverSim::observation_names() {
  std::vector<std::string> n = {"time", "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz",
                                "wx", "wy", "wz", "roll", "pitch", "yaw", "gimbal_yaw",
                                "gimbal_roll", "gimbal_yaw_rate", "gimbal_roll_rate", "yaw_torque",
                                "roll_torque"};
  const char* w[4] = {"FL", "FR", "RL", "RR"};
  for (auto s : w) n.push_back(std::string("wheel_speed_") + s);
  for (auto s : w) n.push_back(std::string("wheel_torque_") + s);
  const char* c[6] = {"Fx", "Fy", "Fz", "Tx", "Ty", "Tz"};
  for (auto s : w)
    for (auto k : c) n.push_back(std::string("fts_") + s + "_" + k);
  for (auto s : w) n.push_back(std::string("wheel_load_") + s);
  for (auto s : w) n.push_back(std::string("sinkage_") + s);
  n.push_back("energy");
  n.push_back("clutch");
  return n;
}

void RoverSim::observation(double* o) const {
  const RoverState& s = impl_->st;
  int k = 0;
  o[k++] = s.time;
  for (int i = 0; i < 3; ++i) o[k++] = s.position[i];
  for (int i = 0; i < 4; ++i) o[k++] = s.quaternion[i];
  for (int i = 0; i < 3; ++i) o[k++] = s.linear_velocity[i];
  for (int i = 0; i < 3; ++i) o[k++] = s.angular_velocity[i];
  o[k++] = s.roll;
  o[k++] = s.pitch;
  o[k++] = s.yaw;
  o[k++] = s.gimbal_yaw;
  o[k++] = s.gimbal_roll;
  o[k++] = s.gimbal_yaw_rate;
  o[k++] = s.gimbal_roll_rate;
  o[k++] = s.yaw_torque;
  o[k++] = s.roll_torque;
  for (int i = 0; i < 4; ++i) o[k++] = s.wheel_speed[i];
  for (int i = 0; i < 4; ++i) o[k++] = s.wheel_torque[i];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 6; ++j) o[k++] = s.fts[i][j];
  for (int i = 0; i < 4; ++i) o[k++] = s.wheel_load[i];
  for (int i = 0; i < 4; ++i) o[k++] = s.sinkage[i];
  o[k++] = s.energy;
  o[k++] = static_cast<double>(static_cast<int>(s.clutch));
}

Snapshot RoverSim::snapshot() const {
  Snapshot s;
  for (int b = 0; b < 6; ++b) {
    const dBodyID id = impl_->body[b];
    const dReal* x = dBodyGetPosition(id);
    const dReal* q = dBodyGetQuaternion(id);
    const dReal* v = dBodyGetLinearVel(id);
    const dReal* w = dBodyGetAngularVel(id);
    for (int k = 0; k < 3; ++k) {
      s.bodies[b].pos[k] = x[k];
      s.bodies[b].lin[k] = v[k];
      s.bodies[b].ang[k] = w[k];
    }
    for (int k = 0; k < 4; ++k) s.bodies[b].quat[k] = q[k];
  }
  s.state = impl_->st;
  s.commands = impl_->cmd;
  s.shear_x = impl_->shear_x;
  s.shear_y = impl_->shear_y;
  s.compaction = impl_->compaction;
  s.valid = true;
  return s;
}

void RoverSim::restore(const Snapshot& s) {
  require(s.valid, "RoverSim.restore: empty snapshot");
  init_ode_once();
  for (int b = 0; b < 6; ++b) {
    const dBodyID id = impl_->body[b];
    const auto& sb = s.bodies[b];
    dQuaternion q = {sb.quat[0], sb.quat[1], sb.quat[2], sb.quat[3]};
    dBodySetPosition(id, sb.pos[0], sb.pos[1], sb.pos[2]);
    dBodySetQuaternion(id, q);
    dBodySetLinearVel(id, sb.lin[0], sb.lin[1], sb.lin[2]);
    dBodySetAngularVel(id, sb.ang[0], sb.ang[1], sb.ang[2]);
    dBodySetForce(id, 0, 0, 0);
    dBodySetTorque(id, 0, 0, 0);
  }
  impl_->st = s.state;
  impl_->cmd = s.commands;
  impl_->shear_x = s.shear_x;
  impl_->shear_y = s.shear_y;
  impl_->compaction = s.compaction;
  impl_->pending_force.setZero();
  impl_->diverged = false;
}

void RoverSim::apply_chassis_force(const Eigen::Vector3d& force) {
  require(force.allFinite(), "RoverSim.apply_chassis_force: force must be finite");
  impl_->pending_force += force;
}

double RoverSim::kinetic_energy() const {
  double e = 0.0;
  for (auto b : impl_->body) {
    dMass m;
    dBodyGetMass(b, &m);
    const Vec3 v = to_vec(dBodyGetLinearVel(b));
    const Mat3 r = to_mat(dBodyGetRotation(b));
    const Vec3 wl = r.transpose() * to_vec(dBodyGetAngularVel(b));
    Mat3 inertia;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) inertia(i, j) = m.I[4 * i + j];
    e += 0.5 * m.mass * v.squaredNorm() + 0.5 * wl.dot(inertia * wl);
  }
  return e;
}

double RoverSim::potential_energy() const {
  double e = 0.0;
  for (auto b : impl_->body) {
    dMass m;
    dBodyGetMass(b, &m);
    e += m.mass * impl_->opt.soil.gravity * dBodyGetPosition(b)[2];
  }
  return e;
}

double RoverSim::friction() const { return impl_->mu; }
const RoverParameters& RoverSim::parameters() const { return impl_->p; }
const SimOptions& RoverSim::options() const { return impl_->opt; }
const HeightMap& RoverSim::terrain() const { return impl_->hm; }

}  // namespace ernest::dynamics
