/// @file ShapeFields.h
/// @brief Per-node geometric fields of a shape, computed from its signed-distance grid.
///
/// For the signed distance d of a shape (negative inside, paper [subsec:notation]) sampled on the
/// nodes of a level-set `openvdb::FloatGrid`, every node whose finite-difference stencil consists
/// of active voxels gets
/// - d, the distance value itself,
/// - n = ∇d / |∇d|, the unit outer normal of the offset surface through the node (central
///   differences); where the discrete gradient (nearly) vanishes, on the medial axis, n = e_x so
///   that d stays available there,
/// - R = S^{1/2} with S the regularized shape operator of eq:defSi,
///   @f[ S = \mathcal{R}\big(D^2 d + n \otimes n\big)
///         := Q^T \mathrm{diag}\big(\max(|\lambda_1|,\tau), \dots, \max(|\lambda_D|,\tau)\big) Q,
///   @f]
///   with D²d from second central differences (mixed derivatives: 4-point stencil).
///
/// Spaces and units: node ijk sits at world position ijk*h (the grid's linear transform is a
/// pure uniform scale), so the grid's world space is the Omega space of vdbmatch. d is in world
/// units, n is dimensionless, S and τ are in 1/length, R in 1/sqrt(length). In 2D (D == 2) only
/// the k = 0 slice of the grid is read.
///
/// @see paper [subsec:notation], [subsec:tangential], [eq:defSi], [eq:regularizedGaussianCurvs]
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/math/MatrixOps.h>

#include <Eigen/Eigenvalues>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace vdbmatch {

/// Default τ of eq:defSi in 1/length (Omega units).
/// @note The paper gives no value for τ. With 1, curvature radii larger than the unit box count
/// as flat, and the factor S^{-1/2} of Λ [eq:lambdadef] stays <= 1 on flat parts of the shapes,
/// whose curvatures in the unit box are of order 1-100. EnergyParameters::tau uses this value.
constexpr Real DEFAULT_SHAPE_OPERATOR_TAU = 1.0;

/// Options for the computation of the shape fields.
struct ShapeFieldOptions
{
    /// τ > 0 of eq:defSi, in 1/length (the grid's world units). Eigenvalues of D²d + n⊗n are
    /// replaced by max(|λ|, τ).
    Real tau = DEFAULT_SHAPE_OPERATOR_TAU;
    /// Number of iterations (>= 0) of separable binomial [1,2,1]/4 smoothing applied to the
    /// Hessian field D²d before the eigenvalue regularization. An axis pass changes a node only
    /// when both of its neighbours along that axis have a Hessian. Meant for signed distances
    /// computed from meshes, whose second differences are noisy.
    int hessianSmoothing = 0;
    /// Smoothing length s >= 0 (world units of the grid) of further passes, an addition to the
    /// paper: at voxel size h, min(round(2 s^2 / h^2), MAX_LENGTH_SMOOTHING_PASSES) passes, on top
    /// of hessianSmoothing. n passes are a binomial filter of variance n h^2 / 2 per axis, so the
    /// Hessian is smoothed over about the same length s at every level: none where s < h / 2
    /// (coarse levels, whose second differences amplify noise less), more at finer ones.
    /// match() sets it per shape from the shape's own noise (geometry/SurfaceNoise.h).
    Real hessianSmoothingLength = 0;
    /// Use TBB. The results do not depend on this flag or on the number of threads.
    bool threaded = true;
};

/// Most passes that ShapeFieldOptions::hessianSmoothingLength adds at one grid: a binomial
/// filter of width h sqrt(32) (5.7 voxels), enough for a scan's noise at the finest levels match()
/// accepts; a very coarse or faceted mesh, whose measured noise is large, costs at most this.
constexpr int MAX_LENGTH_SMOOTHING_PASSES = 64;

/// Passes that a smoothing length @a s adds at voxel size @a h:
/// min(round(2 s^2 / h^2), MAX_LENGTH_SMOOTHING_PASSES), 0 if s or h is not positive.
int lengthSmoothingPasses(double s, double h);

/// The larger of lengthSmoothingPasses(@a sourceLength, h) and lengthSmoothingPasses(
/// @a targetLength, h): the noise smoothing passes of a pair of shapes at voxel size @a h, which
/// the noise-adaptive bending weight reads (noiseBendingFactor, Parameters.h).
int pairSmoothingPasses(double sourceLength, double targetLength, double h);

/// Hessian smoothing passes of ShapeFields at voxel size @a h: opts.hessianSmoothing plus
/// lengthSmoothingPasses(opts.hessianSmoothingLength, h).
int hessianSmoothingPasses(const ShapeFieldOptions& opts, double h);

/// Fields at one node, in the grid's world (Omega) units.
template <int D> struct NodeFields
{
    Real d;   ///< signed distance
    Vec<D> n; ///< unit normal ∇d/|∇d|
    Mat<D> R; ///< S^{1/2}, symmetric positive definite
};

