/// @file TangentialDerivative.h
/// @brief The projected tangential derivative D_tt phi (eq:Dttdef), its inverse counterpart
///        (the argument of eq:Fmeminverse) and the curvature classifier Lambda (eq:lambdadef)
///        in the direct (eq:Fbenddirect) and inverse (eq:Fbendinverse) directions.
///
/// Pure functions on Eigen fixed-size matrices. A is the deformation gradient D phi(x),
/// n1 = n_1(x), n2 = n_2(phi(x)) unit normals.
/// @see paper eq:Dttdef, eq:Fmemdirect, eq:Fmeminverse, eq:lambdadef, eq:Fbenddirect,
///      eq:Fbendinverse, eq:curvaturematching
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/math/MatrixOps.h>

#include <Eigen/Eigenvalues>

#include <cmath>

namespace vdbmatch {
namespace kinematics {

/// D_tt phi = P2 A P1 + n2 (x) n1, paper eq:Dttdef (argument of F_mem, eq:Fmemdirect).
template <int D>
inline Mat<D>
projectedTangentialDerivative(const Mat<D>& A, const Vec<D>& n1, const Vec<D>& n2)
{
    return math::projection<D>(n2) * A * math::projection<D>(n1) + n2 * n1.transpose();
}

/// P1 (cof A^T / det A) P2 + n1 (x) n2: the projected tangential derivative of phi^{-1},
/// argument of the inverse membrane density, paper eq:Fmeminverse. Requires det A != 0.
template <int D>
inline Mat<D>
projectedInverseTangentialDerivative(const Mat<D>& A, const Vec<D>& n1, const Vec<D>& n2)
{
    const Mat<D> B = math::cof(A).transpose() / A.determinant();
    return math::projection<D>(n1) * B * math::projection<D>(n2) + n1 * n2.transpose();
}

/// Symmetric positive definite square root (and, with power = -1/2, inverse square root).
template <int D>
inline Mat<D>
spdPower(const Mat<D>& M, Real power)
{
    Eigen::SelfAdjointEigenSolver<Mat<D>> es(M);
    const Vec<D> l = es.eigenvalues().array().pow(power).matrix();
    return es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
}

/// The classifier of eq:lambdadef,
/// Lambda[M, N, A, v, w] = P_w N^{1/2} P_w A P_v M^{-1/2} P_v + w (x) v,
/// for symmetric positive definite M, N and unit vectors v, w.
template <int D>
inline Mat<D>
curvatureClassifier(const Mat<D>& M, const Mat<D>& N, const Mat<D>& A, const Vec<D>& v,
                    const Vec<D>& w)
{
    const Mat<D> Pv = math::projection<D>(v), Pw = math::projection<D>(w);
    return Pw * spdPower<D>(N, 0.5) * Pw * A * Pv * spdPower<D>(M, -0.5) * Pv + w * v.transpose();
}

/// Direct bending argument, eq:Fbenddirect: Lambda[S1, S2(phi), D phi, n1, n2(phi)].
template <int D>
inline Mat<D>
directBendingArgument(const Mat<D>& A, const Mat<D>& S1, const Mat<D>& S2, const Vec<D>& n1,
                      const Vec<D>& n2)
{
    return curvatureClassifier<D>(S1, S2, A, n1, n2);
}

/// Inverse bending argument, eq:Fbendinverse:
/// Lambda[S2(phi), S1, cof D phi^T / det D phi, n2(phi), n1]. Requires det A != 0.
template <int D>
inline Mat<D>
inverseBendingArgument(const Mat<D>& A, const Mat<D>& S1, const Mat<D>& S2, const Vec<D>& n1,
                       const Vec<D>& n2)
{
    const Mat<D> B = math::cof(A).transpose() / A.determinant();
    return curvatureClassifier<D>(S2, S1, B, n2, n1);
}

} // namespace kinematics
} // namespace vdbmatch
