// ERNEST on ODE: ODE set-up, model building and placement; the public API is in rover_sim_api.cpp,
// the step in rover_step.cpp.
// Equation numbers refer to seed 004.
#include "ernest/dynamics/rover_sim.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <string>
#include <mutex>
#include <random>

#include "ernest/common/validation.hpp"
#include "ernest/dynamics/rover_sim_impl.hpp"

namespace ernest::dynamics {

namespace detail {

const char* const kBodyNames[6] = {"chassis", "bogie", "wheel FL", "wheel FR", "wheel RL", "wheel RR"};

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
  double h = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    Vec3 d = n - n.dot(axle) * axle;  // in-plane direction of n
    const double dn = d.norm();
    d = dn > 1e-9 ? Vec3(d * (1.0 / dn)) : Vec3::Zero();
    p = centre - r0 * d - tube * n;
    const Vec3 used = n;
    h = hm.height_normal(p.x(), p.y(), n);
    if (n == used) break;  // planar there: another pass would give the same point, bit for bit
  }
  dp.point = p;
  dp.normal = n;
  dp.depth = (h - p.z()) * n.z();
  return dp;
}

}  // namespace detail

using namespace detail;

void SimOptions::validate() const {
  const char* o = "SimOptions";
  require_in_range(o, "dt", dt, 1e-5, 0.05);
  soil.validate();
  require_in_range(o, "soil_points_per_panel", soil_points_per_panel, 1,
                   soil::BekkerWongModel::kMaxPointsPerPanel);
  require_in_range(o, "soil_normal_damping", soil_normal_damping, 1e-3, 1e7);
  rigid.validate();
  if (friction) require_in_range(o, "friction", *friction, 0.0, 10.0);  // unset: drawn
  require_in_range(o, "rigid_slip", rigid_slip, 0.0, 1.0);
  require_in_range(o, "rigid_tyre_stiffness_x", rigid_tyre_stiffness_x, 0.0, 1e8);
  require_in_range(o, "rigid_tyre_stiffness_y", rigid_tyre_stiffness_y, 0.0, 1e8);
  // (> 0: with no damping a tyre without stiffness would be a perfectly sticking row)
  require_in_range(o, "rigid_tyre_damping", rigid_tyre_damping, 1e-3, 1e8);
  require_in_range(o, "max_speed", max_speed, 1e-3, 1e6);
  require_in_range(o, "max_angular_speed", max_angular_speed, 1e-3, 1e7);
  require_in_range(o, "slip_force_tolerance", slip_force_tolerance, 1e-6, 1e9);
  require_in_range(o, "obstacle_substeps", obstacle_substeps, 1, 64);
  require(stepper == Stepper::Ode || stepper == Stepper::Own,
          "SimOptions.stepper = " + std::to_string(static_cast<int>(stepper)) +
              " must be Stepper.Ode (0) or Stepper.Own (1)");
  require(wheel_obstacle_contact == WheelObstacleContact::Ode ||
              wheel_obstacle_contact == WheelObstacleContact::Exact,
          "SimOptions.wheel_obstacle_contact = " +
              std::to_string(static_cast<int>(wheel_obstacle_contact)) +
              " must be WheelObstacleContact.Ode (0) or WheelObstacleContact.Exact (1)");
}

void Commands::validate() const {
  // Physical ranges, far beyond any motor of the rover but small enough that ODE's constraint
  // solve stays finite: a velocity target of 1e306 rad/s passed finite checks and made ODE abort
  // the process.
  const char* o = "Commands";
  for (int i = 0; i < 4; ++i) {
    const std::string k = "[" + std::to_string(i) + "]";
    require_in_range(o, ("wheel_speed" + k).c_str(), wheel_speed[i], -kMaxCommandRate,
                     kMaxCommandRate);
    require_in_range(o, ("wheel_torque" + k).c_str(), wheel_torque[i], -kMaxCommandTorque,
                     kMaxCommandTorque);
  }
  require_in_range(o, "yaw_rate", yaw_rate, -kMaxCommandRate, kMaxCommandRate);
  require_in_range(o, "roll_rate", roll_rate, -kMaxCommandRate, kMaxCommandRate);
  require_in_range(o, "yaw_torque", yaw_torque, -kMaxCommandTorque, kMaxCommandTorque);
  require_in_range(o, "roll_torque", roll_torque, -kMaxCommandTorque, kMaxCommandTorque);
}

