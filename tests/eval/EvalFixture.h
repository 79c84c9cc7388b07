/// @file EvalFixture.h
/// @brief Deformation grids of analytic maps for the evaluation tests: phi(x) = x + a B(x) on
///        Omega = (0,1)^D (B vanishes on the boundary, so phi = Id there) sampled at every node of
///        a level, its inverse solved per node by fixed-point iteration, and the identity; all in
///        a world space that is a scaled and shifted copy of Omega.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/io/DeformationField.h>

#include <openvdb/openvdb.h>

#include <cmath>
#include <functional>

namespace vdbmatch {
namespace test {

/// World = WORLD_SCALE * unit + WORLD_OFFSET (z offset 0 in 2D).
constexpr double WORLD_SCALE = 2.0;
inline openvdb::Vec3d
worldOffset(int dim)
{
    return openvdb::Vec3d(1.0, -0.5, dim == 3 ? 0.25 : 0.0);
}

/// Amplitude of the analytic map (Omega units); a |DB| < 1, so phi is invertible.
constexpr double MAP_AMPLITUDE = 0.05;

/// B(x): prod_b sin(pi x_b) times a smooth direction field.
template <int D>
Vec<D>
bump(const Vec<D>& x)
{
    double s = 1;
    for (int b = 0; b < D; ++b)
        s *= std::sin(M_PI * x[b]);
    Vec<D> v;
    for (int a = 0; a < D; ++a)
        v[a] = s * std::cos(2.0 * x[(a + 1) % D] + a);
    return v;
}

/// phi(x) - x in Omega units.
template <int D>
Vec<D>
forwardDisplacement(const Vec<D>& x)
{
    return MAP_AMPLITUDE * bump<D>(x);
}

/// phi^{-1}(x) - x: y = x - a B(y) iterated (a contraction) to round-off.
template <int D>
Vec<D>
inverseDisplacement(const Vec<D>& x)
{
    /// Iterations of the contraction (rate < 0.5): far beyond double precision.
    constexpr int FIXED_POINT_ITERATIONS = 100;
    Vec<D> y = x;
    for (int it = 0; it < FIXED_POINT_ITERATIONS; ++it)
        y = x - MAP_AMPLITUDE * bump<D>(y);
    return y - x;
}

/// A deformation grid with u(node) = WORLD_SCALE * displacement(node) at every node of
/// [0, 2^level]^D (all active, zeros included).
template <int D>
DeformationField
makeField(int level, const std::function<Vec<D>(const Vec<D>&)>& displacement)
{
    const double h = std::ldexp(1.0, -level);
    const int n = 1 << level;
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    auto xform = openvdb::math::Transform::createLinearTransform(h * WORLD_SCALE);
    xform->postTranslate(worldOffset(D));
    grid->setTransform(xform);
    grid->setName("displacement");
    auto acc = grid->getAccessor();
    for (int k = 0; k <= (D == 3 ? n : 0); ++k) {
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                Vec<D> x;
                x[0] = i * h;
                x[1] = j * h;
                if constexpr (D == 3) x[2] = k * h;
                const Vec<D> u = displacement(x) * WORLD_SCALE;
                openvdb::Vec3s value(0.0f);
                for (int a = 0; a < D; ++a)
                    value[a] = float(u[a]);
                acc.setValueOn(openvdb::Coord(i, j, k), value);
            }
        }
    }
    return DeformationField(grid);
}

template <int D>
Vec<D>
zeroDisplacement(const Vec<D>&)
{
    return Vec<D>::Zero();
}

/// A shape in Omega units mapped to the world space of makeField.
template <int D>
Surface<D>
toWorld(Surface<D> s)
{
    for (Vec<D>& p : s.points) {
        for (int a = 0; a < D; ++a)
            p[a] = WORLD_SCALE * p[a] + worldOffset(D)[a];
    }
    return s;
}

} // namespace test
} // namespace vdbmatch
