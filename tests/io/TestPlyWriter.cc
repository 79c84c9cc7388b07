/// @file TestPlyWriter.cc
/// @brief writePly round trips, binary and ASCII, through a small PLY parser written here:
///        header lines, vertex positions (as floats), colours and faces come back unchanged.
#include <vdbmatch/io/PlyWriter.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cstring>
#include <sstream>
#include <string>

using namespace vdbmatch;

namespace {

struct ParsedPly
{
    std::string format;
    std::vector<std::string> vertexProperties;
    std::vector<openvdb::Vec3d> points;
    std::vector<std::array<std::uint8_t, 3>> colors;
    std::vector<std::array<std::int32_t, 3>> triangles;
};

std::uint32_t
readLe32(std::istream& is)
{
    unsigned char b[4];
    is.read(reinterpret_cast<char*>(b), 4);
    return b[0] | (b[1] << 8) | (b[2] << 16) | (std::uint32_t(b[3]) << 24);
}

ParsedPly
parsePly(const std::string& data)
{
    std::istringstream is(data);
    ParsedPly ply;
    std::string line;
    std::getline(is, line);
    EXPECT_EQ(line, "ply");
    size_t vertexCount = 0, faceCount = 0;
    std::string element;
    while (std::getline(is, line) && line != "end_header") {
        std::istringstream ls(line);
        std::string word;
        ls >> word;
        if (word == "format") {
            ls >> ply.format;
        } else if (word == "element") {
            ls >> element;
            (element == "vertex" ? vertexCount : faceCount) = 0;
            ls >> (element == "vertex" ? vertexCount : faceCount);
        } else if (word == "property" && element == "vertex") {
            std::string type, name;
            ls >> type >> name;
            ply.vertexProperties.push_back(type + " " + name);
        } else if (word == "property") {
            EXPECT_EQ(line, "property list uchar int vertex_indices");
        }
    }
    const bool hasColors = ply.vertexProperties.size() == 6;
    const bool binary = ply.format == "binary_little_endian";
    for (size_t i = 0; i < vertexCount; ++i) {
        openvdb::Vec3d p;
        std::array<std::uint8_t, 3> c{};
        if (binary) {
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t bits = readLe32(is);
                float f;
                std::memcpy(&f, &bits, 4);
                p[k] = f;
            }
            if (hasColors) is.read(reinterpret_cast<char*>(c.data()), 3);
        } else {
            float x, y, z;
            is >> x >> y >> z;
            p = openvdb::Vec3d(x, y, z);
            if (hasColors) {
                int r, g, b;
                is >> r >> g >> b;
                c = {std::uint8_t(r), std::uint8_t(g), std::uint8_t(b)};
            }
        }
        ply.points.push_back(p);
        if (hasColors) ply.colors.push_back(c);
    }
    for (size_t i = 0; i < faceCount; ++i) {
        std::array<std::int32_t, 3> t{};
        if (binary) {
            char n;
            is.get(n);
            EXPECT_EQ(n, 3);
            for (auto& v : t)
                v = static_cast<std::int32_t>(readLe32(is));
        } else {
            int n;
            is >> n >> t[0] >> t[1] >> t[2];
            EXPECT_EQ(n, 3);
        }
        ply.triangles.push_back(t);
    }
    EXPECT_TRUE(is.good() || is.eof());
    return ply;
}

void
checkRoundTrip(PlyFormat format, bool withColors)
{
    const std::vector<openvdb::Vec3d> points = {
        {0.0, 0.0, 0.0}, {1.5, -0.25, 3.0}, {0.1, 0.2, 0.3}, {-7.0, 1e-3, 2.5e4}};
    const std::vector<std::array<std::int32_t, 3>> triangles = {{0, 1, 2}, {0, 2, 3}, {3, 2, 1}};
    std::vector<std::array<std::uint8_t, 3>> colors;
    if (withColors) colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {12, 34, 56}};
    std::ostringstream os(std::ios::binary);
    writePly(os, points, triangles, colors, format, "vdbmatch test\nsecond line");
    const std::string data = os.str();
    EXPECT_NE(data.find("comment vdbmatch test\ncomment second line\n"), std::string::npos);

    const ParsedPly ply = parsePly(data);
    EXPECT_EQ(ply.format, format == PlyFormat::Ascii ? "ascii" : "binary_little_endian");
    ASSERT_EQ(ply.points.size(), points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(ply.points[i][k], double(float(points[i][k])));
    }
    EXPECT_EQ(ply.colors, colors);
    EXPECT_EQ(ply.triangles, triangles);
    if (withColors) {
        EXPECT_EQ(ply.vertexProperties,
                  (std::vector<std::string>{"float x", "float y", "float z", "uchar red",
                                            "uchar green", "uchar blue"}));
    }
}

} // namespace

TEST(PlyWriter, BinaryRoundTrip)
{
    checkRoundTrip(PlyFormat::BinaryLittleEndian, true);
}
TEST(PlyWriter, AsciiRoundTrip)
{
    checkRoundTrip(PlyFormat::Ascii, true);
}
TEST(PlyWriter, WithoutColors)
{
    checkRoundTrip(PlyFormat::BinaryLittleEndian, false);
}

TEST(PlyWriter, RejectsBadInput)
{
    std::ostringstream os;
    const std::vector<openvdb::Vec3d> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    EXPECT_THROW(writePly(os, points, {{0, 1, 3}}, {}), openvdb::ValueError);
    EXPECT_THROW(writePly(os, points, {{0, 1, 2}}, {{1, 2, 3}}), openvdb::ValueError);
    std::ostringstream failed;
    failed.setstate(std::ios::badbit);
    EXPECT_THROW(writePly(failed, points, {{0, 1, 2}}, {}), openvdb::IoError);
}
