/// @file CellKinematics.h
/// @brief The kinematics (A = D phi, cof A, det A, A^{-1}) and the symmetric volume density of
///        eq:EsymVol for all D! Kuhn simplices of one lattice cell at once, lane by lane.
///
/// Every simplex of the lattice carries the volume term, and at the fine levels most carry
/// nothing else, so this is the part of the energy evaluated most often. The arrays are laid
/// out lane-last (a[i][j][p], p the simplex of the cell) and every function is one loop over
/// the lanes with a straight-line body, which the compiler vectorises across the simplices
/// (SSE2, and AVX2 in the x86-64-v3 clone of the 3D loop, vdbmatch/CpuClones.h).
///
/// **The same bits as the per-simplex code.** Each lane performs the operations of
/// SimplexKinematics, volumeDirect, volumeInverse (VolumeTerm.h, math::W of StoredEnergy.h) and
/// DensityGradient::finish in the order Eigen evaluates them there: the Frobenius norm as
/// ((a0+a2)+(a4+a6)) + ((a1+a3)+(a5+a7)) + a8 (SSE2 packets of two, column-major), the
/// determinant's Laplace expansion (x0+x1)+x2, B^T dB as (y0+y1)+y2 and its product with B^T as
/// y0+(y1+y2) (the library is built with -ffp-contract=off, so no product is fused into an
/// addition). tests/energy/TestCellKinematics.cc compares both bitwise on random matrices, so a
/// change of Eigen's evaluation order shows there.
/// @see paper eq:EsymVol, eq:Wbounded, sec:numerics
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/energy/SimplexState.h>
#include <vdbmatch/math/StoredEnergy.h>

#include <cmath>

