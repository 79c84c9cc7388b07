/// @file SimplexLattice.cc
#include "SimplexLattice.h"

#include <vdbmatch/Assert.h>

#include <openvdb/Exceptions.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <numeric>
#include <utility>

namespace vdbmatch {

namespace {

constexpr int MIN_LEVEL = 1;
constexpr int MAX_LEVEL = 12;
/// Nesting depth beyond which a hanging-node constraint chain is malformed (a chain climbs one
/// cell size per step, and there are at most MAX_LEVEL + 1 sizes).
constexpr int MAX_CONSTRAINT_DEPTH = MAX_LEVEL + 1;

/// Number of trailing zero bits of c >= 0 (a large number for c = 0).
inline int
trailingZeros(int c)
{
    if (c == 0) return 8 * int(sizeof(int));
    int k = 0;
    while (!(c & 1)) {
        c >>= 1;
        ++k;
    }
    return k;
}

/// Outcome of classifying one node in fromCellMasks().
enum class NodeClass : char { Regular, Hanging, Overlap, Unbalanced };

template <int D>
std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)>
makeKuhn(bool wantAxis)
{
    std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)> out{};
    std::array<int, D> perm;
    std::iota(perm.begin(), perm.end(), 0);
    int p = 0;
    do {
        int mask = 0;
        out[p][0] = wantAxis ? -1 : 0;
        for (int m = 1; m <= D; ++m) {
            mask |= 1 << perm[m - 1];
            out[p][m] = wantAxis ? perm[m - 1] : mask;
        }
        ++p;
    } while (std::next_permutation(perm.begin(), perm.end()));
    return out;
}

} // namespace

template <int D>
const std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)>&
KuhnSplit<D>::path()
{
    static const auto table = makeKuhn<D>(false);
    return table;
}

template <int D>
const std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)>&
KuhnSplit<D>::axis()
{
    static const auto table = makeKuhn<D>(true);
    return table;
}

template <int D>
Vec<D>
SimplexLattice<D>::nodePosition(std::size_t i) const
{
    Vec<D> x;
    for (int a = 0; a < D; ++a)
        x[a] = mNodeCoords[i][a] * mH;
    return x;
}

template <int D>
NodeVectors<D>
SimplexLattice<D>::nodePositions() const
{
    NodeVectors<D> X(D, nodeCount());
    for (std::size_t i = 0; i < nodeCount(); ++i)
        X.col(i) = nodePosition(i);
    return X;
}

template <int D>
bool
SimplexLattice<D>::isBoundaryNode(std::size_t i) const
{
    const int n = resolution();
    for (int a = 0; a < D; ++a) {
        const int c = mNodeCoords[i][a];
        if (c <= 0 || c >= n) return true;
    }
    return false;
}

template <int D>
int32_t
SimplexLattice<D>::findNode(const openvdb::Coord& ijk) const
{
    return mNodeIndex->tree().getValue(ijk);
}

template <int D>
SimplexLattice<D>
SimplexLattice<D>::dense(int level)
{
    const int n = 1 << level;
    return box(level, openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(n - 1)));
}

template <int D>
SimplexLattice<D>
SimplexLattice<D>::box(int level, const openvdb::CoordBBox& bbox)
{
    if (level < MIN_LEVEL || level > MAX_LEVEL)
        OPENVDB_THROW(openvdb::ValueError, "SimplexLattice::box: level must be in ["
                                               << MIN_LEVEL << ", " << MAX_LEVEL << "], got "
                                               << level);
    const int n = 1 << level;
    openvdb::Coord lo = openvdb::Coord::maxComponent(bbox.min(), openvdb::Coord(0));
    openvdb::Coord hi = openvdb::Coord::minComponent(bbox.max(), openvdb::Coord(n - 1));
    if (D == 2) lo.z() = hi.z() = 0;
    auto mask = openvdb::MaskGrid::create(false);
    if (lo.x() <= hi.x() && lo.y() <= hi.y() && lo.z() <= hi.z()) {
        mask->tree().denseFill(openvdb::CoordBBox(lo, hi), true, true);
    }
    return fromCellMasks(level, {mask});
}

