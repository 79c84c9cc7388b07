/// @file Camera.h
/// @brief A look-at camera (orthographic or perspective) for the software renderers, its
///        projection to pixel coordinates, and fitCamera(), which frames a bounding box.
///
/// Spaces: points are openvdb::Vec3d in world coordinates (the same units as the mesh; vdbmatch
/// meshes are in world units of the input grids). World axes follow OpenVDB / Houdini: y is up.
/// Pixel coordinates as in Canvas.h: x right, y down, pixel (i, j) centred at (i + 0.5, j + 0.5).
/// The view spans the shorter image side: orthoExtent world units (orthographic) or fovDegrees
/// (perspective) across min(width, height) pixels, centred on the image; pixels are square.
#pragma once

#include <openvdb/Types.h>

namespace vdbmatch {

struct Camera
{
    openvdb::Vec3d eye{0.0, 0.0, 5.0};    ///< camera position, world
    openvdb::Vec3d target{0.0, 0.0, 0.0}; ///< the point seen at the image centre, world
    openvdb::Vec3d up{0.0, 1.0, 0.0};     ///< world direction drawn upwards (need not be unit)
    bool perspective = false;
    double orthoExtent = 2.0; ///< orthographic: world units across the shorter image side
    double fovDegrees = 30.0; ///< perspective: full view angle across the shorter image side
};

/// A point projected by a Projector.
struct ProjectedPoint
{
    double x = 0.0, y = 0.0; ///< pixel coordinates
    double depth = 0.0;      ///< distance along the viewing direction from the eye, world units
};

/// Projects world points to pixels for a camera and an image size.
class Projector
{
public:
    /// @throw openvdb::ValueError if eye == target, up is zero or parallel to the viewing
    ///        direction, the image size is not positive, orthoExtent <= 0 (orthographic) or
    ///        fovDegrees is not in (0, 180) (perspective)
    Projector(const Camera& camera, int width, int height);

    /// Projects @a p; returns false if @a p is not in front of a perspective camera (depth below
    /// a small near distance). Orthographic projection accepts every point.
    bool project(const openvdb::Vec3d& p, ProjectedPoint& out) const;

    /// Unit direction from @a p towards the eye (a headlight): -forward for an orthographic
    /// camera, normalized eye - p for a perspective one.
    openvdb::Vec3d towardsEye(const openvdb::Vec3d& p) const;

    const openvdb::Vec3d& forward() const { return mForward; }
    bool isPerspective() const { return mCamera.perspective; }

private:
    Camera mCamera;
    openvdb::Vec3d mRight, mUp, mForward;
    double mCenterX, mCenterY;
    double mScale; ///< orthographic: pixels per world unit; perspective: focal length in pixels
    double mNear;  ///< perspective: smallest accepted depth
};

/// A camera looking along @a viewDirection (world, need not be unit) at the centre of @a box,
/// with @a up drawn upwards, framing the box's bounding sphere with a small margin for any image
/// aspect ratio. The eye is placed outside the bounding sphere.
/// @throw openvdb::ValueError if the box is empty or not finite, viewDirection is zero, or up is
///        zero or parallel to viewDirection
Camera fitCamera(const openvdb::BBoxd& box, const openvdb::Vec3d& viewDirection,
                 const openvdb::Vec3d& up, bool perspective = false, double fovDegrees = 30.0);

} // namespace vdbmatch
