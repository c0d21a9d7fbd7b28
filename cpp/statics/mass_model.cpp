// Seed 004 §3.2, eq 11: the two-body mass model, its statics and its Levenberg–Marquardt fit.
#include "ernest/statics/mass_model.hpp"
#include "ernest/common/interrupt.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <unsupported/Eigen/NonLinearOptimization>

#include "ernest/common/validation.hpp"

namespace ernest::statics {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;

void MassModel::validate() const {
  const char* o = "MassModel";
  require_in_range(o, "chassis_mass", chassis_mass, 1e-6, 1e5);
  require_in_range(o, "bogie_mass", bogie_mass, 1e-6, 1e5);
  for (int k = 0; k < 3; ++k) require_in_range(o, "chassis_com", chassis_com[k], -10.0, 10.0);
  require_in_range(o, "bogie_com_height", bogie_com_height, -10.0, 10.0);
}

Vec6 MassModel::vector() const {
  Vec6 v;
  v << chassis_mass, bogie_mass, chassis_com, bogie_com_height;
  return v;
}

MassModel MassModel::from_vector(const Eigen::Ref<const Vec6>& v) {
  MassModel m;
  m.chassis_mass = v[0];
  m.bogie_mass = v[1];
  m.chassis_com = v.segment<3>(2);
  m.bogie_com_height = v[5];
  return m;
}

MassModel MassModel::from_parameters(const dynamics::RoverParameters& p) {
  p.validate();
  const double wa = p.wheel_assembly_mass;
  MassModel m;
  m.chassis_mass = p.chassis_mass + 2.0 * wa;
  m.bogie_mass = p.bogie_mass + 2.0 * wa;
  // rear assemblies at the rear wheel centres (z = 0), front ones at the front centres
  m.chassis_com = (p.chassis_mass * p.chassis_com + wa * (p.wheel_centre(dynamics::kRL) +
                                                          p.wheel_centre(dynamics::kRR))) /
                  m.chassis_mass;
  m.bogie_com_height = p.bogie_mass * p.bogie_com_height / m.bogie_mass;
  return m;
}

const std::array<const char*, 6>& mass_model_parameter_names() {
  static const std::array<const char*, 6> names = {"chassis_mass", "bogie_mass", "x_c", "y_c",
                                                   "z_c", "bogie_com_height"};
  return names;
}

void RoverGeometry::validate() const {
  const char* o = "RoverGeometry";
  require_in_range(o, "wheelbase", wheelbase, 0.01, 100.0);
  require_in_range(o, "track", track, 0.01, 100.0);
  require_in_range(o, "wheel_radius", wheel_radius, 1e-3, 10.0);
  require_in_range(o, "tube_radius", tube_radius, 0.0, wheel_radius);
  require_in_range(o, "gimbal_height", gimbal_height, -10.0, 10.0);
  require_in_range(o, "gravity", gravity, 1e-3, 100.0);
}

RoverGeometry RoverGeometry::from_parameters(const dynamics::RoverParameters& p, double gravity) {
  p.validate();
  RoverGeometry g;
  g.wheelbase = p.wheelbase;
  g.track = p.track;
  g.wheel_radius = p.wheel_radius;
  g.tube_radius = p.tyre_tube_radius();
  g.gimbal_height = p.gimbal_height;
  g.gravity = gravity;
  g.validate();
  return g;
}

void LoadPose::validate(std::optional<int> index) const {
  const std::string o = index ? "poses[" + std::to_string(*index) + "]" : std::string("LoadPose");
  for (int k = 0; k < 4; ++k) {
    require_finite(o.c_str(), "chassis_quaternion", chassis_quaternion[k]);
    require_finite(o.c_str(), "loads", loads[k]);
  }
  for (int k = 0; k < 3; ++k) require_finite(o.c_str(), "ground_normal", ground_normal[k]);
  for (int k = 0; k < 8; ++k) require_finite(o.c_str(), "horizontal_forces", horizontal_forces(k));
  require(chassis_quaternion.norm() > 1e-9, o + ".chassis_quaternion must not be zero");
  require(ground_normal.norm() > 1e-9 && ground_normal.normalized().z() > 0.05,
          o + ".ground_normal must be non-zero and point up (n_z > 0)");
  require_finite(o.c_str(), "psi", psi);
  require_finite(o.c_str(), "phi", phi);
  require_in_range(o.c_str(), "psi", psi, -M_PI, M_PI);
  require_in_range(o.c_str(), "phi", phi, -M_PI / 2, M_PI / 2);
  require_finite(o.c_str(), "roll_torque", roll_torque);
}

namespace {

// Everything of one pose that does not depend on the mass parameters.
struct PoseGeometry {
  Mat3 rc;        // chassis rotation (world from rover frame)
  Vec3 gimbal;    // gimbal point (world axes, from the rover origin)
  Vec3 bogie_z;   // bogie z axis, world: the bogie CoM is gimbal + (z_b - h_g) bogie_z
  double roll_s;  // a_r . (bogie_z x e_z): roll-axis moment arm factor of the bogie weight
  double hg;      // gimbal height above the axles
  Eigen::Vector4d bh = Eigen::Vector4d::Zero();  // right-hand side from known horizontal forces
  LoadEquations eq;
};

// Deepest point of the torus tyre on a plane of normal n (as cpp/dynamics/rover_sim.cpp
// locates the reference contact, §3.3): centre-circle point farthest along -n, plus the tube.
Vec3 contact_point(const Vec3& centre, const Vec3& axle, const Vec3& n, const RoverGeometry& g) {
  Vec3 d = n - n.dot(axle) * axle;
  const double dn = d.norm();
  d = dn > 1e-9 ? Vec3(d / dn) : Vec3::Zero();
  return centre - (g.wheel_radius - g.tube_radius) * d - g.tube_radius * n;
}

PoseGeometry pose_geometry(const RoverGeometry& g, const LoadPose& pose) {
  PoseGeometry pg;
  const Eigen::Vector4d& q = pose.chassis_quaternion;
  pg.rc = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  const Mat3 rb = (Eigen::AngleAxisd(pose.psi, Vec3::UnitZ()) *
                   Eigen::AngleAxisd(pose.phi, Vec3::UnitX())).toRotationMatrix();  // yaw then roll
  const Vec3 n = pose.ground_normal.normalized();
  const Vec3 gimbal_rel(0.5 * g.wheelbase, 0.0, g.gimbal_height);
  pg.gimbal = pg.rc * gimbal_rel;
  pg.hg = g.gimbal_height;
  pg.bogie_z = pg.rc * rb.col(2);
  const Vec3 roll_axis = pg.rc * rb.col(0);  // bogie x (the roll joint's axis, §2.2)
  pg.roll_s = roll_axis.dot(pg.bogie_z.cross(Vec3::UnitZ()));
  LoadEquations& e = pg.eq;
  e.A.setZero();
  e.t << 0.0, 0.0, 0.0, -1.0;
  for (int i = 0; i < 4; ++i) {
    const bool front = i < 2;
    const Vec3 nominal(front ? 0.5 * g.wheelbase : -0.5 * g.wheelbase,
                       i % 2 == 0 ? 0.5 * g.track : -0.5 * g.track, 0.0);
    const Vec3 centre = front ? Vec3(pg.rc * (gimbal_rel + rb * (nominal - gimbal_rel)))
                              : Vec3(pg.rc * nominal);
    const Vec3 axle = front ? Vec3(pg.rc * rb.col(1)) : Vec3(pg.rc.col(1));
    const Vec3 p = contact_point(centre, axle, n, g);
    e.contact[i] = p;
    e.A(0, i) = 1.0;   // sum f_i = (m_c + m_b) g
    e.A(1, i) = p.y();  // moment about world x through the origin: sum p_y f = g sum m c_y
    e.A(2, i) = p.x();  // moment about world y: sum p_x f = g sum m c_x
    // roll axis through the gimbal, bogie assembly only: a . ((p - G) x f e_z) + weight + tau = 0
    if (front) e.A(3, i) = roll_axis.dot((p - pg.gimbal).cross(Vec3::UnitZ()));
    // known horizontal force h at p: moves p x h to the right-hand side (rows 1-3)
    const Vec3 h(pose.horizontal_forces(0, i), pose.horizontal_forces(1, i), 0.0);
    const Vec3 mh = p.cross(h);
    pg.bh[1] += -mh.x();
    pg.bh[2] += mh.y();
    if (front) pg.bh[3] -= roll_axis.dot((p - pg.gimbal).cross(h));
  }
  return pg;
}

// Gravity side b(theta) of A f = b + t tau and its Jacobian db/dtheta (theta as MassModel::vector).
void gravity_terms(const PoseGeometry& pg, double g, const Vec6& th, Eigen::Vector4d& b,
                   Eigen::Matrix<double, 4, 6>* db) {
  const double mc = th[0], mb = th[1], arm = th[5] - pg.hg;  // bogie CoM below the gimbal
  const Vec3 c = pg.rc * th.segment<3>(2);
  const Vec3 bc = pg.gimbal + arm * pg.bogie_z;
  b << (mc + mb) * g, g * (mc * c.y() + mb * bc.y()), g * (mc * c.x() + mb * bc.x()),
      mb * g * arm * pg.roll_s;
  b += pg.bh;
  if (!db) return;
  db->setZero();
  (*db)(0, 0) = g;
  (*db)(0, 1) = g;
  for (int r = 1; r <= 2; ++r) {
    const int k = r == 1 ? 1 : 0;  // row 1 uses world y, row 2 world x
    (*db)(r, 0) = g * c[k];
    (*db)(r, 1) = g * bc[k];
    for (int j = 0; j < 3; ++j) (*db)(r, 2 + j) = g * mc * pg.rc(k, j);
    (*db)(r, 5) = g * mb * pg.bogie_z[k];
  }
  (*db)(3, 1) = g * arm * pg.roll_s;
  (*db)(3, 5) = g * mb * pg.roll_s;
}

Eigen::Matrix4d checked_inverse(const Eigen::Matrix4d& a) {
  Eigen::Matrix4d inv;
  bool ok = false;
  double det = 0.0;
  a.computeInverseAndDetWithCheck(inv, det, ok, 1e-12);
  require(ok && inv.allFinite(),
          "mass model: the pose's statics are singular (wheels collinear or roll axis vertical)");
  return inv;
}

}  // namespace

LoadEquations load_equations(const MassModel& model, const RoverGeometry& geometry,
                             const LoadPose& pose) {
  model.validate();
  geometry.validate();
  pose.validate();
  PoseGeometry pg = pose_geometry(geometry, pose);
  gravity_terms(pg, geometry.gravity, model.vector(), pg.eq.b, nullptr);
  return pg.eq;
}

Eigen::Vector4d predict_loads(const MassModel& model, const RoverGeometry& geometry,
                              const LoadPose& pose) {
  const LoadEquations e = load_equations(model, geometry, pose);
  return checked_inverse(e.A) * (e.b + e.t * pose.roll_torque);
}

void MassFitOptions::validate() const {
  require_in_range("MassFitOptions", "max_evaluations", max_evaluations, 10, 1e7);
  require_in_range("MassFitOptions", "tolerance", tolerance, 1e-16, 1e-2);
}

namespace {

// Residuals f̂ - f of every load (eq 11) and their analytic Jacobian, for Eigen's LM. Per-pose
// geometry and A^-1 are computed once; evaluations do not allocate.
struct Eq11Functor {
  using Scalar = double;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;

