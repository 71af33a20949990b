// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the energy terms of the deployment simulation as residuals (private header).
//
// Discrete elastic rods after Bergou et al. 2008/2010 and the connection, anchor, notch-limit and
// pseudo-friction terms of paper Section 5. Every term is written as a residual vector r whose
// energy is E = 1/2 |r|^2 (Ceres' convention), templated on the scalar so that the same code is
// evaluated with doubles (reporting, tests) and with Ceres jets (automatic Jacobians).
//
// Conventions
//   A rod has vertices x_0..x_n and edges e_k = x_{k+1} - x_k with one twist angle theta_k each.
//   Each edge carries a reference frame (t_ref, d1_ref) from the last frame update; within a
//   solve the reference director of the current edge is the time-parallel transport of d1_ref
//   from t_ref to the current tangent t (the minimal rotation taking t_ref to t), which is a
//   smooth function of the vertices (singular only if an edge reverses within one update).
//   Material frame: m1 = cos(theta) d1 + sin(theta) d2, m2 = t x m1 (right-handed (t, m1, m2)).
//   m1 is the lamella's material normal (its thickness direction, the target surface normal at
//   the start); m2 its width direction. Bending with the curvature vector along m1 (out of the
//   lamella's plane) is the weak axis, with stiffness E w t^3 / 12; bending along m2 (in the
//   lamella's plane) the strong axis, E t w^3 / 12.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <tuple>

