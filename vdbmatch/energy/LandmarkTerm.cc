/// @file LandmarkTerm.cc
#include "LandmarkTerm.h"

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace vdbmatch {
namespace energy {

namespace {

template <int D>
std::string
format(const Vec<D>& x)
{
    std::ostringstream os;
    os << "(";
    for (int a = 0; a < D; ++a)
        os << (a ? ", " : "") << x[a];
    os << ")";
    return os.str();
}

} // namespace

template <int D>
LandmarkTerm<D>::LandmarkTerm(const SimplexLattice<D>& lattice, const LandmarkPairs<D>& pairs)
    : mSource(pairs.source), mTarget(pairs.target), mPairWeights(pairs.pairWeights),
      mWeight(pairs.weight)
{
    if (pairs.source.size() != pairs.target.size()) {
        OPENVDB_THROW(openvdb::ValueError,
                      "landmarks: " << pairs.source.size() << " source points but "
                                    << pairs.target.size() << " target points");
    }
    if (!(pairs.weight >= 0) || !std::isfinite(pairs.weight)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "landmarks: the weight must be finite and >= 0, got " << pairs.weight);
    }
    if (!mPairWeights.empty()) {
        if (mPairWeights.size() != mSource.size()) {
            OPENVDB_THROW(openvdb::ValueError, "landmarks: " << mPairWeights.size()
                                                             << " pair weights for "
                                                             << mSource.size() << " pairs");
        }
        for (Real w : mPairWeights) {
            if (!(w >= 0) || !std::isfinite(w)) {
                OPENVDB_THROW(openvdb::ValueError,
                              "landmarks: a pair weight must be finite and >= 0, got " << w);
            }
        }
    }
    const multiscale::PiecewiseLinearInterpolator<D> locator(lattice);
    for (std::size_t k = 0; k < mSource.size(); ++k) {
        if (!mSource[k].allFinite() || !mTarget[k].allFinite()) {
            OPENVDB_THROW(openvdb::ValueError,
                          "landmarks: pair " << k + 1 << " has a coordinate that is not finite");
        }
        Location loc;
        if (!locator.locate(mSource[k], loc)) {
            OPENVDB_THROW(openvdb::ValueError, "landmarks: source point "
                                                   << k + 1 << " " << format<D>(mSource[k])
                                                   << " (unit box) lies outside the lattice");
        }
        mLocations.push_back(loc);
    }
}

template <int D>
Vec<D>
LandmarkTerm<D>::mapped(const NodeVectors<D>& u, std::size_t k) const
{
    return mSource[k] + multiscale::PiecewiseLinearInterpolator<D>::interpolate(u, mLocations[k]);
}

template <int D>
Real
LandmarkTerm<D>::value(const NodeVectors<D>& u) const
{
    if (mTarget.empty()) return 0;
    Real sum = 0;
    if (!mPairWeights.empty()) {
        for (std::size_t k = 0; k < mTarget.size(); ++k)
            sum += mPairWeights[k] * (mapped(u, k) - mTarget[k]).squaredNorm();
        return sum; // as addGradient(), to the last bit
    }
    for (std::size_t k = 0; k < mTarget.size(); ++k)
        sum += (mapped(u, k) - mTarget[k]).squaredNorm();
    return (mWeight / Real(mTarget.size())) * sum; // as addGradient(), to the last bit
}

template <int D>
Real
LandmarkTerm<D>::addGradient(const NodeVectors<D>& u, NodeVectors<D>& gradient) const
{
    if (mTarget.empty()) return 0;
    if (!mPairWeights.empty()) {
        Real sum = 0;
        for (std::size_t k = 0; k < mTarget.size(); ++k) {
            const Vec<D> r = mapped(u, k) - mTarget[k];
            sum += mPairWeights[k] * r.squaredNorm();
            const Location& loc = mLocations[k];
            for (int m = 0; m <= D; ++m)
                if (loc.weights[m] != 0)
                    gradient.col(loc.nodes[m]) += (2 * mPairWeights[k] * loc.weights[m]) * r;
        }
        return sum;
    }
    const Real scale = mWeight / Real(mTarget.size());
    Real sum = 0;
    for (std::size_t k = 0; k < mTarget.size(); ++k) {
        const Vec<D> r = mapped(u, k) - mTarget[k];
        sum += r.squaredNorm();
        const Location& loc = mLocations[k];
        for (int m = 0; m <= D; ++m)
            if (loc.weights[m] != 0) gradient.col(loc.nodes[m]) += (2 * scale * loc.weights[m]) * r;
    }
    return scale * sum;
}

template <int D>
void
LandmarkTerm<D>::residual(const NodeVectors<D>& u, Real& mean, Real& max) const
{
    mean = max = 0;
    for (std::size_t k = 0; k < mTarget.size(); ++k) {
        const Real r = (mapped(u, k) - mTarget[k]).norm();
        mean += r;
        max = std::max(max, r);
    }
    if (!mTarget.empty()) mean /= Real(mTarget.size());
}

template class LandmarkTerm<2>;
template class LandmarkTerm<3>;

} // namespace energy
} // namespace vdbmatch