////////////////////////////////////////////////////////////////////////////////
// Pointwise formulas

namespace detail {

/// Applies f to the eigenvalues of the symmetric matrix M: Q diag(f(λ_i)) Q^T. Uses Eigen's
/// closed-form (computeDirect) solver for 2x2 and 3x3 matrices.
template <int D, typename F>
inline Mat<D>
applyToEigenvalues(const Mat<D>& M, F&& f)
{
    Eigen::SelfAdjointEigenSolver<Mat<D>> solver;
    solver.computeDirect(M);
    Vec<D> values = solver.eigenvalues();
    for (int i = 0; i < D; ++i)
        values[i] = f(values[i]);
    const Mat<D>& Q = solver.eigenvectors();
    return Q * values.asDiagonal() * Q.transpose();
}

/// The regularized absolute value 𝓡 of eq:defSi: Q diag(max(|λ_i|, τ)) Q^T.
template <int D>
inline Mat<D>
regularizedAbs(const Mat<D>& M, Real tau)
{
    return applyToEigenvalues<D>(M, [tau](Real l) { return std::max(std::abs(l), tau); });
}

/// P H P + n⊗n with P = 1 - n⊗n. For an exact signed distance D²d n = 0, so this equals
/// D²d + n⊗n; with discrete Hessians it makes n an exact eigenvector with eigenvalue 1.
template <int D>
inline Mat<D>
shapeMatrix(const Mat<D>& hessian, const Vec<D>& n)
{
    const Mat<D> P = math::projection<D>(n);
    Mat<D> M = P * hessian * P + n * n.transpose();
    return Real(0.5) * (M + M.transpose());
}

} // namespace detail

/// The regularized shape operator S = 𝓡(D²d + n⊗n) of eq:defSi.
/// @param hessian  D²d at the point (symmetric), in 1/length
/// @param n        unit normal ∇d
/// @param tau      τ > 0 in 1/length
/// @note Deviation: D²d is replaced by P D²d P (P = 1 - n⊗n), which is the same matrix for an
/// exact signed distance (D²d n = 0) and keeps n an exact eigenvector with eigenvalue 1 (for
/// τ <= 1) under discretization error, as the paper assumes in [subsec:tangential].
/// @see paper [eq:defSi]
template <int D>
inline Mat<D>
regularizedShapeOperator(const Mat<D>& hessian, const Vec<D>& n, Real tau)
{
    return detail::regularizedAbs<D>(detail::shapeMatrix<D>(hessian, n), tau);
}

/// R = S^{1/2} for S = regularizedShapeOperator(hessian, n, tau), from one eigendecomposition:
/// Q diag(sqrt(max(|λ_i|, τ))) Q^T.
/// @see paper [eq:defSi], [eq:lambdadef]
template <int D>
inline Mat<D>
regularizedShapeOperatorSqrt(const Mat<D>& hessian, const Vec<D>& n, Real tau)
{
    return detail::applyToEigenvalues<D>(detail::shapeMatrix<D>(hessian, n), [tau](Real l) {
        return std::sqrt(std::max(std::abs(l), tau));
    });
}

/// Symmetric square root Q diag(sqrt(max(λ_i, 0))) Q^T of a symmetric positive semi-definite
/// matrix.
template <int D>
inline Mat<D>
symmetricSqrt(const Mat<D>& spd)
{
    return detail::applyToEigenvalues<D>(spd, [](Real l) { return std::sqrt(std::max(l, 0.0)); });
}

/// Regularized Gaussian curvature K = n^T cof(S) n of eq:regularizedGaussianCurvs. When n is an
/// eigenvector of S with eigenvalue 1 this is the product of the tangential eigenvalues.
/// @see paper [eq:regularizedGaussianCurvs]
template <int D>
inline Real
regularizedGaussianCurvature(const Mat<D>& S, const Vec<D>& n)
{
    return n.dot(math::cof(S) * n);
}

////////////////////////////////////////////////////////////////////////////////
// Fields of a grid

namespace detail {

/// Dense table of block indices over the bounding box of a set of block coordinates
/// (coordinates of blocks of 8^D nodes, i.e. node coordinates >> 3); -1 where there is no block.
class DenseBlockTable
{
public:
    /// Builds the table; blockCoords[i] gets index i. In 2D pass z = 0.
    void build(const std::vector<openvdb::Coord>& blockCoords);

    /// Index of the block at blockCoord, or -1.
    int32_t find(int bx, int by, int bz) const
    {
        const uint32_t x = uint32_t(bx - mMin[0]), y = uint32_t(by - mMin[1]);
        const uint32_t z = uint32_t(bz - mMin[2]);
        if (x >= mDim[0] || y >= mDim[1] || z >= mDim[2]) return -1;
        return mIndex[(size_t(z) * mDim[1] + y) * mDim[0] + x];
    }
    int32_t find(const openvdb::Coord& c) const { return find(c[0], c[1], c[2]); }