  std::vector<PoseGeometry> geo;
  std::vector<Eigen::Matrix4d> inv;
  std::vector<Eigen::Vector4d> measured, torque_part;
  double g = 9.81;
  Vec6 base;              // values of the fixed parameters
  std::vector<int> free;  // indices of the free parameters (the LM's unknowns)
  mutable bool non_finite = false;

  int inputs() const { return static_cast<int>(free.size()); }
  int values() const { return 4 * static_cast<int>(geo.size()); }
  Vec6 full(const Eigen::VectorXd& x) const {
    Vec6 th = base;
    for (size_t k = 0; k < free.size(); ++k) th[free[k]] = x[k];
    return th;
  }

  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& fvec) const {
    poll_interrupt();  // Ctrl-C in a long fit (common/interrupt.hpp): the exception ends the solve
    const Vec6 th = full(x);
    Eigen::Vector4d b;
    for (size_t k = 0; k < geo.size(); ++k) {
      gravity_terms(geo[k], g, th, b, nullptr);
      fvec.segment<4>(4 * k) = inv[k] * b + torque_part[k] - measured[k];
    }
    if (!fvec.allFinite()) {  // never let NaN through the solver: stop it (status UserAsked)
      non_finite = true;
      return -1;
    }
    return 0;
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& fjac) const {
    const Vec6 th = full(x);
    Eigen::Vector4d b;
    Eigen::Matrix<double, 4, 6> db;
    Eigen::Matrix<double, 4, 6> jk;
    for (size_t k = 0; k < geo.size(); ++k) {
      gravity_terms(geo[k], g, th, b, &db);
      jk.noalias() = inv[k] * db;
      for (size_t j = 0; j < free.size(); ++j) fjac.block<4, 1>(4 * k, j) = jk.col(free[j]);
    }
    if (!fjac.allFinite()) {
      non_finite = true;
      return -1;
    }
    return 0;
  }
};

const char* lm_status_name(int s) {
  switch (s) {
    case 0: return "improper input parameters";
    case 1: return "relative reduction too small";
    case 2: return "relative error too small";
    case 3: return "relative error and reduction too small";
    case 4: return "cosinus too small";
    case 5: return "too many function evaluations";
    case 6: return "ftol too small";
    case 7: return "xtol too small";
    case 8: return "gtol too small";
    case 9: return "stopped: non-finite residual";
    default: return "unknown";
  }
}

}  // namespace

