#include "ernest/walker_sim/walker_sim.hpp"
#include "ernest/common/interrupt.hpp"

#include <ode/ode.h>

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "ernest/common/validation.hpp"
#include "ernest/solver/ode_init.hpp"  // init_ode_once, OdeInternalError, OdeCallScope

namespace ernest::walker_sim {

namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

Vec3 v3(const dReal* p) { return {p[0], p[1], p[2]}; }

Mat3 m3(const dReal* r) {
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = r[4 * i + j];
  return m;
}

void to_ode(const Mat3& m, dMatrix3 r) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r[4 * i + j] = m(i, j);
    r[4 * i + 3] = 0.0;
  }
}

void place(dBodyID b, const Vec3& p, const Mat3& r) {
  const Eigen::Quaterniond q(r);
  const dQuaternion dq = {q.w(), q.x(), q.y(), q.z()};
  dBodySetPosition(b, p.x(), p.y(), p.z());
  dBodySetQuaternion(b, dq);
}

// ODE mass of a body whose CoM is its origin: principal inertias in its own frame.
void set_mass(dBodyID b, double m, const Vec3& inertia) {
  dMass mass;
  dMassSetZero(&mass);
  dMassSetParameters(&mass, m, 0, 0, 0, inertia.x(), inertia.y(), inertia.z(), 0, 0, 0);
  dBodySetMass(b, &mass);
}

// Lowest rim point of a wheel (middle plane) over z = 0.
Vec3 lowest_rim_point(const Vec3& centre, const Vec3& axle, double radius) {
  Vec3 down = -Vec3::UnitZ() + axle.z() * axle;  // -z projected onto the wheel plane
  const double n = down.norm();
  if (n < 1e-9) return centre;  // axle vertical: the face is level (never while walking)
  return centre + radius * down / n;
}

}  // namespace

void Rock::validate() const {
  const char* o = "Rock";
  for (int k = 0; k < 3; ++k) {
    require_finite(o, "centre", centre[k]);
    require_in_range(o, "half_extents", half_extents[k], 1e-4, 100.0);
  }
  require_finite(o, "yaw", yaw);
}

void WalkerSimOptions::validate() const {
  const char* o = "WalkerSimOptions";
  require_in_range(o, "dt", dt, 1e-5, 0.05);
  require_in_range(o, "contact_stiffness", contact_stiffness, 1.0, 1e9);
  require_in_range(o, "contact_damping", contact_damping, 0.0, 1e8);
  require_in_range(o, "friction", friction, 0.0, 10.0);
  require_in_range(o, "rock_stiffness", rock_stiffness, 1.0, 1e10);
  require_in_range(o, "rock_damping", rock_damping, 0.0, 1e9);
  require_in_range(o, "position_gain", position_gain, 1e-6, 1000.0);
  require_in_range(o, "max_joint_rate", max_joint_rate, 1e-6, 100.0);
  require_in_range(o, "torque_scale", torque_scale, 1e-6, 100.0);
  require_in_range(o, "min_link_mass", min_link_mass, 1e-6, 100.0);
}

double wheel_rock_clearance(const Vec3& centre, const Vec3& axle, double radius, double width,
                            const Rock& rock) {
  // FCL asserts (aborting the process) on non-finite or degenerate shapes: refuse them here.
  const char* o = "wheel_rock_clearance";
  for (int k = 0; k < 3; ++k) {
    require_finite(o, "centre", centre[k]);
    require_finite(o, "axle", axle[k]);
  }
  require(axle.norm() > 1e-12, "wheel_rock_clearance: axle must be a non-zero vector");
  require_in_range(o, "radius", radius, 1e-4, 100.0);
  require_in_range(o, "width", width, 1e-4, 100.0);
  rock.validate();
  // FCL cylinders lie along their local z axis, centred at the origin.
  const fcl::Cylinderd wheel(radius, width);
  fcl::Transform3d tw = fcl::Transform3d::Identity();
  tw.translation() = centre;
  tw.linear() = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), axle.normalized()).toRotationMatrix();
  const fcl::Boxd box(2.0 * rock.half_extents);
  fcl::Transform3d tb = fcl::Transform3d::Identity();
  tb.translation() = rock.centre;
  tb.linear() = Eigen::AngleAxisd(rock.yaw, Vec3::UnitZ()).toRotationMatrix();
  fcl::CollisionRequestd creq(1, true);
  fcl::CollisionResultd cres;
  if (fcl::collide(&wheel, tw, &box, tb, creq, cres) > 0) {
    double depth = 0.0;
    for (std::size_t i = 0; i < cres.numContacts(); ++i)
      depth = std::max(depth, cres.getContact(i).penetration_depth);
    return -depth;
  }
  fcl::DistanceRequestd dreq;
  fcl::DistanceResultd dres;
  return std::max(0.0, fcl::distance(&wheel, tw, &box, tb, dreq, dres));
}

