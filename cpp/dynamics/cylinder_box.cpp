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
//     ellipse's support function, minimised by branch and bound over its arc with Newton on the
//     last arcs (RimEdge, rim_piece).
// The first two need no iteration; the pieces of the third are searched most promising first,
// each only while a lower bound of the overlap on it (lower_bound) is under the best so far.
// The depth is seed 004 §3.4's compression of the wheel–obstacle spring (Fig. 9).
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

  double overlap(const Vec3& m) const {  // cylinder_box_overlap, inlined
    return e.dot(m.cwiseAbs()) - m.dot(q) + r * m.cross(a).norm() + hl * std::abs(m.dot(a));
  }
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
  // A smooth piece of the overlap on the great circle normal to e_i (rim_piece below).
  struct Piece {
    int i;
    Vec2 lo, hi, g, al, al_unit, g_unit;
    double rho, gn;  // |al|, |G|
    double bound;    // a lower bound of the overlap on it
  };
  std::array<Piece, 24> pieces;
  int n_pieces = 0;
  void add_pieces(int i);
  void add_piece(int i, const Vec2& lo, const Vec2& hi, const Vec2& p2, const Vec2& al);
  double lower_bound(const Piece& p, const Vec2& l, const Vec2& h) const;
  void rim_piece(const Piece& p);
  void rim_edges();
};

double cross2(const Vec2& s, const Vec2& t) { return s.x() * t.y() - s.y() * t.x(); }

// Whether direction d lies on the arc from unit lo to unit hi (counterclockwise, < pi).
bool on_arc(const Vec2& d, const Vec2& lo, const Vec2& hi) {
  return cross2(lo, d) >= 0.0 && cross2(d, hi) >= 0.0;
}

// Least m.x over the arc of unit m from lo to hi.
double arc_min(const Vec2& x, const Vec2& lo, const Vec2& hi) {
  if (on_arc(-x, lo, hi)) return -x.norm();
  return std::min(lo.dot(x), hi.dot(x));
}

// The box edges along e_i against the rims: the great circle of n normal to e_i, in the plane
// (j, k) = (i + 1, i + 2); each quadrant is one edge's (at (sj e_j, sk e_k)) normal cone.
void Search::add_pieces(int i) {
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const Vec2 al(a[j], a[k]);
  static const std::array<Vec2, 5> kEnds = {Vec2(1, 0), Vec2(0, 1), Vec2(-1, 0), Vec2(0, -1),
                                            Vec2(1, 0)};
  for (int quad = 0; quad < 4; ++quad) {
    const Vec2 &lo = kEnds[quad], &hi = kEnds[quad + 1];
    const Vec2 corner = lo + hi;  // (sj, sk)
    const Vec2 p2(corner.x() * e[j] - q[j], corner.y() * e[k] - q[k]);
    // f = m.P + r sqrt(1 - c^2) + hl |c| >= min m.P + min(r, hl) (concave in |c| <= 1): with
    // m = (sj cos t, sk sin t), t in [0, pi / 2], m.P = A cos t + B sin t
    const double pa = corner.x() * p2.x(), pb = corner.y() * p2.y();
    const double quad_min = pa < 0.0 && pb < 0.0 ? -std::hypot(pa, pb) : std::min(pa, pb);
    if (quad_min + std::min(r, hl) >= best) continue;
    // The cross axes +-(-al.y, al.x) inside the quadrant split it where n.a changes sign.
    Vec2 split = lo;
    for (double s : {1.0, -1.0}) {
      const Vec2 c(-s * al.y(), s * al.x());
      if (c.x() * corner.x() > 0.0 && c.y() * corner.y() > 0.0) split = c.normalized();
    }
    if (split != lo) {
      add_piece(i, lo, split, p2, al);
      add_piece(i, split, hi, p2, al);
    } else {
      add_piece(i, lo, hi, p2, al);
    }
  }
}

// One smooth piece: f(m) = m.G + r sqrt(1 - (m.al)^2), G = P + sigma hl al, with m = (cos phi,
// sin phi), P the edge's corner minus the cylinder's centre and sigma = sign(m.al) on the piece
// (the rim at -sigma a): the support function of an ellipse (the rim seen along e_i) moved by G.
void Search::add_piece(int i, const Vec2& lo, const Vec2& hi, const Vec2& p2, const Vec2& al) {
  Piece& p = pieces[n_pieces];
  p.i = i;
  p.lo = lo;
  p.hi = hi;
  p.al = al;
  p.g = p2 + ((lo + hi).dot(al) < 0.0 ? -hl : hl) * al;
  p.rho = al.norm();
  p.al_unit = p.rho > 0.0 ? Vec2(al / p.rho) : Vec2(1.0, 0.0);
  p.gn = p.g.norm();
  p.g_unit = p.gn > 0.0 ? Vec2(p.g / p.gn) : Vec2(1.0, 0.0);
  p.bound = lower_bound(p, lo, hi);
  if (p.bound < best) ++n_pieces;
}