MassFitResult fit_mass_model(const std::vector<LoadPose>& poses, const RoverGeometry& geometry,
                             const MassModel& initial, const MassFitOptions& options) {
  geometry.validate();
  initial.validate();
  options.validate();
  require(poses.size() >= 2, "fit_mass_model: poses needs at least 2 poses (8 loads for 6 "
                             "parameters), got " + std::to_string(poses.size()));
  Eq11Functor fn;
  fn.g = geometry.gravity;
  const size_t n = poses.size();
  fn.geo.reserve(n);
  fn.inv.reserve(n);
  for (size_t k = 0; k < n; ++k) {
    poses[k].validate(static_cast<int>(k));
    fn.geo.push_back(pose_geometry(geometry, poses[k]));
    fn.inv.push_back(checked_inverse(fn.geo.back().eq.A));
    fn.measured.push_back(poses[k].loads);
    fn.torque_part.push_back(fn.inv.back() * fn.geo.back().eq.t * poses[k].roll_torque);
  }

  fn.base = initial.vector();
  for (int k = 0; k < 6; ++k)
    if (!options.fixed[k]) fn.free.push_back(k);
  require(!fn.free.empty(), "MassFitOptions.fixed: every parameter is fixed, nothing to fit");
  const int nf = static_cast<int>(fn.free.size());
  Eigen::VectorXd x(nf);
  for (int k = 0; k < nf; ++k) x[k] = fn.base[fn.free[k]];
  Eigen::LevenbergMarquardt<Eq11Functor> lm(fn);
  lm.parameters.maxfev = options.max_evaluations;
  lm.parameters.xtol = options.tolerance;
  lm.parameters.ftol = options.tolerance;
  const int status = static_cast<int>(lm.minimize(x));
  if (fn.non_finite) throw std::runtime_error("fit_mass_model: non-finite residuals during the fit");

  MassFitResult r;
  r.status = lm_status_name(status);
  r.evaluations = static_cast<int>(lm.nfev);
  r.converged = status >= 1 && status <= 8 && status != 5;
  r.model = MassModel::from_vector(fn.full(x));

  const int m = 4 * static_cast<int>(n);
  Eigen::VectorXd res(m);
  Eigen::MatrixXd jac(m, nf);
  fn(x, res);
  fn.df(x, jac);
  Eigen::VectorXd all(m);
  for (size_t k = 0; k < n; ++k) all.segment<4>(4 * k) = poses[k].loads;
  const double sse = res.squaredNorm();
  const double sst = (all.array() - all.mean()).square().sum();
  r.r_squared = sst > 0.0 ? 1.0 - sse / sst : 0.0;
  r.rmse = std::sqrt(sse / m);

  // Uncertainty from the Jacobian at the optimum (columns scaled to unit norm): SVD; directions of
  // singular value < 1e-8 of the largest are not identified, and a parameter with a component
  // along one of them is reported unidentifiable (inf). Covariance sigma^2 (J^T J)^+.
  Eigen::VectorXd scale(nf);
  for (int j = 0; j < nf; ++j) scale[j] = jac.col(j).norm() > 0.0 ? jac.col(j).norm() : 1.0;
  const Eigen::MatrixXd js = jac * scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(js, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const Eigen::MatrixXd& v = svd.matrixV();
  r.rank = 0;
  for (int k = 0; k < sv.size(); ++k) r.rank += sv[k] > 1e-8 * sv[0] ? 1 : 0;
  r.residual_sigma = m > r.rank ? std::sqrt(sse / (m - r.rank)) : 0.0;
  Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(nf, nf);  // (Js^T Js)^+
  for (int k = 0; k < r.rank; ++k) pinv += v.col(k) * v.col(k).transpose() / (sv[k] * sv[k]);
  r.covariance.setZero();
  r.std_error.setZero();
  r.identifiable.fill(true);
  for (int a = 0; a < nf; ++a) {
    const int pa = fn.free[a];
    double null_part = 0.0;
    for (int k = r.rank; k < nf; ++k) null_part = std::max(null_part, std::abs(v(a, k)));
    r.identifiable[pa] = null_part < 1e-6;
    for (int b = 0; b < nf; ++b)
      r.covariance(pa, fn.free[b]) = r.residual_sigma * r.residual_sigma * pinv(a, b) /
                                     (scale[a] * scale[b]);
  }
  for (int a = 0; a < nf; ++a) {
    const int pa = fn.free[a];
    r.std_error[pa] = r.identifiable[pa] ? std::sqrt(std::max(r.covariance(pa, pa), 0.0)) : kInf;
    if (!r.identifiable[pa]) {
      r.covariance.row(pa).setConstant(std::numeric_limits<double>::quiet_NaN());
      r.covariance.col(pa).setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
  return r;
}

}  // namespace ernest::statics
