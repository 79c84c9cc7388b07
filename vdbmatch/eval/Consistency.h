/// @file Consistency.h
/// @brief Inverse consistency and matching quality of a pair of deformations phi (M1 -> M2) and
///        psi (M2 -> M1), as in the paper's table tab:inverseError: |psi o phi - Id| and
///        |phi o psi - Id| over Omega and over the shapes, the residuals |d2 o phi| on M1 and
///        |d1 o psi| on M2, det D phi, det D psi statistics, and psi compared with the exact
///        inverse of phi.
///
/// Every composition is the exact evaluation of the piecewise-linear maps stored in the grids
/// (DeformationField: Kuhn simplices of the voxels, phi = Id outside Omega); no resampling.
///
/// Measures (world units, and divided by the domain size, the world side of Omega):
/// - over Omega: the points x = min + i s of Omega_phi (resp. Omega_psi), s = stride times the
///   finer of the two voxel sizes, i on every axis from 0 while x <= max;
///   @f[ \|e\|_{L^2} = \Big(\frac{1}{N}\sum_x |e(x)|^2\Big)^{1/2}, \quad
///       \|e\|_{L^\infty} = \max_x |e(x)| @f]
///   with e = psi(phi(x)) - x (resp. phi(psi(x)) - x): the L2 norm is a root mean square, i.e.
///   the L2 norm divided by sqrt(|Omega|), in the units of e;
/// - over a shape: mean and max of |e| over its vertices (mesh vertices, curve vertices, or the
///   vertices of the surface extracted from a level set input);
/// - residuals: |d2(phi(x))| over the vertices x of M1 and |d1(psi(y))| over the vertices y of
///   M2, with d_i the signed distance to M_i (ShapeDistance.h; accurate to about 1e-5 of the
///   domain at the default distance level);
/// - det D phi over every Kuhn simplex of every voxel cell of phi's grid (d! per cell, cells
///   between active voxels of the grid's bounding box): min, max, and the number and fraction of
///   simplices with det < DET_LOW_THRESHOLD and with det <= 0 (inverted or flat); the same for
///   psi;
/// - against the exact inverse phi^{-1} of phi (DeformationField::inverse: the walk through the
///   deformed Kuhn simplices, exact up to rounding where det D phi > 0; issue 9):
///   - the round trip e = phi^{-1}(phi(x)) - x over the sample points x of Omega_phi, each walk
///     starting from the fixed-point guess of DeformationField::inverse(y) (what
///     `vdb_match apply --inverse` does). It checks that the exact inverse is exact: phi and the
///     walk both work in double precision on the same stored values, so this is rounding error
///     (5e-16 of the domain on a 129^3 match);
///   - e = psi(y) - phi^{-1}(y) over the sample points y of Omega_psi (the norms above) and over
///     the vertices y of M2 (mean and max), each walk starting from psi(y): how far the reverse
///     match is from the exact inverse of the forward one. Since psi(phi(x)) - x =
///     (psi - phi^{-1})(phi(x)), |psi o phi - Id| is this same error sampled at the images
///     phi(x) of the regular points (denser where phi compresses) and at phi(M1) instead of M2;
///     phi(psi(y)) - y is about D phi (psi(y) - phi^{-1}(y)), the error after phi. Here it is
///     sampled uniformly in M2's space and on M2 itself;
///   - the number of walks that did not end (found == false: they met a simplex with
///     det D phi <= 0, where phi has no inverse); such points count with the last point the walk
///     reached.
///
/// Determinism: sums are accumulated per row of sample points and added in row order, and each
/// inverse walk starts from a guess that depends on its point only, so the result does not
/// depend on the number of threads.
/// @see paper tab:inverseError, sec:numerics
#pragma once

#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/io/DeformationField.h>

#include <openvdb/util/NullInterrupter.h>

#include <cstddef>

