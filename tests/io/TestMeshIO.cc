/// @file TestMeshIO.cc
/// @brief Tests of the mesh and polyline readers and writers (round trips through every format,
/// error types and messages) and of writeFileAtomically.

#include "support/TestSurfaces.h"

#include <vdbmatch/io/AtomicFile.h>
#include <vdbmatch/io/MeshIO.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

using namespace vdbmatch;
using namespace vdbmatch::test;
namespace fs = std::filesystem;

namespace {

void
writeText(const std::string& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
}

/// Expects readMesh / readPolyline to throw E with a message naming the file and containing
/// @a text.
template <typename E, typename F>
void
expectError(F&& read, const std::string& path, const std::string& text)
{
    try {
        read(path);
        ADD_FAILURE() << "no exception for " << path;
    } catch (const E& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(text), std::string::npos) << what;
        EXPECT_NE(what.find(fs::path(path).filename().string()), std::string::npos) << what;
    }
}

/// Same vertices (after welding, in any order) and same triangle count and volume as a cube.
void
expectUnitCube(const Surface<3>& s)
{
    EXPECT_EQ(s.points.size(), 8u);
    EXPECT_EQ(s.elements.size(), 12u);
    EXPECT_NEAR(std::abs(signedVolume(s)), 1.0, 1e-12);
    EXPECT_NEAR(measure(s), 6.0, 1e-12);
}

/// Bytes of a value in the given byte order.
template <typename T>
void
put(std::string& out, T v, bool bigEndian)
{
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    const uint16_t one = 1;
    char first;
    std::memcpy(&first, &one, 1);
    const bool hostLittle = first == 1;
    if (bigEndian == hostLittle) std::reverse(b, b + sizeof(T));
    out.append(b, sizeof(T));
}

std::string
binaryPly(const Surface<3>& s, bool bigEndian)
{
    std::ostringstream h;
    h << "ply\nformat " << (bigEndian ? "binary_big_endian" : "binary_little_endian")
      << " 1.0\ncomment test\nelement vertex " << s.points.size()
      << "\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\n"
      << "element face " << s.elements.size()
      << "\nproperty list uchar uint vertex_indices\nelement edge 1\nproperty int vertex1\n"
      << "property int vertex2\nend_header\n";
    std::string out = h.str();
    for (const auto& p : s.points) {
        for (int a = 0; a < 3; ++a)
            put<double>(out, p[a], bigEndian);
        put<uint8_t>(out, 200, bigEndian);
    }
    for (const auto& t : s.elements) {
        put<uint8_t>(out, 3, bigEndian);
        for (int c = 0; c < 3; ++c)
            put<uint32_t>(out, uint32_t(t[size_t(c)]), bigEndian);
    }
    put<int32_t>(out, 0, bigEndian);
    put<int32_t>(out, 1, bigEndian);
    return out;
}

std::string
asciiStl(const Surface<3>& s)
{
    std::ostringstream o;
    o.precision(17);
    o << "solid cube\n";
    for (const auto& t : s.elements) {
        o << "  facet normal 0 0 0\n    outer loop\n";
        for (int c = 0; c < 3; ++c) {
            const auto& p = s.points[size_t(t[size_t(c)])];
            o << "      vertex " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
        }
        o << "    endloop\n  endfacet\n";
    }
    o << "endsolid cube\n";
    return o.str();
}

std::string
binaryStl(const Surface<3>& s)
{
    std::string out(80, ' ');
    put<uint32_t>(out, uint32_t(s.elements.size()), false);
    for (const auto& t : s.elements) {
        for (int k = 0; k < 3; ++k)
            put<float>(out, 0.0f, false);
        for (int c = 0; c < 3; ++c)
            for (int a = 0; a < 3; ++a)
                put<float>(out, float(s.points[size_t(t[size_t(c)])][a]), false);
        put<uint16_t>(out, 0, false);
    }
    return out;
}

class MeshIOTest : public ::testing::Test
{
protected:
    ScratchDir mDir;
};

} // namespace

TEST_F(MeshIOTest, ObjRoundTrip)
{
    const Surface<3> sphere = uvSphere(Vec<3>(0.1, -0.2, 0.3), 0.7, 6, 9);
    const std::string path = mDir.file("sphere.obj");
    writeFileAtomically(path, [&](std::ostream& out) { writeObj(out, sphere); });
    const Surface<3> back = readMesh(path);
    ASSERT_EQ(back.points.size(), sphere.points.size());
    EXPECT_EQ(back.elements, sphere.elements);
    for (size_t i = 0; i < back.points.size(); ++i)
        EXPECT_EQ(back.points[i], sphere.points[i]); // round-trip precision
}

