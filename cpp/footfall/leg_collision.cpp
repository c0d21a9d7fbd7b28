#include "ernest/footfall/leg_collision.hpp"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "ernest/common/interrupt.hpp"
#include "ernest/common/validation.hpp"

namespace ernest::footfall {

using GeometryPtr = std::shared_ptr<fcl::CollisionGeometryd>;

Eigen::MatrixXd default_clearance_table(int joints) {
  // a leg has a handful of joints; a negative count would be a bad_alloc deep in Eigen
  require_in_range("default_clearance_table", "joints", joints, 1, 64);
  Eigen::MatrixXd t = Eigen::MatrixXd::Constant(joints + 1, joints + 2, 0.05);
  t.col(joints + 1).setConstant(0.03);
  return t;
}

void CollisionOptions::validate(int joints) const {
  const char* o = "CollisionOptions";
  require_in_range(o, "environment_clearance", environment_clearance, 0.0, 1.0);
  require_in_range(o, "own_leg_clearance", own_leg_clearance, 0.0, 1.0);
  require_in_range(o, "terrain_margin", terrain_margin, 0.0, 10.0);
  if (clearance_table.size() == 0) return;
  require(clearance_table.rows() == joints + 1 && clearance_table.cols() == joints + 2,
          std::string(o) + ".clearance_table is " + std::to_string(clearance_table.rows()) + " x " +
              std::to_string(clearance_table.cols()) + ", expected " + std::to_string(joints + 1) +
              " x " + std::to_string(joints + 2) + " (swing shapes x other shapes + chassis)");
  for (Eigen::Index i = 0; i < clearance_table.size(); ++i)
    require_in_range(o, "clearance_table[]", clearance_table.data()[i], 0.0, 1.0);
}

namespace {

// A capsule of the leg in its link frame: centre, axis and length; its FCL geometry lies along
// the local z axis (a sphere when the length is zero).
struct ShapeSpec {
  int type = 0;  // link index, or n for the wheel
  double radius = 0.0, length = 0.0;
};

GeometryPtr make_capsule(double radius, double length) {
  if (length < 1e-9) return std::make_shared<fcl::Sphered>(radius);
  return std::make_shared<fcl::Capsuled>(radius, length);
}

fcl::Transform3d segment_pose(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1) {
  fcl::Transform3d t = fcl::Transform3d::Identity();
  t.translation() = 0.5 * (p0 + p1);
  const Eigen::Vector3d axis = p1 - p0;
  const double len = axis.norm();
  if (len > 1e-9) t.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis / len).toRotationMatrix();
  return t;
}

struct Obstacle {  // a fixed shape (another leg's capsule or the chassis), world frame
  int type = 0;
  GeometryPtr geometry;
  fcl::Transform3d pose;
  Eigen::Vector3d centre;
  double bound = 0.0;  // bounding-sphere radius
};

}  // namespace