namespace detail {

RoverModel::RoverModel(const RoverParameters& params, const HeightMap& terrain,
                       const std::vector<BoxObstacle>& obstacles, const SimOptions& options)
    : p(params), hm(terrain), boxes(obstacles), opt(options),
      // sign(v_x) exact in the model: its regularisation is the compaction row's (rover_step.cpp)
      soil([&] {
        soil::SoilParameters s = options.soil;
        s.eps_direction = 0.0;
        return s;
      }(), soil::WheelGeometry{params.wheel_radius, params.wheel_width},
           options.soil_points_per_panel),
      mu([&] {
        std::mt19937_64 rng(options.seed);
        return options.friction ? *options.friction : options.rigid.sample_friction(rng);
      }()) {}

RoverModel::~RoverModel() {
  if (contacts) dJointGroupDestroy(contacts);
  if (rover_space) dSpaceDestroy(rover_space);  // destroys its geoms (cleanup on by default)
  if (obstacle_space) dSpaceDestroy(obstacle_space);
  if (world) {
    dWorldSetStepThreadingImplementation(world, nullptr, nullptr);
    dWorldDestroy(world);
  }
  if (threading) dThreadingFreeImplementation(threading);
}

}  // namespace detail

RoverSim::Impl::Impl(const RoverParameters& params, const HeightMap& terrain,
                     const std::vector<BoxObstacle>& obstacles, const SimOptions& options)
    : RoverModel(params, terrain, obstacles, options) {}

