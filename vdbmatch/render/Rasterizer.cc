/// @file Rasterizer.cc
/// @brief Z-buffered triangle rasterization with flat headlight shading; standard views.
#include "Rasterizer.h"

#include <vdbmatch/render/BitmapFont.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace vdbmatch {

namespace {

constexpr int SUPERSAMPLE = 2; ///< samples per pixel along each axis
constexpr Rgb8 SEPARATOR_COLOR = {160, 160, 160};
constexpr Rgb8 LABEL_COLOR = {40, 40, 40};
constexpr int LABEL_SCALE = 2;
constexpr int LABEL_MARGIN_PX = 6;
/// Viewing direction of the three-quarter view (from +x, +y, +z towards the centre).
const openvdb::Vec3d THREE_QUARTER_DIRECTION(-1.0, -0.7, -1.0);

inline double
edge(double ax, double ay, double bx, double by, double px, double py)
{
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

} // namespace

Image8
renderMesh(const std::vector<openvdb::Vec3d>& points,
           const std::vector<std::array<std::int32_t, 3>>& triangles,
           const std::vector<Rgb8>& colors, const Camera& camera, int width, int height,
           const RenderOptions& options)
{
    if (!colors.empty() && colors.size() != points.size()) {
        OPENVDB_THROW(openvdb::ValueError, "renderMesh: " + std::to_string(colors.size()) +
                                               " colours for " + std::to_string(points.size()) +
                                               " points");
    }
    for (const auto& t : triangles) {
        for (const std::int32_t i : t) {
            if (i < 0 || static_cast<size_t>(i) >= points.size()) {
                OPENVDB_THROW(openvdb::ValueError, "renderMesh: triangle index " +
                                                       std::to_string(i) + " out of range [0, " +
                                                       std::to_string(points.size()) + ")");
            }
        }
    }
    const int ss = options.supersample ? SUPERSAMPLE : 1;
    const int W = width * ss, H = height * ss;
    const Projector projector(camera, W, H);
    const double ambient = std::clamp(options.ambient, 0.0, 1.0);

    std::vector<ProjectedPoint> projected(points.size());
    std::vector<char> visible(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        visible[i] = projector.project(points[i], projected[i]);
    }

    Image8 image(W, H, options.background);
    std::vector<double> zbuffer(static_cast<size_t>(W) * H,
                                std::numeric_limits<double>::infinity());
    for (const auto& tri : triangles) {
        if (!visible[tri[0]] || !visible[tri[1]] || !visible[tri[2]]) continue;
        const ProjectedPoint& a = projected[tri[0]];
        const ProjectedPoint& b = projected[tri[1]];
        const ProjectedPoint& c = projected[tri[2]];
        const double area = edge(a.x, a.y, b.x, b.y, c.x, c.y);
        if (area == 0.0 || !std::isfinite(area)) continue;

        const openvdb::Vec3d& p0 = points[tri[0]];
        openvdb::Vec3d normal = (points[tri[1]] - p0).cross(points[tri[2]] - p0);
        const double normalLength = normal.length();
        if (!(normalLength > 0.0)) continue;
        normal /= normalLength;
        const openvdb::Vec3d centroid = (p0 + points[tri[1]] + points[tri[2]]) / 3.0;
        const double shade =
            ambient + (1.0 - ambient) * std::abs(normal.dot(projector.towardsEye(centroid)));

        std::array<Rgb8, 3> vc;
        for (int k = 0; k < 3; ++k)
            vc[k] = colors.empty() ? options.defaultColor : colors[tri[k]];

        const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}))));
        const int x1 = std::min(W - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}))));
        const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}))));
        const int y1 = std::min(H - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}))));
        // Perspective-correct interpolation weights barycentric / depth.
        const bool persp = projector.isPerspective();
        const double ia = persp ? 1.0 / a.depth : 1.0, ib = persp ? 1.0 / b.depth : 1.0,
                     ic = persp ? 1.0 / c.depth : 1.0;
        for (int y = y0; y <= y1; ++y) {
            const double py = y + 0.5;
            for (int x = x0; x <= x1; ++x) {
                const double px = x + 0.5;
                double wa = edge(b.x, b.y, c.x, c.y, px, py) / area;
                double wb = edge(c.x, c.y, a.x, a.y, px, py) / area;
                double wc = edge(a.x, a.y, b.x, b.y, px, py) / area;
                if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
                double depth;
                if (persp) {
                    const double inv = wa * ia + wb * ib + wc * ic;
                    depth = 1.0 / inv;
                    wa *= ia * depth;
                    wb *= ib * depth;
                    wc *= ic * depth;
                } else {
                    depth = wa * a.depth + wb * b.depth + wc * c.depth;
                }
                double& z = zbuffer[static_cast<size_t>(y) * W + x];
                if (!(depth < z)) continue;
                z = depth;
                Rgb8 color;
                for (int k = 0; k < 3; ++k) {
                    const double v = shade * (wa * vc[0][k] + wb * vc[1][k] + wc * vc[2][k]);
                    color[k] = static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
                }
                image.set(x, y, color);
            }
        }
    }
    return ss == 1 ? image : downsample2x(image);
}