    bool empty() const { return mIndex.empty(); }
    /// Smallest and largest block coordinates covered (inclusive).
    openvdb::Coord minBlock() const { return mMin; }
    openvdb::Coord maxBlock() const
    {
        return mMin + openvdb::Coord(int(mDim[0]) - 1, int(mDim[1]) - 1, int(mDim[2]) - 1);
    }
    size_t memoryUsage() const { return mIndex.size() * sizeof(int32_t); }

private:
    openvdb::Coord mMin{0, 0, 0};
    std::array<uint32_t, 3> mDim{{0, 0, 0}};
    std::vector<int32_t> mIndex;
};

} // namespace detail

/// Per-node fields (d, n, R) of a shape, computed from a signed-distance level-set grid and stored
/// in blocks of 8^D nodes aligned with the grid's leaf nodes. Blocks without any valid node are
/// not stored. This is the input of FieldSampler.
///
/// Storage of a block: NUM_COMPONENTS floats per node, nodes ordered with x fastest
/// (local offset x + 8 (y + 8 z)). Components: d, n_0..n_{D-1}, then the upper triangle of R row by
/// row (R00, R01, R02, R11, R12, R22 in 3D; R00, R01, R11 in 2D). A node without fields has all
/// components NaN.
///
/// Thread-safety: immutable after construction.
template <int D> class ShapeFields
{
public:
    static_assert(D == 2 || D == 3, "ShapeFields: D must be 2 or 3");

    static constexpr int BLOCK_LOG2DIM = 3;
    static constexpr int BLOCK_DIM = 1 << BLOCK_LOG2DIM;
    static constexpr int BLOCK_NODES =
        D == 2 ? BLOCK_DIM * BLOCK_DIM : BLOCK_DIM * BLOCK_DIM * BLOCK_DIM;
    static constexpr int SYM_COMPONENTS = D * (D + 1) / 2;
    static constexpr int D_COMPONENT = 0;
    static constexpr int N_COMPONENT = 1;
    static constexpr int R_COMPONENT = 1 + D;
    static constexpr int NUM_COMPONENTS = 1 + D + SYM_COMPONENTS;

    /// Position of R(i,j) in the upper triangle storage (i, j in [0, D)).
    static constexpr int symIndex(int i, int j)
    {
        const int a = i < j ? i : j, b = i < j ? j : i;
        return a * D - a * (a - 1) / 2 + (b - a);
    }

    /// Computes the fields of @a grid.
    /// @param grid  level set (class GRID_LEVEL_SET), signed distance negative inside, uniform
    ///              voxel size h, index-to-world map ijk -> ijk*h (no translation or rotation).
    ///              Only active voxels are read as distances; in 2D only k = 0.
    /// @param opts  see ShapeFieldOptions
    /// @throw openvdb::ValueError if the grid is not a valid level set (tools::checkLevelSet,
    /// checks 1-8), its transform is not ijk -> ijk*h, or the options are invalid.
    ShapeFields(const openvdb::FloatGrid& grid, const ShapeFieldOptions& opts);

    /// Voxel size h of the input grid.
    Real voxelSize() const { return mVoxelSize; }
    /// Options used.
    const ShapeFieldOptions& options() const { return mOptions; }

    size_t blockCount() const { return mOrigins.size(); }
    /// Node coordinates of the first node of block i (multiples of 8; z = 0 in 2D).
    const openvdb::Coord& blockOrigin(size_t i) const { return mOrigins[i]; }
    /// The NUM_COMPONENTS * BLOCK_NODES floats of block i.
    const float* blockValues(size_t i) const
    {
        return mValues.data() + i * size_t(NUM_COMPONENTS * BLOCK_NODES);
    }
    /// Index of the block with the given block coordinates (node coordinates >> 3), or -1.
    int32_t findBlock(const openvdb::Coord& blockCoord) const { return mTable.find(blockCoord); }

    /// Pointer to the NUM_COMPONENTS floats of node ijk (k ignored in 2D), or nullptr when no
    /// block holds it. The node has fields iff the pointer is non-null and its d is not NaN.
    const float* nodeValues(const openvdb::Coord& ijk) const;

    /// Fields of node ijk (k ignored in 2D); false if the node has none.
    bool getNode(const openvdb::Coord& ijk, NodeFields<D>& fields) const;

    /// Number of nodes with fields.
    size_t validNodeCount() const { return mValidNodeCount; }

private:
    Real mVoxelSize = 0;
    ShapeFieldOptions mOptions;
    std::vector<openvdb::Coord> mOrigins;
    std::vector<float> mValues;
    detail::DenseBlockTable mTable;
    size_t mValidNodeCount = 0;
};

/// Checks that @a grid is usable as a signed distance by ShapeFields and FieldSampler and returns
/// its voxel size.
/// @param caller  function name used in the exception message
/// @throw openvdb::ValueError as ShapeFields::ShapeFields
Real validateDistanceGrid(const openvdb::FloatGrid& grid, const char* caller);

extern template class ShapeFields<2>;
extern template class ShapeFields<3>;

} // namespace vdbmatch