TEST_F(MeshIOTest, ObjQuadsNegativeIndicesAndIgnoredLines)
{
    // The unit cube as 6 quads, with texture/normal references, relative indices, comments.
    const std::string path = mDir.file("cube.OBJ");
    writeText(path, "# cube\r\no cube\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\n"
                    "v 0 1 1\nv 1 1 1 1.0\nvt 0 0\nvn 0 0 1\ns off\nusemtl none\n"
                    "f 1/1/1 3/1/1 4/1/1 2/1/1\nf 5//1 6//1 8//1 7//1\nf -8 -7 -3 -4\n"
                    "f 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6 # last\n");
    expectUnitCube(readMesh(path));
}

TEST_F(MeshIOTest, ObjVertexColours)
{
    // Scanners and Blender write 'v x y z r g b' (and some 'r g b a'): the colours are skipped.
    const std::string path = mDir.file("coloured.obj");
    writeText(path, "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 1 1 0 0.5 0.5 0.5 1\n"
                    "v 0 0 1 1 1 1\nv 1 0 1 1 1 1\nv 0 1 1 1 1 1\nv 1 1 1 0.2 0.3 0.4\n"
                    "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n");
    expectUnitCube(readMesh(path));
    writeText(mDir.file("text.obj"), "v 0 0 0 red green blue\n");
    EXPECT_THROW(readMesh(mDir.file("text.obj")), openvdb::ValueError);
    writeText(mDir.file("long.obj"), "v 0 0 0 1 2 3 4 5 6\n");
    EXPECT_THROW(readMesh(mDir.file("long.obj")), openvdb::ValueError);
}

TEST_F(MeshIOTest, PlyAsciiWithQuads)
{
    const std::string path = mDir.file("cube.ply");
    writeText(path, "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 8\n"
                    "property float x\nproperty float y\nproperty float z\nproperty float nx\n"
                    "element face 6\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0 9\n1 0 0 9\n0 1 0 9\n1 1 0 9\n0 0 1 9\n1 0 1 9\n0 1 1 9\n1 1 1 9\n"
                    "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
    expectUnitCube(readMesh(path));
}

TEST_F(MeshIOTest, PlyBinaryBothByteOrders)
{
    const Surface<3> sphere = uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.3, 5, 7);
    for (const bool big : {false, true}) {
        const std::string path = mDir.file(big ? "big.ply" : "little.ply");
        writeText(path, binaryPly(sphere, big));
        const Surface<3> back = readMesh(path);
        EXPECT_EQ(back.elements, sphere.elements) << big;
        ASSERT_EQ(back.points.size(), sphere.points.size());
        for (size_t i = 0; i < back.points.size(); ++i)
            EXPECT_EQ(back.points[i], sphere.points[i]);
    }
}

TEST_F(MeshIOTest, StlAsciiAndBinary)
{
    const Surface<3> cube = cubeMesh();
    writeText(mDir.file("a.stl"), asciiStl(cube));
    writeText(mDir.file("b.stl"), binaryStl(cube));
    for (const char* name : {"a.stl", "b.stl"}) {
        const Surface<3> s = readMesh(mDir.file(name));
        expectUnitCube(s);
        EXPECT_NEAR(signedVolume(s), 1.0, 1e-12) << name; // orientation kept
    }
}

TEST_F(MeshIOTest, PolylineRoundTrip)
{
    const std::string path = mDir.file("curves.polyline");
    writeText(path, "# two curves: a square with a square hole\n\n0 0\n4 0 # corner\n4 4\n0 4\n"
                    "\n\n# hole\n1 1\n1 2\n2 2\n2 1\n");
    const Surface<2> s = readPolyline(path);
    EXPECT_EQ(s.points.size(), 8u);
    EXPECT_EQ(s.elements.size(), 8u);
    EXPECT_EQ(countLoops(s), 2);
    EXPECT_NEAR(signedVolume(s), 16.0 - 1.0, 1e-12);

    const std::string again = mDir.file("again.txt");
    writeFileAtomically(again, [&](std::ostream& out) { writePolyline(out, s); });
    const Surface<2> back = readPolyline(again);
    EXPECT_EQ(back.points, s.points);
    EXPECT_EQ(back.elements, s.elements);

    std::ostringstream obj;
    writeObj(obj, s);
    EXPECT_NE(obj.str().find("v 4 0 0\n"), std::string::npos);
    EXPECT_NE(obj.str().find("l 4 1\n"), std::string::npos);
}

