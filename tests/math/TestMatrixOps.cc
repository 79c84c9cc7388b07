/// @file TestMatrixOps.cc
#include "support/RandomMatrices.h"

#include <vdbmatch/math/MatrixOps.h>

#include <Eigen/LU>
#include <gtest/gtest.h>

using namespace vdbmatch;

namespace {

template <int D>
void
checkCof()
{
    test::RandomSource rng(3 + D);
    for (int trial = 0; trial < 100; ++trial) {
        const Mat<D> A = rng.matrix<D>(2.0);
        const Mat<D> C = math::cof(A);
        // cof A = det(A) A^{-T}, i.e. A^T cof A = det A 1
        EXPECT_LE((A.transpose() * C - A.determinant() * Mat<D>::Identity()).norm(), 1e-12 * 10);
        // d det / dA = cof A (central differences)
        const Real eps = 1e-6;
        for (int i = 0; i < D; ++i)
            for (int j = 0; j < D; ++j) {
                Mat<D> Ap = A, Am = A;
                Ap(i, j) += eps;
                Am(i, j) -= eps;
                EXPECT_NEAR((Ap.determinant() - Am.determinant()) / (2 * eps), C(i, j), 1e-8);
            }
        // cofAdjoint is the transpose of the derivative of cof: <G, dcof[H]> = <cofAdjoint(G), H>
        const Mat<D> G = rng.matrix<D>(), H = rng.matrix<D>();
        const Real lhs =
            G.cwiseProduct((math::cof(Mat<D>(A + eps * H)) - math::cof(Mat<D>(A - eps * H))) /
                           (2 * eps))
                .sum();
        EXPECT_NEAR(lhs, math::cofAdjoint<D>(A, G).cwiseProduct(H).sum(), 1e-7);
    }
    // cof of a singular matrix is still defined.
    Mat<D> S = Mat<D>::Zero();
    S(0, 0) = 1;
    EXPECT_TRUE(math::cof(S).allFinite());
}

} // namespace

TEST(MatrixOps, Cofactor2D)
{
    checkCof<2>();
}
TEST(MatrixOps, Cofactor3D)
{
    checkCof<3>();
}

TEST(MatrixOps, Projection)
{
    test::RandomSource rng;
    const Vec<3> n = rng.unitVector<3>();
    const Mat<3> P = math::projection<3>(n);
    EXPECT_LE((P * P - P).norm(), 1e-14);
    EXPECT_LE((P * n).norm(), 1e-14);
    EXPECT_NEAR(P.trace(), 2.0, 1e-14);
}