double wheel_ground_clearance(const Vec3& centre, const Vec3& axle, double radius) {
  return lowest_rim_point(centre, axle, radius).z();
}

struct WalkerSim::Impl {
  const walker::WalkerModel& model;
  WalkerSimOptions o;
  std::vector<Rock> rocks;
  int legs, n;
  dWorldID world = nullptr;
  dJointGroupID contacts = nullptr;
  std::vector<dBodyID> bodies;          // chassis, then leg k link i at 1 + k n + i
  std::vector<Vec3> frame_offset;       // model frame origin in the ODE body's frame (-CoM)
  std::vector<dJointID> hinges;         // leg k joint i at k n + i
  Eigen::MatrixXd q0;                   // angles at which ODE's hinge angles are zero
  std::vector<Vec3> wheel_local, axle_local;  // in the foot link's ODE frame
  std::vector<dGeomID> wheel_geoms, rock_geoms;
  std::vector<dJointFeedback> feedback;
  std::vector<char> on_ground;  // wheel k had a ground contact in the last step
  Eigen::VectorXd loads;
  double t = 0.0;
  bool broken = false;

  Impl(const walker::WalkerModel& m, const WalkerSimOptions& opt, const std::vector<Rock>& r)
      : model(m), o(opt), rocks(r), legs(m.legs()), n(m.joints_per_leg()) {}

  ~Impl() {
    for (dGeomID g : wheel_geoms) dGeomDestroy(g);
    for (dGeomID g : rock_geoms) dGeomDestroy(g);
    if (contacts) dJointGroupDestroy(contacts);
    if (world) dWorldDestroy(world);
  }

  dBodyID link(int leg, int i) const { return bodies[1 + leg * n + i]; }

  dBodyID add_body(const Vec3& com, const Mat3& rotation, const Vec3& origin, double mass,
                   const Vec3& inertia) {
    dBodyID b = dBodyCreate(world);
    place(b, com, rotation);
    set_mass(b, std::max(mass, o.min_link_mass), inertia.cwiseMax(1e-4));
    bodies.push_back(b);
    frame_offset.push_back(rotation.transpose() * (origin - com));
    return b;
  }

  void build(const Eigen::Isometry3d& body, const Eigen::MatrixXd& q) {
    solver::init_ode_once();
    world = dWorldCreate();
    contacts = dJointGroupCreate(0);
    const walker::WalkerParameters& p = model.params();
    dWorldSetGravity(world, 0.0, 0.0, -p.gravity);
    const Mat3 rb = body.linear();
    add_body(body * p.chassis_com, rb, body.translation(), p.chassis_mass, p.chassis_inertia);
    walker::LegWorkspace ws(model);
    for (int k = 0; k < legs; ++k) {
      model.forward(k, q.col(k), ws);
      for (int i = 0; i < n; ++i) {
        const walker::JointSpec& js = p.joints[i];
        const Mat3 r = rb * ws.rotation.middleCols<3>(3 * i);
        add_body(body * Vec3(ws.link_com.col(i)), r, body * Vec3(ws.joint_position.col(i)), js.mass,
                 js.inertia);
        dJointID h = dJointCreateHinge(world, nullptr);
        dJointAttach(h, link(k, i), i == 0 ? bodies[0] : link(k, i - 1));
        const Vec3 a = body * Vec3(ws.joint_position.col(i)), ax = rb * ws.joint_axis.col(i);
        dJointSetHingeAnchor(h, a.x(), a.y(), a.z());
        dJointSetHingeAxis(h, ax.x(), ax.y(), ax.z());
        dJointSetHingeParam(h, dParamFMax, o.torque_scale * js.torque_limit);
        hinges.push_back(h);
      }
      // The wheel: a cylinder along the axle (y of the foot frame) on the last link.
      const dBodyID foot = link(k, n - 1);
      const Mat3 rf = m3(dBodyGetRotation(foot));
      const Vec3 centre = body * ws.wheel_centre, axle = rb * ws.foot_rotation.col(1);
      wheel_local.push_back(rf.transpose() * (centre - v3(dBodyGetPosition(foot))));
      axle_local.push_back(rf.transpose() * axle);
      dGeomID g = dCreateCylinder(nullptr, p.wheel_radius, p.wheel_width);
      dGeomSetBody(g, foot);
      Mat3 rg;
      rg << rb * ws.foot_rotation.col(2), rb * ws.foot_rotation.col(0), axle;  // local z = axle
      dMatrix3 dr;
      to_ode(rg, dr);
      dGeomSetOffsetWorldRotation(g, dr);
      dGeomSetOffsetWorldPosition(g, centre.x(), centre.y(), centre.z());
      wheel_geoms.push_back(g);
    }
    for (const Rock& r : rocks) {
      dGeomID g = dCreateBox(nullptr, 2 * r.half_extents.x(), 2 * r.half_extents.y(), 2 * r.half_extents.z());
      dGeomSetPosition(g, r.centre.x(), r.centre.y(), r.centre.z());
      dMatrix3 dr;
      to_ode(Eigen::AngleAxisd(r.yaw, Vec3::UnitZ()).toRotationMatrix(), dr);
      dGeomSetRotation(g, dr);
      rock_geoms.push_back(g);
    }
    q0 = q;
    feedback.resize(legs);
    on_ground.assign(legs, 0);
    loads.setZero(legs);
  }