namespace gridshell::rod_terms {

template <typename T>
using V3 = Eigen::Matrix<T, 3, 1>;

/// The value part of a scalar: the double itself, or a Ceres jet's .a.
inline double ceres_value(double v) { return v; }
template <typename J>
auto ceres_value(const J& jet) -> decltype(ceres_value(jet.a)) {
  return ceres_value(jet.a);
}

template <typename T>
V3<T> load(const T* p) {
  return V3<T>(p[0], p[1], p[2]);
}

template <typename T>
void store(const V3<T>& v, T* out) {
  out[0] = v[0];
  out[1] = v[1];
  out[2] = v[2];
}

/// The minimal rotation taking unit vector a to unit vector b, applied to v (parallel transport
/// along the shortest arc). R v = (a.b) v + (a x b) x v + ((a x b).v / (1 + a.b)) (a x b): smooth
/// at a = b, singular only at a = -b.
template <typename T>
V3<T> transport(const V3<T>& a, const V3<T>& b, const V3<T>& v) {
  const V3<T> k = a.cross(b);
  const T c = a.dot(b);
  return c * v + k.cross(v) + (k.dot(v) / (T(1) + c)) * k;
}

/// Reference frame of one edge from the last frame update (constants within a solve).
struct EdgeReference {
  Eigen::Vector3d tangent = Eigen::Vector3d::UnitX();  ///< unit tangent at the update
  Eigen::Vector3d d1 = Eigen::Vector3d::UnitY();       ///< unit reference director, ⟂ tangent
};

/// Frame of an edge at the current vertices and twist.
template <typename T>
struct EdgeFrame {
  V3<T> t, d1, m1, m2;
  T length;
};

template <typename T>
EdgeFrame<T> edge_frame(const T* xa, const T* xb, const T* theta, const EdgeReference& ref) {
  EdgeFrame<T> f;
  const V3<T> e = load(xb) - load(xa);
  f.length = e.norm();
  f.t = e / f.length;
  f.d1 = transport<T>(ref.tangent.cast<T>(), f.t, ref.d1.cast<T>());
  const V3<T> d2 = f.t.cross(f.d1);
  using std::cos;
  using std::sin;
  const T c = cos(*theta), s = sin(*theta);
  f.m1 = c * f.d1 + s * d2;
  f.m2 = -s * f.d1 + c * d2;
  return f;
}

/// The angle from the space-parallel transport of d1_0 onto edge 1 to d1_1, about t1, in
/// (-pi, pi].
template <typename T>
T raw_reference_twist(const EdgeFrame<T>& f0, const EdgeFrame<T>& f1) {
  const V3<T> u = transport<T>(f0.t, f1.t, f0.d1);
  using std::atan2;
  return atan2(u.cross(f1.d1).dot(f1.t), u.dot(f1.d1));
}

/// Stretching of one edge: E = 1/2 (EA / l̄) (|e| - l̄)^2. One residual.
struct Stretch {
  double sqrt_stiffness = 1;  ///< sqrt(EA / l̄)
  double rest_length = 1;     ///< l̄
  template <typename T>
  bool operator()(const T* xa, const T* xb, T* r) const {
    const T length = (load(xb) - load(xa)).norm();
    r[0] = T(sqrt_stiffness) * (length - T(rest_length));
    return true;
  }
};

/// Second-order correction r Hess(r) of a Stretch residual (the geometric stiffness of the edge,
/// the term Gauss-Newton drops; NewtonSolver::Term::curvature). With e = x_b - x_a, t = e / |e|
/// and Hess_e |e| = (I - t t^T) / |e|:
///   r Hess(r) = (T / |e|) (I - t t^T) on e,  T = sqrt(EA / l̄) r the axial force
/// (T > 0 stretched, T < 0 compressed: then the block is negative semidefinite). Adds it to the
/// 6 x 6 local Hessian `H` of the parameters (x_a, x_b) (both free): +S on the diagonal blocks,
/// -S off them. `r`: the term's one residual at (x_a, x_b). Uses term.sqrt_stiffness only.
/// `compression_scale` multiplies a compressive force's block (1: exact).
inline void add_stretch_curvature(const Stretch& term, const double* xa, const double* xb,
                                  const double* r, Eigen::MatrixXd& H,
                                  double compression_scale = 1.0) {
  using Vec3d = Eigen::Vector3d;
  const Vec3d e = Eigen::Map<const Vec3d>(xb) - Eigen::Map<const Vec3d>(xa);
  const double length = e.norm();
  const Vec3d t = e / length;
  double force = term.sqrt_stiffness * r[0];
  if (force < 0) force *= compression_scale;
  const Eigen::Matrix3d S = (force / length) * (Eigen::Matrix3d::Identity() - t * t.transpose());
  H.block<3, 3>(0, 0) += S;
  H.block<3, 3>(3, 3) += S;
  H.block<3, 3>(0, 3) -= S;
  H.block<3, 3>(3, 0) -= S;
}

/// Bending and twisting at the interior vertex between edges e0 = x1 - x0 and e1 = x2 - x1.
///   curvature binormal  kb = 2 e0 x e1 / (|e0| |e1| + e0.e1)   (|kb| = 2 tan(phi/2))
///   material curvatures k1 = (m2_0 + m2_1)/2 . kb   (weak axis: curvature vector along m1)
///                       k2 = -(m1_0 + m1_1)/2 . kb  (strong axis: in the lamella's plane)
///   twist               m = theta1 - theta0 + m_ref, m_ref the angle from the space-parallel
///                       transport of d1_0 onto edge 1 to d1_1, about t1
///   E = 1/2 (EI_weak k1^2 + EI_strong k2^2 + GJ m^2) / l̄_v,  l̄_v = (l̄_0 + l̄_1) / 2.
/// Straight and untwisted rest state. Three residuals.
struct BendTwist {
  const EdgeReference* ref0 = nullptr;
  const EdgeReference* ref1 = nullptr;
  double sqrt_weak = 1;    ///< sqrt(EI_weak / l̄_v)
  double sqrt_strong = 1;  ///< sqrt(EI_strong / l̄_v)
  double sqrt_twist = 1;   ///< sqrt(GJ / l̄_v)
  /// The reference twist at the last frame update. atan2 alone wraps at +-pi; the reference
  /// twist is tracked continuously as this value plus the (wrapped) change since, as in DER.
  /// Null: the value in (-pi, pi].
  const double* previous_reference_twist = nullptr;
  template <typename T>
  bool operator()(const T* x0, const T* x1, const T* x2, const T* theta0, const T* theta1,
                  T* r) const {
    const EdgeFrame<T> f0 = edge_frame(x0, x1, theta0, *ref0);
    const EdgeFrame<T> f1 = edge_frame(x1, x2, theta1, *ref1);
    const V3<T> e0 = load(x1) - load(x0), e1 = load(x2) - load(x1);
    const T denominator = f0.length * f1.length + e0.dot(e1);
    if (!(denominator > T(1e-12) * f0.length * f1.length)) return false;  // folded back
    const V3<T> kb = T(2) * e0.cross(e1) / denominator;
    const T k1 = T(0.5) * (f0.m2 + f1.m2).dot(kb);
    const T k2 = T(-0.5) * (f0.m1 + f1.m1).dot(kb);
    T reference_twist = raw_reference_twist(f0, f1);
    if (previous_reference_twist) {
      // Unwrap: the offset is a multiple of 2 pi (piecewise constant, so derivatives are
      // unaffected).
      const double pi = 3.14159265358979323846;
      const double turns =
          std::round((ceres_value(reference_twist) - *previous_reference_twist) / (2 * pi));
      reference_twist -= T(2 * pi * turns);
    }
    r[0] = T(sqrt_weak) * k1;
    r[1] = T(sqrt_strong) * k2;
    r[2] = T(sqrt_twist) * (*theta1 - *theta0 + reference_twist);
    return true;
  }
};

/// The point of a member at a connection and the member's material normal there.
/// q = (1 - b) x_a + b x_b on edge (x_a, x_b). The discrete material normal is constant per edge
/// and jumps by the turning angle at a vertex; a connection sliding across a vertex would jump
/// with it. So past the middle of the edge the normal is blended towards the neighbouring
/// edge's with weight w = 2 (b - 1/2)^2, reaching the vertex normal (m1 + m1') / |m1 + m1'| at
/// the vertex from both sides with the same slope: continuously differentiable along the
/// member (a kink would stall Newton's method where a connection comes to rest mid-edge).
/// `neighbour` is the next edge (x_b, x_n) when side > 0, the previous one (x_n, x_a) when side <
/// 0, or absent (rod end).
template <typename T>
struct MemberPoint {
  V3<T> q, m;
};

struct MemberEdge {
  const EdgeReference* ref = nullptr;
  const EdgeReference* neighbour = nullptr;  ///< null: no blending
  int side = 0;                              ///< +1 next edge, -1 previous edge
};

template <typename T>
MemberPoint<T> member_point(const T* const* p, const MemberEdge& edge) {
  // p: x_a, x_b, theta, beta [, x_n, theta_n]
  const EdgeFrame<T> f = edge_frame(p[0], p[1], p[2], *edge.ref);
  const T beta = *p[3];
  MemberPoint<T> out;
  out.q = (T(1) - beta) * load(p[0]) + beta * load(p[1]);
  out.m = f.m1;
  if (edge.neighbour) {
    const T d = edge.side > 0 ? beta - T(0.5) : T(0.5) - beta;
    if (d > T(0)) {
      const T w = T(2) * d * d;
      const EdgeFrame<T> n = edge.side > 0 ? edge_frame(p[1], p[4], p[5], *edge.neighbour)
                                           : edge_frame(p[4], p[0], p[5], *edge.neighbour);
      const V3<T> blend = (T(1) - w) * f.m1 + w * n.m1;
      out.m = blend / blend.norm();
    }
  }
  return out;
}

/// A connection q of paper Section 5: q_g on an edge of member g and q_h on an edge of member
/// h, with the thickness offset t along the material normals:
///   E_q = w1 |q_g - q_h + t m_g|^2 + w1 |q_h - q_g - t m_h|^2 + w2 |angle(m_g, m_h)|^2,
/// so h lies on the m side of g and the lamellas may only rotate about their common normal.
/// The angle term uses the chord |m_g - m_h| = 2 sin(angle / 2) (smooth, = angle to third order).
/// Residuals carry sqrt(2 w) so that 1/2 |r|^2 equals the paper's energy. Nine residuals.
struct ConnectionResidual {
  static constexpr int kResiduals = 9;
  MemberEdge g, h;
  double thickness = 0;
  double sqrt_position = 1;   ///< sqrt(2 w_q1)
  double sqrt_direction = 1;  ///< sqrt(2 w_q2)
  template <typename T>
  bool evaluate(const T* const* pg, const T* const* ph, T* r) const {
    const MemberPoint<T> a = member_point(pg, g), b = member_point(ph, h);
    const T t(thickness), wp(sqrt_position), wd(sqrt_direction);
    store<T>(wp * (a.q - b.q + t * a.m), r);
    store<T>(wp * (b.q - a.q - t * b.m), r + 3);
    store<T>(wd * (a.m - b.m), r + 6);
    return true;
  }
};

/// Anchor E_a of paper Section 5 at a connection, as a support holds it: the lamella stack is
/// clamped there, so each lamella's point is pinned, half the thickness below (g) and above (h)
/// the anchor's target position q_a on the surface, and both material normals are pinned to the
/// surface normal m_a:
///   E_a = w1 (|q_g - (q_a - t/2 m_a)|^2 + |q_h - (q_a + t/2 m_a)|^2)
///       + w2 (|angle(m_g, m_a)|^2 + |angle(m_h, m_a)|^2).
/// (Pinning only the midpoint (q_g + q_h)/2 left the two lamellas free to be pulled apart at
/// the support, held only by the connection term: gaps of up to 3% of the thickness opened at
/// anchors once their directions were held as well; docs/decisions.md, issue 18.)
/// Twelve residuals with the same sqrt(2 w) convention.
struct AnchorResidual {
  static constexpr int kResiduals = 12;
  MemberEdge g, h;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double thickness = 0;
  double sqrt_position = 1;
  double sqrt_direction = 1;
  template <typename T>
  bool evaluate(const T* const* pg, const T* const* ph, T* r) const {
    const MemberPoint<T> a = member_point(pg, g), b = member_point(ph, h);
    const T wp(sqrt_position), wd(sqrt_direction);
    const V3<T> n = normal.cast<T>();
    const V3<T> offset = T(0.5 * thickness) * n;
    store<T>(wp * (a.q - position.cast<T>() + offset), r);
    store<T>(wp * (b.q - position.cast<T>() - offset), r + 3);
    store<T>(wd * (a.m - n), r + 6);
    store<T>(wd * (b.m - n), r + 9);
    return true;
  }
};

/// Fixed-arity adaptor for Ceres: a member contributes 4 parameter blocks (x_a, x_b, theta,
/// beta) or 6 with a neighbouring edge (+ x_n, theta_n). G and H are 4 or 6; Ceres calls it with
/// the G + H blocks, then the residuals.
template <typename Residual, int G, int H>
struct PairFunctor {
  static_assert((G == 4 || G == 6) && (H == 4 || H == 6));
  Residual residual;
  template <typename T, typename... Rest>
  bool operator()(const T* first, Rest... rest) const {
    static_assert(sizeof...(Rest) == G + H, "G + H parameter blocks, then the residuals");
    const T* blocks[] = {first, rest...};
    T* r = std::get<G + H - 1>(std::forward_as_tuple(rest...));
    return residual.evaluate(blocks, blocks + G, r);
  }
};

/// Pseudo-friction E_p = (mu log(eps + b))^2 + (mu log(eps + 1 - b))^2 of a sliding connection
/// on its current edge (paper Section 5). Two residuals, sqrt(2) mu log(...). Undefined (the
/// step is rejected) when b leaves (-eps, 1 + eps).
struct Friction {
  double mu = 0.1;
  double epsilon = 1e-4;
  template <typename T>
  bool operator()(const T* beta, T* r) const {
    const T a = T(epsilon) + *beta, b = T(epsilon) + T(1) - *beta;
    if (!(a > T(0)) || !(b > T(0))) return false;
    using std::log;
    const T scale(std::sqrt(2.0) * mu);
    r[0] = scale * log(a);
    r[1] = scale * log(b);
    return true;
  }
};

/// Second-order correction sum_i r_i Hess(r_i) of a Friction residual (the curvature of the log
/// barriers, the term Gauss-Newton drops). With c = sqrt(2) mu, u = eps + b, v = eps + 1 - b:
/// r_0 = c log u, r_0'' = -c / u^2; r_1 = c log v, r_1'' = -c / v^2, so
///   r_0 r_0'' + r_1 r_1'' = -r_0 c / u^2 - r_1 c / v^2
/// (positive where u, v < 1, the logs being negative there). Adds it to the 1 x 1
/// local Hessian `H` of the parameter b (free). `r`: the term's two residuals at b. Uses
/// term.mu and term.epsilon.
inline void add_friction_curvature(const Friction& term, const double* beta, const double* r,
                                   Eigen::MatrixXd& H) {
  const double c = std::sqrt(2.0) * term.mu, epsilon = term.epsilon;
  const double u = epsilon + *beta, v = epsilon + 1 - *beta;
  H(0, 0) += -r[0] * c / (u * u) - r[1] * c / (v * v);
}

/// Notch limit E_n = (w log(b - b_lo))^2 or (w log(b_hi - b))^2 (paper: w = 1/10), active while
/// the connection lies on the edge of that notch bound. One residual, sqrt(2) w log(...).
/// Undefined (the step is rejected) beyond the bound.
struct NotchLimit {
  double bound = 0;   ///< b_lo or b_hi on the edge
  bool upper = true;  ///< bound is an upper limit (b < bound) or a lower one (b > bound)
  double weight = 0.1;
  template <typename T>
  bool operator()(const T* beta, T* r) const {
    const T gap = upper ? T(bound) - *beta : *beta - T(bound);
    if (!(gap > T(0))) return false;
    using std::log;
    r[0] = T(std::sqrt(2.0) * weight) * log(gap);
    return true;
  }
};

/// Second-order correction r Hess(r) of a NotchLimit residual (the curvature of the log
/// barrier). With c = sqrt(2) w and gap = b_hi - b or b - b_lo: r = c log(gap) and r'' = -c /
/// gap^2 on either side, so r r'' = -r c / gap^2. Adds it to the 1 x 1 local Hessian `H` of the
/// parameter b (free). `r`: the term's residual at b. Uses term.bound, term.upper, term.weight.
inline void add_notch_limit_curvature(const NotchLimit& term, const double* beta, const double* r,
                                      Eigen::MatrixXd& H) {
  const double cw = std::sqrt(2.0) * term.weight;
  const double gap = term.upper ? term.bound - *beta : *beta - term.bound;
  H(0, 0) += -r[0] * cw / (gap * gap);
}

/// The direction of a lamella at an anchor: a support holds the lamella's orientation about the
/// surface normal as well as the normal itself (paper 4.6 and 6.1: the supports "provide
/// correct orientation for the lamellas by inclined contact areas"). The anchor's normal term
/// already holds the rotations about the lamella's tangent and width; this term holds the one
/// left, about the normal n_a: the edge's unit tangent t has no component along the anchor's
/// in-plane perpendicular c_a = n_a x t_a (t_a the member's direction on the target there):
///   E = w (t . c_a)^2,  t = (x_b - x_a) / |x_b - x_a|   (t . c_a = sin of the turn about n_a).
/// Only that component: the edge's chord of a curved lamella is tilted out of the tangent plane
/// by up to half its turning angle, which the normal term allows; holding the whole tangent
/// would fight it and open the connection at the anchor. One residual, sqrt(2 w) convention;
/// parameters x_a, x_b.
struct AnchorTangent {
  Eigen::Vector3d across = Eigen::Vector3d::UnitY();  ///< c_a, unit, in the tangent plane
  double sqrt_weight = 1;
  template <typename T>
  bool operator()(const T* xa, const T* xb, T* r) const {
    const V3<T> e = load(xb) - load(xa);
    r[0] = T(sqrt_weight) * (e / e.norm()).dot(across.cast<T>());
    return true;
  }
};

}  // namespace gridshell::rod_terms
