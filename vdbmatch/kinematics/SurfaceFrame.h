/// @file SurfaceFrame.h
/// @brief The geometry of one shape at one point as the energy densities use it: unit normal n,
///        tangential projection P, and the tangential curvature operators
///        T+ = P S^{1/2} P and T- = (T+ + n(x)n)^{-1} - n(x)n; plus the adjoint (reverse-mode)
///        map from derivatives with respect to these back to a spatial gradient.
///
/// T+ and T- are the factors P_i S_i^{1/2} P_i and P_i S_i^{-1/2} P_i of the classifier Lambda
/// (eq:lambdadef, eq:Fbenddirect, eq:Fbendinverse).
/// @note Deviation: T- is the inverse of T+ on the tangent space, computed from the
///       interpolated S^{1/2} and the normalised interpolated normal, instead of interpolating
///       S^{-1/2} separately. For an exact signed distance n is an eigenvector of
///       S = R(D^2 d + n (x) n) and both agree; with interpolated fields this choice keeps
///       T+ T- = P exactly, so that Lambda = 1 for identical shapes and phi = Id.
/// @see paper eq:lambdadef, eq:defSi
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/RawFields.h>

#include <Eigen/LU>

#include <cmath>

namespace vdbmatch {
namespace kinematics {

template <int D> struct SurfaceFrame
{
    Real d;       ///< signed distance
    Vec<D> n;     ///< unit normal
    Mat<D> P;     ///< 1 - n (x) n
    Mat<D> Tp;    ///< P S^{1/2} P
    Mat<D> Tm;    ///< (Tp + n (x) n)^{-1} - n (x) n
    Real nLength; ///< |interpolated n| (kept for the adjoint)
    Mat<D> Minv;  ///< (Tp + n (x) n)^{-1} (kept for the adjoint)
};

/// Derivatives of an energy with respect to the members of a SurfaceFrame, treated as
/// independent variables. Accumulated by the energy terms, then mapped back by frameAdjoint().
template <int D> struct FrameAdjoint
{
    Real d = 0;
    Vec<D> n = Vec<D>::Zero();
    Mat<D> P = Mat<D>::Zero();
    Mat<D> Tp = Mat<D>::Zero();
    Mat<D> Tm = Mat<D>::Zero();
};

/// Builds the frame from sampled raw fields.
template <int D>
inline void
makeFrame(const RawFields<D>& raw, SurfaceFrame<D>& f)
{
    f.d = raw.d;
    f.nLength = raw.n.norm();
    f.n = raw.n / f.nLength;
    const Mat<D> nn = f.n * f.n.transpose();
    f.P = Mat<D>::Identity() - nn;
    f.Tp = f.P * raw.R * f.P;
    f.Minv = (f.Tp + nn).inverse();
    f.Tm = f.Minv - nn;
}

/// Reverse mode through makeFrame() and the field interpolants: given a = dE/d(frame members)
/// and the spatial derivatives of the raw fields at the point, returns dE/dx.
template <int D>
inline Vec<D>
frameAdjoint(const RawFields<D>& raw, const RawFieldDerivatives<D>& deriv, const SurfaceFrame<D>& f,
             FrameAdjoint<D> a)
{
    // Tm = Minv - n n^T, Minv = (Tp + n n^T)^{-1}
    const Mat<D> aM = -f.Minv.transpose() * a.Tm * f.Minv.transpose();
    a.Tp += aM;
    a.n += (aM + aM.transpose()) * f.n - (a.Tm + a.Tm.transpose()) * f.n;
    // Tp = P R P
    const Mat<D> aR = f.P * a.Tp * f.P;
    a.P += a.Tp * f.P * raw.R.transpose() + raw.R.transpose() * f.P * a.Tp;
    // P = 1 - n n^T
    a.n -= (a.P + a.P.transpose()) * f.n;
    // n = n~ / |n~|
    const Vec<D> aRawN = (a.n - f.n * f.n.dot(a.n)) / f.nLength;
    Vec<D> g = a.d * deriv.dd + deriv.dn.transpose() * aRawN;
    for (int k = 0; k < D; ++k)
        g[k] += aR.cwiseProduct(deriv.dR[k]).sum();
    return g;
}

} // namespace kinematics
} // namespace vdbmatch