void RoverSim::Impl::build() {
  solver::init_ode_once();
  // find ODE's own solver now (throws here, not inside a step); warns once if the hook is off
  // (our own island step calls the sparse solver itself: it needs no hook)
  const bool hook = solver::sparse_lcp_active();
  stats.fast_lcp = opt.sparse_lcp && (hook || opt.stepper == Stepper::Own);
  lcp.enabled = opt.sparse_lcp;
  world = dWorldCreate();
  // ODE's default step threading implementation is one object shared by every world and is not
  // thread-safe (ReleaseAJob assertions when two worlds step on two threads): each world gets
  // its own self-threaded implementation so that rovers can step concurrently.
  threading = dThreadingAllocateSelfThreadedImplementation();
  dWorldSetStepThreadingImplementation(world, dThreadingImplementationGetFunctions(threading),
                                       threading);
  dWorldSetGravity(world, 0.0, 0.0, -opt.soil.gravity);
  dWorldSetERP(world, 0.2);
  dWorldSetCFM(world, kWorldCfm);
  dWorldSetAutoDisableFlag(world, 0);
  rover_space = dSimpleSpaceCreate(nullptr);
  obstacle_space = dSimpleSpaceCreate(nullptr);
  contacts = dJointGroupCreate(0);

  lcp.exact_friction = opt.ground == GroundType::Rigid;  // Coulomb's cap for sliding tyres
  // On soil the rocks' sliding contacts: Coulomb's cap in the sparse path.
  lcp.coulomb_friction = opt.ground == GroundType::Soil && opt.guess_obstacle_contacts;
  set_step_length(opt.dt);

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
    std::array<double, 6> aabb;  // static: the broad phase's (obstacle_contacts.cpp)
    dGeomGetAABB(gb, aabb.data());
    obstacle_aabb.push_back(aabb);
    obstacle_max_width = std::max(obstacle_max_width, aabb[1] - aabb[0]);
  }
  obstacle_by_x.resize(obstacle_aabb.size());  // the broad phase's search by lowest x
  for (std::size_t i = 0; i < obstacle_by_x.size(); ++i) obstacle_by_x[i] = static_cast<int>(i);
  std::sort(obstacle_by_x.begin(), obstacle_by_x.end(),
            [&](int a, int b) { return obstacle_aabb[a][0] < obstacle_aabb[b][0]; });

  // Nominal placement so that joints are created in a consistent pose. place() tilts the chassis
  // to the terrain under the origin, so the axes below are given as body axes in the world (on a
  // terrain sloped at the origin, world z is not the chassis z: a yaw axis set as world z was
  // tilted by the slope in the chassis, and the bogie's x pitched out of the chassis plane by
  // sin(slope)(1 - cos psi)). On level ground they are exactly the world axes, as before.
  place(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
  const Mat3 rc0 = rot(kChassis);  // = the bogie's and the wheels' rotation at psi = phi = 0
  // Active Gimbal Suspension: yaw axis fixed in the chassis (z), roll axis fixed in the bogie (x),
  // collocated and intersecting (§2.2) — an ODE universal joint.
  const Vec3 gw = pos(kChassis) + rot(kChassis) * (g - p.chassis_com);
  gimbal = dJointCreateUniversal(world, nullptr);
  dJointAttach(gimbal, body[kChassis], body[kBogie]);
  dJointSetUniversalAnchor(gimbal, gw.x(), gw.y(), gw.z());
  dJointSetUniversalAxis1(gimbal, rc0(0, 2), rc0(1, 2), rc0(2, 2));  // chassis z
  dJointSetUniversalAxis2(gimbal, rc0(0, 0), rc0(1, 0), rc0(2, 0));  // bogie x
  dJointSetFeedback(gimbal, &gimbal_fb);
  // The drives are AMotors beside the joints, not the joints' own motors: a hinge or universal
  // with a bounded motor row is a "mixed" joint whose rows ODE cannot factorise up front, and the
  // drives' rows are switched between bounded, unbounded and explicit each step (rover_step.cpp).
  gimbal_motor = dJointCreateAMotor(world, nullptr);
  dJointAttach(gimbal_motor, body[kChassis], body[kBogie]);
  dJointSetAMotorMode(gimbal_motor, dAMotorUser);
  dJointSetAMotorNumAxes(gimbal_motor, 2);
  dJointSetAMotorAxis(gimbal_motor, 0, 1, rc0(0, 2), rc0(1, 2), rc0(2, 2));  // yaw: chassis z
  dJointSetAMotorAxis(gimbal_motor, 1, 2, rc0(0, 0), rc0(1, 0), rc0(2, 0));  // roll: bogie x
  dJointSetFeedback(gimbal_motor, &gimbal_motor_fb);
  for (int i = 0; i < 4; ++i) {
    hinge[i] = dJointCreateHinge(world, nullptr);
    dJointAttach(hinge[i], body[2 + i], body[parent_of(i)]);
    const Vec3 c = pos(2 + i);
    dJointSetHingeAnchor(hinge[i], c.x(), c.y(), c.z());
    dJointSetHingeAxis(hinge[i], rc0(0, 1), rc0(1, 1), rc0(2, 1));  // axle: y
    dJointSetFeedback(hinge[i], &hinge_fb[i]);
    wheel_motor[i] = dJointCreateAMotor(world, nullptr);
    dJointAttach(wheel_motor[i], body[2 + i], body[parent_of(i)]);
    dJointSetAMotorMode(wheel_motor[i], dAMotorUser);
    dJointSetAMotorNumAxes(wheel_motor[i], 1);
    dJointSetAMotorAxis(wheel_motor[i], 0, 1, rc0(0, 1), rc0(1, 1), rc0(2, 1));
    dJointSetFeedback(wheel_motor[i], &wheel_motor_fb[i]);
  }
  // Our own island step (SimOptions::stepper): the same bodies and joints, the hinges' second
  // axes read while the bodies are where the axes were set.
  island.bind(body);
  island.add_universal(gimbal);
  island.add_amotor(gimbal_motor);
  for (int i = 0; i < 4; ++i) {
    const dReal axle[3] = {rc0(0, 1), rc0(1, 1), rc0(2, 1)};
    island.add_hinge(hinge[i], axle);
    island.add_amotor(wheel_motor[i]);
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
    solver::canonicalise_quaternion(b);
  }
  st = RoverState{};
  st.gimbal_yaw = psi;
  st.gimbal_roll = phi;
  st.bogie_frame_angle = phi;
  shear_x.fill(0.0);
  shear_y.fill(0.0);
  compaction.fill(0.0);
  guesser.reset();
  rigid_deflection.fill(Vec3::Zero());
  obstacle_mode.fill(RowState::Free);
  obstacle_next = obstacle_mode;  // (see restore())
  slip_rate = 0.0;
  shear_x_past = compaction_past = {};
  soil_steps.fill(0);
  slip_offset = no_slip_offset();
  lcp.clear();
  row_force.fill(0.0);
  explicit_motor_torque.fill(0.0);
  pending_force.setZero();
  diverged = false;
}

}  // namespace ernest::dynamics
