/// @file AdaptiveLattice.cc
#include "AdaptiveLattice.h"

#include <vdbmatch/Parallel.h>

#include <openvdb/Exceptions.h>

#include <cmath>
#include <vector>

namespace vdbmatch {

namespace {

constexpr int MIN_LEVEL = 1;
constexpr int MAX_LEVEL = 12;

/// The 2^D children (voxel keys at side 2^{s-1}) of the cell with key @a key at side 2^s.
template <int D>
openvdb::Coord
childKey(const openvdb::Coord& key, int child)
{
    openvdb::Coord c = key << 1;
    for (int a = 0; a < D; ++a)
        if (child & (1 << a)) c[a] += 1;
    return c;
}

} // namespace

template <int D>
SimplexLattice<D>
buildAdaptiveLattice(int level, int coarsestLog2Size, const RefinementPredicate<D>& needsFine,
                     const SimplexLattice<D>* coarser, bool threaded)
{
    if (level < MIN_LEVEL || level > MAX_LEVEL)
        OPENVDB_THROW(openvdb::ValueError, "buildAdaptiveLattice: level must be in ["
                                               << MIN_LEVEL << ", " << MAX_LEVEL << "], got "
                                               << level);
    if (coarsestLog2Size < 0 || coarsestLog2Size > level)
        OPENVDB_THROW(openvdb::ValueError, "buildAdaptiveLattice: coarsestLog2Size must be in [0, "
                                               << level << "], got " << coarsestLog2Size);
    if (coarser && coarser->level() != level - 1)
        OPENVDB_THROW(openvdb::ValueError,
                      "buildAdaptiveLattice: the coarser lattice must have level "
                          << level - 1 << ", got " << coarser->level());
    const int c = coarsestLog2Size;
    const int n = 1 << level;
    const Real h = 1.0 / Real(n);

    // Cells of the coarser lattice, one key set per size (keys = origin / 2^t, level l-1 units).
    std::vector<openvdb::MaskTree::Ptr> coarseCells;
    if (coarser) {
        for (const auto& cell : coarser->cells()) {
            const auto t = std::size_t(cell.log2Size);
            if (t >= coarseCells.size()) coarseCells.resize(t + 1);
            if (!coarseCells[t]) coarseCells[t] = std::make_shared<openvdb::MaskTree>(false);
            coarseCells[t]->setValueOn(cell.origin >> cell.log2Size);
        }
    }
    // May the cell with key @a key at side 2^s (s >= 1) exist? Only inside one coarser cell of
    // side >= 2^{s-1} h_{l-1}. Thread-safe (const tree queries without accessors).
    auto nested = [&](const openvdb::Coord& key, int s) {
        if (!coarser) return true;
        const openvdb::Coord originCoarse = key
                                            << std::size_t(s - 1); // origin / 2, exact for s >= 1
        for (int t = s - 1; t < int(coarseCells.size()); ++t)
            if (coarseCells[t] && coarseCells[t]->isValueOn(originCoarse >> std::size_t(t)))
                return true;
        return false;
    };

    // 1.-2. Top-down: candidates at side 2^s, split ones recorded in split[s].
    std::vector<openvdb::MaskTree::Ptr> split(std::size_t(c) + 1);
    for (auto& tree : split)
        tree = std::make_shared<openvdb::MaskTree>(false);
    std::vector<openvdb::Coord> candidates;
    {
        const int m = n >> c;
        const int mz = D == 3 ? m : 1;
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j)
                for (int k = 0; k < mz; ++k)
                    candidates.emplace_back(i, j, k);
    }
    const Real radiusFactor = 0.5 * std::sqrt(Real(D));
    for (int s = c; s >= 1; --s) {
        const Real side = h * Real(1 << s);
        std::vector<char> flag(candidates.size(), 0);
        detail::forEachIndex(candidates.size(), threaded, [&](std::size_t i) {
            const openvdb::Coord& key = candidates[i];
            if (!nested(key, s)) {
                flag[i] = 1;
                return;
            }
            if (!needsFine) return;
            Vec<D> center;
            for (int a = 0; a < D; ++a)
                center[a] = (Real(key[a]) + 0.5) * side;
            flag[i] = needsFine(center, radiusFactor * side) ? 1 : 0;
        });
        std::vector<openvdb::Coord> next;
        openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(*split[s]);
        for (std::size_t i = 0; i < candidates.size(); ++i) {
            if (!flag[i]) continue;
            acc.setValueOn(candidates[i]);
            for (int child = 0; child < (1 << D); ++child)
                next.push_back(childKey<D>(candidates[i], child));
        }
        candidates.swap(next);
    }

    // 3. 2:1 balance: every 3^D - 1 neighbour (inside Omega) of a split cell of side 2^s exists,
    //    i.e. the cell of side 2^{s+1} containing it is split.
    for (int s = 1; s < c; ++s) {
        const int m = n >> s;
        openvdb::tree::ValueAccessor<openvdb::MaskTree> parentAcc(*split[s + 1]);
        for (auto v = split[s]->cbeginValueOn(); v; ++v) {
            const openvdb::Coord key = v.getCoord();
            const int neighbours = D == 3 ? 27 : 9;
            for (int q = 0; q < neighbours; ++q) {
                openvdb::Coord nb = key;
                int rest = q;
                bool inside = true;
                for (int a = 0; a < D; ++a) {
                    nb[a] += rest % 3 - 1;
                    rest /= 3;
                    inside = inside && nb[a] >= 0 && nb[a] < m;
                }
                if (inside) parentAcc.setValueOn(nb >> 1);
            }
        }
    }

    // 4. Leaves: unsplit cells at side 2^c, and unsplit children of split cells.
    std::vector<openvdb::MaskGrid::ConstPtr> masks(std::size_t(c) + 1);
    std::vector<openvdb::MaskGrid::Ptr> leaves(std::size_t(c) + 1);
    for (auto& grid : leaves)
        grid = openvdb::MaskGrid::create(false);
    {
        const int m = n >> c;
        const int mz = D == 3 ? m : 1;
        openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(leaves[c]->tree());
        for (int i = 0; i < m; ++i)
            for (int j = 0; j < m; ++j)
                for (int k = 0; k < mz; ++k) {
                    const openvdb::Coord key(i, j, k);
                    if (c == 0 || !split[c]->isValueOn(key)) acc.setValueOn(key);
                }
    }
    for (int s = c; s >= 1; --s) {
        openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(leaves[s - 1]->tree());
        openvdb::tree::ValueAccessor<const openvdb::MaskTree> below(*split[s - 1]);
        for (auto v = split[s]->cbeginValueOn(); v; ++v)
            for (int child = 0; child < (1 << D); ++child) {
                const openvdb::Coord key = childKey<D>(v.getCoord(), child);
                if (s - 1 == 0 || !below.isValueOn(key)) acc.setValueOn(key);
            }
    }
    for (std::size_t s = 0; s < leaves.size(); ++s)
        masks[s] = leaves[s];
    return SimplexLattice<D>::fromCellMasks(level, masks);
}

template SimplexLattice<2> buildAdaptiveLattice<2>(int, int, const RefinementPredicate<2>&,
                                                   const SimplexLattice<2>*, bool);
template SimplexLattice<3> buildAdaptiveLattice<3>(int, int, const RefinementPredicate<3>&,
                                                   const SimplexLattice<3>*, bool);

} // namespace vdbmatch
