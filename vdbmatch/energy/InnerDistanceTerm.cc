/// @file InnerDistanceTerm.cc
#include "InnerDistanceTerm.h"

#include <openvdb/Exceptions.h>

#include <cmath>

namespace vdbmatch {
namespace energy {

template <int D>
InnerDistanceTerm<D>::InnerDistanceTerm(const SimplexLattice<D>& lattice,
                                        const InnerDistanceSamples<D>& samples)
    : mPoints(samples.points), mValues(samples.values), mWeights(samples.weights),
      mFields(samples.fields), mTargets(samples.targets), mTolerance(samples.tolerance)
{
    if (mValues.size() != mPoints.size() || mWeights.size() != mPoints.size() ||
        mFields.size() != mPoints.size()) {
        OPENVDB_THROW(openvdb::ValueError,
                      "inner distance: " << mPoints.size() << " points, " << mValues.size()
                                         << " values, " << mWeights.size() << " weights and "
                                         << mFields.size() << " field indices");
    }
    if (!(mTolerance >= 0) || !std::isfinite(mTolerance)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "inner distance: the tolerance must be finite and >= 0, got " << mTolerance);
    }
    for (const auto& f : mTargets) {
        if (!f || f->empty())
            OPENVDB_THROW(openvdb::ValueError,
                          "inner distance: a target field is missing or empty");
    }
    const multiscale::PiecewiseLinearInterpolator<D> locator(lattice);
    for (std::size_t i = 0; i < mPoints.size(); ++i) {
        if (!(mWeights[i] >= 0) || !std::isfinite(mWeights[i]) || !std::isfinite(mValues[i]) ||
            !mPoints[i].allFinite() || !(mFields[i] < mTargets.size())) {
            OPENVDB_THROW(openvdb::ValueError, "inner distance: point "
                                                   << i + 1
                                                   << " has a weight < 0, a value, weight or "
                                                      "coordinate that is not finite, or a field "
                                                      "index out of range");
        }
        Location loc;
        if (!locator.locate(mPoints[i], loc)) {
            OPENVDB_THROW(openvdb::ValueError,
                          "inner distance: point " << i + 1 << " lies outside the lattice");
        }
        mLocations.push_back(loc);
    }
}

template <int D>
Real
InnerDistanceTerm<D>::evaluate(const NodeVectors<D>& u, NodeVectors<D>* gradient) const
{
    Real sum = 0;
    Vec<D> grad;
    for (std::size_t i = 0; i < mPoints.size(); ++i) {
        const Location& loc = mLocations[i];
        const Vec<D> y =
            mPoints[i] + multiscale::PiecewiseLinearInterpolator<D>::interpolate(u, loc);
        Real f;
        mTargets[mFields[i]]->sample(y, f, gradient ? &grad : nullptr);
        const Real r = f - mValues[i];
        const Real excess = std::abs(r) - mTolerance;
        if (!(excess > 0)) continue;
        sum += mWeights[i] * excess * excess;
        if (!gradient) continue;
        const Vec<D> g = (2 * mWeights[i] * (r > 0 ? excess : -excess)) * grad;
        for (int m = 0; m <= D; ++m)
            if (loc.weights[m] != 0) gradient->col(loc.nodes[m]) += loc.weights[m] * g;
    }
    return sum;
}

template <int D>
void
InnerDistanceTerm<D>::residual(const NodeVectors<D>& u, Real& mean, Real& beyondTolerance) const
{
    mean = beyondTolerance = 0;
    Real total = 0;
    for (std::size_t i = 0; i < mPoints.size(); ++i) {
        const Vec<D> y =
            mPoints[i] + multiscale::PiecewiseLinearInterpolator<D>::interpolate(u, mLocations[i]);
        Real f;
        mTargets[mFields[i]]->sample(y, f);
        const Real r = std::abs(f - mValues[i]);
        mean += mWeights[i] * r;
        if (r > mTolerance) beyondTolerance += mWeights[i];
        total += mWeights[i];
    }
    if (total > 0) {
        mean /= total;
        beyondTolerance /= total;
    }
}

template class InnerDistanceTerm<2>;
template class InnerDistanceTerm<3>;

} // namespace energy
} // namespace vdbmatch