struct LegCollisionChecker::Impl {
  Eigen::Isometry3d body;
  int n = 0;
  Eigen::VectorXd lower, upper;
  std::vector<ShapeSpec> specs;                 // swing shapes (the leg's capsules, then the wheel)
  std::vector<std::vector<GeometryPtr>> inflated;  // [shape][0 terrain, 1 own leg, 2 + type]
  std::vector<GeometryPtr> plain;               // swing shapes, not inflated
  double env_clearance = 0.0, own_clearance = 0.0;
  std::vector<Obstacle> obstacles;              // other legs and the chassis
  // Obstacles grouped by leg (the chassis its own group) with a bounding sphere each: a swing
  // shape far from a whole leg skips its capsules (most legs are far from the swing leg).
  struct Group {
    Eigen::Vector3d centre;
    double bound = 0.0;
    std::size_t begin = 0, end = 0;
  };
  std::vector<Group> groups;
  std::vector<double> max_clearance;            // per swing shape: its largest table entry
  std::vector<std::array<int, 2>> own_pairs;    // swing shape pairs checked within the leg
  Eigen::MatrixXd table;
  std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> terrain;
  double terrain_top = 0.0;  // highest terrain point of the mesh
  // Highest terrain point per block of the mesh window: a shape entirely above the blocks under
  // it (plus the clearance) needs no mesh query (most of a swing happens in the air).
  double block = 0.05, block_x0 = 0.0, block_y0 = 0.0;
  int blocks = 0;
  Eigen::MatrixXd block_top;
  double local_top(const Eigen::Vector3d& centre, double bound) const {
    const int i0 = std::clamp(int(std::floor((centre.x() - bound - block_x0) / block)), 0, blocks - 1);
    const int i1 = std::clamp(int(std::floor((centre.x() + bound - block_x0) / block)), 0, blocks - 1);
    const int j0 = std::clamp(int(std::floor((centre.y() - bound - block_y0) / block)), 0, blocks - 1);
    const int j1 = std::clamp(int(std::floor((centre.y() + bound - block_y0) / block)), 0, blocks - 1);
    return block_top.block(i0, j0, i1 - i0 + 1, j1 - j0 + 1).maxCoeff();
  }
  walker::LegWorkspace ws;
  std::vector<fcl::Transform3d> poses;  // current swing shapes
  std::vector<Eigen::Vector3d> centres;
  std::vector<std::array<Eigen::Vector3d, 2>> ends;  // axis end points (world)
  std::vector<double> lowest;            // lowest point of each swing shape (world z)
  // The mesh's vertex heights (grid(i, j) at (grid_x0 + i grid_h, grid_y0 + j grid_h)).
  Eigen::MatrixXd grid;
  double grid_x0 = 0.0, grid_y0 = 0.0, grid_h = 1.0;
  // Height of the triangle mesh at (x, y) exactly as FCL sees it (cell (i, j) split along its
  // (i, j)-(i+1, j+1) diagonal); false outside the mesh.
  bool surface(double x, double y, double& z) const {
    const double u0 = (x - grid_x0) / grid_h, v0 = (y - grid_y0) / grid_h;
    const double fi = std::floor(u0), fj = std::floor(v0);
    if (!(fi >= 0.0 && fj >= 0.0 && fi < double(grid.rows() - 1) && fj < double(grid.cols() - 1))) return false;
    const int i = int(fi), j = int(fj);
    const double u = u0 - fi, v = v0 - fj;
    const double z00 = grid(i, j), z10 = grid(i + 1, j), z01 = grid(i, j + 1), z11 = grid(i + 1, j + 1);
    z = u >= v ? z00 + u * (z10 - z00) + v * (z11 - z10) : z00 + v * (z01 - z00) + u * (z11 - z01);
    return true;
  }
  // Highest block top over an axis-aligned box (clamped to the mesh window).
  double box_top(double xa, double xb, double ya, double yb) const {
    const int i0 = std::clamp(int(std::floor((xa - block_x0) / block)), 0, blocks - 1);
    const int i1 = std::clamp(int(std::floor((xb - block_x0) / block)), 0, blocks - 1);
    const int j0 = std::clamp(int(std::floor((ya - block_y0) / block)), 0, blocks - 1);
    const int j1 = std::clamp(int(std::floor((yb - block_y0) / block)), 0, blocks - 1);
    return block_top.block(i0, j0, i1 - i0 + 1, j1 - j0 + 1).maxCoeff();
  }
  // Terrain test of swing shape k inflated to radius r without FCL where it is decided: 1 free
  // (every piece of the axis, one block long, lies higher than r above the highest block under
  // it), 0 colliding (a point of the axis lies less than r above the surface point straight below
  // it, which is then inside the capsule; or below the surface: the terrain is solid), -1 open.
  int terrain_quick(std::size_t k, double r) const {
    const Eigen::Vector3d &a = ends[k][0], &b = ends[k][1];
    const int pieces = std::max(1, int(std::ceil((b - a).head<2>().norm() / block)));
    bool free = true;
    for (int p = 0; p < pieces && free; ++p) {
      const Eigen::Vector3d q0 = a + (double(p) / pieces) * (b - a), q1 = a + (double(p + 1) / pieces) * (b - a);
      free = std::min(q0.z(), q1.z()) - r > box_top(std::min(q0.x(), q1.x()) - r, std::max(q0.x(), q1.x()) + r,
                                                   std::min(q0.y(), q1.y()) - r, std::max(q0.y(), q1.y()) + r) + 1e-9;
    }
    if (free) return 1;
    const int samples = std::max(1, int(std::ceil((b - a).head<2>().norm() / (0.5 * grid_h))));
    for (int p = 0; p <= samples; ++p) {
      const Eigen::Vector3d x = a + (double(p) / samples) * (b - a);
      double z;
      if (surface(x.x(), x.y(), z) && x.z() - z <= r) return 0;
    }
    return -1;
  }
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  Eigen::VectorXd mid;                   // bisection scratch
  std::vector<std::array<double, 2>> queue;

