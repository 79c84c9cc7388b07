/// @file TestMeshTransport.cc
/// @brief Tests of transportMesh: forward then inverse restores the file, normals stay normal to
/// the moved faces (Nanson's formula), faces and UVs are kept, the PLY attributes equal the
/// affine map's det, area ratio and displacement, and the thread count does not matter.

#include "support/SwirlGrid.h"
#include "support/TestSurfaces.h"

#include <vdbmatch/io/MeshDocument.h>
#include <vdbmatch/io/MeshIO.h>
#include <vdbmatch/transport/MeshTransport.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

using namespace vdbmatch;
using namespace vdbmatch::test;
using openvdb::Mat3d;
using openvdb::Vec3d;

namespace {

constexpr double VOXEL = 0.125; // domain [0, 4]^3 at level 5

void
writeText(const std::string& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
}

std::string
readText(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// A sphere around the domain centre as an OBJ with vt and vn (per-vertex normals), quads
/// kept as written (one quad face added).
std::string
sphereObj(const Vec3d& centre, double radius)
{
    const Surface<3> s = uvSphere(Vec<3>(centre[0], centre[1], centre[2]), radius, 12, 16);
    std::ostringstream o;
    o.precision(17);
    o << "# test sphere\nmtllib none.mtl\ng ball\n";
    for (const auto& p : s.points)
        o << "v " << p[0] << " " << p[1] << " " << p[2] << " 0.5 0.25 1\n";
    for (const auto& p : s.points) {
        const Vec<3> n = (p - Vec<3>(centre[0], centre[1], centre[2])).normalized();
        o << "vn " << n[0] << " " << n[1] << " " << n[2] << "\n";
    }
    o << "vt 0.25 0.75\n";
    for (const auto& t : s.elements) {
        o << "f";
        for (int v : t)
            o << " " << v + 1 << "/1/" << v + 1;
        o << "\n";
    }
    o << "f 1/1/1 2/1/2 3/1/3 4/1/4\n"; // a quad, to check it stays a quad
    return o.str();
}

/// The same sphere as an ascii PLY with faces and no normals.
std::string
spherePly(const Vec3d& centre, double radius)
{
    const Surface<3> s = uvSphere(Vec<3>(centre[0], centre[1], centre[2]), radius, 10, 14);
    std::ostringstream o;
    o.precision(17);
    o << "ply\nformat ascii 1.0\nelement vertex " << s.points.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face "
      << s.elements.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& p : s.points)
        o << float(p[0]) << " " << float(p[1]) << " " << float(p[2]) << "\n";
    for (const auto& t : s.elements)
        o << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
    return o.str();
}

Mat3d
shear()
{
    return Mat3d(1.2, 0.3, 0.0, //
                 0.0, 0.9, 0.1, //
                 0.05, 0.0, 1.1);
}

} // namespace

TEST(MeshTransport, ForwardThenInverseRestoresTheFile)
{
    ScratchDir dir;
    const DeformationField phi(swirlGrid(3, 5, 1.2, VOXEL));
    const Vec3d centre = phi.worldBounds().getCenter();
    // Off the lattice planes: D phi jumps across simplex faces, so a vertex on one would make
    // its normal's Jacobian depend on rounding.
    const std::string obj = sphereObj(centre + Vec3d(0.3017, 0.0123, 0.0071), 1.1);
    writeText(dir.file("a.obj"), obj);
    MeshDocument mesh = MeshDocument::read(dir.file("a.obj"));
    const std::vector<Vec3d> original = mesh.positions();
    const std::vector<Vec3d> originalNormals = mesh.normals();

    const MeshTransportResult forward = transportMesh(mesh, phi);
    EXPECT_EQ(forward.vertices, original.size());
    EXPECT_EQ(forward.normals, originalNormals.size());
    EXPECT_EQ(forward.inverseFailures, 0u);
    EXPECT_GT(forward.maxDisplacement, 4 * VOXEL); // the swirl moves the sphere a lot
    mesh.write(dir.file("b.obj"));

    MeshDocument moved = MeshDocument::read(dir.file("b.obj"));
    MeshTransportOptions inverse;
    inverse.inverse = true;
    const MeshTransportResult back = transportMesh(moved, phi, inverse);
    EXPECT_EQ(back.inverseFailures, 0u);
    for (std::size_t i = 0; i < original.size(); ++i)
        EXPECT_LT((moved.positions()[i] - original[i]).length(), 1e-9);
    for (std::size_t i = 0; i < originalNormals.size(); ++i)
        EXPECT_LT((moved.normals()[i] - originalNormals[i]).length(), 1e-6);

    // Everything but the numbers is kept: faces (the quad), UVs, groups, colours.
    const std::string text = readText(dir.file("b.obj"));
    EXPECT_NE(text.find("f 1/1/1 2/1/2 3/1/3 4/1/4\n"), std::string::npos);
    EXPECT_NE(text.find("vt 0.25 0.75\n"), std::string::npos);
    EXPECT_NE(text.find("g ball\nv "), std::string::npos);
    EXPECT_NE(text.find(" 0.5 0.25 1\n"), std::string::npos);
}

