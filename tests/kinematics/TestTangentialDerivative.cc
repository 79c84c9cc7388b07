/// @file TestTangentialDerivative.cc
/// @brief The identities of lem:polyconvexity (eq:inversearea, eq:tancof, eq:shapecof,
///        eq:invshapecof) and the curvature transformation rule eq:curvaturematching, on random
///        matrices and unit vectors.
#include "support/RandomMatrices.h"

#include <vdbmatch/kinematics/SurfaceFrame.h>
#include <vdbmatch/kinematics/TangentialDerivative.h>
#include <vdbmatch/math/MatrixOps.h>

#include <gtest/gtest.h>

using namespace vdbmatch;
using namespace vdbmatch::kinematics;

namespace {

/// S = P M P + n (x) n for a random SPD M: the form of R(D^2 d + n (x) n) for an exact signed
/// distance (n is an eigenvector with eigenvalue 1).
template <int D>
Mat<D>
shapeMatrix(test::RandomSource& rng, const Vec<D>& n)
{
    const Mat<D> P = math::projection<D>(n);
    return P * rng.spd<D>(0.3, 4.0) * P + n * n.transpose();
}

/// Regularised Gaussian curvature K = n^T cof S n, eq:regularizedGaussianCurvs.
template <int D>
Real
gaussK(const Mat<D>& S, const Vec<D>& n)
{
    return n.dot(math::cof(S) * n);
}

template <int D>
void
checkIdentities()
{
    test::RandomSource rng(99 + D);
    for (int trial = 0; trial < 300; ++trial) {
        const Mat<D> A = rng.matrix<D>(1.5);
        const Real J = A.determinant();
        if (std::abs(J) < 1e-3) continue;
        const Vec<D> n1 = rng.unitVector<D>(), n2 = rng.unitVector<D>();
        const Real tol = 1e-10 * (1 + A.norm() * A.norm() * A.norm() / std::abs(J));
        // eq:inversearea
        EXPECT_NEAR(projectedInverseTangentialDerivative<D>(A, n1, n2).determinant(),
                    n2.dot(A * n1) / J, tol);
        // eq:tancof
        EXPECT_NEAR(projectedTangentialDerivative<D>(A, n1, n2).determinant(),
                    n2.dot(math::cof(A) * n1), tol);
        // eq:shapecof and eq:invshapecof
        const Mat<D> S1 = shapeMatrix<D>(rng, n1), S2 = shapeMatrix<D>(rng, n2);
        const Real K1 = gaussK<D>(S1, n1), K2 = gaussK<D>(S2, n2);
        const Real scale = 1 + 10 * A.norm() * A.norm() * A.norm() / std::abs(J);
        EXPECT_NEAR(directBendingArgument<D>(A, S1, S2, n1, n2).determinant(),
                    std::sqrt(K2 / K1) * n2.dot(math::cof(A) * n1), 1e-9 * scale);
        EXPECT_NEAR(inverseBendingArgument<D>(A, S1, S2, n1, n2).determinant(),
                    std::sqrt(K1 / K2) * n2.dot(A * n1) / J, 1e-9 * scale);
        // K = det of the tangential part = 1 / (n^T S^{-1} n / det S), eq:regularizedGaussianCurvs
        EXPECT_NEAR(K1, S1.determinant() / n1.dot(S1.inverse() * n1), 1e-9 * K1);
    }
}

/// The frame operators T+ = P S^{1/2} P and T- agree with the paper's P S^{+-1/2} P when n is
/// an eigenvector of S, and the energy's classifier equals eq:lambdadef.
template <int D>
void
checkFrameOperators()
{
    test::RandomSource rng(5 + D);
    for (int trial = 0; trial < 100; ++trial) {
        const Vec<D> n = rng.unitVector<D>();
        const Mat<D> S = shapeMatrix<D>(rng, n);
        RawFields<D> raw;
        raw.d = 0;
        raw.n = 1.3 * n; // the interpolated normal need not be unit length
        raw.R = spdPower<D>(S, 0.5);
        SurfaceFrame<D> f;
        makeFrame(raw, f);
        const Mat<D> P = math::projection<D>(n);
        EXPECT_LE((f.n - n).norm(), 1e-14);
        EXPECT_LE((f.Tp - P * spdPower<D>(S, 0.5) * P).norm(), 1e-12);
        EXPECT_LE((f.Tm - P * spdPower<D>(S, -0.5) * P).norm(), 1e-10);
        EXPECT_LE((f.Tp * f.Tm - P).norm(), 1e-12);
    }
}

/// eq:curvaturematching: for A with A P1 = P2 A and M, N of the form P M P + n (x) n,
/// A^T P2 N P2 A = P1 M P1  <=>  Lambda[M, N, A, n1, n2] in O(d).
template <int D>
void
checkCurvatureMatching()
{
    test::RandomSource rng(77 + D);
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Vec<D> n1 = rng.unitVector<D>(), n2 = rng.unitVector<D>();
        // A rotation taking n1 to n2 (Householder reflections composed).
        const Mat<D> R = rng.rotation<D>();
        const Vec<D> m = R * n1;
        auto householder = [](const Vec<D>& a, const Vec<D>& b) {
            const Vec<D> v = a - b;
            if (v.norm() < 1e-12) return Mat<D>(Mat<D>::Identity());
            return Mat<D>(Mat<D>::Identity() - 2 * v * v.transpose() / v.squaredNorm());
        };
        // H1 maps m to n2; H2 = reflection fixing n2 to restore orientation.
        const Mat<D> H1 = householder(m, n2);
        Vec<D> t = math::projection<D>(n2) * rng.unitVector<D>();
        if (t.norm() < 1e-3) continue;
        t.normalize();
        const Mat<D> H2 = Mat<D>::Identity() - 2 * t * t.transpose();
        const Mat<D> Q = H2 * H1 * R; // proper rotation with Q n1 = n2
        ASSERT_LE((Q * n1 - n2).norm(), 1e-12);
        const Mat<D> P1 = math::projection<D>(n1), P2 = math::projection<D>(n2);
        const Mat<D> G = P1 * (Mat<D>::Identity() + 0.4 * rng.matrix<D>()) * P1;
        const Mat<D> A = Q * (G + 0.7 * n1 * n1.transpose());
        if (std::abs(A.determinant()) < 1e-2) continue;
        ASSERT_LE((A * P1 - P2 * A).norm(), 1e-12);

        const Mat<D> M = shapeMatrix<D>(rng, n1);
        const Mat<D> Ainv = A.inverse();
        // N such that A^T P2 N P2 A = P1 M P1 (the transformation rule).
        const Mat<D> N = P2 * Ainv.transpose() * P1 * M * P1 * Ainv * P2 + n2 * n2.transpose();
        ASSERT_LE((A.transpose() * P2 * N * P2 * A - P1 * M * P1).norm(), 1e-9);
        const Mat<D> L = curvatureClassifier<D>(M, N, A, n1, n2);
        EXPECT_LE((L.transpose() * L - Mat<D>::Identity()).norm(), 1e-8) << "Lambda orthogonal";

        // Break the rule: scale N's tangential part in one direction -> Lambda not orthogonal.
        const Mat<D> Nbad = N + 0.5 * t * t.transpose();
        const Mat<D> Lbad = curvatureClassifier<D>(M, Nbad, A, n1, n2);
        EXPECT_GT((Lbad.transpose() * Lbad - Mat<D>::Identity()).norm(), 1e-3);
        ++checked;
    }
    EXPECT_GT(checked, 100);
}

} // namespace