template <int D>
SimplexLattice<D>
SimplexLattice<D>::fromCellMasks(int level, const std::vector<openvdb::MaskGrid::ConstPtr>& masks)
{
    if (level < MIN_LEVEL || level > MAX_LEVEL)
        OPENVDB_THROW(openvdb::ValueError, "SimplexLattice::fromCellMasks: level must be in ["
                                               << MIN_LEVEL << ", " << MAX_LEVEL << "], got "
                                               << level);
    SimplexLattice L;
    L.mLevel = level;
    L.mH = 1.0 / Real(1 << level);
    const int n = 1 << level;

    // 1. Cells, block by block (one block per leaf node of each mask), in a fixed order.
    std::vector<char> hasCells(masks.size(), 0);
    for (std::size_t s = 0; s < masks.size(); ++s) {
        if (!masks[s]) continue;
        const int side = 1 << s;
        openvdb::MaskTree tree(masks[s]->tree());
        tree.voxelizeActiveTiles();
        for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
            Block b{L.mCells.size(), 0, 0, 0};
            for (auto v = leaf->cbeginValueOn(); v; ++v) {
                Cell c;
                c.origin = v.getCoord() << s;
                if (D == 2) {
                    if (v.getCoord().z() != 0) continue;
                    c.origin.z() = 0;
                }
                for (int a = 0; a < D; ++a) {
                    if (c.origin[a] < 0 || c.origin[a] + side > n)
                        OPENVDB_THROW(openvdb::ValueError, "SimplexLattice::fromCellMasks: cell "
                                                               << c.origin << " of side " << side
                                                               << " lies outside the unit box");
                }
                c.log2Size = int(s);
                L.mCells.push_back(c);
                hasCells[s] = 1;
            }
            b.cellEnd = L.mCells.size();
            if (b.cellEnd > b.cellBegin) L.mBlocks.push_back(b);
        }
    }

    // Small lattices (the coarse levels) have few leaves, too few blocks to keep two threads
    // busy: blocks are split into slabs of at most cellCount / MIN_BLOCKS cells (not below
    // MIN_BLOCK_CELLS), in the same fixed order. Large lattices keep one block per leaf, which
    // shares the most nodes between the cells of a block.
    {
        constexpr std::size_t MIN_BLOCKS = 64, MIN_BLOCK_CELLS = 32;
        const std::size_t maxCells = std::max(MIN_BLOCK_CELLS, L.mCells.size() / MIN_BLOCKS);
        std::vector<Block> split;
        for (const Block& b : L.mBlocks) {
            const std::size_t count = b.cellEnd - b.cellBegin;
            const std::size_t pieces = (count + maxCells - 1) / maxCells;
            for (std::size_t k = 0; k < pieces; ++k)
                split.push_back(Block{b.cellBegin + count * k / pieces,
                                      b.cellBegin + count * (k + 1) / pieces, 0, 0});
        }
        L.mBlocks.swap(split);
    }

    // 2. Nodes: every cell corner, numbered in the leaf order of a node mask.
    auto cornerCoord = [](const Cell& c, int corner) {
        openvdb::Coord ijk = c.origin;
        for (int a = 0; a < D; ++a)
            if (corner & (1 << a)) ijk[a] += 1 << c.log2Size;
        return ijk;
    };
    auto nodeMask = openvdb::MaskGrid::create(false);
    {
        auto acc = nodeMask->getAccessor();
        for (const Cell& c : L.mCells)
            for (int k = 0; k < CORNERS; ++k)
                acc.setValueOn(cornerCoord(c, k));
    }
    L.mNodeIndex = openvdb::Int32Grid::create(-1);
    L.mNodeIndex->tree().topologyUnion(nodeMask->tree());
    {
        auto acc = L.mNodeIndex->getAccessor();
        int32_t next = 0;
        for (auto leaf = L.mNodeIndex->tree().beginLeaf(); leaf; ++leaf) {
            for (auto v = leaf->beginValueOn(); v; ++v) {
                v.setValue(next++);
                L.mNodeCoords.push_back(v.getCoord());
            }
        }
    }

    // 3. Corner node indices, and per block the sorted list of touched nodes (slots).
    std::vector<std::vector<int32_t>> blockNodes(L.mBlocks.size());
    L.mCellSlots.resize(L.mCells.size() * CORNERS);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, L.mBlocks.size()),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          openvdb::Int32Grid::ConstAccessor acc = L.mNodeIndex->getConstAccessor();
                          for (std::size_t bi = r.begin(); bi != r.end(); ++bi) {
                              const Block& b = L.mBlocks[bi];
                              auto& nodes = blockNodes[bi];
                              for (std::size_t ci = b.cellBegin; ci < b.cellEnd; ++ci) {
                                  Cell& c = L.mCells[ci];
                                  for (int k = 0; k < CORNERS; ++k) {
                                      c.corners[k] = acc.getValue(cornerCoord(c, k));
                                      nodes.push_back(c.corners[k]);
                                  }
                              }
                              std::sort(nodes.begin(), nodes.end());
                              nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
                          }
                      });
    std::size_t slots = 0;
    for (std::size_t bi = 0; bi < L.mBlocks.size(); ++bi) {
        L.mBlocks[bi].slotBegin = slots;
        slots += blockNodes[bi].size();
        L.mBlocks[bi].slotEnd = slots;
    }
    L.mSlotNodes.resize(slots);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, L.mBlocks.size()),
        [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t bi = r.begin(); bi != r.end(); ++bi) {
                const Block& b = L.mBlocks[bi];
                const auto& nodes = blockNodes[bi];
                std::copy(nodes.begin(), nodes.end(), L.mSlotNodes.begin() + b.slotBegin);
                for (std::size_t ci = b.cellBegin; ci < b.cellEnd; ++ci) {
                    for (int k = 0; k < CORNERS; ++k) {
                        auto it =
                            std::lower_bound(nodes.begin(), nodes.end(), L.mCells[ci].corners[k]);
                        L.mCellSlots[ci * CORNERS + k] =
                            int32_t(b.slotBegin + (it - nodes.begin()));
                    }
                }
            }
        });

    L.findHangingNodes(masks, hasCells);

    // 4. Gather lists: for each node, its slots in block order.
    L.mGatherBegin.assign(L.nodeCount() + 1, 0);
    for (int32_t node : L.mSlotNodes)
        ++L.mGatherBegin[node + 1];
    std::partial_sum(L.mGatherBegin.begin(), L.mGatherBegin.end(), L.mGatherBegin.begin());
    L.mGatherSlots.resize(slots);
    std::vector<std::size_t> fill(L.mGatherBegin.begin(), L.mGatherBegin.end() - 1);
    for (std::size_t s = 0; s < slots; ++s)
        L.mGatherSlots[fill[L.mSlotNodes[s]]++] = int32_t(s);
    return L;
}