TEST(MeshTransport, NormalsStayNormalToTheMovedFaces)
{
    // An affine phi moves each flat facet to a flat facet: the carried facet normal must be its
    // normal exactly (Nanson: n' ~ cof(A) n). STL stores one normal per facet.
    ScratchDir dir;
    const DeformationField phi(affineGrid(3, 5, shear(), Vec3d(0.1, -0.2, 0.05), VOXEL));
    const Surface<3> cube = cubeMesh(1.3, 1.4);
    std::ostringstream stl;
    stl.precision(17);
    stl << "solid cube\n";
    for (const auto& t : cube.elements) {
        const Vec<3> n = (cube.points[t[1]] - cube.points[t[0]])
                             .cross(cube.points[t[2]] - cube.points[t[0]])
                             .normalized();
        stl << " facet normal " << n[0] << " " << n[1] << " " << n[2] << "\n  outer loop\n";
        for (int v : t) {
            const auto& p = cube.points[v];
            stl << "   vertex " << p[0] << " " << p[1] << " " << p[2] << "\n";
        }
        stl << "  endloop\n endfacet\n";
    }
    stl << "endsolid cube\n";
    writeText(dir.file("cube.stl"), stl.str());
    for (bool inverse : {false, true}) {
        MeshDocument mesh = MeshDocument::read(dir.file("cube.stl"));
        MeshTransportOptions options;
        options.inverse = inverse;
        transportMesh(mesh, phi, options);
        ASSERT_EQ(mesh.normals().size(), cube.elements.size());
        for (std::size_t f = 0; f < mesh.normals().size(); ++f) {
            const Vec3d* p = &mesh.positions()[3 * f];
            Vec3d expected = (p[1] - p[0]).cross(p[2] - p[0]);
            expected.normalize();
            // (the grid stores single precision: affine to ~1e-7)
            EXPECT_LT((mesh.normals()[f] - expected).length(), 1e-6)
                << "facet " << f << (inverse ? " (inverse)" : "");
        }
    }
}

TEST(TransportNormal, IsOrthogonalToTheImageOfTheTangentPlane)
{
    const Mat3d A = shear();
    const Vec3d n = Vec3d(0.2, -0.5, 0.8).unit();
    const Vec3d t1 = n.cross(Vec3d(1, 0, 0)).unit(), t2 = n.cross(t1);
    const Vec3d forward = transportNormal(A, n, false);
    EXPECT_NEAR(forward.length(), 1.0, 1e-12);
    EXPECT_NEAR(forward.dot(A * t1), 0.0, 1e-12);
    EXPECT_NEAR(forward.dot(A * t2), 0.0, 1e-12);
    EXPECT_GT(forward.dot(A * n), 0.0); // still outward
    const Mat3d Ainv = A.inverse();
    const Vec3d back = transportNormal(A, n, true);
    EXPECT_NEAR(back.dot(Ainv * t1), 0.0, 1e-12);
    EXPECT_NEAR(back.dot(Ainv * t2), 0.0, 1e-12);
    EXPECT_EQ(transportNormal(A, Vec3d(0.0), false), Vec3d(0.0));
}

