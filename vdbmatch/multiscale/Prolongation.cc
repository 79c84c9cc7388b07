/// @file Prolongation.cc
#include "Prolongation.h"

#include <openvdb/Exceptions.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vdbmatch {
namespace multiscale {

template <int D>
PiecewiseLinearInterpolator<D>::PiecewiseLinearInterpolator(const SimplexLattice<D>& lattice)
    : mLattice(&lattice)
{
    const auto& cells = lattice.cells();
    for (std::size_t ci = 0; ci < cells.size(); ++ci) {
        const int s = cells[ci].log2Size;
        if (std::size_t(s) >= mCellIndex.size()) mCellIndex.resize(std::size_t(s) + 1);
        if (!mCellIndex[s]) mCellIndex[s] = openvdb::Int32Grid::create(-1);
        mCellIndex[s]->tree().setValueOn(cells[ci].origin >> s, int32_t(ci));
    }
}

template <int D>
Vec<D>
PiecewiseLinearInterpolator<D>::interpolate(const NodeVectors<D>& u, const Location& loc)
{
    Vec<D> v = Vec<D>::Zero();
    for (int m = 0; m <= D; ++m)
        if (loc.weights[m] != 0) v += loc.weights[m] * u.col(loc.nodes[m]);
    return v;
}

template <int D>
bool
PiecewiseLinearInterpolator<D>::locate(const Vec<D>& x, Location& loc) const
{
    return locateWith(x, loc, [this](std::size_t s, const openvdb::Coord& c) {
        return mCellIndex[s]->tree().getValue(c);
    });
}

template <int D>
PiecewiseLinearInterpolator<D>::Cursor::Cursor(const PiecewiseLinearInterpolator& interpolator)
    : mInterpolator(&interpolator)
{
    for (const auto& grid : interpolator.mCellIndex)
        mAccessors.push_back(
            grid ? std::make_unique<openvdb::Int32Grid::ConstAccessor>(grid->constTree())
                 : nullptr);
}

template <int D>
bool
PiecewiseLinearInterpolator<D>::Cursor::locate(const Vec<D>& x, Location& loc)
{
    return mInterpolator->locateWith(x, loc, [this](std::size_t s, const openvdb::Coord& c) {
        return mAccessors[s]->getValue(c);
    });
}

template <int D>
bool
PiecewiseLinearInterpolator<D>::Cursor::evaluate(const NodeVectors<D>& u, const Vec<D>& x,
                                                 Vec<D>& value)
{
    Location loc;
    if (!locate(x, loc)) return false;
    value = interpolate(u, loc);
    return true;
}

template <int D>
int32_t
PiecewiseLinearInterpolator<D>::Cursor::cell(const Vec<D>& x)
{
    Location loc;
    int32_t found = -1;
    mInterpolator->locateWith(
        x, loc,
        [this](std::size_t s, const openvdb::Coord& c) { return mAccessors[s]->getValue(c); },
        &found);
    return found;
}

template <int D>
void
PiecewiseLinearInterpolator<D>::simplexIn(const typename SimplexLattice<D>::Cell& cell,
                                          const Vec<D>& p, Location& loc)
{
    const Real side = Real(1 << cell.log2Size);
    Vec<D> t;
    for (int a = 0; a < D; ++a)
        t[a] = (p[a] - Real(cell.origin[a])) / side;
    // Axes by decreasing t, ties in axis order: the Kuhn path through the simplex containing t.
    // (Insertion sort: stable like std::stable_sort, which allocates a buffer at every call; the
    // dense output grid calls this at every node.)
    std::array<int, D> order;
    std::iota(order.begin(), order.end(), 0);
    for (int i = 1; i < D; ++i)
        for (int j = i; j > 0 && t[order[j]] > t[order[j - 1]]; --j)
            std::swap(order[j], order[j - 1]);
    int mask = 0;
    loc.nodes[0] = cell.corners[0];
    loc.weights[0] = 1 - t[order[0]];
    for (int m = 1; m <= D; ++m) {
        mask |= 1 << order[m - 1];
        loc.nodes[m] = cell.corners[mask];
        loc.weights[m] = m < D ? t[order[m - 1]] - t[order[m]] : t[order[D - 1]];
    }
}

template <int D>
void
PiecewiseLinearInterpolator<D>::locateInCell(std::size_t cellIndex, const Vec<D>& x,
                                             Location& loc) const
{
    // The same index coordinates as locateWith().
    simplexIn(mLattice->cells()[cellIndex], x * Real(mLattice->resolution()), loc);
}

template <int D>
std::vector<typename PiecewiseLinearInterpolator<D>::Location>
PiecewiseLinearInterpolator<D>::cellTable(int log2Size)
{
    // A cell at the origin whose corner c is node c: simplexIn's t = (p - origin) / side is then
    // l / side, exactly as for any cell of this size at any origin (integers, a power of two).
    typename SimplexLattice<D>::Cell cell{};
    cell.log2Size = log2Size;
    for (int c = 0; c < SimplexLattice<D>::CORNERS; ++c)
        cell.corners[std::size_t(c)] = c;
    const std::size_t side = std::size_t(1) << log2Size;
    std::size_t count = 1;
    for (int a = 0; a < D; ++a)
        count *= side;
    std::vector<Location> table(count);
    for (std::size_t e = 0; e < count; ++e) {
        Vec<D> p;
        std::size_t rest = e;
        for (int a = 0; a < D; ++a) {
            p[a] = Real(rest % side);
            rest /= side;
        }
        simplexIn(cell, p, table[e]);
    }
    return table;
}

template <int D>
template <typename CellAt>
bool
PiecewiseLinearInterpolator<D>::locateWith(const Vec<D>& x, Location& loc, CellAt&& cellAt,
                                           int32_t* found) const
{
    for (int a = 0; a < D; ++a)
        if (!(x[a] >= 0 && x[a] <= 1)) return false;
    const auto& L = *mLattice;
    // Index coordinates at the lattice level: exact for dyadic x.
    const Vec<D> p = x * Real(L.resolution());
    for (std::size_t s = 0; s < mCellIndex.size(); ++s) {
        if (!mCellIndex[s]) continue;
        const Real side = Real(1 << s);
        openvdb::Coord base(0);
        int faceAxes = 0; // bit a: p lies on a cell boundary along axis a
        for (int a = 0; a < D; ++a) {
            const Real q = p[a] / side;
            const Real f = std::floor(q);
            base[a] = int(f);
            if (q == f) faceAxes |= 1 << a;
        }
        // Candidates: base, and base - 1 along any subset of the face axes.
        for (int sub = 0; sub < (1 << D); ++sub) {
            if ((sub & faceAxes) != sub) continue;
            openvdb::Coord c = base;
            for (int a = 0; a < D; ++a)
                if (sub & (1 << a)) c[a] -= 1;
            const int32_t ci = cellAt(s, c);
            if (ci < 0) continue;
            simplexIn(L.cells()[std::size_t(ci)], p, loc);
            if (found) *found = ci;
            return true;
        }
    }
    return false;
}

template <int D>
bool
PiecewiseLinearInterpolator<D>::evaluate(const NodeVectors<D>& u, const Vec<D>& x,
                                         Vec<D>& value) const
{
    Location loc;
    if (!locate(x, loc)) return false;
    value = interpolate(u, loc);
    return true;
}

template <int D>
NodeVectors<D>
prolongate(const SimplexLattice<D>& coarse, const NodeVectors<D>& uCoarse,
           const SimplexLattice<D>& fine, bool threaded)
{
    if (fine.level() < coarse.level())
        OPENVDB_THROW(openvdb::ValueError, "prolongate: the fine lattice (level "
                                               << fine.level()
                                               << ") is coarser than the coarse one (level "
                                               << coarse.level() << ")");
    if (std::size_t(uCoarse.cols()) != coarse.nodeCount() || uCoarse.rows() != D)
        OPENVDB_THROW(openvdb::ValueError, "prolongate: expected "
                                               << D << " x " << coarse.nodeCount()
                                               << " coarse values, got " << uCoarse.rows() << " x "
                                               << uCoarse.cols());
    const PiecewiseLinearInterpolator<D> interpolator(coarse);
    NodeVectors<D> u = NodeVectors<D>::Zero(D, fine.nodeCount());
    auto body = [&](const tbb::blocked_range<std::size_t>& r) {
        typename PiecewiseLinearInterpolator<D>::Cursor cursor(interpolator);
        Vec<D> value;
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            if (cursor.evaluate(uCoarse, fine.nodePosition(i), value)) u.col(i) = value;
    };
    const tbb::blocked_range<std::size_t> range(0, fine.nodeCount(), 1024);
    if (threaded)
        tbb::parallel_for(range, body);
    else
        body(range);
    return u;
}

template class PiecewiseLinearInterpolator<2>;
template class PiecewiseLinearInterpolator<3>;
template NodeVectors<2> prolongate<2>(const SimplexLattice<2>&, const NodeVectors<2>&,
                                      const SimplexLattice<2>&, bool);
template NodeVectors<3> prolongate<3>(const SimplexLattice<3>&, const NodeVectors<3>&,
                                      const SimplexLattice<3>&, bool);

} // namespace multiscale
} // namespace vdbmatch