  Vec3 wheel_centre(int k) const {
    const dBodyID b = link(k, n - 1);
    return v3(dBodyGetPosition(b)) + m3(dBodyGetRotation(b)) * wheel_local[k];
  }
  Vec3 wheel_axle(int k) const { return m3(dBodyGetRotation(link(k, n - 1))) * axle_local[k]; }
  double angle(int k, int i) const { return q0(i, k) + dJointGetHingeAngle(hinges[k * n + i]); }

  // A soft contact: ERP and CFM of a spring k and damper c at step h (ODE manual).
  void add_contact(dBodyID b, const Vec3& pos, const Vec3& normal, double depth, double k, double c,
                   dJointFeedback* fb) {
    dContact ct{};
    ct.surface.mode = dContactSoftERP | dContactSoftCFM | dContactApprox1;
    ct.surface.mu = o.friction;
    ct.surface.soft_erp = o.dt * k / (o.dt * k + c);
    ct.surface.soft_cfm = 1.0 / (o.dt * k + c);
    for (int a = 0; a < 3; ++a) ct.geom.pos[a] = pos[a], ct.geom.normal[a] = normal[a];
    ct.geom.depth = depth;
    dJointID j = dJointCreateContact(world, contacts, &ct);
    dJointAttach(j, b, nullptr);
    if (fb) dJointSetFeedback(j, fb);
  }

  void step(const Eigen::Ref<const Eigen::MatrixXd>& target, const Eigen::Ref<const Eigen::MatrixXd>& rate) {
    if (broken) throw WalkerSimDiverged("WalkerSim: the simulation diverged earlier and cannot continue");
    const walker::WalkerParameters& p = model.params();
    for (int k = 0; k < legs; ++k)
      for (int i = 0; i < n; ++i) {
        const double ff = rate.size() ? rate(i, k) : 0.0;
        const double v = std::clamp(ff + o.position_gain * (target(i, k) - angle(k, i)), -o.max_joint_rate,
                                    o.max_joint_rate);
        dJointSetHingeParam(hinges[k * n + i], dParamVel, v);
      }
    dJointGroupEmpty(contacts);
    for (int k = 0; k < legs; ++k) {
      on_ground[k] = 0;
      const dBodyID foot = link(k, n - 1);
      const Vec3 low = lowest_rim_point(wheel_centre(k), wheel_axle(k), p.wheel_radius);
      if (low.z() < 0.0) {
        add_contact(foot, low, Vec3::UnitZ(), -low.z(), o.contact_stiffness, o.contact_damping, &feedback[k]);
        on_ground[k] = 1;
      }
      for (dGeomID rg : rock_geoms) {
        dContactGeom cg[4];
        const int count = dCollide(wheel_geoms[k], rg, 4, cg, sizeof(dContactGeom));
        for (int c = 0; c < count; ++c)
          add_contact(foot, v3(cg[c].pos), v3(cg[c].normal), cg[c].depth, o.rock_stiffness / count,
                      o.rock_damping / count, nullptr);
      }
    }
    try {
      const solver::OdeCallScope own;  // ODE's errors in here throw
      dWorldStep(world, o.dt);
    } catch (const solver::OdeInternalError& e) {
      broken = true;
      throw WalkerSimDiverged(std::string("WalkerSim: ") + e.what());
    }
    t += o.dt;
    for (int k = 0; k < legs; ++k) loads[k] = on_ground[k] ? feedback[k].f1[2] : 0.0;
    for (dBodyID b : bodies) {
      const Vec3 x = v3(dBodyGetPosition(b)), v = v3(dBodyGetLinearVel(b)), w = v3(dBodyGetAngularVel(b));
      // squared norms: a NaN fails the comparison, an infinity exceeds the bound
      if (!(x.squaredNorm() < 1e8 && v.squaredNorm() < 2500.0 && w.squaredNorm() < 1e4)) {
        broken = true;
        throw WalkerSimDiverged("WalkerSim: the state blew up at t = " + std::to_string(t) +
                                " s (non-finite or runaway body)");
      }
    }
  }
};