namespace vdbmatch {
namespace eval {

/// Threshold of the "low determinant" count: simplices compressed to less than 10% of their
/// volume (the paper's volume term keeps det well above it in its examples).
constexpr double DET_LOW_THRESHOLD = 0.1;

/// Options of measureConsistency().
struct ConsistencyOptions
{
    /// Omega is sampled every @a stride nodes of the finer of the two grids, >= 1.
    int stride = 1;
    /// Level of the distance samplers (ShapeDistance.h); 0: defaultDistanceLevel() of the finer
    /// deformation level.
    int distanceLevel = 0;
    bool threaded = true; ///< use TBB (the results do not depend on it)
};

/// Norms of an error over Omega, world units.
struct DomainError
{
    double l2 = 0;          ///< root mean square of |e| over the sample points
    double linf = 0;        ///< max |e|
    std::size_t points = 0; ///< number of sample points
};

/// Mean and max of a non-negative quantity over the vertices of a shape, world units.
struct VertexError
{
    double mean = 0;
    double max = 0;
    std::size_t points = 0;
};

/// det D of a deformation over the Kuhn simplices of its voxels.
struct JacobianStats
{
    double min = 1;
    double max = 1;
    std::size_t simplices = 0;
    std::size_t belowThreshold = 0; ///< det < DET_LOW_THRESHOLD
    std::size_t nonPositive = 0;    ///< det <= 0
    double fractionBelowThreshold() const
    {
        return simplices ? double(belowThreshold) / double(simplices) : 0.0;
    }
    double fractionNonPositive() const
    {
        return simplices ? double(nonPositive) / double(simplices) : 0.0;
    }
};

/// Everything measureConsistency() computes; lengths in world units.
struct ConsistencyReport
{
    int dim = 3;
    double domainSize = 1;    ///< world side of Omega (of phi's grid)
    double sampleSpacing = 0; ///< spacing of the Omega sample points, world units
    int distanceLevel = 0;    ///< level of the distance samplers
    double distanceVoxel = 0; ///< their finest node spacing, world units
    DomainError psiPhiDomain; ///< |psi(phi(x)) - x| over Omega
    VertexError psiPhiShape;  ///< |psi(phi(x)) - x| over the vertices of M1
    DomainError phiPsiDomain; ///< |phi(psi(y)) - y| over Omega
    VertexError phiPsiShape;  ///< |phi(psi(y)) - y| over the vertices of M2
    /// |phi^{-1}(phi(x)) - x| over Omega_phi, phi^{-1} the exact inverse (file comment)
    DomainError inverseRoundTripDomain;
    std::size_t inverseFailures = 0; ///< walks of inverseRoundTripDomain that did not end
    DomainError psiVsInverseDomain;  ///< |psi(y) - phi^{-1}(y)| over Omega_psi
    VertexError psiVsInverseShape;   ///< |psi(y) - phi^{-1}(y)| over the vertices of M2
    /// Walks of psiVsInverseDomain and psiVsInverseShape that did not end.
    std::size_t psiVsInverseFailures = 0;
    VertexError residualPhi;  ///< |d2(phi(x))| over the vertices of M1
    VertexError residualPsi;  ///< |d1(psi(y))| over the vertices of M2
    JacobianStats detPhi;     ///< det D phi
    JacobianStats detPsi;     ///< det D psi
    bool interrupted = false; ///< the interrupter fired: the figures are incomplete

    /// A world length as a fraction of the domain size.
    double relative(double worldLength) const { return worldLength / domainSize; }
};

/// Measures the inverse consistency and the matching quality of phi and psi (file comment).
/// @param phi, psi  deformations of M1 -> M2 and M2 -> M1 (DeformationField), same dimension D
/// @param m1, m2    the source and target shapes, world units, closed (checkSurface)
/// @param interrupter  checked once per row range; if it fires the result is returned with
///                     interrupted = true
/// @throw openvdb::ValueError if a deformation's dimension is not D, a shape lies outside
///        phi's domain, the stride or distance level is out of range, or a shape fails
///        checkSurface
template <int D>
ConsistencyReport measureConsistency(const DeformationField& phi, const DeformationField& psi,
                                     const Surface<D>& m1, const Surface<D>& m2,
                                     const ConsistencyOptions& options = ConsistencyOptions(),
                                     openvdb::util::NullInterrupter* interrupter = nullptr);

/// |psi(phi(x)) - x| over the regular points of phi's Omega with the given world spacing
/// (the Omega part of measureConsistency, exposed for tests).
/// @throw openvdb::ValueError if spacing is not positive and finite
DomainError compositionErrorOverDomain(const DeformationField& phi, const DeformationField& psi,
                                       double spacing, bool threaded = true,
                                       openvdb::util::NullInterrupter* interrupter = nullptr);

/// |phi^{-1}(phi(x)) - x| over the regular points of phi's Omega with the given world spacing,
/// phi^{-1} the exact inverse from its default guess (the round trip of measureConsistency,
/// exposed for tests).
/// @param failures  if not null, set to the number of walks that did not end
/// @throw openvdb::ValueError if spacing is not positive and finite
DomainError inverseRoundTripOverDomain(const DeformationField& phi, double spacing,
                                       std::size_t* failures = nullptr, bool threaded = true,
                                       openvdb::util::NullInterrupter* interrupter = nullptr);

/// |psi(y) - phi^{-1}(y)| over the regular points of psi's Omega with the given world spacing,
/// phi^{-1} the exact inverse, each walk starting from psi(y) (exposed for tests).
/// @param failures  if not null, set to the number of walks that did not end
/// @throw openvdb::ValueError if spacing is not positive and finite
DomainError psiVsInverseOverDomain(const DeformationField& phi, const DeformationField& psi,
                                   double spacing, std::size_t* failures = nullptr,
                                   bool threaded = true,
                                   openvdb::util::NullInterrupter* interrupter = nullptr);

/// det D statistics over the Kuhn simplices of every voxel cell of @a field's grid.
JacobianStats jacobianStats(const DeformationField& field, bool threaded = true,
                            openvdb::util::NullInterrupter* interrupter = nullptr);

extern template ConsistencyReport measureConsistency<2>(const DeformationField&,
                                                        const DeformationField&, const Surface<2>&,
                                                        const Surface<2>&,
                                                        const ConsistencyOptions&,
                                                        openvdb::util::NullInterrupter*);
extern template ConsistencyReport measureConsistency<3>(const DeformationField&,
                                                        const DeformationField&, const Surface<3>&,
                                                        const Surface<3>&,
                                                        const ConsistencyOptions&,
                                                        openvdb::util::NullInterrupter*);

} // namespace eval
} // namespace vdbmatch
