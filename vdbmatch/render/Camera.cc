/// @file Camera.cc
/// @brief Look-at camera projection and framing.
#include "Camera.h"

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace vdbmatch {

namespace {

/// Relative size of the margin around a framed bounding sphere.
constexpr double FRAME_MARGIN = 1.08;
/// The eye of a fitted orthographic camera sits this many bounding radii from the centre.
constexpr double ORTHO_EYE_DISTANCE_RADII = 3.0;
/// Perspective near distance, as a fraction of the eye-target distance.
constexpr double NEAR_FRACTION = 1e-3;
/// |cos| of the angle between up and the viewing direction above which they count as parallel.
constexpr double PARALLEL_COSINE = 1.0 - 1e-9;
constexpr double DEG_TO_RAD = 3.14159265358979323846 / 180.0;

} // namespace

Projector::Projector(const Camera& camera, int width, int height) : mCamera(camera)
{
    if (width <= 0 || height <= 0) {
        OPENVDB_THROW(openvdb::ValueError, "Projector: image size " + std::to_string(width) +
                                               " x " + std::to_string(height) + " is not positive");
    }
    const openvdb::Vec3d view = camera.target - camera.eye;
    const double distance = view.length();
    if (!(distance > 0.0) || !std::isfinite(distance)) {
        OPENVDB_THROW(openvdb::ValueError, "Projector: the camera eye and target coincide");
    }
    mForward = view / distance;
    const double upLength = camera.up.length();
    if (!(upLength > 0.0) || std::abs(mForward.dot(camera.up / upLength)) > PARALLEL_COSINE) {
        OPENVDB_THROW(openvdb::ValueError,
                      "Projector: the camera up vector is zero or parallel to the view direction");
    }
    mRight = mForward.cross(camera.up);
    mRight.normalize();
    mUp = mRight.cross(mForward);
    mCenterX = 0.5 * width;
    mCenterY = 0.5 * height;
    const double shortSide = std::min(width, height);
    if (camera.perspective) {
        if (!(camera.fovDegrees > 0.0 && camera.fovDegrees < 180.0)) {
            OPENVDB_THROW(openvdb::ValueError,
                          "Projector: fovDegrees = " + std::to_string(camera.fovDegrees) +
                              " is not in (0, 180)");
        }
        mScale = 0.5 * shortSide / std::tan(0.5 * camera.fovDegrees * DEG_TO_RAD);
        mNear = NEAR_FRACTION * distance;
    } else {
        if (!(camera.orthoExtent > 0.0) || !std::isfinite(camera.orthoExtent)) {
            OPENVDB_THROW(openvdb::ValueError,
                          "Projector: orthoExtent = " + std::to_string(camera.orthoExtent) +
                              " is not positive");
        }
        mScale = shortSide / camera.orthoExtent;
        mNear = 0.0;
    }
}

bool
Projector::project(const openvdb::Vec3d& p, ProjectedPoint& out) const
{
    const openvdb::Vec3d d = p - mCamera.eye;
    const double xc = d.dot(mRight), yc = d.dot(mUp), zc = d.dot(mForward);
    double s = mScale;
    if (mCamera.perspective) {
        if (!(zc > mNear)) return false;
        s = mScale / zc;
    }
    out.x = mCenterX + s * xc;
    out.y = mCenterY - s * yc;
    out.depth = zc;
    return std::isfinite(out.x) && std::isfinite(out.y);
}

openvdb::Vec3d
Projector::towardsEye(const openvdb::Vec3d& p) const
{
    if (!mCamera.perspective) return -mForward;
    openvdb::Vec3d d = mCamera.eye - p;
    const double length = d.length();
    return length > 0.0 ? d / length : -mForward;
}

Camera
fitCamera(const openvdb::BBoxd& box, const openvdb::Vec3d& viewDirection, const openvdb::Vec3d& up,
          bool perspective, double fovDegrees)
{
    const openvdb::Vec3d extent = box.max() - box.min();
    if (!(extent.x() >= 0.0 && extent.y() >= 0.0 && extent.z() >= 0.0) ||
        !std::isfinite(extent.length())) {
        OPENVDB_THROW(openvdb::ValueError, "fitCamera: the bounding box is empty or not finite");
    }
    const double viewLength = viewDirection.length();
    if (!(viewLength > 0.0)) {
        OPENVDB_THROW(openvdb::ValueError, "fitCamera: the view direction is zero");
    }
    const openvdb::Vec3d dir = viewDirection / viewLength;
    const double upLength = up.length();
    if (!(upLength > 0.0) || std::abs(dir.dot(up / upLength)) > PARALLEL_COSINE) {
        OPENVDB_THROW(openvdb::ValueError,
                      "fitCamera: the up vector is zero or parallel to the view direction");
    }
    // A degenerate (flat or point) box still gets a positive radius.
    const double radius = std::max(0.5 * extent.length(), 1e-9);
    Camera camera;
    camera.target = box.getCenter();
    camera.up = up;
    camera.perspective = perspective;
    camera.fovDegrees = fovDegrees;
    if (perspective) {
        if (!(fovDegrees > 0.0 && fovDegrees < 180.0)) {
            OPENVDB_THROW(openvdb::ValueError,
                          "fitCamera: fovDegrees = " + std::to_string(fovDegrees) +
                              " is not in (0, 180)");
        }
        // The bounding sphere subtends the half angle when seen from this distance.
        const double distance = FRAME_MARGIN * radius / std::sin(0.5 * fovDegrees * DEG_TO_RAD);
        camera.eye = camera.target - dir * distance;
    } else {
        camera.orthoExtent = 2.0 * FRAME_MARGIN * radius;
        camera.eye = camera.target - dir * (ORTHO_EYE_DISTANCE_RADII * radius);
    }
    return camera;
}

} // namespace vdbmatch
