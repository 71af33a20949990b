// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — hand-derived first derivatives of the rod terms (private header).
//
// The residuals of kernel/simulation/rod_terms.h as Ceres cost functions with analytic
// Jacobians. Automatic differentiation of the bending-and-twisting term (Ceres jets over its 11
// parameters) was about a third of a deployment run; the same Jacobian from the chain rule
// through the edges' frames costs a few 3 x 3 products. The templated functors of rod_terms.h
// stay the definition: the tests compare these Jacobians with their automatic ones and with
// central differences (tests/simulation/test_rod_terms.cpp).
//
// Notation: [a]x is the cross-product matrix ([a]x b = a x b); D f / D x the Jacobian, rows
// the components of f.
#pragma once

#include <ceres/cost_function.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <cmath>
#include <type_traits>

#include "rod_terms.h"

namespace gridshell::rod_terms {

using Vec3d = Eigen::Vector3d;
using Mat3d = Eigen::Matrix3d;

inline Mat3d cross_matrix(const Vec3d& a) {
  Mat3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

/// u = transport(a, b, v) of rod_terms.h with its Jacobians in a, b and v (a, b, v vary
/// freely: the formula is differentiated as written, not on the unit sphere). With k = a x b,
/// c = a.b, q = k.v, f = q / (1 + c): u = c v + k x v + f k.
struct TransportDerivatives {
  Vec3d u;
  Mat3d da, db, dv;
};

inline TransportDerivatives transport_derivatives(const Vec3d& a, const Vec3d& b, const Vec3d& v) {
  const Vec3d k = a.cross(b);
  const double c = a.dot(b), s = 1 / (1 + c), q = k.dot(v), f = q * s;
  TransportDerivatives out;
  out.u = c * v + k.cross(v) + f * k;
  const Mat3d vx = cross_matrix(v);
  // x = a: Dc = b^T, Dk = -[b]x;  x = b: Dc = a^T, Dk = [a]x.
  const auto by = [&](const Vec3d& dc, const Mat3d& dk) {
    const Eigen::RowVector3d dq = v.transpose() * dk;
    const Eigen::RowVector3d df = s * dq - q * s * s * dc.transpose();
    return Mat3d(v * dc.transpose() - vx * dk + k * df + f * dk);
  };
  out.da = by(b, -cross_matrix(b));
  out.db = by(a, cross_matrix(a));
  out.dv = c * Mat3d::Identity() + cross_matrix(k) + s * k * k.transpose();
  return out;
}

/// An edge's frame (rod_terms::edge_frame) with its Jacobians in the edge vector e = x_b - x_a
/// and in the twist angle theta (the reference is constant).
struct EdgeFrameDerivatives {
  Vec3d t, d1, d2, m1, m2;
  double length = 0;
  Mat3d dt, dd1, dd2, dm1, dm2;  // D / D e
  // D m1 / D theta = m2, D m2 / D theta = -m1.
};

inline EdgeFrameDerivatives edge_frame_derivatives(const Vec3d& e, double theta,
                                                   const EdgeReference& ref) {
  EdgeFrameDerivatives f;
  f.length = e.norm();
  f.t = e / f.length;
  f.dt = (Mat3d::Identity() - f.t * f.t.transpose()) / f.length;
  const TransportDerivatives d1 = transport_derivatives(ref.tangent, f.t, ref.d1);
  f.d1 = d1.u;
  f.dd1 = d1.db * f.dt;
  f.d2 = f.t.cross(f.d1);
  // D (t x d1) = -[d1]x Dt + [t]x Dd1.
  f.dd2 = -cross_matrix(f.d1) * f.dt + cross_matrix(f.t) * f.dd1;
  const double c = std::cos(theta), s = std::sin(theta);
  f.m1 = c * f.d1 + s * f.d2;
  f.m2 = -s * f.d1 + c * f.d2;
  f.dm1 = c * f.dd1 + s * f.dd2;
  f.dm2 = -s * f.dd1 + c * f.dd2;
  return f;
}

/// Stretch with its analytic Jacobian: r = sqrt(EA / l̄) (|e| - l̄), D r / D x_b = sqrt(...) t.
class StretchCost : public ceres::SizedCostFunction<1, 3, 3> {
 public:
  explicit StretchCost(const Stretch& term) : term_(term) {}
  bool Evaluate(const double* const* p, double* r, double** jacobians) const override {
    const Vec3d e = Eigen::Map<const Vec3d>(p[1]) - Eigen::Map<const Vec3d>(p[0]);
    const double length = e.norm();
    r[0] = term_.sqrt_stiffness * (length - term_.rest_length);
    if (jacobians) {
      const Vec3d g = term_.sqrt_stiffness * e / length;
      if (jacobians[0]) Eigen::Map<Vec3d>{jacobians[0]} = -g;
      if (jacobians[1]) Eigen::Map<Vec3d>{jacobians[1]} = g;
    }
    return true;
  }
  const Stretch& term() const { return term_; }

 private:
  Stretch term_;
};

/// BendTwist (rod_terms.h) with its analytic Jacobian. Parameters x0, x1, x2, theta0, theta1;
/// e0 = x1 - x0, e1 = x2 - x1.
///   kb = 2 e0 x e1 / D, D = |e0||e1| + e0.e1:
///     D kb / D e0 = (-2 [e1]x - kb (|e1| t0 + e1)^T) / D
///     D kb / D e1 = ( 2 [e0]x - kb (|e0| t1 + e0)^T) / D
///   k1 = (m2_0 + m2_1).kb / 2, k2 = -(m1_0 + m1_1).kb / 2, through the edges' frames;
///   reference twist atan2(y, x) with u = transport(t0, t1, d1_0), x = u.d1_1,
///   y = (u x d1_1).t1: D atan2 = (x Dy - y Dx) / (x^2 + y^2).
class BendTwistCost : public ceres::SizedCostFunction<3, 3, 3, 3, 1, 1> {
 public:
  explicit BendTwistCost(const BendTwist& term) : term_(term) {}
  bool Evaluate(const double* const* p, double* r, double** jacobians) const override {
    if (!jacobians) return term_(p[0], p[1], p[2], p[3], p[4], r);  // the value alone
    const Vec3d x0 = Eigen::Map<const Vec3d>(p[0]), x1 = Eigen::Map<const Vec3d>(p[1]),
                x2 = Eigen::Map<const Vec3d>(p[2]);
    const double theta0 = *p[3], theta1 = *p[4];
    const Vec3d e0 = x1 - x0, e1 = x2 - x1;
    const EdgeFrameDerivatives f0 = edge_frame_derivatives(e0, theta0, *term_.ref0);
    const EdgeFrameDerivatives f1 = edge_frame_derivatives(e1, theta1, *term_.ref1);
    const double denominator = f0.length * f1.length + e0.dot(e1);
    if (!(denominator > 1e-12 * f0.length * f1.length)) return false;  // folded back
    const Vec3d kb = 2 * e0.cross(e1) / denominator;
    const Vec3d m2 = f0.m2 + f1.m2, m1 = f0.m1 + f1.m1;
    const double k1 = 0.5 * m2.dot(kb), k2 = -0.5 * m1.dot(kb);
    // Reference twist.
    const TransportDerivatives tr = transport_derivatives(f0.t, f1.t, f0.d1);
    const Vec3d& u = tr.u;
    const Vec3d& w = f1.d1;
    const double x = u.dot(w), y = u.cross(w).dot(f1.t);
    double reference_twist = std::atan2(y, x);
    if (term_.previous_reference_twist) {
      const double pi = 3.14159265358979323846;
      reference_twist -=
          2 * pi * std::round((reference_twist - *term_.previous_reference_twist) / (2 * pi));
    }
    r[0] = term_.sqrt_weak * k1;
    r[1] = term_.sqrt_strong * k2;
    r[2] = term_.sqrt_twist * (theta1 - theta0 + reference_twist);

    const Mat3d dkb0 =
        (-2 * cross_matrix(e1) - kb * (f1.length * f0.t + e1).transpose()) / denominator;
    const Mat3d dkb1 =
        (2 * cross_matrix(e0) - kb * (f0.length * f1.t + e0).transpose()) / denominator;
    // Rows: k1, k2, reference twist; columns: e0 then e1.
    Eigen::Matrix<double, 3, 6> de;
    de.block<1, 3>(0, 0) = 0.5 * (kb.transpose() * f0.dm2 + m2.transpose() * dkb0);
    de.block<1, 3>(0, 3) = 0.5 * (kb.transpose() * f1.dm2 + m2.transpose() * dkb1);
    de.block<1, 3>(1, 0) = -0.5 * (kb.transpose() * f0.dm1 + m1.transpose() * dkb0);
    de.block<1, 3>(1, 3) = -0.5 * (kb.transpose() * f1.dm1 + m1.transpose() * dkb1);
    // u depends on e0 through t0 and d1_0, on e1 through t1; w = d1_1 and t1 on e1.
    const Mat3d du0 = tr.da * f0.dt + tr.dv * f0.dd1, du1 = tr.db * f1.dt;
    const Vec3d wt = w.cross(f1.t), tu = f1.t.cross(u), uw = u.cross(w);
    const double norm2 = x * x + y * y;
    // Dx = w^T Du + u^T Dw, Dy = (w x t1)^T Du + (t1 x u)^T Dw + (u x w)^T Dt1.
    const Eigen::RowVector3d dx0 = w.transpose() * du0, dy0 = wt.transpose() * du0;
    const Eigen::RowVector3d dx1 = w.transpose() * du1 + u.transpose() * f1.dd1;
    const Eigen::RowVector3d dy1 =
        wt.transpose() * du1 + tu.transpose() * f1.dd1 + uw.transpose() * f1.dt;
    de.block<1, 3>(2, 0) = (x * dy0 - y * dx0) / norm2;
    de.block<1, 3>(2, 3) = (x * dy1 - y * dx1) / norm2;
    const Eigen::Vector3d scale(term_.sqrt_weak, term_.sqrt_strong, term_.sqrt_twist);
    de = scale.asDiagonal() * de;
    using RowMajor33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    if (jacobians[0]) Eigen::Map<RowMajor33>{jacobians[0]} = -de.leftCols<3>();
    if (jacobians[1]) Eigen::Map<RowMajor33>{jacobians[1]} = de.leftCols<3>() - de.rightCols<3>();
    if (jacobians[2]) Eigen::Map<RowMajor33>{jacobians[2]} = de.rightCols<3>();
    // D k1 / D theta_i = -m1_i.kb / 2, D k2 / D theta_i = -m2_i.kb / 2; the twist -1, +1.
    if (jacobians[3]) {
      jacobians[3][0] = -0.5 * term_.sqrt_weak * f0.m1.dot(kb);
      jacobians[3][1] = -0.5 * term_.sqrt_strong * f0.m2.dot(kb);
      jacobians[3][2] = -term_.sqrt_twist;
    }
    if (jacobians[4]) {
      jacobians[4][0] = -0.5 * term_.sqrt_weak * f1.m1.dot(kb);
      jacobians[4][1] = -0.5 * term_.sqrt_strong * f1.m2.dot(kb);
      jacobians[4][2] = term_.sqrt_twist;
    }
    return true;
  }

 private:
  BendTwist term_;
};

/// A member's point q and material normal m at a connection (rod_terms::member_point) with
/// their Jacobians in the member's parameters x_a, x_b, theta, beta [, x_n, theta_n]: rows q
/// (3) then m (3), columns in that parameter order (8 or 12).
struct MemberPointDerivatives {
  Vec3d q, m;
  Eigen::Matrix<double, 6, 12> d = Eigen::Matrix<double, 6, 12>::Zero();
  int columns = 8;
};

inline MemberPointDerivatives member_point_derivatives(const double* const* p,
                                                       const MemberEdge& edge) {
  MemberPointDerivatives out;
  const Vec3d xa = Eigen::Map<const Vec3d>(p[0]), xb = Eigen::Map<const Vec3d>(p[1]);
  const double beta = *p[3];
  const EdgeFrameDerivatives f = edge_frame_derivatives(xb - xa, *p[2], *edge.ref);
  out.q = (1 - beta) * xa + beta * xb;
  out.d.block<3, 3>(0, 0) = (1 - beta) * Mat3d::Identity();
  out.d.block<3, 3>(0, 3) = beta * Mat3d::Identity();
  out.d.block<3, 1>(0, 7) = xb - xa;
  out.columns = edge.neighbour ? 12 : 8;
  const double d = edge.neighbour ? (edge.side > 0 ? beta - 0.5 : 0.5 - beta) : 0.0;
  if (!(d > 0)) {
    out.m = f.m1;
    out.d.block<3, 3>(3, 0) = -f.dm1;
    out.d.block<3, 3>(3, 3) = f.dm1;
    out.d.block<3, 1>(3, 6) = f.m2;
    return out;
  }
  // Blended towards the neighbouring edge's normal: b = (1 - w) m1 + w n.m1, w = 2 d^2,
  // m = b / |b|, D m = (I - m m^T) / |b| D b.
  const Vec3d xn = Eigen::Map<const Vec3d>(p[4]);
  const Vec3d en = edge.side > 0 ? Vec3d(xn - xb) : Vec3d(xa - xn);
  const EdgeFrameDerivatives n = edge_frame_derivatives(en, *p[5], *edge.neighbour);
  const double w = 2 * d * d, dw = 4 * d * (edge.side > 0 ? 1 : -1);
  const Vec3d b = (1 - w) * f.m1 + w * n.m1;
  const double length = b.norm();
  out.m = b / length;
  const Mat3d project = (Mat3d::Identity() - out.m * out.m.transpose()) / length;
  const Mat3d own = project * ((1 - w) * f.dm1), other = project * (w * n.dm1);
  out.d.block<3, 3>(3, 0) = -own;
  out.d.block<3, 3>(3, 3) = own;
  out.d.block<3, 1>(3, 6) = project * ((1 - w) * f.m2);
  out.d.block<3, 1>(3, 7) = project * (dw * (n.m1 - f.m1));
  out.d.block<3, 3>(3, 8) = edge.side > 0 ? Mat3d(other) : Mat3d(-other);
  if (edge.side > 0)
    out.d.block<3, 3>(3, 3) -= other;
  else
    out.d.block<3, 3>(3, 0) += other;
  out.d.block<3, 1>(3, 11) = project * (w * n.m2);
  return out;
}

/// ConnectionResidual or AnchorResidual (rod_terms.h) with analytic Jacobians: the member
/// points' Jacobians combined linearly. Parameters: member g's 4 or 6 blocks, then member h's.
template <typename Residual>
class PairCost : public ceres::CostFunction {
 public:
  explicit PairCost(const Residual& residual) : residual_(residual) {
    set_num_residuals(kRows);
    auto* sizes = mutable_parameter_block_sizes();
    for (const MemberEdge* edge : {&residual.g, &residual.h}) {
      for (int size : {3, 3, 1, 1}) sizes->push_back(size);
      if (edge->neighbour)
        for (int size : {3, 1}) sizes->push_back(size);
    }
    g_blocks_ = residual.g.neighbour ? 6 : 4;
  }
  bool Evaluate(const double* const* p, double* r, double** jacobians) const override {
    if (!jacobians) return residual_.evaluate(p, p + g_blocks_, r);  // the value alone
    const MemberPointDerivatives a = member_point_derivatives(p, residual_.g);
    const MemberPointDerivatives b = member_point_derivatives(p + g_blocks_, residual_.h);
    // Residual rows as linear maps of (q_a, m_a) and (q_b, m_b): r = A [q_a; m_a] + B [q_b; m_b]
    // + constant.
    Eigen::Matrix<double, kRows, 6> A = Eigen::Matrix<double, kRows, 6>::Zero(), B = A;
    const Mat3d I = Mat3d::Identity();
    Eigen::Matrix<double, kRows, 1> value;
    if constexpr (std::is_same_v<Residual, ConnectionResidual>) {
      const double wp = residual_.sqrt_position, wd = residual_.sqrt_direction,
                   t = residual_.thickness;
      value << wp * (a.q - b.q + t * a.m), wp * (b.q - a.q - t * b.m), wd * (a.m - b.m);
      A.template block<3, 3>(0, 0) = wp * I;
      A.template block<3, 3>(0, 3) = wp * t * I;
      B.template block<3, 3>(0, 0) = -wp * I;
      A.template block<3, 3>(3, 0) = -wp * I;
      B.template block<3, 3>(3, 0) = wp * I;
      B.template block<3, 3>(3, 3) = -wp * t * I;
      A.template block<3, 3>(6, 3) = wd * I;
      B.template block<3, 3>(6, 3) = -wd * I;
    } else {
      const double wp = residual_.sqrt_position, wd = residual_.sqrt_direction;
      const Vec3d offset = 0.5 * residual_.thickness * residual_.normal;
      value << wp * (a.q - residual_.position + offset), wp * (b.q - residual_.position - offset),
          wd * (a.m - residual_.normal), wd * (b.m - residual_.normal);
      A.template block<3, 3>(0, 0) = wp * I;
      B.template block<3, 3>(3, 0) = wp * I;
      A.template block<3, 3>(6, 3) = wd * I;
      B.template block<3, 3>(9, 3) = wd * I;
    }
    Eigen::Map<Eigen::Matrix<double, kRows, 1>>{r} = value;
    const Eigen::Matrix<double, kRows, 12> ja = A * a.d, jb = B * b.d;
    static constexpr int kColumn[6] = {0, 3, 6, 7, 8, 11};  // first column of each block
    static constexpr int kSize[6] = {3, 3, 1, 1, 3, 1};
    const int blocks = static_cast<int>(parameter_block_sizes().size());
    for (int block = 0; block < blocks; ++block) {
      double* out = jacobians[block];
      if (!out) continue;
      const bool on_g = block < g_blocks_;
      const int local = on_g ? block : block - g_blocks_;
      const auto& j = on_g ? ja : jb;
      const int size = kSize[local], column = kColumn[local];
      for (int row = 0; row < kRows; ++row)
        for (int c = 0; c < size; ++c) out[row * size + c] = j(row, column + c);
    }
    return true;
  }

 private:
  static constexpr int kRows = Residual::kResiduals;
  Residual residual_;
  int g_blocks_ = 4;
};

/// The direction of a lamella at an anchor (rod_terms::AnchorTangent) with its analytic
/// Jacobian: r = w t . c_a, t = e / |e|, D t / D x_b = (I - t t^T) / |e| = -D t / D x_a.
class AnchorTangentCost : public ceres::SizedCostFunction<1, 3, 3> {
 public:
  explicit AnchorTangentCost(const AnchorTangent& term) : term_(term) {}
  bool Evaluate(const double* const* p, double* r, double** jacobians) const override {
    const Vec3d e = Eigen::Map<const Vec3d>(p[1]) - Eigen::Map<const Vec3d>(p[0]);
    const double length = e.norm();
    if (!(length > 0)) return false;
    const Vec3d t = e / length;
    r[0] = term_.sqrt_weight * t.dot(term_.across);
    if (jacobians) {
      const Vec3d row = term_.sqrt_weight * (term_.across - t.dot(term_.across) * t) / length;
      if (jacobians[0]) Eigen::Map<Vec3d>{jacobians[0]} = -row;
      if (jacobians[1]) Eigen::Map<Vec3d>{jacobians[1]} = row;
    }
    return true;
  }

 private:
  AnchorTangent term_;
};

}  // namespace gridshell::rod_terms