template <int D>
void
SimplexLattice<D>::findHangingNodes(const std::vector<openvdb::MaskGrid::ConstPtr>& masks,
                                    const std::vector<char>& hasCells)
{
    const std::size_t n = nodeCount();
    mHangingIndex.assign(n, -1);
    mHangingNodes.clear();
    mConstraintOffsets.assign(1, 0);
    mConstraintMasters.clear();
    mConstraintWeights.clear();
    int maxLog2Size = -1;
    for (std::size_t s = 0; s < hasCells.size(); ++s)
        if (hasCells[s]) maxLog2Size = int(s);

    // 1. Per node, the direct constraint: a node p inside an edge or face of a cell of side
    //    2^s (s > the trailing zeros of some coordinate of p, else p can only be a corner).
    //    Along the "unaligned" axes (p not a multiple of 2^s) p must be the midpoint; its masters
    //    are p rounded down / up to multiples of 2^s along those axes (edge endpoints, or the
    //    face's min and max corners).
    std::vector<std::array<int32_t, 2>> direct(n, {-1, -1});
    std::vector<NodeClass> nodeClass(n, NodeClass::Regular);
    if (maxLog2Size >= 1) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& r) {
            std::vector<std::unique_ptr<openvdb::tree::ValueAccessor<const openvdb::MaskTree>>>
                cellAcc(std::size_t(maxLog2Size) + 1);
            for (int s = 1; s <= maxLog2Size; ++s)
                if (hasCells[s])
                    cellAcc[s] =
                        std::make_unique<openvdb::tree::ValueAccessor<const openvdb::MaskTree>>(
                            masks[s]->tree());
            openvdb::Int32Grid::ConstAccessor nodeAcc = mNodeIndex->getConstAccessor();
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const openvdb::Coord& p = mNodeCoords[i];
                int k = trailingZeros(p[0]);
                for (int a = 1; a < D; ++a)
                    k = std::min(k, trailingZeros(p[a]));
                for (int s = k + 1; s <= maxLog2Size; ++s) {
                    if (!hasCells[s]) continue;
                    const int side = 1 << s;
                    int aligned = 0;
                    openvdb::Coord base(0);
                    for (int a = 0; a < D; ++a) {
                        base[a] = p[a] >> s;
                        if ((p[a] & (side - 1)) == 0) aligned |= 1 << a;
                    }
                    bool found = false;
                    for (int sub = 0; sub < (1 << D) && !found; ++sub) {
                        if ((sub & aligned) != sub) continue;
                        openvdb::Coord c = base;
                        for (int a = 0; a < D; ++a)
                            if (sub & (1 << a)) c[a] -= 1;
                        found = cellAcc[s]->isValueOn(c);
                    }
                    if (!found) continue;
                    if (aligned == 0 || nodeClass[i] != NodeClass::Regular) {
                        nodeClass[i] = aligned == 0 ? NodeClass::Overlap : NodeClass::Unbalanced;
                        break;
                    }
                    openvdb::Coord lo = p, hi = p;
                    for (int a = 0; a < D; ++a) {
                        if (aligned & (1 << a)) continue;
                        if ((p[a] & (side - 1)) != side / 2) nodeClass[i] = NodeClass::Unbalanced;
                        lo[a] = base[a] << s;
                        hi[a] = lo[a] + side;
                    }
                    if (nodeClass[i] == NodeClass::Unbalanced) break;
                    nodeClass[i] = NodeClass::Hanging;
                    direct[i] = {nodeAcc.getValue(lo), nodeAcc.getValue(hi)};
                }
            }
        });
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (nodeClass[i] == NodeClass::Overlap)
            OPENVDB_THROW(openvdb::ValueError, "SimplexLattice::fromCellMasks: node "
                                                   << mNodeCoords[i]
                                                   << " lies inside a cell: overlapping cells");
        if (nodeClass[i] == NodeClass::Unbalanced)
            OPENVDB_THROW(openvdb::ValueError,
                          "SimplexLattice::fromCellMasks: node "
                              << mNodeCoords[i]
                              << " lies inside an edge or face of a cell other than at its "
                                 "midpoint: the cells violate the 2:1 balance");
        VDBMATCH_ASSERT(nodeClass[i] != NodeClass::Hanging ||
                        (direct[i][0] >= 0 && direct[i][1] >= 0));
    }

    // 2. Transitive resolution (masters of masters), in node order: each chain climbs to
    //    strictly larger cells, so it ends at non-hanging nodes.
    std::vector<std::pair<int32_t, Real>> terms;
    std::function<void(int32_t, Real, int)> push = [&](int32_t node, Real w, int depth) {
        if (depth > MAX_CONSTRAINT_DEPTH)
            OPENVDB_THROW(openvdb::ValueError,
                          "SimplexLattice::fromCellMasks: hanging-node constraints do not "
                          "resolve at node "
                              << mNodeCoords[std::size_t(node)]);
        const auto& m = direct[std::size_t(node)];
        if (m[0] < 0) {
            terms.emplace_back(node, w);
            return;
        }
        push(m[0], 0.5 * w, depth + 1);
        push(m[1], 0.5 * w, depth + 1);
    };
    for (std::size_t i = 0; i < n; ++i) {
        if (direct[i][0] < 0) continue;
        terms.clear();
        push(int32_t(i), 1.0, 0);
        std::sort(terms.begin(), terms.end());
        mHangingIndex[i] = int32_t(mHangingNodes.size());
        mHangingNodes.push_back(int32_t(i));
        for (std::size_t t = 0; t < terms.size(); ++t) {
            if (t > 0 && terms[t].first == terms[t - 1].first)
                mConstraintWeights.back() += terms[t].second;
            else {
                mConstraintMasters.push_back(terms[t].first);
                mConstraintWeights.push_back(terms[t].second);
            }
        }
        mConstraintOffsets.push_back(mConstraintMasters.size());
    }
    mFreeNodeCount = 0;
    for (std::size_t i = 0; i < n; ++i)
        mFreeNodeCount += isFreeNode(i);
}