Camera
standardViewCamera(const openvdb::BBoxd& box, StandardView view, bool perspective)
{
    const openvdb::Vec3d yUp(0.0, 1.0, 0.0);
    switch (view) {
    case StandardView::Front:
        return fitCamera(box, openvdb::Vec3d(0, 0, -1), yUp, perspective);
    case StandardView::Side:
        return fitCamera(box, openvdb::Vec3d(-1, 0, 0), yUp, perspective);
    case StandardView::Top:
        return fitCamera(box, openvdb::Vec3d(0, -1, 0), openvdb::Vec3d(0, 0, -1), perspective);
    case StandardView::ThreeQuarter:
        return fitCamera(box, THREE_QUARTER_DIRECTION, yUp, perspective);
    }
    OPENVDB_THROW(openvdb::ValueError, "standardViewCamera: unknown view");
}

Image8
renderViews(const std::vector<openvdb::Vec3d>& points,
            const std::vector<std::array<std::int32_t, 3>>& triangles,
            const std::vector<Rgb8>& colors, int viewSize, const RenderOptions& options,
            bool perspective, bool labels)
{
    if (points.empty()) OPENVDB_THROW(openvdb::ValueError, "renderViews: the mesh has no points");
    if (viewSize <= 0) {
        OPENVDB_THROW(openvdb::ValueError,
                      "renderViews: viewSize " + std::to_string(viewSize) + " is not positive");
    }
    openvdb::BBoxd box(points.front(), points.front());
    for (const auto& p : points)
        box.expand(p);
    return renderViews(points, triangles, colors, box, viewSize, options, perspective, labels);
}

Image8
renderViews(const std::vector<openvdb::Vec3d>& points,
            const std::vector<std::array<std::int32_t, 3>>& triangles,
            const std::vector<Rgb8>& colors, const openvdb::BBoxd& box, int viewSize,
            const RenderOptions& options, bool perspective, bool labels)
{
    if (points.empty()) OPENVDB_THROW(openvdb::ValueError, "renderViews: the mesh has no points");
    if (viewSize <= 0) {
        OPENVDB_THROW(openvdb::ValueError,
                      "renderViews: viewSize " + std::to_string(viewSize) + " is not positive");
    }
    const StandardView views[] = {StandardView::Front, StandardView::Side, StandardView::Top,
                                  StandardView::ThreeQuarter};
    const char* names[] = {"FRONT", "SIDE", "TOP", "3/4"};
    constexpr int VIEW_COUNT = 4;
    Image8 strip(VIEW_COUNT * viewSize + VIEW_COUNT - 1, viewSize, SEPARATOR_COLOR);
    for (int v = 0; v < VIEW_COUNT; ++v) {
        const Image8 image =
            renderMesh(points, triangles, colors, standardViewCamera(box, views[v], perspective),
                       viewSize, viewSize, options);
        const int x = v * (viewSize + 1);
        paste(strip, image, x, 0);
        if (labels) {
            drawText(strip, x + LABEL_MARGIN_PX, LABEL_MARGIN_PX, names[v], LABEL_COLOR,
                     LABEL_SCALE);
        }
    }
    return strip;
}

} // namespace vdbmatch
