/// @file SliceImage.h
/// @brief Pictures of a deformation on an axis-aligned plane of Omega: the float channels
///        inverse_error, residual, det, displacement, d1 and d2 sampled on a regular pixel grid
///        (for an OpenEXR file), and a preview picture of one channel with the shapes' outlines.
///
/// Plane: 3D, the plane {x_axis = position} of Omega with image columns along the next axis and
/// rows along the one after (axis z: columns x, rows y; axis x: columns y, rows z; axis y:
/// columns z, rows x), row 0 at the top (the largest row coordinate); 2D, the plane of the
/// deformation itself (columns x, rows y). Pixel (c, r) samples the world point at its centre,
/// origin + ((c + 1/2) p, (H - r - 1/2) p) in (column, row) coordinates, p the pixel size: by
/// default the deformation grid's voxel size (one pixel per voxel cell), or the side of Omega
/// divided by the requested resolution.
///
/// Channels (world units; see SLICE_CHANNELS):
/// - d1, d2: signed distance to M1, M2 (ShapeDistance.h: exact on the nodes of a band around the
///   shape, coarser tiers over the rest of Omega, quasi-interpolated between nodes), < 0 inside;
/// - residual: d2(phi(x)) - d1(x), 0 where phi maps the level sets of d1 onto those of d2 (in
///   particular M1 onto M2);
/// - det: det D phi on the Kuhn simplex of the voxel cell that contains x (DeformationField);
/// - displacement: |phi(x) - x|;
/// - inverse_error: |psi(phi(x)) - x|, only when psi is given.
/// Every value is finite: phi = Id outside its grid and the distances are defined everywhere.
/// @see paper tab:inverseError, sec:numerics
#pragma once

#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/ImageIO.h>
#include <vdbmatch/render/Canvas.h>

#include <openvdb/util/NullInterrupter.h>

#include <optional>
#include <string>

namespace vdbmatch {
namespace eval {

/// Channel names, in the order of SliceImage::image (inverse_error only with psi).
constexpr const char* SLICE_CHANNELS[] = {"d1",  "d2",       "displacement",
                                          "det", "residual", "inverse_error"};

/// Largest number of pixels along a side of a slice.
constexpr int MAX_SLICE_RESOLUTION = 16384;

/// Options of sampleSlice().
struct SliceOptions
{
    /// Normal of the plane: 0 (x), 1 (y) or 2 (z); unset: z. 2D: unset or 2.
    std::optional<int> axis;
    /// World coordinate of the plane along the axis (3D).
    std::optional<double> position;
    /// Position as a fraction of Omega along the axis, in [0, 1] (3D; not with position).
    /// Neither: the centre of M1's bounding box along the axis.
    std::optional<double> unitPosition;
    /// Pixels along the longer side of the plane, in [2, MAX_SLICE_RESOLUTION]; 0: one pixel per
    /// voxel of phi's grid.
    int resolution = 0;
    /// Level of the distance samplers (ShapeDistance.h); 0: defaultDistanceLevel().
    int distanceLevel = 0;
    bool threaded = true; ///< use TBB (the result does not depend on it)
};

/// A sampled slice.
struct SliceImage
{
    ImageChannels image;        ///< the channels, world units
    int dim = 3;                ///< of the deformation
    int axis = 2;               ///< normal of the plane
    int columnAxis = 0;         ///< world axis along image columns
    int rowAxis = 1;            ///< world axis along image rows (upwards)
    double position = 0;        ///< world coordinate of the plane along axis
    double unitPosition = 0;    ///< the same as a fraction of Omega along axis
    double pixelSize = 0;       ///< world units
    openvdb::Vec3d origin{0.0}; ///< world corner of the picture (bottom left, on the plane)
    double domainSize = 1;      ///< world side of Omega
};

/// Samples the channels of the file comment on a plane of phi's Omega.
/// @param phi   deformation M1 -> M2
/// @param psi   deformation M2 -> M1 (may be null: no inverse_error channel)
/// @param m1, m2  source and target shapes in world units, same dimension as phi
/// @throw openvdb::ValueError on a dimension mismatch, an axis not in {0, 1, 2} (2D: not 2),
///        a position outside Omega or both position and unitPosition, a resolution out of
///        range, shapes outside Omega, or a shape failing checkSurface
template <int D>
SliceImage sampleSlice(const DeformationField& phi, const DeformationField* psi,
                       const Surface<D>& m1, const Surface<D>& m2,
                       const SliceOptions& options = SliceOptions(),
                       openvdb::util::NullInterrupter* interrupter = nullptr);

/// True for the signed channels (residual, d1, d2), drawn with the diverging map around 0.
bool isSignedChannel(const std::string& channel);

/// The preview picture of one channel (render/Preview.h): diverging colour map with the range
/// [-m, m] (m the largest |value|) for signed channels, inferno over [min, max] otherwise; the
/// zero contours of d1 (green) and d2 (magenta); the title names the channel, the plane and the
/// units.
/// @throw openvdb::ValueError if the slice has no such channel
Image8 renderSlicePreview(const SliceImage& slice, const std::string& channel);

/// Contour colours of the previews.
constexpr Rgb8 SLICE_M1_COLOR = {0, 170, 0};
constexpr Rgb8 SLICE_M2_COLOR = {200, 0, 200};

extern template SliceImage sampleSlice<2>(const DeformationField&, const DeformationField*,
                                          const Surface<2>&, const Surface<2>&, const SliceOptions&,
                                          openvdb::util::NullInterrupter*);
extern template SliceImage sampleSlice<3>(const DeformationField&, const DeformationField*,
                                          const Surface<3>&, const Surface<3>&, const SliceOptions&,
                                          openvdb::util::NullInterrupter*);

} // namespace eval
} // namespace vdbmatch