  explicit Impl(const walker::WalkerModel& m) : ws(m) {}

  // World poses of the swing shapes at q (after model.forward).
  void place(const walker::WalkerModel& model) {
    std::size_t k = 0;
    for (int i = 0; i < n; ++i) {
      const walker::Capsule& g = model.params().joints[i].geometry;
      if (g.radius <= 0.0) continue;
      const auto r = ws.rotation.block<3, 3>(0, 3 * i);
      const Eigen::Vector3d p0 = body * (ws.joint_position.col(i) + r * g.p0);
      const Eigen::Vector3d p1 = body * (ws.joint_position.col(i) + r * g.p1);
      poses[k] = segment_pose(p0, p1);
      ends[k] = {p0, p1};
      centres[k] = 0.5 * (p0 + p1);
      lowest[k] = std::min(p0.z(), p1.z()) - g.radius;
      ++k;
    }
    const Eigen::Vector3d axle = body.linear() * ws.foot_rotation.col(1);
    const Eigen::Vector3d c = body * ws.wheel_centre;
    const double half = 0.5 * model.params().wheel_width;
    poses[k] = segment_pose(c - half * axle, c + half * axle);
    ends[k] = {c - half * axle, c + half * axle};
    centres[k] = c;
    lowest[k] = c.z() - half * std::abs(axle.z()) - model.params().wheel_radius;
  }

  bool hit(const GeometryPtr& a, const fcl::Transform3d& ta, const fcl::CollisionGeometryd* b,
           const fcl::Transform3d& tb) {
    result.clear();
    return fcl::collide(a.get(), ta, b, tb, request, result) > 0;
  }
};