TEST(TangentialDerivative, PolyconvexityIdentities2D)
{
    checkIdentities<2>();
}
TEST(TangentialDerivative, PolyconvexityIdentities3D)
{
    checkIdentities<3>();
}
TEST(TangentialDerivative, FrameOperators2D)
{
    checkFrameOperators<2>();
}
TEST(TangentialDerivative, FrameOperators3D)
{
    checkFrameOperators<3>();
}
TEST(TangentialDerivative, CurvatureMatching2D)
{
    checkCurvatureMatching<2>();
}
TEST(TangentialDerivative, CurvatureMatching3D)
{
    checkCurvatureMatching<3>();
}

TEST(TangentialDerivative, IdentityMapGivesIdentity)
{
    test::RandomSource rng;
    const Vec<3> n = rng.unitVector<3>();
    EXPECT_LE(
        (projectedTangentialDerivative<3>(Mat<3>::Identity(), n, n) - Mat<3>::Identity()).norm(),
        1e-14);
    // The counterexample of subsec:tangential: tangent spaces mapped with reversed orientation.
    const Vec<2> e1(1, 0), e2(0, 1);
    const Mat<2> X = projectedTangentialDerivative<2>(Mat<2>::Identity(), e1, Vec<2>(-e1));
    EXPECT_LT(X.determinant(), 0);
    (void)e2;
}
