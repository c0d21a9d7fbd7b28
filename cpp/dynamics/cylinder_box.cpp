// The exact wheel–rock contact (cylinder_box.hpp). Everything in the box's frame: q the
// cylinder's centre, a its axis, e the box's half sizes. The overlap along a unit n (n from the
// box towards the cylinder) is h_B(n) + h_A(-n) = e.|n| - n.q + r sqrt(1 - (n.a)^2) + hl |n.a|;
// the depth is its minimum over the sphere. Every patch of B - A has its normals on one of:
//   - the box's face normals and the cylinder's axis (Face, Cap): single directions;
//   - the great circle normal to the axis (generator against vertex or edge): the overlap there
//     is linear in n between the cross axes a x e_i (Cross), so its minimum is at one of them or
//     at n = -perp_a(v - q) for a vertex v (Vertex: depth r - |perp_a(v - q)|);
//   - the three great circles normal to a box axis e_i (box edge along e_i against the rim): on
//     each, the overlap is piecewise smooth in the angle, with kinks at the face normals and at
//     the cross axis (where n.a changes sign and the rim changes end); each smooth piece is an
//     ellipse's support function, minimised by safeguarded Newton (RimEdge).
// The first two need no iteration; a piece of the third is searched only if a lower bound of the
// overlap along it (a tangent plane of the support function, below) is under the best so far.
#include "ernest/dynamics/cylinder_box.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Geometry>

namespace ernest::dynamics::detail {

namespace {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;

struct Search {
  Vec3 q, a, e;
  double r, hl;
  double best = HUGE_VAL;
  Vec3 n = Vec3::Zero();
  int axis = -1;

