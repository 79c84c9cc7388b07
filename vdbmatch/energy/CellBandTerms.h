/// @file CellBandTerms.h
/// @brief The band terms of the symmetric energy (eq:EsymMatch, eq:EsymMem, eq:EsymBend) for the
///        band simplices of one lattice cell at once, lane by lane: the frame of shape 2 at the
///        deformed centroid, the direct and inverse densities with their derivatives, and the
///        reverse mode through the frame to dE/dy. The directional energy (eq:Ecomparison) uses
///        the direct halves alone.
///
/// A simplex in the band of M1 or of M2 costs about five times one that carries only the volume
/// term, and at the fine levels a quarter of the simplices are in a band. The caller samples the
/// fields (one query per simplex) and fills the lanes of the cell's band simplices; the rest is
/// done here with the arrays lane-last (a[i][j][q], q the lane) and each step one loop over the
/// lanes with a straight-line body, which the compiler vectorises across the simplices (as in
/// CellKinematics.h). The loops over matrix entries inside are fully unrolled (`#pragma GCC
/// unroll`: GCC does not unroll loops with bodies this large by itself, and a loop left inside
/// keeps the one around it from being vectorised). Both halves are computed in every lane, also
/// where a band weight is zero; their contributions are then exact zeros (lanes::add), and the
/// caller adds only the densities of the halves that are on.
///
/// **The same bits as the per-simplex code.** Each lane performs the operations of
/// kinematics::makeFrame, matchDirect/membraneDirect/bendingDirect, matchInverse/
/// membraneInverse/bendingInverse (MatchTerm.h, MembraneTerm.h, BendingTerm.h,
/// ProjectedDensity.h, math::W) and kinematics::frameAdjoint, in the order Eigen evaluates their
/// expressions there (the library is built with -ffp-contract=off). The order of a 3-term sum
/// in a 3 x 3 product depends on the form of the expression; found on random matrices:
/// - "LLR": rows 0 and 1 summed (y0+y1)+y2, row 2 y0+(y1+y2): a product of plain matrices, or
///   of a plain matrix and a transpose, assigned or added (A*B, A*B^T, G*n);
/// - "LLL": a transpose times a plain matrix or vector (A^T*B, A^T*n);
/// - "RRR": the second product of a chain with a transpose added to a matrix (dA += A^T*B*C^T,
///   (A*B)*C^T inside a sum of products), and (A+A^T)*n;
/// - a chain initialising a new matrix (const Mat aM = -A^T*B*A^T): LLL, then LLR.
/// - 3-vector norms, dot products and determinants (y0+y1)+y2; 3 x 3 Frobenius sums in SSE2
///   packets ((s0+s2)+(s4+s6)) + ((s1+s3)+(s5+s7)) + s8 (column-major memory order).
/// tests/energy/TestCellBandTerms.cc compares every output bitwise with the per-simplex code, so
/// a change of Eigen's evaluation order shows there.
/// @see paper eq:EsymMatch, eq:EsymMem, eq:EsymBend, eq:Fmemdirect, eq:Fmeminverse,
///      eq:Fbenddirect, eq:Fbendinverse
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/energy/CellKinematics.h>
#include <vdbmatch/math/Saturation.h>
#include <vdbmatch/math/StoredEnergy.h>

#include <cmath>