template <int D>
void
SimplexLattice<D>::expand(NodeVectors<D>& u) const
{
    VDBMATCH_ASSERT(std::size_t(u.cols()) == nodeCount());
    for (std::size_t k = 0; k < mHangingNodes.size(); ++k) {
        Vec<D> value = Vec<D>::Zero();
        for (std::size_t j = mConstraintOffsets[k]; j < mConstraintOffsets[k + 1]; ++j)
            value += mConstraintWeights[j] * u.col(mConstraintMasters[j]);
        u.col(mHangingNodes[k]) = value;
    }
}

template <int D>
void
SimplexLattice<D>::reduce(NodeVectors<D>& g) const
{
    VDBMATCH_ASSERT(std::size_t(g.cols()) == nodeCount());
    for (std::size_t k = 0; k < mHangingNodes.size(); ++k) {
        const Vec<D> gh = g.col(mHangingNodes[k]);
        for (std::size_t j = mConstraintOffsets[k]; j < mConstraintOffsets[k + 1]; ++j)
            g.col(mConstraintMasters[j]) += mConstraintWeights[j] * gh;
        g.col(mHangingNodes[k]).setZero();
    }
}

template <int D>
LatticeStats
SimplexLattice<D>::stats() const
{
    LatticeStats st;
    for (const Cell& c : mCells) {
        if (std::size_t(c.log2Size) >= st.cellsPerLog2Size.size())
            st.cellsPerLog2Size.resize(std::size_t(c.log2Size) + 1, 0);
        ++st.cellsPerLog2Size[std::size_t(c.log2Size)];
    }
    st.nodes = nodeCount();
    st.freeNodes = freeNodeCount();
    st.hangingNodes = hangingNodeCount();
    for (std::size_t i = 0; i < nodeCount(); ++i)
        st.boundaryNodes += isBoundaryNode(i);
    st.denseNodes = 1;
    for (int a = 0; a < D; ++a)
        st.denseNodes *= std::size_t(resolution() + 1);
    return st;
}