TEST(MeshTransport, AttributesOfAnAffineMap)
{
    ScratchDir dir;
    const Mat3d A = shear();
    const Vec3d b(0.1, -0.2, 0.05);
    const DeformationField phi(affineGrid(3, 5, A, b, VOXEL));
    const Vec3d centre = phi.worldBounds().getCenter();
    writeText(dir.file("s.ply"), spherePly(centre, 1.0));
    const Surface<3> faces = readMesh(dir.file("s.ply"));

    for (bool inverse : {false, true}) {
        MeshDocument mesh = MeshDocument::read(dir.file("s.ply"));
        const std::vector<Vec3d> before = mesh.positions();
        MeshTransportOptions options;
        options.inverse = inverse;
        options.attributes = true;
        options.triangles = faces.elements;
        options.signedDistance = [&](const Vec3d& x) { return (x - centre).length() - 0.5; };
        const MeshTransportResult r = transportMesh(mesh, phi, options);
        ASSERT_EQ(r.added.size(), 4u);
        const std::string out = dir.file(inverse ? "inv.ply" : "fwd.ply");
        mesh.write(out);
        const std::string text = readText(out);
        EXPECT_NE(text.find("property float det_jacobian\nproperty float area_stretch\nproperty "
                            "float displacement\nproperty float residual\n"),
                  std::string::npos);
        // Parse the vertex rows back: x y z det stretch displacement residual.
        std::istringstream in(text.substr(text.find("end_header\n") + 11));
        const double det = inverse ? 1.0 / A.det() : A.det();
        const Mat3d M = inverse ? A.inverse() : A;
        for (std::size_t i = 0; i < before.size(); ++i) {
            double x, y, z, d, stretch, disp, res;
            in >> x >> y >> z >> d >> stretch >> disp >> res;
            ASSERT_TRUE(in) << "row " << i;
            EXPECT_NEAR(d, det, 1e-5 * det);
            // area ratio of the sphere's tangent plane: |cof(M) n| with n the radial normal
            // (the faces' area-weighted normal is close to it).
            const Vec3d n = (before[i] - centre).unit();
            const Vec3d cofn = M.det() * M.inverse().transpose() * n;
            EXPECT_NEAR(stretch, cofn.length(), 0.05 * cofn.length());
            EXPECT_NEAR(disp, (mesh.positions()[i] - before[i]).length(), 1e-5);
            EXPECT_NEAR(res, std::abs((mesh.positions()[i] - centre).length() - 0.5), 1e-5);
        }
    }
}

TEST(MeshTransport, RejectsAttributesOutsidePly)
{
    ScratchDir dir;
    const DeformationField phi(swirlGrid(3, 4, 0.5, VOXEL));
    writeText(dir.file("a.obj"), sphereObj(phi.worldBounds().getCenter(), 0.5));
    MeshDocument mesh = MeshDocument::read(dir.file("a.obj"));
    MeshTransportOptions options;
    options.attributes = true;
    EXPECT_THROW(transportMesh(mesh, phi, options), openvdb::ValueError);
}

TEST(MeshTransport, ResultDoesNotDependOnThreads)
{
    ScratchDir dir;
    const DeformationField phi(swirlGrid(3, 5, 1.2, VOXEL));
    writeText(dir.file("a.obj"), sphereObj(phi.worldBounds().getCenter(), 1.2));
    std::string rendered[2];
    for (int threaded = 0; threaded < 2; ++threaded) {
        MeshDocument mesh = MeshDocument::read(dir.file("a.obj"));
        MeshTransportOptions options;
        options.inverse = true;
        options.threaded = threaded == 1;
        transportMesh(mesh, phi, options);
        rendered[threaded] = mesh.render();
    }
    EXPECT_EQ(rendered[0], rendered[1]);
}
