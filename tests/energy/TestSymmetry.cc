/// @file TestSymmetry.cc
/// @brief Symmetry of eq:Esym: for an analytic diffeomorphism phi with analytic inverse psi and
///        M2 = phi(M1), E[phi; M1, M2] and E[psi; M2, M1] agree term by term (direct half of one =
///        inverse half of the other, by eq:inverseIntegral), the gap shrinking with h and sigma;
///        the directional energy eq:Ecomparison has an O(1) gap. Slow: levels 4..6 in 3D.
#include "energy/EnergyFixture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

/// Smooth bump (1 - (r/R)^2)^3 on r < R, 0 outside: C^2.
inline Real
bump(Real r, Real R)
{
    if (r >= R) return 0;
    const Real a = 1 - (r / R) * (r / R);
    return a * a * a;
}

/// phi = B o S about the centre c: S rotates the point about the z axis (2D: the plane) by the
/// angle alpha * bump(|x - c|), B moves it radially, r -> g(r) = r + beta * r * bump(r). Both keep
/// |x - c| level sets, so S maps any sphere about c to itself, B maps the sphere of radius r to
/// the sphere of radius g(r); both are the identity outside the ball of radius R.
template <int D> struct SwirlBulge
{
    Vec<D> c;
    Real R = 0.42, alpha = 0.5, beta = 0.35;

    Real g(Real r) const { return r + beta * r * bump(r, R); }
    Real gInverse(Real s) const
    {
        Real r = s;
        for (int it = 0; it < 60; ++it) { // Newton with numerical derivative, g' > 0
            const Real e = 1e-7;
            const Real f = g(r) - s, fp = (g(r + e) - g(r - e)) / (2 * e);
            r -= f / fp;
        }
        return r;
    }
    Vec<D> rotate(const Vec<D>& v, Real angle) const
    {
        Vec<D> w = v;
        const Real ca = std::cos(angle), sa = std::sin(angle);
        w[0] = ca * v[0] - sa * v[1];
        w[1] = sa * v[0] + ca * v[1];
        return w;
    }
    Vec<D> forward(const Vec<D>& x) const
    {
        const Vec<D> v = x - c;
        const Real r = v.norm();
        if (r < 1e-14 || r >= R) return x;
        const Vec<D> s = rotate(v, alpha * bump(r, R));
        return c + s * (g(r) / r);
    }
    Vec<D> inverse(const Vec<D>& y) const
    {
        const Vec<D> v = y - c;
        const Real s = v.norm();
        if (s < 1e-14 || s >= R) return y;
        const Real r = gInverse(s);
        return c + rotate(v * (r / s), -alpha * bump(r, R));
    }
};

template <int D>
NodeVectors<D>
interpolate(const SimplexLattice<D>& L, const std::function<Vec<D>(const Vec<D>&)>& map)
{
    NodeVectors<D> u(D, L.nodeCount());
    for (std::size_t i = 0; i < L.nodeCount(); ++i) {
        const Vec<D> x = L.nodePosition(i);
        u.col(i) = map(x) - x;
    }
    return u;
}

struct Gap
{
    Real match, mem, bend, vol, total, scale;
};

template <int D>
Gap
symmetryGap(int level, EnergyKind kind, bool print)
{
    SwirlBulge<D> phi;
    phi.c.setConstant(0.5);
    const Real r0 = 0.2, r1 = phi.g(r0);
    auto sphere = [&](Real r) {
        return createSdfGrid<D>(level, [c = phi.c, r](const Vec<D>& x) { return (x - c).norm() - r; });
    };
    const auto sdf1 = sphere(r0), sdf2 = sphere(r1);
    const EnergyParameters params = EnergyParameters::defaults(D);
    MatchingProblem<D> forward(level, sdf1, sdf2, params, kind);
    MatchingProblem<D> backward(level, sdf2, sdf1, params, kind);
    const auto& L = *forward.lattice;
    const NodeVectors<D> uPhi = interpolate<D>(L, [&](const Vec<D>& x) { return phi.forward(x); });
    const NodeVectors<D> uPsi = interpolate<D>(L, [&](const Vec<D>& x) { return phi.inverse(x); });
    EnergyTerms a, b;
    const Real ea = forward.energy->value(uPhi, &a);
    const Real eb = backward.energy->value(uPsi, &b);
    EXPECT_TRUE(std::isfinite(ea) && std::isfinite(eb));
    // Direct half of one energy <-> inverse half of the other.
    auto pairGap = [](const Real* x, const Real* y) {
        return std::abs(x[0] - y[1]) + std::abs(x[1] - y[0]);
    };
    Gap gap;
    if (kind == EnergyKind::Symmetric) {
        gap.match = pairGap(a.match, b.match);
        gap.mem = pairGap(a.mem, b.mem);
        gap.bend = pairGap(a.bend, b.bend);
        gap.vol = pairGap(a.vol, b.vol);
    } else {
        gap.match = std::abs(a.match[0] - b.match[0]);
        gap.mem = std::abs(a.mem[0] - b.mem[0]);
        gap.bend = std::abs(a.bend[0] - b.bend[0]);
        gap.vol = std::abs(a.vol[0] - b.vol[0]);
    }
    gap.total = std::abs(ea - eb);
    gap.scale = std::abs(ea);
    if (print)
        std::printf("%dD %-11s level %d h=%.5f: E[phi]=%.6g E[psi]=%.6g  gaps: match %.3e mem %.3e "
                    "bend %.3e vol %.3e total %.3e (rel %.3e)\n",
                    D, toString(kind).c_str(), level, L.h(), ea, eb, gap.match, gap.mem, gap.bend,
                    gap.vol, gap.total, gap.total / gap.scale);
    return gap;
}

template <int D>
void
checkSymmetryConvergence(const std::vector<int>& levels)
{
    std::vector<Gap> sym, dir;
    for (int level : levels) {
        sym.push_back(symmetryGap<D>(level, EnergyKind::Symmetric, true));
        dir.push_back(symmetryGap<D>(level, EnergyKind::Directional, true));
    }
    for (std::size_t i = 1; i < levels.size(); ++i) {
        const Real rate = std::log2(sym[i - 1].total / sym[i].total) / (levels[i] - levels[i - 1]);
        std::printf("%dD symmetric gap rate level %d -> %d: %.2f (mem %.2f, bend %.2f, vol %.2f, "
                    "match %.2f)\n",
                    D, levels[i - 1], levels[i], rate, std::log2(sym[i - 1].mem / sym[i].mem),
                    std::log2(sym[i - 1].bend / sym[i].bend), std::log2(sym[i - 1].vol / sym[i].vol),
                    std::log2(sym[i - 1].match / sym[i].match));
        EXPECT_GT(rate, 0.8) << "symmetric gap must shrink with h";
    }
    const Gap& s = sym.back();
    const Gap& d = dir.back();
    // At the finest level the symmetric gap is small relative to the energy, the directional gap
    // is not, and it is much larger than the symmetric one.
    EXPECT_LT(s.total / s.scale, 0.02);
    EXPECT_GT(d.total / d.scale, 0.05);
    EXPECT_GT(d.total, 10 * s.total);
}

} // namespace

TEST(Symmetry, SwirlBulgeSphere3D) { checkSymmetryConvergence<3>({4, 5, 6}); }
TEST(Symmetry, SwirlBulgeCircle2D) { checkSymmetryConvergence<2>({5, 6, 7, 8}); }