// Lower bounds of f on the arc of unit m from l to h (counterclockwise, < pi; no trigonometry):
//  - the tangent plane at its middle direction (m.x <= f(m) for the ellipse's support point x);
//  - min m.G + r sqrt(1 - max (m.al)^2);
//  - from each end, f'' >= -f >= -F (f + f'' is the ellipse's radius of curvature, >= 0; F an
//    upper bound of f on the arc): f(l + t) >= f(l) + f'(l) t - F t^2 / 2, least at t = 0 or at
//    the width w; likewise from h. These decide the arcs next to a kink where the minimum is.
// The cheapest first: most arcs are dropped by the first.
double Search::lower_bound(const Piece& p, const Vec2& l, const Vec2& h) const {
  const auto linear_min = [&](const Vec2& x, const Vec2& x_unit, double x_norm) {
    return on_arc(-x_unit, l, h) ? -x_norm : std::min(l.dot(x), h.dot(x));
  };
  double cmax = std::max(std::abs(l.dot(p.al)), std::abs(h.dot(p.al)));
  if (on_arc(p.al_unit, l, h) || on_arc(-p.al_unit, l, h)) cmax = p.rho;
  const double separable =
      linear_min(p.g, p.g_unit, p.gn) + r * std::sqrt(std::max(0.0, 1.0 - cmax * cmax));
  if (separable >= best) return separable;
  const Vec2 m = (l + h).normalized();
  const double c = m.dot(p.al), root = std::sqrt(std::max(0.0, 1.0 - c * c));
  const Vec2 x = p.g + (root > 1e-12 ? r / root : 0.0) * (m - c * p.al);  // the support point
  const double tangent = arc_min(x, l, h);
  if (tangent >= best) return tangent;
  const double chord = (h - l).norm(), w = chord * (1.0 + chord * chord / 12.0);  // >= the angle
  const auto value = [&](const Vec2& mm, double& f, double& d1) {
    const Vec2 mp(-mm.y(), mm.x());
    const double cc = mm.dot(p.al), cp = mp.dot(p.al);
    const double rt = std::max(std::sqrt(std::max(0.0, 1.0 - cc * cc)), 1e-12);
    f = mm.dot(p.g) + r * rt;
    d1 = mp.dot(p.g) - r * cc * cp / rt;
    return rt > 1e-9;  // f' is unbounded where the normal is the axis
  };
  double fl, dl, fh, dh;
  if (!value(l, fl, dl) || !value(h, fh, dh)) return std::max(separable, tangent);
  // f <= max(f(l), f(h)) / cos(w / 2) on the arc: a support function is sublinear, and each m of
  // the arc is l s + h t with s, t >= 0, s + t <= 1 / cos(w / 2) = 2 / |l + h|
  const double fmax = std::max({fl, fh, 0.0}) * 2.0 / (l + h).norm();
  const auto end = [&](double f, double d1) {
    return std::min(f, f + d1 * w - 0.5 * fmax * w * w);
  };
  return std::max({separable, tangent, end(fl, dl), end(fh, -dh)});
}

// All pieces, the most promising (least bound) first, each dropped once its bound is not below
// the best overlap so far.
void Search::rim_edges() {
  for (int i = 0; i < 3; ++i) add_pieces(i);
  std::array<int, 24> order;
  for (int k = 0; k < n_pieces; ++k) order[k] = k;
  std::sort(order.begin(), order.begin() + n_pieces,
            [&](int x, int y) { return pieces[x].bound < pieces[y].bound; });
  for (int k = 0; k < n_pieces; ++k)
    if (pieces[order[k]].bound < best) rim_piece(pieces[order[k]]);
}