template <int D>
void
SimplexLattice<D>::gatherSlots(const NodeVectors<D>& perSlot, NodeVectors<D>& out,
                               bool threaded) const
{
    out.resize(D, nodeCount());
    auto body = [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            Vec<D> g = Vec<D>::Zero();
            for (std::size_t k = mGatherBegin[i]; k < mGatherBegin[i + 1]; ++k)
                g += perSlot.col(mGatherSlots[k]);
            out.col(i) = g;
        }
    };
    const tbb::blocked_range<std::size_t> range(0, nodeCount(), 1024);
    if (threaded)
        tbb::parallel_for(range, body);
    else
        body(range);
}

template <int D>
openvdb::Vec3dGrid::Ptr
SimplexLattice<D>::toGrid(const NodeVectors<D>& u) const
{
    if (std::size_t(u.cols()) != nodeCount())
        OPENVDB_THROW(openvdb::ValueError, "SimplexLattice::toGrid: expected "
                                               << nodeCount() << " node values, got " << u.cols());
    auto grid = openvdb::Vec3dGrid::create(openvdb::Vec3d(0.0));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(mH));
    grid->setName("displacement");
    grid->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    grid->tree().topologyUnion(mNodeIndex->tree());
    auto acc = mNodeIndex->getConstAccessor();
    for (auto leaf = grid->tree().beginLeaf(); leaf; ++leaf) {
        for (auto v = leaf->beginValueOn(); v; ++v) {
            const int32_t i = acc.getValue(v.getCoord());
            openvdb::Vec3d value(0.0);
            for (int a = 0; a < D; ++a)
                value[a] = u(a, i);
            v.setValue(value);
        }
    }
    return grid;
}

template <int D>
NodeVectors<D>
SimplexLattice<D>::fromGrid(const openvdb::Vec3dGrid& grid) const
{
    const openvdb::Vec3d vs = grid.voxelSize();
    if (std::abs(vs[0] - mH) > 1e-12 * mH || !grid.hasUniformVoxels())
        OPENVDB_THROW(openvdb::ValueError, "SimplexLattice::fromGrid: expected uniform voxel size "
                                               << mH << ", got " << vs);
    NodeVectors<D> u = NodeVectors<D>::Zero(D, nodeCount());
    auto acc = grid.getConstAccessor();
    for (std::size_t i = 0; i < nodeCount(); ++i) {
        openvdb::Vec3d value;
        if (acc.probeValue(mNodeCoords[i], value))
            for (int a = 0; a < D; ++a)
                u(a, i) = value[a];
    }
    return u;
}

template class SimplexLattice<2>;
template class SimplexLattice<3>;
template struct KuhnSplit<2>;
template struct KuhnSplit<3>;

} // namespace vdbmatch