WalkerSim::WalkerSim(const walker::WalkerModel& model, const Eigen::Isometry3d& body,
                     const Eigen::Ref<const Eigen::MatrixXd>& q, const std::vector<Rock>& rocks,
                     const WalkerSimOptions& options) {
  options.validate();
  model.check_configuration(q);
  require(body.matrix().allFinite(), "WalkerSim: body pose is not finite");
  for (const Rock& r : rocks) r.validate();
  impl_ = std::make_unique<Impl>(model, options, rocks);
  impl_->build(body, q);
}

WalkerSim::~WalkerSim() = default;

const walker::WalkerModel& WalkerSim::model() const { return impl_->model; }
const WalkerSimOptions& WalkerSim::options() const { return impl_->o; }
const std::vector<Rock>& WalkerSim::rocks() const { return impl_->rocks; }
double WalkerSim::time() const { return impl_->t; }

void WalkerSim::step(const Eigen::Ref<const Eigen::MatrixXd>& q_target,
                     const Eigen::Ref<const Eigen::MatrixXd>& rate) {
  impl_->model.check_configuration(q_target, "WalkerSim.step: q_target");
  require(rate.size() == 0 || (rate.rows() == q_target.rows() && rate.cols() == q_target.cols() &&
                               rate.allFinite()),
          "WalkerSim.step: rate must be empty or finite with the shape of q_target");
  poll_interrupt();  // Ctrl-C (common/interrupt.hpp) before the step: the walk drivers loop on it
  impl_->step(q_target, rate);
}

void WalkerSim::hold(const Eigen::Ref<const Eigen::MatrixXd>& q_target, double seconds) {
  require_in_range("WalkerSim.hold", "seconds", seconds, 0.0, 1e4);
  impl_->model.check_configuration(q_target, "WalkerSim.hold: q_target");
  const Eigen::MatrixXd none;
  for (int s = 0, steps = static_cast<int>(std::ceil(seconds / impl_->o.dt - 1e-9)); s < steps; ++s) {
    poll_interrupt();  // Ctrl-C between whole physics steps (common/interrupt.hpp)
    impl_->step(q_target, none);
  }
}

Eigen::Isometry3d WalkerSim::body_pose() const {
  const dBodyID b = impl_->bodies[0];
  const Mat3 r = m3(dBodyGetRotation(b));
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = r;
  out.translation() = v3(dBodyGetPosition(b)) + r * impl_->frame_offset[0];
  return out;
}

Eigen::MatrixXd WalkerSim::joint_angles() const {
  Eigen::MatrixXd q(impl_->n, impl_->legs);
  for (int k = 0; k < impl_->legs; ++k)
    for (int i = 0; i < impl_->n; ++i) q(i, k) = impl_->angle(k, i);
  return q;
}

Eigen::Matrix3Xd WalkerSim::wheel_centres() const {
  Eigen::Matrix3Xd c(3, impl_->legs);
  for (int k = 0; k < impl_->legs; ++k) c.col(k) = impl_->wheel_centre(k);
  return c;
}

Eigen::Matrix3Xd WalkerSim::wheel_axles() const {
  Eigen::Matrix3Xd c(3, impl_->legs);
  for (int k = 0; k < impl_->legs; ++k) c.col(k) = impl_->wheel_axle(k);
  return c;
}

Eigen::VectorXd WalkerSim::wheel_loads() const { return impl_->loads; }

double WalkerSim::rock_clearance(int leg) const {
  impl_->model.check_leg(leg);
  const walker::WalkerParameters& p = impl_->model.params();
  const Vec3 centre = impl_->wheel_centre(leg), axle = impl_->wheel_axle(leg);
  // Bounding spheres give each rock a lower bound on its clearance: FCL runs first on the rock
  // with the smallest bound, then only on rocks whose bound is below the best so far (exact).
  const double wheel_sphere = std::hypot(p.wheel_radius, 0.5 * p.wheel_width);
  auto bound = [&](const Rock& r) { return (r.centre - centre).norm() - wheel_sphere - r.half_extents.norm(); };
  const std::vector<Rock>& rocks = impl_->rocks;
  std::size_t first = 0;
  for (std::size_t i = 1; i < rocks.size(); ++i)
    if (bound(rocks[i]) < bound(rocks[first])) first = i;
  if (rocks.empty()) return kInf;
  double c = wheel_rock_clearance(centre, axle, p.wheel_radius, p.wheel_width, rocks[first]);
  for (std::size_t i = 0; i < rocks.size(); ++i)
    if (i != first && bound(rocks[i]) < c)
      c = std::min(c, wheel_rock_clearance(centre, axle, p.wheel_radius, p.wheel_width, rocks[i]));
  return c;
}

double WalkerSim::ground_clearance(int leg) const {
  impl_->model.check_leg(leg);
  return wheel_ground_clearance(impl_->wheel_centre(leg), impl_->wheel_axle(leg),
                                impl_->model.params().wheel_radius);
}

}  // namespace ernest::walker_sim
