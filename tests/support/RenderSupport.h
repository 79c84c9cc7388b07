/// @file RenderSupport.h
/// @brief Helpers for the picture tests: a UV sphere mesh, and the directory where tests save
///        sample pictures for a person to look at (only when VDBMATCH_RENDER_SAMPLES is set).
#pragma once

#include <openvdb/Types.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

namespace vdbmatch::test {

struct TriangleMesh
{
    std::vector<openvdb::Vec3d> points;
    std::vector<std::array<std::int32_t, 3>> triangles;
};

/// A closed UV sphere (poles on the y axis) of @a radius about @a center: @a slices segments
/// around, @a stacks from pole to pole; outward-facing counter-clockwise triangles.
inline TriangleMesh
uvSphere(double radius, int slices, int stacks, const openvdb::Vec3d& center = openvdb::Vec3d(0.0))
{
    constexpr double PI = 3.14159265358979323846;
    TriangleMesh mesh;
    mesh.points.push_back(center + openvdb::Vec3d(0, radius, 0)); // north pole, index 0
    for (int i = 1; i < stacks; ++i) {
        const double theta = PI * i / stacks;
        for (int j = 0; j < slices; ++j) {
            const double phi = 2.0 * PI * j / slices;
            mesh.points.push_back(
                center + radius * openvdb::Vec3d(std::sin(theta) * std::cos(phi), std::cos(theta),
                                                 std::sin(theta) * std::sin(phi)));
        }
    }
    mesh.points.push_back(center + openvdb::Vec3d(0, -radius, 0)); // south pole
    const int south = static_cast<int>(mesh.points.size()) - 1;
    auto ring = [&](int i, int j) { return 1 + (i - 1) * slices + (j % slices); };
    for (int j = 0; j < slices; ++j)
        mesh.triangles.push_back({0, ring(1, j + 1), ring(1, j)});
    for (int i = 1; i + 1 < stacks; ++i) {
        for (int j = 0; j < slices; ++j) {
            mesh.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)});
            mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)});
        }
    }
    for (int j = 0; j < slices; ++j) {
        mesh.triangles.push_back({south, ring(stacks - 1, j), ring(stacks - 1, j + 1)});
    }
    return mesh;
}

/// The directory named by VDBMATCH_RENDER_SAMPLES, or "" when sample pictures are not wanted.
inline std::string
sampleDirectory()
{
    const char* dir = std::getenv("VDBMATCH_RENDER_SAMPLES");
    return dir ? std::string(dir) : std::string();
}

} // namespace vdbmatch::test
