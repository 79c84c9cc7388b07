/// @file EnergyFixture.h
/// @brief Small matching problems with analytic signed distances, shared by the energy tests.
#pragma once

#include "support/AnalyticShapes.h"

#include <vdbmatch/energy/Energy.h>

#include <cmath>
#include <memory>
#include <random>

namespace vdbmatch {
namespace test {

/// Shape fields and a dense lattice at one level, plus an Energy on them.
template <int D> struct MatchingProblem
{
    std::unique_ptr<SimplexLattice<D>> lattice;
    typename FieldSampler<D>::Ptr shape1, shape2;
    std::unique_ptr<Energy<D>> energy;

    /// @param cellBox  if given, only the cells in this index box (default: every cell of Omega)
    MatchingProblem(int level, openvdb::FloatGrid::Ptr sdf1, openvdb::FloatGrid::Ptr sdf2,
                    const EnergyParameters& params, EnergyKind kind,
                    const openvdb::CoordBBox* cellBox = nullptr)
    {
        lattice = std::make_unique<SimplexLattice<D>>(
            cellBox ? SimplexLattice<D>::box(level, *cellBox) : SimplexLattice<D>::dense(level));
        ShapeFieldOptions opts;
        opts.tau = params.tau;
        shape1 = FieldSampler<D>::build({sdf1}, opts);
        shape2 = FieldSampler<D>::build({sdf2}, opts);
        energy = std::make_unique<Energy<D>>(*lattice, *shape1, *shape2, params, kind);
    }

    /// A smooth random displacement with amplitude ~ @a amplitude (Omega units), zero on the
    /// boundary of Omega, plus small nodal noise so that every simplex sees a different A.
    NodeVectors<D> randomDisplacement(unsigned seed, Real amplitude) const
    {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<Real> U(-1, 1);
        Vec<D> k, phase;
        for (int a = 0; a < D; ++a) {
            k[a] = 2 + 2 * std::abs(U(rng));
            phase[a] = 3 * U(rng);
        }
        NodeVectors<D> u(D, lattice->nodeCount());
        for (std::size_t i = 0; i < lattice->nodeCount(); ++i) {
            const Vec<D> x = lattice->nodePosition(i);
            Real bump = 1;
            for (int a = 0; a < D; ++a)
                bump *= std::sin(M_PI * x[a]);
            for (int a = 0; a < D; ++a) {
                u(a, i) = amplitude *
                          (bump * std::sin(k[a] * x[(a + 1) % D] * M_PI + phase[a]) + 0.1 * U(rng));
            }
            if (lattice->isBoundaryNode(i)) u.col(i).setZero();
        }
        return u;
    }

    /// A random direction with entries in [-h, h] (zero on the boundary).
    NodeVectors<D> randomDirection(unsigned seed) const
    {
        std::mt19937 rng(seed);
        std::uniform_real_distribution<Real> U(-1, 1);
        NodeVectors<D> v(D, lattice->nodeCount());
        for (std::size_t i = 0; i < lattice->nodeCount(); ++i)
            for (int a = 0; a < D; ++a)
                v(a, i) = lattice->isBoundaryNode(i) ? 0 : lattice->h() * U(rng);
        return v;
    }
};

/// M1 = sphere/circle of radius 0.22 at (0.5, ...), M2 = ellipsoid/ellipse nearby: every term of
/// the energy is active and nonzero.
template <int D>
inline openvdb::FloatGrid::Ptr
sourceSdf(int level)
{
    if constexpr (D == 3)
        return createSphereSdf(level, Vec<3>(0.5, 0.5, 0.5), 0.22);
    else
        return createCircleSdf(level, Vec<2>(0.5, 0.5), 0.22);
}

template <int D>
inline openvdb::FloatGrid::Ptr
targetSdf(int level)
{
    if constexpr (D == 3)
        return createEllipsoidSdf(level, Vec<3>(0.52, 0.49, 0.5), Vec<3>(0.27, 0.2, 0.23));
    else
        return createEllipseSdf(level, Vec<2>(0.52, 0.49), Vec<2>(0.27, 0.19));
}

/// Parameters with a single active term (c_match, c_mem, c_bend or c_vol by index 0..3).
inline EnergyParameters
singleTerm(int dim, int term)
{
    EnergyParameters p = EnergyParameters::defaults(dim);
    const Real c[4] = {p.cMatch, p.cMem, p.cBend, p.cVol};
    p.cMatch = p.cMem = p.cBend = p.cVol = 0;
    Real* slot[4] = {&p.cMatch, &p.cMem, &p.cBend, &p.cVol};
    *slot[term] = c[term];
    return p;
}

inline const char*
termName(int term)
{
    static const char* names[4] = {"match", "mem", "bend", "vol"};
    return names[term];
}

} // namespace test
} // namespace vdbmatch