// The minimum of f on a piece. f can have two minima and a maximum close together (a point near
// the ellipse's evolute), so sampling f' is not enough: branch and bound over the arc, an arc
// dropped where lower_bound is not below the best overlap so far, down to leaves of about kLeaf
// rad, where f' going from - to + brackets a minimum refined by Newton (kept in its bracket:
// bisection where a step leaves it).
void Search::rim_piece(const Piece& p) {
  constexpr double kLeaf = M_PI / 16;
  const double leaf_chord = 2.0 * std::sin(0.5 * kLeaf);
  const Vec2 &g = p.g, &al = p.al;
  const auto derivs = [&](const Vec2& m, double& d1, double& d2) {
    const Vec2 mp(-m.y(), m.x());
    const double c = m.dot(al), cp = mp.dot(al);
    const double root = std::max(std::sqrt(std::max(0.0, 1.0 - c * c)), 1e-12);
    d1 = mp.dot(g) - r * c * cp / root;
    d2 = -m.dot(g) - r * ((cp * cp - c * c) / root + c * c * cp * cp / (root * root * root));
  };
  const auto try_dir = [&](const Vec2& m2) {
    Vec3 m = Vec3::Zero();
    m[(p.i + 1) % 3] = m2.x();
    m[(p.i + 2) % 3] = m2.y();
    const double d = overlap(m);  // exact at any direction: an upper bound of the depth
    if (d < best) best = d, n = m, axis = RimEdge;
  };
  std::array<std::array<Vec2, 2>, 32> stack;
  int top = 0;
  stack[top++] = {p.lo, p.hi};
  while (top > 0) {
    const auto [l, h] = stack[--top];
    if (lower_bound(p, l, h) >= best) continue;
    if ((h - l).norm() > leaf_chord && top + 2 <= static_cast<int>(stack.size())) {
      const Vec2 mid = (l + h).normalized();
      try_dir(mid);
      stack[top++] = {l, mid};
      stack[top++] = {mid, h};
      continue;
    }
    double dl, dh, d2;
    derivs(l, dl, d2);
    derivs(h, dh, d2);
    if (!(dl < 0.0 && dh >= 0.0)) {  // no minimum inside: the ends
      try_dir(l);
      try_dir(h);
      continue;
    }
    // Newton in the angle t from l: m(t) = cos t l + sin t l_perp, t in [0, width]
    const Vec2 lp(-l.y(), l.x());
    double a0 = 0.0, b0 = std::atan2(cross2(l, h), l.dot(h)), t = 0.5 * b0;
    for (int it = 0; it < 40; ++it) {
      double f1, f2;
      derivs(std::cos(t) * l + std::sin(t) * lp, f1, f2);
      (f1 < 0.0 ? a0 : b0) = t;
      double next = f2 > 0.0 ? t - f1 / f2 : 0.5 * (a0 + b0);
      if (!(next > a0 && next < b0)) next = 0.5 * (a0 + b0);
      const bool done = std::abs(next - t) < 1e-14;
      t = next;
      if (done || b0 - a0 < 1e-14) break;
    }
    try_dir(std::cos(t) * l + std::sin(t) * lp);
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
  s.rim_edges();  // RimEdge
  if (!(s.best >= 0.0)) return false;          // NaN poses: no contact

  // The point: ODE's clipping (collision_cylinder_box.cpp), exact. Where the normal is within
  // acos 0.9 of normal to the axis, the cylinder's generator nearest the box clipped to the box,
  // its ends weighted by their depths h_B(n) - y.n (what merge_contact_points makes of ODE's two
  // points); else its cap nearest the box (a 16-gon) clipped to the box and to the depth >= 0
  // side, and the depth-weighted centroid of that area.
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
    constexpr int kSides = 16, kMax = kSides + 8;  // each plane adds at most one vertex
    static const std::array<std::array<double, 2>, kSides> kCircle = [] {
      std::array<std::array<double, 2>, kSides> t{};
      for (int v = 0; v < kSides; ++v)
        t[v] = {std::cos(2.0 * M_PI * v / kSides), std::sin(2.0 * M_PI * v / kSides)};
      return t;
    }();
    std::array<Vec3, kMax> buf_a, buf_b;
    Vec3 *poly = buf_a.data(), *next = buf_b.data();
    int count = kSides;
    const Vec3 cc = q - side * hl * a, u1 = r * w, u2 = r * a.cross(w);
    for (int v = 0; v < kSides; ++v) poly[v] = cc + kCircle[v][0] * u1 + kCircle[v][1] * u2;
    // Sutherland–Hodgman against the box planes the cap crosses (its reach along e_k is
    // r sqrt(1 - a_k^2) from its centre) and depth >= 0 (plane.y <= offset)
    for (int pl = 0; pl < 7 && count > 0; ++pl) {
      if (pl < 6) {
        const int k = pl / 2;
        const double reach = r * std::sqrt(std::max(0.0, 1.0 - a[k] * a[k]));
        if ((pl % 2 ? -cc[k] : cc[k]) + reach <= e[k]) continue;
      }
      const Vec3 pn = pl < 6 ? Vec3((pl % 2 ? -1.0 : 1.0) * Vec3::Unit(pl / 2)) : n;
      const double off = pl < 6 ? e[pl / 2] : hb;
      int m = 0;
      double dp = pn.dot(poly[0]) - off;
      for (int v = 0; v < count && m + 2 <= kMax; ++v) {
        const Vec3 &p = poly[v], &pq = poly[v + 1 < count ? v + 1 : 0];
        const double dq = pn.dot(pq) - off;
        if (dp <= 0.0) next[m++] = p;
        if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0))
          next[m++] = p + dp / (dp - dq) * (pq - p);
        dp = dq;
      }
      count = m;
      std::swap(poly, next);
    }
    // The depth-weighted centroid of the clipped cap (depth d linear on it): over each triangle
    // of a fan, int d dA = A (d0 + d1 + d2) / 3 and int d x dA = A / 12 (sum d_i x_i +
    // sum d_i sum x_i). A vertex mean would lean towards the arc (many vertices) and jump as
    // vertices appear.
    for (int v = 1; v + 1 < count; ++v) {
      const Vec3 &x0 = poly[0], &x1 = poly[v], &x2 = poly[v + 1];
      const double area = 0.5 * (x1 - x0).cross(x2 - x0).norm();
      const double d0 = std::max(0.0, hb - x0.dot(n)), d1 = std::max(0.0, hb - x1.dot(n)),
                   d2 = std::max(0.0, hb - x2.dot(n));
      wsum += area * (d0 + d1 + d2) / 3.0;
      wx += area / 12.0 * (d0 * x0 + d1 * x1 + d2 * x2 + (d0 + d1 + d2) * (x0 + x1 + x2));
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
