/// @file RandomMatrices.h
/// @brief Deterministic random matrices, rotations and unit vectors for the identity tests.
#pragma once

#include <vdbmatch/Types.h>

#include <Eigen/QR>

#include <random>

namespace vdbmatch {
namespace test {

class RandomSource
{
public:
    explicit RandomSource(unsigned seed = 12345) : mEngine(seed) {}

    Real uniform(Real a = -1, Real b = 1)
    {
        return std::uniform_real_distribution<Real>(a, b)(mEngine);
    }

    template <int D> Mat<D> matrix(Real scale = 1)
    {
        Mat<D> A;
        for (int i = 0; i < D; ++i)
            for (int j = 0; j < D; ++j)
                A(i, j) = scale * uniform();
        return A;
    }

    /// A random matrix with det > 0 near the identity: 1 + scale * random.
    template <int D> Mat<D> positiveMatrix(Real scale = 0.3)
    {
        for (;;) {
            Mat<D> A = Mat<D>::Identity() + matrix<D>(scale);
            if (A.determinant() > 0.1) return A;
        }
    }

    template <int D> Vec<D> unitVector()
    {
        Vec<D> v;
        do {
            for (int i = 0; i < D; ++i)
                v[i] = uniform();
        } while (v.norm() < 0.1);
        return v.normalized();
    }

    /// A random proper rotation (QR of a random matrix, sign-fixed).
    template <int D> Mat<D> rotation()
    {
        Eigen::HouseholderQR<Mat<D>> qr(matrix<D>());
        Mat<D> Q = qr.householderQ();
        if (Q.determinant() < 0) Q.col(0) *= -1;
        return Q;
    }

    /// A random symmetric positive definite matrix with eigenvalues in [lo, hi].
    template <int D> Mat<D> spd(Real lo = 0.5, Real hi = 3)
    {
        const Mat<D> Q = rotation<D>();
        Vec<D> l;
        for (int i = 0; i < D; ++i)
            l[i] = uniform(lo, hi);
        return Q * l.asDiagonal() * Q.transpose();
    }

    std::mt19937_64& engine() { return mEngine; }

private:
    std::mt19937_64 mEngine;
};

} // namespace test
} // namespace vdbmatch
