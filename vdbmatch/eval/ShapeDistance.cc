/// @file ShapeDistance.cc
#include "ShapeDistance.h"

#include <vdbmatch/geometry/DistanceField.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>

namespace vdbmatch {
namespace eval {

double
domainSize(const DeformationField& field)
{
    const openvdb::Vec3d extents = field.worldBounds().extents();
    double side = 0;
    for (int a = 0; a < field.dimension(); ++a)
        side = std::max(side, extents[a]);
    return side;
}

UnitBoxPlacement
domainPlacement(const DeformationField& field)
{
    const double side = domainSize(field);
    if (!(side > 0) || !std::isfinite(side)) {
        OPENVDB_THROW(openvdb::ValueError, "domainPlacement: the deformation grid spans no domain");
    }
    UnitBoxPlacement p;
    p.worldOrigin = field.worldBounds().min();
    p.scale = 1.0 / side;
    p.margin = 0;
    p.worldBox = field.worldBounds();
    return p;
}

int
deformationLevel(const DeformationField& field)
{
    return int(std::lround(std::log2(domainSize(field) / field.voxelSize())));
}

int
defaultDistanceLevel(int dim, int level)
{
    return dim == 2 ? std::clamp(level + 1, MIN_AUTO_DISTANCE_LEVEL_2D, MAX_AUTO_DISTANCE_LEVEL_2D)
                    : std::clamp(level + 1, MIN_AUTO_DISTANCE_LEVEL_3D, MAX_AUTO_DISTANCE_LEVEL_3D);
}

template <int D>
void
checkShapeInDomain(const Surface<D>& worldSurface, const UnitBoxPlacement& omega,
                   const std::string& what)
{
    /// Relative tolerance on the side of Omega (float storage of the grid transform).
    constexpr double DOMAIN_TOLERANCE = 1e-9;
    for (const Vec<D>& p : worldSurface.points) {
        openvdb::Vec3d w(0.0);
        for (int a = 0; a < D; ++a)
            w[a] = p[a];
        const openvdb::Vec3d u = omega.toUnit(w);
        for (int a = 0; a < D; ++a) {
            if (!(u[a] >= -DOMAIN_TOLERANCE && u[a] <= 1 + DOMAIN_TOLERANCE)) {
                OPENVDB_THROW(openvdb::ValueError,
                              what + " does not lie inside the domain of the deformation (point " +
                                  std::to_string(p[0]) + ", " + std::to_string(p[1]) +
                                  (D == 3 ? ", " + std::to_string(p[D - 1]) : std::string()) +
                                  "): is it the shape the deformation was computed for?");
            }
        }
    }
}

template <int D>
ShapeDistance<D>::ShapeDistance(const Surface<D>& worldSurface, const UnitBoxPlacement& omega,
                                int level, bool threaded)
    : mOmega(omega), mLevel(level)
{
    const Surface<D> unit = transformed(worldSurface, omega, PlacementDirection::WorldToUnit);
    ShapeSamplerOptions opts;
    opts.threaded = threaded;
    mSampler = buildShapeSampler<D>(unit, level, opts);
    mVoxelSizeWorld = omega.toWorldLength(std::ldexp(1.0, -level));
}

template <int D>
double
ShapeDistance<D>::signedDistance(const openvdb::Vec3d& xWorld) const
{
    const openvdb::Vec3d u = mOmega.toUnit(xWorld);
    Vec<D> x, clamped;
    double outside2 = 0;
    for (int a = 0; a < D; ++a) {
        x[a] = u[a];
        clamped[a] = std::clamp(u[a], 0.0, 1.0);
        outside2 += (x[a] - clamped[a]) * (x[a] - clamped[a]);
    }
    Real d = 0;
    if (mSampler->sampleDistance(x, d)) return mOmega.toWorldLength(d);
    if (!mSampler->sampleDistance(clamped, d)) {
        OPENVDB_THROW(openvdb::RuntimeError,
                      "ShapeDistance: the sampler does not cover Omega (internal error)");
    }
    return mOmega.toWorldLength(d + std::sqrt(outside2));
}

template void checkShapeInDomain<2>(const Surface<2>&, const UnitBoxPlacement&, const std::string&);
template void checkShapeInDomain<3>(const Surface<3>&, const UnitBoxPlacement&, const std::string&);
template class ShapeDistance<2>;
template class ShapeDistance<3>;

} // namespace eval
} // namespace vdbmatch
