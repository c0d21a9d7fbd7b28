// Support polygon, CPS, SSM and NESM (seed 003 §3.3). The hull (Andrew's monotone chain) and the
// convex clipping (Sutherland–Hodgman) are written out on fixed-size arrays rather than taken
// from Boost.Geometry because the six-contact margins must cost about a microsecond and
// Boost.Geometry allocates per call; the tests check both against Boost.Geometry.
#include "ernest/statics/stability.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "ernest/common/validation.hpp"

namespace ernest::statics {

namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

double segment_distance(const Eigen::Vector2d& q, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((q - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - q).norm();
}

// Length scale of the projected contacts, for the tolerances (relative 1e-9).
double tolerance(const Eigen::Vector2d* p, int n) {
  double scale = 0.0;
  for (int i = 0; i < n; ++i) scale = std::max(scale, p[i].cwiseAbs().maxCoeff());
  return 1e-9 * std::max(scale, 1.0);
}

void check_contacts(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts) {
  if (contacts.cols() > kMaxContacts) {
    throw std::invalid_argument("contacts has " + std::to_string(contacts.cols()) +
                                " columns; at most " + std::to_string(kMaxContacts) +
                                " contacts are supported");
  }
  if (!contacts.allFinite()) throw std::invalid_argument("contacts contains a non-finite value");
}

// Convex hull of the points whose indices are idx[0..m), counter-clockwise, labels = contact
// indices of each edge's end points (mapped through idx).
Polygon hull_of(const Eigen::Vector2d* p, const int* idx, int m, double tol) {
  Polygon poly;
  if (m == 0) return poly;
  std::array<int, kMaxContacts> order;
  for (int k = 0; k < m; ++k) order[k] = idx[k];
  std::sort(order.begin(), order.begin() + m, [&](int a, int b) {
    return p[a].x() < p[b].x() || (p[a].x() == p[b].x() && p[a].y() < p[b].y());
  });
  // Coincident projections count once.
  int u = 0;
  for (int k = 0; k < m; ++k) {
    if (u > 0 && (p[order[k]] - p[order[u - 1]]).norm() <= tol) continue;
    order[u++] = order[k];
  }
  if (u == 1) {
    poly.size = 1;
    poly.vertices[0] = p[order[0]];
    poly.edge_contacts[0] = {order[0], order[0]};
    return poly;
  }
  std::array<int, 2 * kMaxContacts> h;
  int k = 0;
  const double tol2 = tol * tol;
  auto turn = [&](int o, int a, int b) { return cross2(p[a] - p[o], p[b] - p[o]); };
  for (int i = 0; i < u; ++i) {  // lower chain
    while (k >= 2 && turn(h[k - 2], h[k - 1], order[i]) <= tol2) --k;
    h[k++] = order[i];
  }
  for (int i = u - 2, lo = k + 1; i >= 0; --i) {  // upper chain
    while (k >= lo && turn(h[k - 2], h[k - 1], order[i]) <= tol2) --k;
    h[k++] = order[i];
  }
  poly.size = k - 1;  // the last point repeats the first
  for (int i = 0; i < poly.size; ++i) {
    poly.vertices[i] = p[h[i]];
    poly.edge_contacts[i] = {h[i], h[(i + 1) % poly.size]};
  }
  return poly;
}

// Drops vertices that coincide with their successor (keeping the successor's edge label).
void dedupe(Polygon& poly, double tol) {
  int n = 0;
  for (int i = 0; i < poly.size; ++i) {
    const int next = (i + 1) % poly.size;
    if (poly.size > 1 && next != i &&
        (poly.vertices[i] - poly.vertices[next]).norm() <= tol && n + (poly.size - i) > 1) {
      continue;
    }
    poly.vertices[n] = poly.vertices[i];
    poly.edge_contacts[n] = poly.edge_contacts[i];
    ++n;
  }
  poly.size = n;
}

// Sutherland–Hodgman step: keeps the part of `in` left of the directed line a -> b.
void clip(const Polygon& in, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
          std::array<int, 2> label, double tol, Polygon& out) {
  out.size = 0;
  const Eigen::Vector2d dir = b - a;
  const double len = dir.norm();
  if (len <= tol) {  // not a line: nothing to clip against
    out = in;
    return;
  }
  auto dist = [&](const Eigen::Vector2d& q) { return cross2(dir, q - a) / len; };
  auto emit = [&](const Eigen::Vector2d& v, std::array<int, 2> lab) {
    if (out.size < Polygon::kCapacity) {
      out.vertices[out.size] = v;
      out.edge_contacts[out.size] = lab;
      ++out.size;
    }
  };
  for (int i = 0; i < in.size; ++i) {
    const Eigen::Vector2d& P = in.vertices[i];
    const Eigen::Vector2d& Q = in.vertices[(i + 1) % in.size];
    const double dp = dist(P), dq = dist(Q);
    const bool pin = dp >= -tol, qin = dq >= -tol;
    if (pin) emit(P, in.edge_contacts[i]);
    if (pin != qin) {
      const double t = dp / (dp - dq);
      emit(P + t * (Q - P), pin ? label : in.edge_contacts[i]);
    }
  }
  dedupe(out, tol);
}

}  // namespace

ProjectionFrame ProjectionFrame::from_gravity(const Eigen::Vector3d& gravity) {
  const double g = gravity.norm();
  if (!gravity.allFinite() || !(g > 0.0)) {
    throw std::invalid_argument("gravity must be a finite non-zero vector");
  }
  ProjectionFrame f;
  f.up = -gravity / g;
  // e1: world x made perpendicular to up (world y if up is along x), so g = -z gives x, y, z.
  Eigen::Vector3d x = std::abs(f.up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  f.e1 = (x - x.dot(f.up) * f.up).normalized();
  f.e2 = f.up.cross(f.e1);
  return f;
}

double Polygon::area() const {
  double a = 0.0;
  for (int i = 0; i < size; ++i) a += cross2(vertices[i], vertices[(i + 1) % size]);
  return 0.5 * a;
}

double Polygon::signed_distance(const Eigen::Vector2d& q) const {
  if (size == 0) return kNegInf;
  if (size == 1) return -(q - vertices[0]).norm();
  if (size == 2) return -segment_distance(q, vertices[0], vertices[1]);
  double inside = std::numeric_limits<double>::infinity();
  bool is_inside = true;
  for (int i = 0; i < size; ++i) {
    const Eigen::Vector2d e = vertices[(i + 1) % size] - vertices[i];
    const double s = cross2(e, q - vertices[i]) / e.norm();
    if (s < 0.0) is_inside = false;
    inside = std::min(inside, s);
  }
  if (is_inside) return inside;
  double outside = std::numeric_limits<double>::infinity();
  for (int i = 0; i < size; ++i) {
    outside = std::min(outside, segment_distance(q, vertices[i], vertices[(i + 1) % size]));
  }
  return -outside;
}

Eigen::Matrix2Xd Polygon::vertex_matrix() const {
  Eigen::Matrix2Xd m(2, size);
  for (int i = 0; i < size; ++i) m.col(i) = vertices[i];
  return m;
}

Polygon support_polygon(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                        const ProjectionFrame& frame) {
  check_contacts(contacts);
  const int n = static_cast<int>(contacts.cols());
  std::array<Eigen::Vector2d, kMaxContacts> p;
  std::array<int, kMaxContacts> idx;
  for (int i = 0; i < n; ++i) {
    p[i] = frame.project(contacts.col(i));
    idx[i] = i;
  }
  return hull_of(p.data(), idx.data(), n, tolerance(p.data(), n));
}

Polygon conservative_support_polygon(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                     const ProjectionFrame& frame) {
  check_contacts(contacts);
  const int n = static_cast<int>(contacts.cols());
  if (n <= 3) return Polygon{};  // removing one of three contacts leaves a segment: no common area
  std::array<Eigen::Vector2d, kMaxContacts> p;
  for (int i = 0; i < n; ++i) p[i] = frame.project(contacts.col(i));
  const double tol = tolerance(p.data(), n);
  std::array<int, kMaxContacts> idx;
  // Ping-pong between two buffers: a Polygon is a few kB, so no copies in the loop.
  Polygon buffers[2];
  Polygon* cur = &buffers[0];
  Polygon* next = &buffers[1];
  for (int removed = 0; removed < n; ++removed) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
      if (i != removed) idx[m++] = i;
    }
    Polygon& sub = removed == 0 ? *cur : *next;
    sub = hull_of(p.data(), idx.data(), m, tol);
    if (removed == 0) continue;
    if (sub.size == 1) {  // all remaining contacts project to one point
      if (cur->signed_distance(sub.vertices[0]) < -tol) return Polygon{};
      std::swap(cur, next);
      continue;
    }
    const Polygon clip_by = sub;
    for (int e = 0; e < clip_by.size && cur->size > 0; ++e) {
      clip(*cur, clip_by.vertices[e], clip_by.vertices[(e + 1) % clip_by.size],
           clip_by.edge_contacts[e], tol, *next);
      std::swap(cur, next);
    }
    if (cur->size == 0) return Polygon{};
  }
  return *cur;
}

