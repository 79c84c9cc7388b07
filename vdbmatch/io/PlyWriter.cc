/// @file PlyWriter.cc
/// @brief PLY output, binary little endian or ASCII.
#include "PlyWriter.h"

#include <openvdb/Exceptions.h>

#include <cmath>
#include <cstring>
#include <sstream>

namespace vdbmatch {

namespace {

void
putLittleEndian32(std::ostream& os, std::uint32_t bits)
{
    const char bytes[4] = {static_cast<char>(bits & 0xffu), static_cast<char>((bits >> 8) & 0xffu),
                           static_cast<char>((bits >> 16) & 0xffu),
                           static_cast<char>((bits >> 24) & 0xffu)};
    os.write(bytes, 4);
}

void
putFloat(std::ostream& os, float v)
{
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof(bits));
    putLittleEndian32(os, bits);
}

} // namespace

void
writePly(std::ostream& os, const std::vector<openvdb::Vec3d>& points,
         const std::vector<std::array<std::int32_t, 3>>& triangles,
         const std::vector<std::array<std::uint8_t, 3>>& colors, PlyFormat format,
         const std::string& comment)
{
    const bool hasColors = !colors.empty();
    if (hasColors && colors.size() != points.size()) {
        OPENVDB_THROW(openvdb::ValueError, "writePly: " + std::to_string(colors.size()) +
                                               " colours for " + std::to_string(points.size()) +
                                               " points");
    }
    for (const auto& p : points) {
        if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
            OPENVDB_THROW(openvdb::ValueError, "writePly: a point is not finite");
        }
    }
    for (const auto& t : triangles) {
        for (const std::int32_t i : t) {
            if (i < 0 || static_cast<size_t>(i) >= points.size()) {
                OPENVDB_THROW(openvdb::ValueError, "writePly: triangle index " + std::to_string(i) +
                                                       " out of range [0, " +
                                                       std::to_string(points.size()) + ")");
            }
        }
    }

    const bool binary = format == PlyFormat::BinaryLittleEndian;
    os << "ply\n" << (binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n");
    std::istringstream commentLines(comment);
    for (std::string line; std::getline(commentLines, line);)
        os << "comment " << line << "\n";
    os << "element vertex " << points.size() << "\n"
       << "property float x\nproperty float y\nproperty float z\n";
    if (hasColors) os << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    os << "element face " << triangles.size() << "\n"
       << "property list uchar int vertex_indices\nend_header\n";

    if (binary) {
        for (size_t i = 0; i < points.size(); ++i) {
            for (int k = 0; k < 3; ++k)
                putFloat(os, static_cast<float>(points[i][k]));
            if (hasColors) os.write(reinterpret_cast<const char*>(colors[i].data()), 3);
        }
        for (const auto& t : triangles) {
            os.put(static_cast<char>(3));
            for (const std::int32_t i : t)
                putLittleEndian32(os, static_cast<std::uint32_t>(i));
        }
    } else {
        std::ostringstream text;
        text.precision(9); // round-trips a float
        for (size_t i = 0; i < points.size(); ++i) {
            text << static_cast<float>(points[i].x()) << ' ' << static_cast<float>(points[i].y())
                 << ' ' << static_cast<float>(points[i].z());
            if (hasColors) {
                text << ' ' << int(colors[i][0]) << ' ' << int(colors[i][1]) << ' '
                     << int(colors[i][2]);
            }
            text << '\n';
        }
        for (const auto& t : triangles)
            text << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
        os << text.str();
    }
    os.flush();
    if (!os) OPENVDB_THROW(openvdb::IoError, "writePly: the output stream failed");
}

} // namespace vdbmatch