namespace vdbmatch {
namespace energy {

namespace lanes {

/// Inlines a lambda called twice in a loop over the lanes (a call would keep the loop from
/// being vectorised).
#define VDBMATCH_INLINE __attribute__((always_inline))

/// A D x D matrix of one lane, as local values (the compiler keeps them in registers).
template <int D> struct M
{
    Real a[D][D];
};
template <int D> struct V
{
    Real a[D];
};

/// Sum of the D products y_k in Eigen's order: (y0+y1)+y2 (LEFT) or y0+(y1+y2) (RIGHT).
template <int D>
inline Real
sum(const Real (&y)[D], bool right)
{
    if constexpr (D == 2)
        return y[0] + y[1];
    else
        return right ? y[0] + (y[1] + y[2]) : (y[0] + y[1]) + y[2];
}

/// Row patterns of the file comment (bit i set: row i summed y0+(y1+y2)).
constexpr unsigned LLR = 4, LLL = 0, RRR = 7;

/// Z = X Y with X(i, k) = x(i, k) and Y(k, j) = y(k, j) (accessors, so that transposes and
/// negations are written where they occur), rows summed as @a PATTERN says.
template <int D, unsigned PATTERN, class X, class Y>
inline M<D>
product(X x, Y y)
{
    M<D> z;
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
        for (int j = 0; j < D; ++j) {
            Real t[D];
#pragma GCC unroll 3
            for (int k = 0; k < D; ++k)
                t[k] = x(i, k) * y(k, j);
            z.a[i][j] = sum<D>(t, (PATTERN >> i) & 1u);
        }
    return z;
}

/// z = X v, rows summed as @a PATTERN says.
template <int D, unsigned PATTERN, class X>
inline V<D>
apply(X x, const V<D>& v)
{
    V<D> z;
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i) {
        Real t[D];
#pragma GCC unroll 3
        for (int k = 0; k < D; ++k)
            t[k] = x(i, k) * v.a[k];
        z.a[i] = sum<D>(t, (PATTERN >> i) & 1u);
    }
    return z;
}

template <int D>
inline auto
plain(const M<D>& m)
{
    return [&m](int i, int j) { return m.a[i][j]; };
}
template <int D>
inline auto
transposed(const M<D>& m)
{
    return [&m](int i, int j) { return m.a[j][i]; };
}

/// Sum of the entries' products s_k of two D x D matrices in Eigen's redux order (memory order
/// k = i + D j): ((s0+s2)+(s4+s6)) + ((s1+s3)+(s5+s7)) + s8, or (s0+s2)+(s1+s3).
template <int D>
inline Real
frobenius(const M<D>& x, const M<D>& y)
{
    auto s = [&](int k) { return x.a[k % D][k / D] * y.a[k % D][k / D]; };
    if constexpr (D == 2)
        return (s(0) + s(2)) + (s(1) + s(3));
    else
        return (((s(0) + s(2)) + (s(4) + s(6))) + ((s(1) + s(3)) + (s(5) + s(7)))) + s(8);
}

/// The cofactor matrix (math::cof, term by term).
template <int D>
inline M<D>
cof(const M<D>& x)
{
    M<D> c;
    const auto& A = x.a;
    if constexpr (D == 2) {
        c.a[0][0] = A[1][1];
        c.a[0][1] = -A[1][0];
        c.a[1][0] = -A[0][1];
        c.a[1][1] = A[0][0];
    } else {
        c.a[0][0] = A[1][1] * A[2][2] - A[1][2] * A[2][1];
        c.a[0][1] = A[1][2] * A[2][0] - A[1][0] * A[2][2];
        c.a[0][2] = A[1][0] * A[2][1] - A[1][1] * A[2][0];
        c.a[1][0] = A[0][2] * A[2][1] - A[0][1] * A[2][2];
        c.a[1][1] = A[0][0] * A[2][2] - A[0][2] * A[2][0];
        c.a[1][2] = A[0][1] * A[2][0] - A[0][0] * A[2][1];
        c.a[2][0] = A[0][1] * A[1][2] - A[0][2] * A[1][1];
        c.a[2][1] = A[0][2] * A[1][0] - A[0][0] * A[1][2];
        c.a[2][2] = A[0][0] * A[1][1] - A[0][1] * A[1][0];
    }
    return c;
}

/// math::W(X, dW) of eq:Wbounded: returns W(X) and sets @a G = dW/dX (if @a Grad).
/// @a wc and @a off are WboundedConstants<D>::detCoefficient() and offset().
template <int D, bool Grad>
inline Real
W(const M<D>& x, Real wc, Real off, M<D>& G)
{
    const M<D> c = cof<D>(x);
    Real y[D];
#pragma GCC unroll 3
    for (int k = 0; k < D; ++k)
        y[k] = x.a[k][0] * c.a[k][0];
    const Real det = sum<D>(y, false); // Laplace expansion
    const Real s = frobenius<D>(x, x);
    const Real t = det - 2.0;
    const Real r = std::sqrt(1.0 + t * t);
    if constexpr (Grad) {
        const Real pw = math::frobeniusPowerDm1<D>(s);
        const Real k = wc * t / r;
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
            for (int j = 0; j < D; ++j)
                G.a[i][j] = pw * x.a[i][j] + k * c.a[i][j];
    }
    return math::frobeniusPowerDp1<D>(s) / (D + 1) + wc * r - off;
}

} // namespace lanes

template <int D> struct CellBandTerms
{
    static constexpr int N = CellKinematics<D>::N; ///< lanes (the simplices of a cell)
    using Lanes = Real[N];
    using VecLanes = Real[D][N];
    using MatLanes = Real[D][D][N];

    int count = 0; ///< lanes in use, 0..N

    // Inputs, set by the caller for lanes 0..count-1.
    MatLanes A, B;   ///< D phi, A^{-1} (J > 0)
    MatLanes C;      ///< cof A (with gradients only)
    Lanes J;         ///< det A
    MatLanes dA, dB; ///< with gradients: the volume term's dE/dA, dE/dB, plus the band terms
    Lanes eta1, eta2, eta2D; ///< eta_sigma(d1), eta_sigma(d2(y)), eta_sigma'(d2(y))
    Lanes d1;                ///< frame of shape 1 at the centroid x
    VecLanes n1;             ///<
    MatLanes P1, Tp1, Tm1;   ///<
    Lanes d2;                ///< raw fields of shape 2 at y (RawFields)
    VecLanes rawN2;          ///<
    MatLanes R2;             ///<
    VecLanes dd2;            ///< their derivatives (RawFieldDerivatives), with gradients only
    MatLanes dn2;            ///<
    Real dR2[D][D][D][N];    ///< dR2[k] = d R / d x_k

    // Frame of shape 2 at y (makeFrame).
    Lanes nLength2;
    VecLanes n2;
    MatLanes P2, Tp2, Tm2, Minv2;

    // Outputs: the densities (valid where the half's weight is > 0) and dE/dy.
    Lanes matchDirect, memDirect, bendDirect, matchInverse, memInverse, bendInverse;
    VecLanes dy;

    // dE/d(frame of shape 2) (kinematics::FrameAdjoint), accumulated by the terms.
    Lanes ad;
    VecLanes an;
    MatLanes aP, aTp, aTm;

    /// The frame of shape 2 from its raw fields (kinematics::makeFrame).
    void frame();
    /// The six densities with weights c_match sigma^-q, c_mem, c_bend, the membrane ones
    /// saturated by psi_s with s = @a memSaturation (math/Saturation.h; 0: the paper's); with
    /// Grad, their derivatives added to dA, dB and the frame adjoint. Without @a inverseHalves
    /// only the direct halves (the directional energy eq:Ecomparison, whose eta2 is 0): the
    /// inverse densities are not set and dB is not touched.
    template <bool Grad>
    void terms(Real cMatch, Real cMem, Real cBend, bool inverseHalves = true,
               Real memSaturation = 0);
    /// dy = dE/dy through the frame and the field interpolants (kinematics::frameAdjoint).
    void adjoint();
};

namespace lanes {

template <int D, int N>
inline M<D>
load(const Real (&m)[D][D][N], int q)
{
    M<D> r;
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
        for (int j = 0; j < D; ++j)
            r.a[i][j] = m[i][j][q];
    return r;
}

template <int D, int N>
inline V<D>
load(const Real (&v)[D][N], int q)
{
    V<D> r;
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
        r.a[i] = v[i][q];
    return r;
}

template <int D, int N>
inline void
store(const M<D>& r, Real (&m)[D][D][N], int q)
{
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
        for (int j = 0; j < D; ++j)
            m[i][j][q] = r.a[i][j];
}

template <int D, int N>
inline void
store(const V<D>& r, Real (&v)[D][N], int q)
{
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
        v[i][q] = r.a[i];
}

/// a += x. The lanes add both halves' contributions whatever the band weights: a half whose
/// weight is 0 contributes exact zeros (every derivative it adds has the factor eta = 0, or
/// eta' = 0, which vanishes with eta at the edge of the band, times finite values), and adding
/// a zero leaves an accumulator unchanged bit for bit because none is ever -0 (each starts as
/// +0 or as a sum 0.0 + ..., and a sum is -0 only if both terms are). So the lanes add what the
/// per-simplex code, which skips the half, adds; no branch or select in the loop.
inline void
add(Real& a, Real x)
{
    a = a + x;
}

template <int D>
inline void
add(M<D>& m, const M<D>& x)
{
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
        for (int j = 0; j < D; ++j)
            add(m.a[i][j], x.a[i][j]);
}

template <int D>
inline void
add(V<D>& v, const V<D>& x)
{
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
        add(v.a[i], x.a[i]);
}

} // namespace lanes

template <int D>
inline void
CellBandTerms<D>::frame()
{
    using namespace lanes;
    for (int q = 0; q < count; ++q) {
        const V<D> raw = load<D, N>(rawN2, q);
        Real sq[D];
#pragma GCC unroll 3
        for (int k = 0; k < D; ++k)
            sq[k] = raw.a[k] * raw.a[k];
        const Real len = std::sqrt(sum<D>(sq, false));
        V<D> n;
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
            n.a[i] = raw.a[i] / len;
        M<D> nn, P;
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
            for (int j = 0; j < D; ++j) {
                nn.a[i][j] = n.a[i] * n.a[j];
                P.a[i][j] = (i == j ? 1.0 : 0.0) - nn.a[i][j];
            }
        const M<D> R = load<D, N>(R2, q);
        const M<D> PR = product<D, LLR>(plain(P), plain(R));
        const M<D> Tp = product<D, LLR>(plain(PR), plain(P));
        // (Tp + n n^T)^{-1} as Eigen's inverse: the cofactors of the first column, the
        // determinant from them, then every cofactor times 1/det.
        M<D> m, inv;
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
            for (int j = 0; j < D; ++j)
                m.a[i][j] = Tp.a[i][j] + nn.a[i][j];
        if constexpr (D == 2) {
            const Real invdet = 1.0 / (m.a[0][0] * m.a[1][1] - m.a[1][0] * m.a[0][1]);
            inv.a[0][0] = m.a[1][1] * invdet;
            inv.a[1][0] = -m.a[1][0] * invdet;
            inv.a[0][1] = -m.a[0][1] * invdet;
            inv.a[1][1] = m.a[0][0] * invdet;
        } else {
            auto cofactor = [&](int i, int j) {
                const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
                return m.a[i1][j1] * m.a[i2][j2] - m.a[i1][j2] * m.a[i2][j1];
            };
            Real y[3];
#pragma GCC unroll 3
            for (int k = 0; k < 3; ++k)
                y[k] = cofactor(k, 0) * m.a[k][0];
            const Real invdet = 1.0 / sum<3>(y, false);
#pragma GCC unroll 3
            for (int i = 0; i < 3; ++i)
#pragma GCC unroll 3
                for (int j = 0; j < 3; ++j)
                    inv.a[i][j] = cofactor(j, i) * invdet;
        }
        nLength2[q] = len;
        store<D, N>(n, n2, q);
        store<D, N>(P, P2, q);
        store<D, N>(Tp, Tp2, q);
        store<D, N>(inv, Minv2, q);
        M<D> Tm;
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
            for (int j = 0; j < D; ++j)
                Tm.a[i][j] = inv.a[i][j] - nn.a[i][j];
        store<D, N>(Tm, Tm2, q);
    }
}

template <int D>
template <bool Grad>
inline void
CellBandTerms<D>::terms(Real cMatch, Real cMem, Real cBend, bool inverseHalves, Real memSaturation)
{
    using namespace lanes;
    using Constants = math::WboundedConstants<D>;
    const Real wc = Constants::detCoefficient();
    const Real off = Constants::offset();
    // Direct halves (weight eta1): matchDirect, membraneDirect, bendingDirect.
    for (int q = 0; q < count; ++q) {
        const V<D> vn1 = load<D, N>(n1, q), vn2 = load<D, N>(n2, q);
        const M<D> a = load<D, N>(A, q);
        const Real r = d2[q] - d1[q];
        matchDirect[q] = cMatch * eta1[q] * r * r;
        // The gradient's accumulators: dA from the volume term, the frame adjoint from zero.
        M<D> gA, gP{}, gTp{};
        V<D> gn{};
        if constexpr (Grad) {
            gA = load<D, N>(dA, q);
            Real gd = 0;
            add(gd, 2.0 * cMatch * eta1[q] * r);
            ad[q] = gd;
        }
        // projectedDirect(L2, R1) = psi_s(W(L2 A R1 + n2 (x) n1)) for (P2, P1) and (Tp2, Tm1).
        auto projected = [&](const MatLanes& L2l, const MatLanes& R1l, Real c, Real sat,
                             Lanes& density, M<D>& gL2) VDBMATCH_INLINE {
            const M<D> L2 = load<D, N>(L2l, q), R1 = load<D, N>(R1l, q);
            const M<D> AR1 = product<D, LLR>(plain(a), plain(R1));
            const M<D> L2AR1 = product<D, LLR>(plain(L2), plain(AR1));
            M<D> X;
#pragma GCC unroll 3
            for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
                for (int j = 0; j < D; ++j)
                    X.a[i][j] = L2AR1.a[i][j] + vn2.a[i] * vn1.a[j];
            const Real w = c * eta1[q];
            M<D> G;
            const Real e = W<D, Grad>(X, wc, off, G);
            density[q] = w * math::saturated(e, sat);
            if constexpr (Grad) {
                const Real gw = sat > 0 ? w * math::saturatedSlope(e, sat) : w;
#pragma GCC unroll 3
                for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
                    for (int j = 0; j < D; ++j)
                        G.a[i][j] = G.a[i][j] * gw;
                const M<D> LG = product<D, LLL>(transposed(L2), plain(G));
                add(gA, product<D, RRR>(plain(LG), transposed(R1)));
                add(gn, apply<D, LLR>(plain(G), vn1));
                add(gL2, product<D, LLR>(plain(G), transposed(AR1)));
            }
        };
        projected(P2, P1, cMem, memSaturation, memDirect, gP);
        projected(Tp2, Tm1, cBend, 0.0, bendDirect, gTp);
        if constexpr (Grad) {
            store<D, N>(gA, dA, q);
            store<D, N>(gn, an, q);
            store<D, N>(gP, aP, q);
            store<D, N>(gTp, aTp, q);
        }
    }
    if (!inverseHalves) {
        if constexpr (Grad)
            for (int q = 0; q < count; ++q)
#pragma GCC unroll 3
                for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
                    for (int j = 0; j < D; ++j)
                        aTm[i][j][q] = 0;
        return;
    }
    // Inverse halves (weight eta2): matchInverse, membraneInverse, bendingInverse.
    for (int q = 0; q < count; ++q) {
        const V<D> vn1 = load<D, N>(n1, q), vn2 = load<D, N>(n2, q);
        const M<D> b = load<D, N>(B, q);
        const Real j = J[q];
        const Real r = d2[q] - d1[q];
        const Real r2 = r * r;
        matchInverse[q] = cMatch * eta2[q] * j * r2;
        M<D> cofA, gA, gB, gP, gTm;
        V<D> gn;
        Real gd = 0;
        if constexpr (Grad) {
            cofA = load<D, N>(C, q);
            gA = load<D, N>(dA, q);
            gB = load<D, N>(dB, q);
            gP = load<D, N>(aP, q);
            gTm = {};
            gn = load<D, N>(an, q);
            gd = ad[q];
            add(gd, cMatch * j * (eta2D[q] * r2 + 2.0 * eta2[q] * r));
            const Real k = cMatch * eta2[q] * r2;
            M<D> x;
#pragma GCC unroll 3
            for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
                for (int l = 0; l < D; ++l)
                    x.a[i][l] = k * cofA.a[i][l];
            add(gA, x);
        }
        // projectedInverse(L1, R2) = psi_s(W(L1 B R2 + n1 (x) n2)) J for (P1, P2) and (Tp1, Tm2).
        auto projected = [&](const MatLanes& L1l, const MatLanes& R2l, Real c, Real sat,
                             Lanes& density, M<D>& gR2) VDBMATCH_INLINE {
            const M<D> L1 = load<D, N>(L1l, q), R2m = load<D, N>(R2l, q);
            const M<D> L1B = product<D, LLR>(plain(L1), plain(b));
            const M<D> L1BR2 = product<D, LLR>(plain(L1B), plain(R2m));
            M<D> X;
#pragma GCC unroll 3
            for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
                for (int l = 0; l < D; ++l)
                    X.a[i][l] = L1BR2.a[i][l] + vn1.a[i] * vn2.a[l];
            M<D> G;
            const Real we = W<D, Grad>(X, wc, off, G);
            const Real e = math::saturated(we, sat);
            density[q] = c * eta2[q] * j * e;
            if constexpr (Grad) {
                const Real s =
                    sat > 0 ? c * eta2[q] * j * math::saturatedSlope(we, sat) : c * eta2[q] * j;
#pragma GCC unroll 3
                for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
                    for (int l = 0; l < D; ++l)
                        G.a[i][l] = G.a[i][l] * s;
                const M<D> LG = product<D, LLL>(transposed(L1), plain(G));
                add(gB, product<D, RRR>(plain(LG), transposed(R2m)));
                add(gn, apply<D, LLL>(transposed(G), vn1));
                add(gd, c * eta2D[q] * j * e);
                const Real k = c * eta2[q] * e;
                M<D> x;
#pragma GCC unroll 3
                for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
                    for (int l = 0; l < D; ++l)
                        x.a[i][l] = k * cofA.a[i][l];
                add(gA, x);
                add(gR2, product<D, LLL>(transposed(L1B), plain(G)));
            }
        };
        projected(P1, P2, cMem, memSaturation, memInverse, gP);
        projected(Tp1, Tm2, cBend, 0.0, bendInverse, gTm);
        if constexpr (Grad) {
            store<D, N>(gA, dA, q);
            store<D, N>(gB, dB, q);
            store<D, N>(gn, an, q);
            store<D, N>(gP, aP, q);
            store<D, N>(gTm, aTm, q);
            ad[q] = gd;
        }
    }
}

template <int D>
inline void
CellBandTerms<D>::adjoint()
{
    using namespace lanes;
    for (int q = 0; q < count; ++q) {
        const M<D> Minv = load<D, N>(Minv2, q), P = load<D, N>(P2, q), R = load<D, N>(R2, q);
        const M<D> aTmq = load<D, N>(aTm, q);
        const V<D> n = load<D, N>(n2, q);
        M<D> aTpq = load<D, N>(aTp, q), aPq = load<D, N>(aP, q);
        V<D> anq = load<D, N>(an, q);
        // Tm = Minv - n n^T, Minv = (Tp + n n^T)^{-1}: aM = -Minv^T aTm Minv^T.
        const M<D> t1 = product<D, LLL>([&](int i, int k) { return -Minv.a[k][i]; }, plain(aTmq));
        const M<D> aM = product<D, LLR>(plain(t1), transposed(Minv));
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
            for (int j = 0; j < D; ++j)
                aTpq.a[i][j] = aTpq.a[i][j] + aM.a[i][j];
        const V<D> v1 = apply<D, RRR>([&](int i, int k) { return aM.a[i][k] + aM.a[k][i]; }, n);
        const V<D> v2 = apply<D, RRR>([&](int i, int k) { return aTmq.a[i][k] + aTmq.a[k][i]; }, n);
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
            anq.a[i] = anq.a[i] + (v1.a[i] - v2.a[i]);
        // Tp = P R P.
        const M<D> t2 = product<D, LLR>(plain(P), plain(aTpq));
        const M<D> aR = product<D, LLR>(plain(t2), plain(P));
        const M<D> t3 = product<D, LLR>(plain(aTpq), plain(P));
        const M<D> x = product<D, RRR>(plain(t3), transposed(R));
        const M<D> t4 = product<D, LLL>(transposed(R), plain(P));
        const M<D> y = product<D, RRR>(plain(t4), plain(aTpq));
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
            for (int j = 0; j < D; ++j)
                aPq.a[i][j] = aPq.a[i][j] + (x.a[i][j] + y.a[i][j]);
        // P = 1 - n n^T.
        const V<D> v3 = apply<D, RRR>([&](int i, int k) { return aPq.a[i][k] + aPq.a[k][i]; }, n);
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
            anq.a[i] = anq.a[i] - v3.a[i];
        // n = n~ / |n~|.
        Real t[D];
#pragma GCC unroll 3
        for (int k = 0; k < D; ++k)
            t[k] = n.a[k] * anq.a[k];
        const Real dot = sum<D>(t, false);
        V<D> aRawN;
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
            aRawN.a[i] = (anq.a[i] - n.a[i] * dot) / nLength2[q];
        const M<D> dn = load<D, N>(dn2, q);
        const V<D> dnT = apply<D, LLL>(transposed(dn), aRawN);
        V<D> g;
#pragma GCC unroll 3
        for (int i = 0; i < D; ++i)
            g.a[i] = ad[q] * dd2[i][q] + dnT.a[i];
#pragma GCC unroll 3
        for (int k = 0; k < D; ++k)
            g.a[k] = g.a[k] + frobenius<D>(aR, load<D, N>(dR2[k], q));
        store<D, N>(g, dy, q);
    }
}

#undef VDBMATCH_INLINE

} // namespace energy
} // namespace vdbmatch