LegCollisionChecker::LegCollisionChecker(const walker::WalkerModel& model,
                                         const dynamics::HeightMap& terrain,
                                         const Eigen::Isometry3d& body,
                                         const Eigen::Ref<const Eigen::MatrixXd>& q, int leg,
                                         const CollisionOptions& options)
    : model_(model), leg_(leg), impl_(std::make_unique<Impl>(model)) {
  model.check_leg(leg);
  model.check_configuration(q);
  require(body.matrix().allFinite(), "LegCollisionChecker: body pose is not finite");
  const int n = model.joints_per_leg();
  options.validate(n);
  Impl& s = *impl_;
  s.body = body;
  s.n = n;
  s.lower = model.lower_limits();
  s.upper = model.upper_limits();
  s.table = options.clearance_table.size() ? options.clearance_table : default_clearance_table(n);
  const walker::WalkerParameters& p = model.params();

  // Swing shapes and their inflated geometries, one per kind of check.
  for (int i = 0; i < n; ++i) {
    const walker::Capsule& g = p.joints[i].geometry;
    if (g.radius > 0.0) s.specs.push_back({i, g.radius, (g.p1 - g.p0).norm()});
  }
  s.specs.push_back({n, p.wheel_radius, p.wheel_width});
  for (const ShapeSpec& sp : s.specs) {
    std::vector<GeometryPtr> g{make_capsule(sp.radius + options.environment_clearance, sp.length),
                               make_capsule(sp.radius + options.own_leg_clearance, sp.length)};
    for (int t = 0; t < n + 2; ++t) g.push_back(make_capsule(sp.radius + s.table(sp.type, t), sp.length));
    s.inflated.push_back(std::move(g));
  }
  const std::size_t count = s.specs.size();
  s.poses.resize(count);
  s.ends.resize(count);
  s.centres.resize(count);
  s.lowest.resize(count);

  // Pairs of the swing leg that touch in the standard stance are joined by construction
  // (walker/self_collision's rule); the others are checked.
  model.forward(leg, model.standard_configuration().col(leg), s.ws);
  const Eigen::Isometry3d saved = s.body;
  s.body = Eigen::Isometry3d::Identity();
  s.place(model);
  std::vector<GeometryPtr>& plain = s.plain;
  for (const ShapeSpec& sp : s.specs) plain.push_back(make_capsule(sp.radius, sp.length));
  s.env_clearance = options.environment_clearance;
  s.own_clearance = options.own_leg_clearance;
  for (std::size_t a = 0; a < count; ++a)
    for (std::size_t b = a + 1; b < count; ++b)
      if (!s.hit(plain[a], s.poses[a], plain[b].get(), s.poses[b])) s.own_pairs.push_back({int(a), int(b)});
  auto chassis = std::make_shared<fcl::Cylinderd>(p.chassis_collision_radius, 2.0 * p.chassis_collision_half_height);
  std::vector<char> touches_chassis(count);
  for (std::size_t a = 0; a < count; ++a)
    touches_chassis[a] = s.hit(plain[a], s.poses[a], chassis.get(), fcl::Transform3d::Identity());
  s.body = saved;

  // Fixed obstacles: the other legs' capsules and the chassis, in the world.
  for (int k = 0; k < model.legs(); ++k) {
    if (k == leg) continue;
    const std::size_t begin = s.obstacles.size();
    for (const walker::LinkCapsule& c : model.leg_capsules(k, q.col(k))) {
      const Eigen::Vector3d p0 = body * c.p0, p1 = body * c.p1;
      const double len = (p1 - p0).norm();
      s.obstacles.push_back({c.link < 0 ? n : c.link, make_capsule(c.radius, len), segment_pose(p0, p1),
                             0.5 * (p0 + p1), 0.5 * len + c.radius});
    }
    s.groups.push_back({Eigen::Vector3d::Zero(), 0.0, begin, s.obstacles.size()});
  }
  fcl::Transform3d chassis_pose = fcl::Transform3d::Identity();
  chassis_pose.linear() = body.linear();
  chassis_pose.translation() = body.translation();
  s.obstacles.push_back({n + 1, chassis, chassis_pose, body.translation(),
                         std::hypot(p.chassis_collision_radius, p.chassis_collision_half_height)});
  s.groups.push_back({Eigen::Vector3d::Zero(), 0.0, s.obstacles.size() - 1, s.obstacles.size()});
  for (Impl::Group& g : s.groups) {
    for (std::size_t o = g.begin; o < g.end; ++o) g.centre += s.obstacles[o].centre / double(g.end - g.begin);
    for (std::size_t o = g.begin; o < g.end; ++o)
      g.bound = std::max(g.bound, (s.obstacles[o].centre - g.centre).norm() + s.obstacles[o].bound);
  }
  for (const ShapeSpec& sp : s.specs) s.max_clearance.push_back(s.table.row(sp.type).maxCoeff());
  // The chassis is checked only against shapes that do not touch it in the standard stance.
  for (std::size_t a = 0; a < count; ++a)
    if (touches_chassis[a]) s.inflated[a][2 + n + 1].reset();

  // Terrain: the height map sampled on its own spacing over the square the leg can reach.
  double reach = p.foot_offset.norm() + p.wheel_radius;
  for (const walker::JointSpec& j : p.joints) reach += j.offset.norm();
  reach += options.terrain_margin;
  const Eigen::Vector3d hip = body * model.hip_mount(leg).translation();
  const double h = terrain.spacing();
  const int cells = std::max(2, static_cast<int>(std::ceil(2.0 * reach / h)) + 1);
  const double x0 = hip.x() - 0.5 * h * (cells - 1), y0 = hip.y() - 0.5 * h * (cells - 1);
  std::vector<fcl::Vector3d> vertices;
  vertices.reserve(std::size_t(cells) * cells);
  s.terrain_top = -kInf;
  s.block_x0 = x0;
  s.block_y0 = y0;
  s.blocks = std::max(1, static_cast<int>(std::ceil(h * (cells - 1) / s.block)));
  s.block_top.setConstant(s.blocks, s.blocks, -kInf);
  s.grid.resize(cells, cells);
  s.grid_x0 = x0;
  s.grid_y0 = y0;
  s.grid_h = h;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j) {
      const double x = x0 + i * h, y = y0 + j * h, z = terrain.height(x, y);
      s.grid(i, j) = z;
      vertices.emplace_back(x, y, z);
      s.terrain_top = std::max(s.terrain_top, z);
    }
  // Each mesh cell (two triangles) raises the top of every block it overlaps.
  for (int i = 0; i + 1 < cells; ++i)
    for (int j = 0; j + 1 < cells; ++j) {
      const double z = std::max(std::max(vertices[i * cells + j].z(), vertices[i * cells + j + 1].z()),
                                std::max(vertices[(i + 1) * cells + j].z(), vertices[(i + 1) * cells + j + 1].z()));
      const int a0 = std::min(s.blocks - 1, int(std::floor(i * h / s.block)));
      const int a1 = std::min(s.blocks - 1, int(std::ceil((i + 1) * h / s.block)) - 1);
      const int b0 = std::min(s.blocks - 1, int(std::floor(j * h / s.block)));
      const int b1 = std::min(s.blocks - 1, int(std::ceil((j + 1) * h / s.block)) - 1);
      for (int a = a0; a <= std::max(a0, a1); ++a)
        for (int b = b0; b <= std::max(b0, b1); ++b) s.block_top(a, b) = std::max(s.block_top(a, b), z);
    }
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(2 * std::size_t(cells - 1) * (cells - 1));
  for (int i = 0; i + 1 < cells; ++i)
    for (int j = 0; j + 1 < cells; ++j) {
      const int a = i * cells + j, b = (i + 1) * cells + j;
      triangles.emplace_back(a, b, b + 1);
      triangles.emplace_back(a, b + 1, a + 1);
    }
  s.terrain = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  s.terrain->beginModel(int(triangles.size()), int(vertices.size()));
  s.terrain->addSubModel(vertices, triangles);
  s.terrain->endModel();
  s.terrain->computeLocalAABB();
  s.mid.resize(n);
}