namespace vdbmatch {
namespace energy {

template <int D> struct CellKinematics
{
    static constexpr int N = D == 2 ? 2 : 6; ///< Kuhn simplices per cell (lanes)

    Real A[D][D][N];       ///< D phi (set by the caller)
    Real C[D][D][N];       ///< cof A
    Real B[D][D][N];       ///< A^{-1} = C^T / det A
    Real J[N];             ///< det A
    Real volumeDirect[N];  ///< c W(A) (volumeDirect)
    Real volumeInverse[N]; ///< c W(B) det A (volumeInverse)
    Real dA[D][D][N];      ///< dE/dA accumulated (DensityGradient::dA)
    Real dB[D][D][N];      ///< dE/dB accumulated (DensityGradient::dB)

    /// C, J and B from A (SimplexKinematics). Lanes with J <= 0 hold non-finite B.
    void kinematics();

    /// volumeDirect and volumeInverse of eq:EsymVol with the factor @a c = c_vol sigma^theta;
    /// with Grad, dA and dB start from their contributions (the rest is zero).
    template <bool Grad> void symmetricVolume(Real c);

    /// dA and dB zero (the directional energy, whose volume term is per simplex).
    void zeroGradient();

    /// dA -= B^T dB B^T (DensityGradient::finish).
    void finish();

    /// Lane @a p as a SimplexKinematics (for the band terms).
    SimplexKinematics<D> simplex(int p) const;
    /// Lane @a p of dA and dB into @a g, and back.
    void loadGradient(int p, DensityGradient<D>& g) const;
    void storeGradient(int p, const DensityGradient<D>& g);
};

template <int D>
inline void
CellKinematics<D>::kinematics()
{
    for (int p = 0; p < N; ++p) {
        if constexpr (D == 2) {
            C[0][0][p] = A[1][1][p];
            C[0][1][p] = -A[1][0][p];
            C[1][0][p] = -A[0][1][p];
            C[1][1][p] = A[0][0][p];
            J[p] = A[0][0][p] * C[0][0][p] + A[1][0][p] * C[1][0][p];
        } else {
            // math::cof, term by term.
            C[0][0][p] = A[1][1][p] * A[2][2][p] - A[1][2][p] * A[2][1][p];
            C[0][1][p] = A[1][2][p] * A[2][0][p] - A[1][0][p] * A[2][2][p];
            C[0][2][p] = A[1][0][p] * A[2][1][p] - A[1][1][p] * A[2][0][p];
            C[1][0][p] = A[0][2][p] * A[2][1][p] - A[0][1][p] * A[2][2][p];
            C[1][1][p] = A[0][0][p] * A[2][2][p] - A[0][2][p] * A[2][0][p];
            C[1][2][p] = A[0][1][p] * A[2][0][p] - A[0][0][p] * A[2][1][p];
            C[2][0][p] = A[0][1][p] * A[1][2][p] - A[0][2][p] * A[1][1][p];
            C[2][1][p] = A[0][2][p] * A[1][0][p] - A[0][0][p] * A[1][2][p];
            C[2][2][p] = A[0][0][p] * A[1][1][p] - A[0][1][p] * A[1][0][p];
            // Laplace expansion along the first column: (x0 + x1) + x2.
            J[p] = (A[0][0][p] * C[0][0][p] + A[1][0][p] * C[1][0][p]) + A[2][0][p] * C[2][0][p];
        }
        for (int i = 0; i < D; ++i)
            for (int j = 0; j < D; ++j)
                B[i][j][p] = C[j][i][p] / J[p];
    }
}

namespace detail {

/// |M|^2 of a D x D matrix in lanes, in Eigen's order for column-major storage (file comment):
/// the squares s_k of the entries in memory order k = i + D j, summed as
/// ((s0 + s2) + (s4 + s6)) + ((s1 + s3) + (s5 + s7)), then + s8 (D = 3); (s0 + s2) + (s1 + s3)
/// (D = 2).
template <int D, int N>
inline Real
squaredNormLane(const Real (&M)[D][D][N], int p)
{
    auto s = [&](int k) {
        const Real v = M[k % D][k / D][p];
        return v * v;
    };
    if constexpr (D == 2)
        return (s(0) + s(2)) + (s(1) + s(3));
    else
        return (((s(0) + s(2)) + (s(4) + s(6))) + ((s(1) + s(3)) + (s(5) + s(7)))) + s(8);
}

} // namespace detail

template <int D>
template <bool Grad>
inline void
CellKinematics<D>::symmetricVolume(Real c)
{
    using Constants = math::WboundedConstants<D>;
    const Real wc = Constants::detCoefficient();
    const Real off = Constants::offset();
    for (int p = 0; p < N; ++p) {
        // Direct half: c W(A) (math::W with det A and cof A).
        const Real s = detail::squaredNormLane<D, N>(A, p);
        const Real t = J[p] - 2.0;
        const Real r = std::sqrt(1.0 + t * t);
        const Real e = math::frobeniusPowerDp1<D>(s) / (D + 1) + wc * r - off;
        volumeDirect[p] = c * e;
        // Inverse half: c W(B) J, with det B = 1/J and cof B = A^T / J.
        const Real invJ = 1.0 / J[p];
        const Real sB = detail::squaredNormLane<D, N>(B, p);
        const Real tB = invJ - 2.0;
        const Real rB = std::sqrt(1.0 + tB * tB);
        const Real eB = math::frobeniusPowerDp1<D>(sB) / (D + 1) + wc * rB - off;
        volumeInverse[p] = c * eB * J[p];
        if constexpr (Grad) {
            const Real powA = math::frobeniusPowerDm1<D>(s);
            const Real kA = wc * t / r;
            const Real powB = math::frobeniusPowerDm1<D>(sB);
            const Real kB = wc * tB / rB;
            const Real cJ = c * J[p];
            const Real ceB = c * eB;
            for (int i = 0; i < D; ++i)
                for (int j = 0; j < D; ++j) {
                    // dW(A) = |A|^{d-1} A + kA cof A; dW(B) = |B|^{d-1} B + kB A^T / J.
                    const Real gA = powA * A[i][j][p] + kA * C[i][j][p];
                    const Real gB = powB * B[i][j][p] + kB * (A[j][i][p] * invJ);
                    dA[i][j][p] = (0.0 + c * gA) + ceB * C[i][j][p];
                    dB[i][j][p] = 0.0 + cJ * gB;
                }
        }
    }
}

template <int D>
inline void
CellKinematics<D>::zeroGradient()
{
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
            for (int p = 0; p < N; ++p) {
                dA[i][j][p] = 0;
                dB[i][j][p] = 0;
            }
}

template <int D>
inline void
CellKinematics<D>::finish()
{
    for (int p = 0; p < N; ++p) {
        // T = B^T dB, entries summed (y0 + y1) + y2; then dA -= T B^T, summed y0 + (y1 + y2).
        Real T[D][D];
        for (int i = 0; i < D; ++i)
            for (int j = 0; j < D; ++j) {
                Real sum = B[0][i][p] * dB[0][j][p] + B[1][i][p] * dB[1][j][p];
                if constexpr (D == 3) sum = sum + B[2][i][p] * dB[2][j][p];
                T[i][j] = sum;
            }
        for (int i = 0; i < D; ++i)
            for (int j = 0; j < D; ++j) {
                Real sum;
                if constexpr (D == 2)
                    sum = T[i][0] * B[j][0][p] + T[i][1] * B[j][1][p];
                else
                    sum = T[i][0] * B[j][0][p] + (T[i][1] * B[j][1][p] + T[i][2] * B[j][2][p]);
                dA[i][j][p] = dA[i][j][p] - sum;
            }
    }
}

template <int D>
inline SimplexKinematics<D>
CellKinematics<D>::simplex(int p) const
{
    SimplexKinematics<D> k;
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
            k.A(i, j) = A[i][j][p];
            k.C(i, j) = C[i][j][p];
            k.B(i, j) = B[i][j][p];
        }
    k.J = J[p];
    return k;
}

template <int D>
inline void
CellKinematics<D>::loadGradient(int p, DensityGradient<D>& g) const
{
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
            g.dA(i, j) = dA[i][j][p];
            g.dB(i, j) = dB[i][j][p];
        }
}

template <int D>
inline void
CellKinematics<D>::storeGradient(int p, const DensityGradient<D>& g)
{
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
            dA[i][j][p] = g.dA(i, j);
            dB[i][j][p] = g.dB(i, j);
        }
}

} // namespace energy
} // namespace vdbmatch
