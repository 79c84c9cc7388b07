#include <vdbmatch/geometry/ExtremityMatching.h>

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace vdbmatch {

template <int D>
ExtremityPairing
matchExtremities(const Extremities<D>& a, const Extremities<D>& b,
                 const ExtremityMatchOptions& opts)
{
    if (!(opts.maxDistortion >= 0 && std::isfinite(opts.maxDistortion) && opts.tolerance >= 0 &&
          std::isfinite(opts.tolerance))) {
        OPENVDB_THROW(openvdb::ValueError,
                      "matchExtremities: maxDistortion and tolerance must be finite and >= 0");
    }
    ExtremityPairing out;
    const std::size_t k = a.size();
    if (k != b.size()) {
        std::ostringstream s;
        s << "the shapes have " << k << " and " << b.size() << " extremities";
        out.reason = s.str();
        return out;
    }
    if (k < 2 || k > MAX_EXTREMITIES) {
        std::ostringstream s;
        s << "the shapes have " << k << " extremities (2 to " << MAX_EXTREMITIES << " are paired)";
        out.reason = s.str();
        return out;
    }
    double scale = 0;
    for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = i + 1; j < k; ++j)
            scale += 0.5 * (a.innerDistance(i, j) + b.innerDistance(i, j));
    }
    std::vector<std::size_t> perm(k);
    std::iota(perm.begin(), perm.end(), std::size_t(0));
    struct Scored
    {
        double distortion, motion;
        std::vector<std::size_t> perm;
    };
    std::vector<Scored> scored;
    do {
        double c = 0, m = 0;
        for (std::size_t i = 0; i < k; ++i) {
            for (std::size_t j = i + 1; j < k; ++j)
                c += std::abs(a.innerDistance(i, j) - b.innerDistance(perm[i], perm[j]));
            m += (a.points[i] - b.points[perm[i]]).squaredNorm();
        }
        scored.push_back({c / scale, m, perm});
    } while (std::next_permutation(perm.begin(), perm.end()));

    out.leastDistortion = scored.front().distortion;
    for (const Scored& s : scored)
        out.leastDistortion = std::min(out.leastDistortion, s.distortion);
    if (!(out.leastDistortion <= opts.maxDistortion)) {
        std::ostringstream s;
        s << "the inner distances between the extremities differ by " << out.leastDistortion
          << " (relative) at best, more than " << opts.maxDistortion;
        out.reason = s.str();
        return out;
    }
    const Scored* best = nullptr;
    for (const Scored& s : scored) {
        if (!(s.distortion <= out.leastDistortion + opts.tolerance)) continue;
        ++out.candidates;
        if (!best || s.motion < best->motion) best = &s; // the first in lexicographic order
    }
    out.ok = true;
    out.distortion = best->distortion;
    for (std::size_t i = 0; i < k; ++i)
        out.pairs.emplace_back(i, best->perm[i]);
    return out;
}

template ExtremityPairing matchExtremities<2>(const Extremities<2>&, const Extremities<2>&,
                                              const ExtremityMatchOptions&);
template ExtremityPairing matchExtremities<3>(const Extremities<3>&, const Extremities<3>&,
                                              const ExtremityMatchOptions&);

} // namespace vdbmatch