TEST_F(MeshIOTest, ErrorsNameTheFileAndTheProblem)
{
    auto mesh = [](const std::string& p) { readMesh(p); };
    auto poly = [](const std::string& p) { readPolyline(p); };
    expectError<openvdb::IoError>(mesh, mDir.file("missing.obj"), "does not exist");
    expectError<openvdb::IoError>(poly, mDir.file("missing.polyline"), "does not exist");
    fs::create_directories(mDir.file("dir.obj"));
    expectError<openvdb::IoError>(mesh, mDir.file("dir.obj"), "is a directory");

    writeText(mDir.file("empty.obj"), "");
    expectError<openvdb::ValueError>(mesh, mDir.file("empty.obj"), "empty");
    writeText(mDir.file("bad.obj"), "v 1 2\n");
    expectError<openvdb::ValueError>(mesh, mDir.file("bad.obj"), "line 1: expected 'v x y z ");
    writeText(mDir.file("range.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    expectError<openvdb::ValueError>(mesh, mDir.file("range.obj"), "out of range");
    writeText(mDir.file("nan.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 1\n"
                                    "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    expectError<openvdb::ValueError>(mesh, mDir.file("nan.obj"), "non-finite");
    writeText(mDir.file("open.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                     "f 1 3 2\nf 1 2 4\nf 2 3 4\n");
    expectError<openvdb::ValueError>(mesh, mDir.file("open.obj"), "not closed");
    writeText(mDir.file("garbage.ply"), "hello\x01\x02");
    expectError<openvdb::ValueError>(mesh, mDir.file("garbage.ply"), "not a PLY file");
    std::string truncated = binaryPly(cubeMesh(), false);
    truncated.resize(truncated.size() - 20);
    writeText(mDir.file("truncated.ply"), truncated);
    expectError<openvdb::ValueError>(mesh, mDir.file("truncated.ply"), "unexpected end");
    writeText(mDir.file("garbage.stl"), "hello world");
    expectError<openvdb::ValueError>(mesh, mDir.file("garbage.stl"), "neither an ascii STL");
    writeText(mDir.file("mesh.xyz"), "1 2 3");
    expectError<openvdb::ValueError>(mesh, mDir.file("mesh.xyz"), "unknown mesh extension");

    writeText(mDir.file("short.polyline"), "0 0\n1 0\n1 1\n\n0 0\n1 1\n");
    expectError<openvdb::ValueError>(poly, mDir.file("short.polyline"), "needs at least 3");
    writeText(mDir.file("words.polyline"), "0 0\n1 zero\n");
    expectError<openvdb::ValueError>(poly, mDir.file("words.polyline"), "line 2: expected 'x y'");
    writeText(mDir.file("flat.polyline"), "0 0\n1 0\n2 0\n");
    expectError<openvdb::ValueError>(poly, mDir.file("flat.polyline"), "degenerate");
    writeText(mDir.file("blank.polyline"), "# nothing\n\n");
    expectError<openvdb::ValueError>(poly, mDir.file("blank.polyline"), "empty");
}

TEST_F(MeshIOTest, AtomicWriteFailuresLeaveNothing)
{
    EXPECT_THROW(writeFileAtomically(mDir.file("no/such/dir.obj"), [](std::ostream& o) { o << 1; }),
                 openvdb::IoError);
    const std::string path = mDir.file("x.txt");
    writeText(path, "old");
    EXPECT_THROW(writeFileAtomically(path,
                                     [](std::ostream& o) {
                                         o << "partial";
                                         throw std::runtime_error("boom");
                                     }),
                 openvdb::IoError);
    // The old file is intact and no temporary file is left.
    std::ifstream in(path);
    std::string text;
    in >> text;
    EXPECT_EQ(text, "old");
    int files = 0;
    for (const auto& entry : fs::directory_iterator(mDir.path())) {
        (void)entry;
        ++files;
    }
    EXPECT_EQ(files, 1);
}

namespace {

/// An ascii PLY tetrahedron (closed) with an extra element of @a count instances declared
/// before the faces, with the given property lines (none: it stores nothing).
std::string
plyTetraWithElement(const std::string& count, const std::string& properties = "")
{
    return "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
           "property float z\nelement junk " +
           count + "\n" + properties +
           "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n";
}

} // namespace

// Issue 10: a PLY header declaring an element of 1e12 (or 9e18) instances without properties
// hung for minutes; such an element stores nothing and is now skipped at once.
TEST_F(MeshIOTest, PlyHugeElementWithoutPropertiesDoesNotHang)
{
    for (const char* count : {"1000000000000", "9000000000000000000", "9223372036854775807"}) {
        writeText(mDir.file("huge.ply"), plyTetraWithElement(count));
        const Surface<3> s = readMesh(mDir.file("huge.ply"));
        EXPECT_EQ(s.points.size(), 4u) << count;
        EXPECT_EQ(s.elements.size(), 4u) << count;
    }
    // With a property, such a count is more than the data can hold.
    writeText(mDir.file("huge_prop.ply"),
              plyTetraWithElement("1000000000000", "property uchar flag\n"));
    auto mesh = [](const std::string& p) { readMesh(p); };
    expectError<openvdb::ValueError>(mesh, mDir.file("huge_prop.ply"),
                                     "more than the data can hold");
}

// Found by review while writing the fuzz targets: an ascii list length of 1e300 was converted
// to an integer (undefined behaviour) before the data ran out.
TEST_F(MeshIOTest, PlyHugeListLengthIsAnError)
{
    std::string ply = plyTetraWithElement("0");
    ply.replace(ply.find("3 0 2 1"), 1, "1e300");
    writeText(mDir.file("list.ply"), ply);
    auto mesh = [](const std::string& p) { readMesh(p); };
    expectError<openvdb::ValueError>(mesh, mDir.file("list.ply"),
                                     "unexpected end of the data: a list of element 'face' "
                                     "claims 1e+300 entries");
}

// NaN coordinates broke the ordering with which STL vertices are welded (std::sort with an
// inconsistent comparison may read out of bounds); every reader rejects non-finite values.
TEST_F(MeshIOTest, NonFiniteCoordinatesAreErrors)
{
    auto mesh = [](const std::string& p) { readMesh(p); };
    auto poly = [](const std::string& p) { readPolyline(p); };
    Surface<3> cube = cubeMesh();
    cube.points[3][1] = std::numeric_limits<double>::quiet_NaN();
    writeText(mDir.file("nan_binary.stl"), binaryStl(cube));
    expectError<openvdb::ValueError>(mesh, mDir.file("nan_binary.stl"), "non-finite");
    writeText(mDir.file("nan_ascii.stl"), asciiStl(cube));
    expectError<openvdb::ValueError>(mesh, mDir.file("nan_ascii.stl"), "non-finite");
    cube.points[3][1] = std::numeric_limits<double>::infinity();
    writeText(mDir.file("inf_binary.stl"), binaryStl(cube));
    expectError<openvdb::ValueError>(mesh, mDir.file("inf_binary.stl"), "non-finite");
    std::string ply = plyTetraWithElement("0");
    ply.replace(ply.find("0 0 1\n"), 5, "0 0 inf");
    writeText(mDir.file("inf.ply"), ply);
    expectError<openvdb::ValueError>(mesh, mDir.file("inf.ply"), "non-finite");
    writeText(mDir.file("nan.polyline"), "0 0\n1 0\nnan 1\n");
    expectError<openvdb::ValueError>(poly, mDir.file("nan.polyline"), "non-finite");
}

// Issue 10, part 6: an STL header claiming 4e9 triangles (the most a binary STL can declare)
// is not taken as binary (the size does not match) and is rejected without allocating.
TEST_F(MeshIOTest, StlHugeTriangleCountIsAnError)
{
    std::string stl = binaryStl(cubeMesh());
    const uint32_t huge = 0xffffffffu;
    std::memcpy(&stl[80], &huge, sizeof(huge));
    writeText(mDir.file("huge.stl"), stl);
    auto mesh = [](const std::string& p) { readMesh(p); };
    expectError<openvdb::ValueError>(mesh, mDir.file("huge.stl"), "does not match 84 + 50");
}
