/// @file Energy.h
/// @brief The discrete matching energy on a simplex lattice: the symmetric E^sigma of eq:Esym and
///        the directional comparison energy of eq:Ecomparison, value and exact gradient with
///        respect to the nodal displacements, assembled in parallel over cell blocks.
///
/// phi = Id + u with u continuous and linear on each Kuhn simplex of the lattice. On a simplex T
/// the deformation gradient A = D phi is constant; every term is integrated with the one-point
/// (centroid) rule: E_T = |T| e(A, x_T, phi(x_T)) with x_T the centroid of T. This is exact for
/// the volume terms (A constant) and second-order accurate for the band terms (docs/numerics.md).
/// The shapes enter only through two FieldSampler objects, so that d1, n1, S1 at x_T and d2, n2,
/// S2 at phi(x_T) (and the spatial derivatives of the latter) come from one C^1 interpolant per
/// field: the gradient is the exact derivative of the discrete energy.
///
/// A simplex with det A <= 0 makes the energy +inf (the gradient is then not computed).
/// Results do not depend on the number of threads: per-block partial sums are added in block
/// order and the gradient is gathered per node in block order.
/// @see paper eq:Esym, eq:EsymMatch, eq:EsymMem, eq:EsymBend, eq:EsymVol, eq:Ecomparison
#pragma once

#include <vdbmatch/Parameters.h>
#include <vdbmatch/ScratchBuffer.h>
#include <vdbmatch/energy/InnerDistanceTerm.h>
#include <vdbmatch/energy/LandmarkTerm.h>
#include <vdbmatch/geometry/FieldSampler.h>
#include <vdbmatch/kinematics/SurfaceFrame.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <openvdb/util/NullInterrupter.h>

#include <array>
#include <cstddef>
#include <vector>

namespace vdbmatch {

/// Value of every term, split in direct (index 0, weight eta_sigma(d1)) and inverse (index 1,
/// weight eta_sigma(d2 o phi)|det D phi|) halves, coefficients c_* included. For the directional
/// energy the inverse halves are 0 and vol[0] holds the W_vol term.
struct EnergyTerms
{
    Real match[2] = {0, 0};
    Real mem[2] = {0, 0};
    Real bend[2] = {0, 0};
    Real vol[2] = {0, 0};
    Real landmark = 0;      ///< E_lm (LandmarkTerm.h), an addition to the paper's terms; 0 without
    Real innerDistance = 0; ///< E_F (InnerDistanceTerm.h), an addition as well; 0 without
    std::size_t invertedSimplices = 0; ///< simplices with det D phi <= 0 (energy +inf)
    std::size_t bandSimplices = 0;     ///< simplices where a band term was evaluated
    /// ... of which in cells larger than h: the band reached beyond the fine region of an
    /// adaptive lattice (Match.h), where it is resolved more coarsely.
    std::size_t coarseBandSimplices = 0;