LegCollisionChecker::~LegCollisionChecker() = default;

const Eigen::Isometry3d& LegCollisionChecker::body() const { return impl_->body; }

bool LegCollisionChecker::valid(const Eigen::Ref<const Eigen::VectorXd>& q_leg, bool include_wheel) {
  Impl& s = *impl_;
  ++checks_;
  for (int i = 0; i < s.n; ++i)
    if (!(q_leg[i] >= s.lower[i] && q_leg[i] <= s.upper[i])) return false;  // NaN fails too
  model_.forward(leg_, q_leg, s.ws);
  s.place(model_);
  const std::size_t count = s.specs.size();
  for (std::size_t a = 0; a < count; ++a) {
    const bool wheel = s.specs[a].type == s.n;
    // Terrain: skip shapes entirely above the highest terrain point (plus clearance).
    if (!(wheel && !include_wheel)) {
      const double bound = 0.5 * s.specs[a].length + s.specs[a].radius + s.env_clearance;
      if (s.lowest[a] <= s.local_top(s.centres[a], bound) + s.env_clearance + 1e-9) {
        const int quick = s.terrain_quick(a, s.specs[a].radius + s.env_clearance);
        if (quick == 0) return false;
        if (quick < 0 && s.hit(s.inflated[a][0], s.poses[a], s.terrain.get(), fcl::Transform3d::Identity()))
          return false;
      }
    }
    const double own = 0.5 * s.specs[a].length + s.specs[a].radius;
    for (const Impl::Group& grp : s.groups) {
      if ((s.centres[a] - grp.centre).squaredNorm() > std::pow(own + s.max_clearance[a] + grp.bound, 2)) continue;
      for (std::size_t k = grp.begin; k < grp.end; ++k) {
        const Obstacle& o = s.obstacles[k];
        const GeometryPtr& g = s.inflated[a][2 + o.type];
        if (!g) continue;
        const double reach = own + s.table(s.specs[a].type, o.type);
        if ((s.centres[a] - o.centre).norm() > reach + o.bound) continue;
        if (s.hit(g, s.poses[a], o.geometry.get(), o.pose)) return false;
      }
    }
  }
  for (const auto& pr : s.own_pairs) {
    const ShapeSpec &sa = s.specs[pr[0]], &sb = s.specs[pr[1]];
    const double reach = 0.5 * (sa.length + sb.length) + sa.radius + sb.radius + s.own_clearance;
    if ((s.centres[pr[0]] - s.centres[pr[1]]).norm() > reach) continue;
    // one side inflated by the clearance, the other plain
    if (s.hit(s.inflated[pr[0]][1], s.poses[pr[0]], s.plain[pr[1]].get(), s.poses[pr[1]])) return false;
  }
  return true;
}