  double overlap(const Vec3& m) const { return cylinder_box_overlap(m, q, a, r, hl, e); }
  // A unit candidate, its sign turned towards the cylinder (the other sign's overlap is larger
  // by 2 |n.q|). False: it separates the shapes.
  bool consider(Vec3 m, int kind) {
    if (m.dot(q) < 0.0) m = -m;
    const double d = overlap(m);
    if (d < best) best = d, n = m, axis = kind;
    return d >= 0.0;
  }
  bool consider_dir(const Vec3& v, int kind) {
    const double len = v.norm();
    return len < 1e-12 || consider(v / len, kind);
  }
  // A point of B - A (the box's support point at m minus the cylinder's at -m): the overlap along
  // any n is at least n.x (the support function's tangent plane at m), the pruning bound.
  Vec3 difference_point(const Vec3& m) const {
    const double ma = m.dot(a);
    Vec3 x = e.cwiseProduct(m.cwiseSign()) - q + (ma < 0.0 ? -hl : hl) * a;
    const Vec3 perp = m - ma * a;
    const double len = perp.norm();
    if (len > 1e-12) x += (r / len) * perp;
    return x;
  }
  void rim_edges(int i);
  void rim_piece(int i, double lo, double hi, const Vec2& p2, const Vec2& al);
};

Vec3 on_circle(int i, double cs, double sn) {  // the unit vector at angle phi in plane (j, k)
  Vec3 m = Vec3::Zero();
  m[(i + 1) % 3] = cs;
  m[(i + 2) % 3] = sn;
  return m;
}

// Least n.x over the arc of directions from angle lo to hi (< pi) in plane (j, k).
double arc_min(const Vec2& x, double lo, double hi) {
  const Vec2 ml(std::cos(lo), std::sin(lo)), mh(std::cos(hi), std::sin(hi));
  const auto cross = [](const Vec2& s, const Vec2& t) { return s.x() * t.y() - s.y() * t.x(); };
  if (cross(ml, -x) >= 0.0 && cross(-x, mh) >= 0.0) return -x.norm();
  return std::min(ml.dot(x), mh.dot(x));
}

// The box edges along e_i against the rims: the great circle of n normal to e_i.
void Search::rim_edges(int i) {
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const Vec2 al(a[j], a[k]), qq(q[j], q[k]);
  const double half_pi = 0.5 * M_PI;
  for (int quad = 0; quad < 4; ++quad) {  // the edge at (sj e_j, sk e_k): n in its quadrant
    const double sj = quad == 0 || quad == 3 ? 1.0 : -1.0, sk = quad < 2 ? 1.0 : -1.0;
    const double lo = quad * half_pi, hi = lo + half_pi;
    const Vec3 mid = on_circle(i, sj * M_SQRT1_2, sk * M_SQRT1_2);
    const Vec3 x = difference_point(mid);
    if (arc_min(Vec2(x[j], x[k]), lo, hi) >= best) continue;
    const Vec2 p2(sj * e[j] - qq.x(), sk * e[k] - qq.y());
    // The cross axes +-(-al.y, al.x) inside the quadrant split it where n.a changes sign.
    double split = lo;
    for (double s : {1.0, -1.0}) {
      const Vec2 c(-s * al.y(), s * al.x());
      if (c.x() * sj > 0.0 && c.y() * sk > 0.0) {
        split = std::atan2(c.y(), c.x());
        if (split < lo) split += 2.0 * M_PI;
      }
    }
    if (split > lo && split < hi) {
      rim_piece(i, lo, split, p2, al);
      rim_piece(i, split, hi, p2, al);
    } else {
      rim_piece(i, lo, hi, p2, al);
    }
  }
}

// One smooth piece: f(phi) = m.G + r sqrt(1 - (m.al)^2), G = P + sigma hl al, with m = (cos phi,
// sin phi), P the edge's corner minus the cylinder's centre and sigma = sign(m.al) on the piece
// (the rim at -sigma a): the support function of an ellipse (the rim seen along e_i) moved by G.
// It can have two minima and a maximum close together (a point near the ellipse's evolute), so
// sampling f' is not enough: branch and bound over the arc, an arc dropped where the lower bound
// (the tangent plane at its middle direction) is not below the best overlap so far, down to
// leaves of kLeaf rad, where f' going from - to + brackets a minimum refined by Newton (kept in
// its bracket: bisection where a step leaves it).
void Search::rim_piece(int i, double lo, double hi, const Vec2& p2, const Vec2& al) {
  constexpr double kLeaf = M_PI / 128;
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const double mid0 = 0.5 * (lo + hi);
  const double sigma = std::cos(mid0) * al.x() + std::sin(mid0) * al.y() < 0.0 ? -1.0 : 1.0;
  const Vec2 g = p2 + sigma * hl * al;
  const auto derivs = [&](double phi, double& d1, double& d2) {
    const double cs = std::cos(phi), sn = std::sin(phi);
    const double c = cs * al.x() + sn * al.y(), cp = -sn * al.x() + cs * al.y();
    const double root = std::max(std::sqrt(std::max(0.0, 1.0 - c * c)), 1e-12);
    d1 = -sn * g.x() + cs * g.y() - r * c * cp / root;
    d2 = -(cs * g.x() + sn * g.y()) -
         r * ((cp * cp - c * c) / root + c * c * cp * cp / (root * root * root));
  };
  const auto try_angle = [&](double phi) {
    const Vec3 m = on_circle(i, std::cos(phi), std::sin(phi));
    const double d = overlap(m);  // exact at any direction: an upper bound of the depth
    if (d < best) best = d, n = m, axis = RimEdge;
  };
  std::array<std::array<double, 2>, 32> stack;
  int top = 0;
  stack[top++] = {lo, hi};
  while (top > 0) {
    const auto [l, h] = stack[--top];
    const double mid = 0.5 * (l + h);
    const Vec3 mm = on_circle(i, std::cos(mid), std::sin(mid));
    const Vec3 x = difference_point(mm);
    if (arc_min(Vec2(x[j], x[k]), l, h) >= best) continue;
    if (h - l > kLeaf && top + 2 <= static_cast<int>(stack.size())) {
      try_angle(mid);
      stack[top++] = {l, mid};
      stack[top++] = {mid, h};
      continue;
    }
    double dl, dh, d2;
    derivs(l, dl, d2);
    derivs(h, dh, d2);
    if (!(dl < 0.0 && dh >= 0.0)) {  // no minimum inside: the ends
      try_angle(l);
      try_angle(h);
      continue;
    }
    double a0 = l, b0 = h, t = mid;
    for (int it = 0; it < 40; ++it) {
      double f1, f2;
      derivs(t, f1, f2);
      (f1 < 0.0 ? a0 : b0) = t;
      double next = f2 > 0.0 ? t - f1 / f2 : 0.5 * (a0 + b0);
      if (!(next > a0 && next < b0)) next = 0.5 * (a0 + b0);
      const bool done = std::abs(next - t) < 1e-14;
      t = next;
      if (done || b0 - a0 < 1e-14) break;
    }
    try_angle(t);
  }
}

// Liang–Barsky: the part t in [t0, t1] of p + t d inside the box |x_k| <= e_k.
bool clip_to_box(const Vec3& p, const Vec3& d, const Vec3& e, double& t0, double& t1) {
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (std::abs(p[k]) > e[k]) return false;
      continue;
    }
    double ta = (-e[k] - p[k]) / d[k], tb = (e[k] - p[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

}  // namespace

double cylinder_box_overlap(const Vec3& n, const Vec3& q, const Vec3& a, double r, double hl,
                            const Vec3& e) {
  // |n x a| rather than sqrt(1 - (n.a)^2): exact (zero) for n along the axis
  return e.dot(n.cwiseAbs()) - n.dot(q) + r * n.cross(a).norm() + hl * std::abs(n.dot(a));
}

bool cylinder_box_contact(const Vec3& c, const Vec3& u, double r, double hl, const Vec3& b,
                          const Eigen::Matrix3d& rb, const Vec3& e, CylinderBoxContact& out) {
  Search s;
  s.q = rb.transpose() * (c - b);
  s.a = rb.transpose() * u;
  s.e = e;
  s.r = r;
  s.hl = hl;
  const Vec3& q = s.q;
  const Vec3& a = s.a;
  for (int i = 0; i < 3; ++i)  // Face
    if (!s.consider(Vec3::Unit(i), Face)) return false;
  if (!s.consider(a, Cap)) return false;
  for (int i = 0; i < 3; ++i)  // Cross: a x e_i
    if (!s.consider_dir(a.cross(Vec3::Unit(i)), Cross)) return false;
  for (int v = 0; v < 8; ++v) {  // Vertex: n = -perp_a(v - q), overlap r - |perp_a(v - q)|
    const Vec3 w = Vec3((v & 1) ? e.x() : -e.x(), (v & 2) ? e.y() : -e.y(),
                        (v & 4) ? e.z() : -e.z()) - q;
    const Vec3 perp = w - w.dot(a) * a;
    const double len = perp.norm();
    if (len < 1e-12) continue;
    const Vec3 m = -perp / len;
    const double d = s.overlap(m);
    if (d < 0.0) return false;
    if (d < s.best) s.best = d, s.n = m, s.axis = Vertex;
  }
  for (int i = 0; i < 3; ++i) s.rim_edges(i);  // RimEdge
  if (!(s.best >= 0.0)) return false;          // NaN poses: no contact

  // The point: ODE's clipping (collision_cylinder_box.cpp), exact. Where the normal is within
  // acos 0.9 of normal to the axis, the cylinder's generator nearest the box clipped to the box;
  // else its cap nearest the box (a 16-gon) clipped to the box and to the depth >= 0 side. The
  // points' depths h_B(n) - y.n weight them (merge_contact_points).
  const Vec3& n = s.n;
  const double na = n.dot(a), hb = e.dot(n.cwiseAbs()), side = na < 0.0 ? -1.0 : 1.0;
  Vec3 w = -(n - na * a);  // the cylinder's radial direction towards the box
  const double wl = w.norm();
  w = wl > 1e-12 ? Vec3(w / wl) : Vec3(a.unitOrthogonal());
  Vec3 point = q + (wl > 1e-12 ? r : 0.0) * w - side * hl * a;  // the support point at -n
  double wsum = 0.0;
  Vec3 wx = Vec3::Zero();
  if (std::abs(na) < 0.9) {
    const Vec3 p0 = q + r * w - hl * a, d = 2.0 * hl * a;
    double t0 = 0.0, t1 = 1.0;
    if (clip_to_box(p0, d, e, t0, t1)) {
      for (double t : {t0, t1}) {
        const Vec3 y = p0 + t * d;
        const double dy = std::max(0.0, hb - y.dot(n));
        wsum += dy;
        wx += dy * y;
      }
      if (wsum <= 0.0) wsum = 1.0, wx = p0 + 0.5 * (t0 + t1) * d;
    }
  } else {
    constexpr int kSides = 16, kMax = kSides + 8;
    std::array<Vec3, kMax> poly, next;
    int count = kSides;
    const Vec3 cc = q - side * hl * a, u1 = w, u2 = a.cross(w);
    for (int v = 0; v < kSides; ++v) {
      const double ang = 2.0 * M_PI * v / kSides;
      poly[v] = cc + r * (std::cos(ang) * u1 + std::sin(ang) * u2);
    }
    // Sutherland–Hodgman against the 6 box planes and depth >= 0 (plane.y <= offset)
    for (int pl = 0; pl < 7 && count > 0; ++pl) {
      const Vec3 pn = pl < 6 ? Vec3((pl % 2 ? -1.0 : 1.0) * Vec3::Unit(pl / 2)) : n;
      const double off = pl < 6 ? e[pl / 2] : hb;
      int m = 0;
      for (int v = 0; v < count; ++v) {
        const Vec3 &p = poly[v], &pq = poly[(v + 1) % count];
        const double dp = pn.dot(p) - off, dq = pn.dot(pq) - off;
        if (dp <= 0.0) next[m++] = p;
        if (((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) && m < kMax)
          next[m++] = p + dp / (dp - dq) * (pq - p);
      }
      count = std::min(m, kMax);
      std::copy(next.begin(), next.begin() + count, poly.begin());
    }
    for (int v = 0; v < count; ++v) {
      const double dy = std::max(0.0, hb - poly[v].dot(n));
      wsum += dy;
      wx += dy * poly[v];
    }
  }
  if (wsum > 0.0) point = wx / wsum;
  out.depth = s.best;
  out.normal = rb * n;
  out.pos = rb * point + b;
  out.axis = s.axis;
  return true;
}

}  // namespace ernest::dynamics::detail
