/// @file MatrixOps.h
/// @brief Small matrix helpers on fixed-size Eigen types: det, cofactor matrix, tangential
///        projection P(n) = 1 - n(x)n (paper, subsec:notation).
///
/// Header-only, templated on the dimension D and free of OpenVDB. The cofactor matrix is written
/// out explicitly so that it is defined (and smooth) for singular A as well; it satisfies
/// cof A = det(A) A^{-T} and d(det A)/dA = cof A.
#pragma once

#include <vdbmatch/Types.h>

namespace vdbmatch {
namespace math {

/// Cofactor matrix, cof A = det(A) A^{-T}, for every A (also singular).
template <typename Derived>
inline Eigen::Matrix<typename Derived::Scalar, Derived::RowsAtCompileTime,
                     Derived::ColsAtCompileTime>
cof(const Eigen::MatrixBase<Derived>& A)
{
    constexpr int D = Derived::RowsAtCompileTime;
    static_assert(D == 2 || D == 3, "cof: only 2x2 and 3x3 matrices");
    Eigen::Matrix<typename Derived::Scalar, D, D> C;
    if constexpr (D == 2) {
        C << A(1, 1), -A(1, 0), -A(0, 1), A(0, 0);
    } else {
        C(0, 0) = A(1, 1) * A(2, 2) - A(1, 2) * A(2, 1);
        C(0, 1) = A(1, 2) * A(2, 0) - A(1, 0) * A(2, 2);
        C(0, 2) = A(1, 0) * A(2, 1) - A(1, 1) * A(2, 0);
        C(1, 0) = A(0, 2) * A(2, 1) - A(0, 1) * A(2, 2);
        C(1, 1) = A(0, 0) * A(2, 2) - A(0, 2) * A(2, 0);
        C(1, 2) = A(0, 1) * A(2, 0) - A(0, 0) * A(2, 1);
        C(2, 0) = A(0, 1) * A(1, 2) - A(0, 2) * A(1, 1);
        C(2, 1) = A(0, 2) * A(1, 0) - A(0, 0) * A(1, 2);
        C(2, 2) = A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
    }
    return C;
}

/// Orthogonal projection onto the tangent space of the offset surface with unit normal n:
/// P = 1 - n (x) n (paper, subsec:notation).
template <int D>
inline Mat<D>
projection(const Vec<D>& n)
{
    return Mat<D>::Identity() - n * n.transpose();
}

/// Adjoint of A -> cof A: given G = dE/d(cof A), returns dE/dA.
/// Uses d(cof A) = d(det A A^{-T}); for D = 2, cof is linear.
template <int D>
inline Mat<D>
cofAdjoint(const Mat<D>& A, const Mat<D>& G)
{
    if constexpr (D == 2) {
        Mat<D> R;
        R << G(1, 1), -G(1, 0), -G(0, 1), G(0, 0);
        return R;
    } else {
        // cof(A)_{ij} = 1/2 eps_{imn} eps_{jpq} A_{mp} A_{nq}; d cof_{ij}/dA_{mp} = eps_{imn}
        // eps_{jpq} A_{nq}
        // => dE/dA_{mp} = sum_{ij} G_ij eps_imn eps_jpq A_nq = cof-like bilinear form; computed
        // by the identity dE/dA = sum over i,j of G_ij * d cof_ij / dA, using cof(A + B) expansion.
        Mat<D> R = Mat<D>::Zero();
        for (int i = 0; i < 3; ++i) {
            const int m = (i + 1) % 3, n = (i + 2) % 3;
            for (int j = 0; j < 3; ++j) {
                const int p = (j + 1) % 3, q = (j + 2) % 3;
                const Real g = G(i, j);
                // cof_ij = A_mp A_nq - A_mq A_np
                R(m, p) += g * A(n, q);
                R(n, q) += g * A(m, p);
                R(m, q) -= g * A(n, p);
                R(n, p) -= g * A(m, q);
            }
        }
        return R;
    }
}

} // namespace math
} // namespace vdbmatch