    Real total() const;
    EnergyTerms& operator+=(const EnergyTerms& o);
};

template <int D> class Energy
{
public:
    /// @param lattice  cells and nodes; must outlive the Energy
    /// @param shape1   fields of M1 (source), @param shape2 fields of M2 (target); must outlive it
    /// @param params   coefficients (validated here: throws openvdb::ValueError)
    /// @param kind     symmetric eq:Esym or directional eq:Ecomparison
    /// @param sigma    band half-width in Omega units; <= 0 selects params.sigmaFactor * h
    Energy(const SimplexLattice<D>& lattice, const FieldSampler<D>& shape1,
           const FieldSampler<D>& shape2, const EnergyParameters& params, EnergyKind kind,
           Real sigma = 0);

    Real sigma() const { return mSigma; }
    /// The energy of phi = Id when both shapes' band terms vanish: the constant part of E that no
    /// deformation changes by itself, c_vol sigma^theta W_vol(1) |lattice| for the directional
    /// energy (eq:EcomparisonVol: W_vol(1) = 13.39 in 3D, 2 in 2D), 0 for the symmetric one
    /// (W(1) = 0). Stopping tests subtract it so that both energies stop at equal convergence.
    Real constantOffset() const;
    EnergyKind kind() const { return mKind; }
    const SimplexLattice<D>& lattice() const { return *mLattice; }

    /// Energy of phi = Id + u (u: one column per lattice node, Omega units). +inf if a simplex
    /// is inverted. Throws openvdb::ValueError if a field is sampled outside its coverage.
    /// If the interrupter asks to stop, returns NaN-free +inf and sets @a terms to 0.
    Real value(const NodeVectors<D>& u, EnergyTerms* terms = nullptr, bool threaded = true,
               openvdb::util::NullInterrupter* interrupter = nullptr) const;

    /// Energy and its gradient with respect to every nodal displacement (Dirichlet nodes
    /// included; the solver discards them). When the energy is +inf the gradient is left 0.
    Real valueAndGradient(const NodeVectors<D>& u, NodeVectors<D>& gradient,
                          EnergyTerms* terms = nullptr, bool threaded = true,
                          openvdb::util::NullInterrupter* interrupter = nullptr) const;

    /// Smallest det D phi over all simplices (may be <= 0).
    Real minJacobianDeterminant(const NodeVectors<D>& u, bool threaded = true) const;

    /// Cell culling of the inverse band (symmetric energy; on by default in 3D, off in 2D): d2 is
    /// sampled at the centroid of every simplex of a cell only if a conservative bound (one
    /// sample of d2 at the mean deformed corner, the 1-Lipschitz distance, the tier's
    /// interpolation slack) says the cell may meet the band |d2 o phi| < sigma. A 3D cell has 6
    /// simplices; a 2D cell only 2, and there the extra sample cost more than it saved (the 2D
    /// figure pair ran 8% faster without it, docs/performance.md). The value and gradient are
    /// the same with and without it (tests/energy/TestEnergy.cc compares them, in 2D and 3D).
    void setCellCulling(bool on) { mCullCells = on; }

    /// Adds E_lm of @a landmarks (on the same lattice; must outlive the energy) to every
    /// evaluation; null removes it.
    void setLandmarks(const energy::LandmarkTerm<D>* landmarks) { mLandmarks = landmarks; }
    /// Adds E_F of @a term (on the same lattice; must outlive the energy) to every evaluation;
    /// null removes it.
    void setInnerDistance(const energy::InnerDistanceTerm<D>* term) { mInnerDistance = term; }

private:
    /// The last sample of d2 of the inverse-band test at a simplex: where (y), |d2| there
    /// (rounded towards 0) and the tier of shape 2 used (-1: none yet).
    struct InverseBandSample
    {
        Vec<D> y;
        float absD2 = 0;
        int32_t tier = -1;
    };

    template <bool Grad>
    Real evaluate(const NodeVectors<D>& u, NodeVectors<D>* gradient, EnergyTerms* terms,
                  bool threaded, openvdb::util::NullInterrupter* interrupter) const;
    /// The loop over the simplices of one block (evaluateBlockBody), compiled for the baseline
    /// x86-64 (evaluateBlock) and, for 3D, also for x86-64-v3 with run-time selection
    /// (evaluateBlockClones); the same bits either way (Energy.cc).
    template <bool Grad>
    void evaluateBlock(std::size_t blockIndex, const NodeVectors<D>& u, EnergyTerms& terms,
                       NodeVectors<D>* perSlot, InverseBandSample* inverseBand) const;
    template <bool Grad>
    void evaluateBlockClones(std::size_t blockIndex, const NodeVectors<D>& u, EnergyTerms& terms,
                             NodeVectors<D>* perSlot, InverseBandSample* inverseBand) const;
    template <bool Grad>
    void evaluateBlockBody(std::size_t blockIndex, const NodeVectors<D>& u, EnergyTerms& terms,
                           NodeVectors<D>* perSlot, InverseBandSample* inverseBand) const;
    /// |d2(y)| < sigma at the deformed centroid y of a simplex outside the band of M1 (the
    /// inverse-band test). With @a last (that simplex's entry of the kept samples, or null), d2
    /// is not sampled when the last sample bounds it: same tier and stencil, and
    /// |d2(last.y)| - INVERSE_BAND_SLOPE |y - last.y| >= sigma. y moves by hundredths of a cell
    /// between evaluations, so this drops almost every sample (about half the simplices of a
    /// fine level take this test, and one in a thousand is in the band). The answer is the
    /// same either way.
    bool inInverseBand(const Vec<D>& y, InverseBandSample* last) const;
    /// Bound on the slope of the interpolated d2 used by inInverseBand: sqrt(D) times 2, twice
    /// what the node values of an exact distance allow (FieldSampler::sameStencil).
    static constexpr Real INVERSE_BAND_SLOPE = 4;

    /// Shape-1 geometry at the centroid of a simplex inside the band of M1: it does not depend on
    /// phi, so it is sampled once, when the Energy is built. T+ and T- are stored as packed
    /// symmetric matrices.
    struct SourcePoint
    {
        static constexpr int SYM = D * (D + 1) / 2;
        Real d;
        Vec<D> n;
        Eigen::Matrix<Real, SYM, 1> Tp, Tm;
    };

    /// Centroid of simplex p of cell ci, Omega units (the quadrature point x_T).
    Vec<D> centroid(std::size_t ci, std::size_t p) const;
    /// May a simplex of the cell (origin, side, corner displacements uc) have |d2(phi(x_T))| <
    /// sigma? False only when certainly not (setCellCulling).
    bool cellMayReachBand2(const Vec<D>& origin, Real side,
                           const std::array<Vec<D>, SimplexLattice<D>::CORNERS>& uc) const;
    /// Slack of the culling bound, in voxels of the tier of shape 2 sampled at the cell: covers
    /// the interpolation error of that tier and of the finest one (both far below a voxel).
    static constexpr Real CULL_SLACK_VOXELS = 2;
    bool mCullCells = D == 3; ///< setCellCulling
    void cacheSourceGeometry();
    /// Frame of shape 1 at x: from the cache when the simplex is in the band of M1, sampled
    /// otherwise.
    void sourceFrame(std::size_t simplex, const Vec<D>& x, kinematics::SurfaceFrame<D>& f) const;

    /// The per-slot gradient array of valueAndGradient, kept between evaluations so that a
    /// descent does not allocate (and fault in) tens of MB per iteration. One buffer; an
    /// evaluation that finds it taken (a concurrent one) allocates its own.
    detail::ScratchBuffer<NodeVectors<D>> mSlotBuffer;
    /// The last inverse-band sample per simplex (inInverseBand), kept between evaluations; an
    /// evaluation that finds it taken (a concurrent one) samples every simplex.
    detail::ScratchBuffer<std::vector<InverseBandSample>> mInverseBandBuffer;

    const SimplexLattice<D>* mLattice;
    std::vector<int32_t> mSourceIndex; ///< per simplex (cell * SIMPLICES + p): index or -1
    std::vector<SourcePoint> mSource;
    const FieldSampler<D>* mShape1;
    const FieldSampler<D>* mShape2;
    EnergyParameters mParams;
    EnergyKind mKind;
    Real mSigma;
    const energy::LandmarkTerm<D>* mLandmarks = nullptr;
    const energy::InnerDistanceTerm<D>* mInnerDistance = nullptr;
    Real mMatchWeight;  ///< c_match sigma^{-q}
    Real mVolumeWeight; ///< c_vol sigma^theta
};

} // namespace vdbmatch