bool LegCollisionChecker::motion_valid(const Eigen::Ref<const Eigen::VectorXd>& a,
                                       const Eigen::Ref<const Eigen::VectorXd>& b, double epsilon,
                                       bool include_wheel) {
  // as first_colliding_edge's resolution: a bound on the bisection depth
  require_in_range("motion_valid", "epsilon", epsilon, kMinResolution, kInf);
  Impl& s = *impl_;
  if (!valid(b, include_wheel)) return false;
  const double length = (b - a).cwiseAbs().maxCoeff();
  if (!(length > epsilon)) return std::isfinite(length);
  if (!(length / epsilon <= kMaxEdgeChecks)) {
    throw std::invalid_argument("motion_valid: the edge a -> b is " + std::to_string(length) +
                                " rad long, more than " + std::to_string(int(kMaxEdgeChecks)) +
                                " checks of epsilon (a and b lie within the joint limits)");
  }
  // Level-by-level bisection (§3.4.1): the midpoint of every sub-interval of a level is checked
  // before the next level, so a colliding middle is found early.
  s.queue.clear();
  s.queue.push_back({0.0, 1.0});
  for (std::size_t head = 0; head < s.queue.size(); ++head) {
    const auto [t0, t1] = s.queue[head];
    if ((t1 - t0) * length <= epsilon) continue;
    poll_interrupt();  // Ctrl-C between configuration checks (common/interrupt.hpp)
    const double tm = 0.5 * (t0 + t1);
    s.mid = a + tm * (b - a);
    if (!valid(s.mid, include_wheel)) return false;
    s.queue.push_back({t0, tm});
    s.queue.push_back({tm, t1});
  }
  return true;
}

int first_colliding_edge(LegCollisionChecker& checker, const Eigen::Ref<const Eigen::MatrixXd>& path,
                         double resolution, int wheel_free_edges) {
  // The lower bound keeps the check count of an edge finite (a full turn of a joint is about
  // 6e5 checks at 1e-5 rad); every check polls for Ctrl-C.
  require_in_range("first_colliding_edge", "resolution", resolution, kMinResolution, kInf);
  require(path.rows() == checker.model().joints_per_leg() && path.cols() >= 1 && path.allFinite(),
          "first_colliding_edge: path must be finite, joints x waypoints (at least one)");
  const int edges = int(path.cols()) - 1;
  Eigen::VectorXd x(path.rows());
  if (edges == 0) return checker.valid(path.col(0)) ? -1 : 0;
  for (int e = 0; e < edges; ++e) {
    const bool wheel = e >= wheel_free_edges && e < edges - wheel_free_edges;
    const Eigen::VectorXd d = path.col(e + 1) - path.col(e);
    const double span = d.cwiseAbs().maxCoeff() / resolution;
    if (!(span <= kMaxEdgeChecks)) {
      throw std::invalid_argument(
          "first_colliding_edge: path edge " + std::to_string(e) + " needs " + std::to_string(span) +
          " checks at this resolution, more than " + std::to_string(int(kMaxEdgeChecks)) +
          " (a path's joint angles lie within the joint limits)");
    }
    const int steps = std::max(1, int(std::ceil(span)));
    for (int k = 0; k <= steps; ++k) {
      poll_interrupt();  // Ctrl-C between configuration checks (common/interrupt.hpp)
      x = path.col(e) + (double(k) / steps) * d;
      // an end shared with a wheel-free edge is checked without the wheel
      const bool w = wheel && !((k == 0 && e == wheel_free_edges && e > 0) ||
                                (k == steps && e == edges - wheel_free_edges - 1 && wheel_free_edges > 0));
      if (!checker.valid(x, w)) return e;
    }
  }
  return -1;
}

}  // namespace ernest::footfall