double nesm_edge(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& cg,
                 const Eigen::Vector3d& up, bool inside) {
  const Eigen::Vector3d e = (b - a).normalized();
  const Eigen::Vector3d d = cg - a;
  const Eigen::Vector3d R = d - d.dot(e) * e;
  const double cos_psi = std::sqrt(std::max(0.0, 1.0 - e.dot(up) * e.dot(up)));
  const double h = std::max(0.0, R.norm() * cos_psi - R.dot(up));  // >= 0 up to rounding
  return inside ? h : -h;
}

double static_stability_margin(const Polygon& polygon, const Eigen::Vector3d& cg,
                               const ProjectionFrame& frame) {
  return polygon.signed_distance(frame.project(cg));
}

double energy_stability_margin(const Polygon& polygon,
                               const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                               const Eigen::Vector3d& cg, const ProjectionFrame& frame) {
  if (polygon.size == 0) return kNegInf;
  const Eigen::Vector2d q = frame.project(cg);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < polygon.size; ++k) {
    const auto [i, j] = polygon.edge_contacts[k];
    double h;
    if (i == j) {  // a single contact: inverted pendulum, apex straight above it
      const Eigen::Vector3d d = cg - contacts.col(i);
      h = -(d.norm() - d.dot(frame.up));
    } else if (polygon.size < 3) {  // a line of contacts: balanced only in its vertical plane
      h = -std::abs(nesm_edge(contacts.col(i), contacts.col(j), cg, frame.up, true));
    } else {
      const Eigen::Vector2d e = polygon.vertices[(k + 1) % polygon.size] - polygon.vertices[k];
      const bool inside = cross2(e, q - polygon.vertices[k]) >= 0.0;
      h = nesm_edge(contacts.col(i), contacts.col(j), cg, frame.up, inside);
    }
    best = std::min(best, h);
  }
  return best;
}

StabilityMargins stability_margins(const Eigen::Ref<const Eigen::Matrix3Xd>& contacts,
                                   const Eigen::Vector3d& cg, const Eigen::Vector3d& gravity) {
  if (!cg.allFinite()) throw std::invalid_argument("cg contains a non-finite value");
  const ProjectionFrame frame = ProjectionFrame::from_gravity(gravity);
  const Polygon support = support_polygon(contacts, frame);
  const Polygon cps = conservative_support_polygon(contacts, frame);
  StabilityMargins m;
  m.support_vertices = support.size;
  m.cps_vertices = cps.size;
  m.ssm = static_stability_margin(support, cg, frame);
  m.nesm = energy_stability_margin(support, contacts, cg, frame);
  m.ssm_cps = static_stability_margin(cps, cg, frame);
  m.nesm_cps = energy_stability_margin(cps, contacts, cg, frame);
  return m;
}

}  // namespace ernest::statics
