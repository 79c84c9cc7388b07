/// @file Rasterizer.h
/// @brief A small software rasterizer for triangle meshes with per-vertex colours (e.g. a
///        textured source surface and its image under phi): z-buffered, flat Lambert + ambient
///        shading with a headlight, optional 2x2 supersampling; and a strip of standard views.
///
/// Spaces and formats: points are openvdb::Vec3d in world coordinates, y up (Camera.h);
/// triangles index the points (any winding: faces are lit from both sides); colours are sRGB
/// bytes per vertex, interpolated across each face (perspective-correct) and multiplied by the
/// face's shade ambient + (1 - ambient) |n . l|, l the direction to the eye. Triangles with a
/// vertex behind a perspective camera's near distance are skipped (no clipping).
#pragma once

#include <vdbmatch/render/Camera.h>
#include <vdbmatch/render/Canvas.h>

#include <array>
#include <cstdint>
#include <vector>

namespace vdbmatch {

struct RenderOptions
{
    Rgb8 background{255, 255, 255};
    bool supersample = true;          ///< render at 2x2 samples per pixel and box-filter
    double ambient = 0.3;             ///< shade of a face seen edge-on, in [0, 1]
    Rgb8 defaultColor{200, 200, 200}; ///< used when no per-vertex colours are given
};

/// Renders a triangle mesh into a @a width x @a height image.
/// @param colors  one colour per point, or empty for RenderOptions::defaultColor
/// @throw openvdb::ValueError if colors is neither empty nor one per point, a triangle index is
///        out of range, the camera is invalid (Projector) or the size is not positive
Image8 renderMesh(const std::vector<openvdb::Vec3d>& points,
                  const std::vector<std::array<std::int32_t, 3>>& triangles,
                  const std::vector<Rgb8>& colors, const Camera& camera, int width, int height,
                  const RenderOptions& options = {});

/// The standard viewpoints of renderViews(), all framing the mesh's bounding box (fitCamera):
/// Front looks along -z (from +z), Side along -x (from +x), Top along -y with -z drawn up, and
/// ThreeQuarter from (+x, +y, +z) towards the centre; y is drawn up except in Top.
enum class StandardView { Front, Side, Top, ThreeQuarter };

/// Camera for a standard view of @a box.
Camera standardViewCamera(const openvdb::BBoxd& box, StandardView view, bool perspective = false);

/// Renders the mesh from Front, Side, Top and ThreeQuarter, each into a @a viewSize square,
/// side by side left to right (separated by a one-pixel grey line), with the view names drawn
/// in the top-left corner of each if @a labels. The image is 4 * viewSize + 3 wide.
/// @throw as renderMesh(); also if the mesh has no points
Image8 renderViews(const std::vector<openvdb::Vec3d>& points,
                   const std::vector<std::array<std::int32_t, 3>>& triangles,
                   const std::vector<Rgb8>& colors, int viewSize, const RenderOptions& options = {},
                   bool perspective = false, bool labels = true);

/// As above, but every view frames @a frame (world) instead of the mesh's bounding box, so that
/// several meshes (e.g. a shape and its image under a deformation) can be drawn at one scale.
/// @throw as renderViews(); also if @a frame is empty or not finite (fitCamera)
Image8 renderViews(const std::vector<openvdb::Vec3d>& points,
                   const std::vector<std::array<std::int32_t, 3>>& triangles,
                   const std::vector<Rgb8>& colors, const openvdb::BBoxd& frame, int viewSize,
                   const RenderOptions& options = {}, bool perspective = false, bool labels = true);

} // namespace vdbmatch
