/// @file MeshTransport.cc
/// @brief Moving a mesh file's vertices and normals by phi or phi^{-1}, and the per-vertex
///        measures of the map.
#include "MeshTransport.h"

#include <vdbmatch/math/MatrixOps.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vdbmatch {

namespace {

/// How far (relative to Omega's diagonal) a vertex may lie from a 2D deformation's plane.
constexpr double PLANE_TOLERANCE = 1e-6;

Eigen::Matrix3d
toEigen(const openvdb::Mat3d& A)
{
    Eigen::Matrix3d M;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            M(r, c) = A(r, c);
    return M;
}

Eigen::Vector3d
toEigen(const openvdb::Vec3d& v)
{
    return Eigen::Vector3d(v[0], v[1], v[2]);
}

/// cof(A) n for the forward map, cof(A^{-1}) n = A^T n / det A for the inverse (not normalised).
Eigen::Vector3d
cofactorTimes(const openvdb::Mat3d& A, const openvdb::Vec3d& n, bool inverse)
{
    const Eigen::Matrix3d M = toEigen(A);
    if (!inverse) return math::cof(M) * toEigen(n);
    return M.transpose() * toEigen(n) / M.determinant();
}

/// Runs body(range) over [0, n), in parallel if @a threaded.
template <typename Body>
void
forEachIndex(std::size_t n, bool threaded, const Body& body)
{
    const tbb::blocked_range<std::size_t> all(0, n, 1024);
    if (threaded) {
        tbb::parallel_for(all, body);
    } else {
        body(all);
    }
}

/// Unit area-weighted vertex normals of a triangle mesh (zero for vertices of no triangle).
std::vector<openvdb::Vec3d>
vertexNormals(const std::vector<openvdb::Vec3d>& points,
              const std::vector<std::array<int32_t, 3>>& triangles)
{
    std::vector<openvdb::Vec3d> normals(points.size(), openvdb::Vec3d(0.0));
    for (const auto& t : triangles) {
        const openvdb::Vec3d n =
            (points[t[1]] - points[t[0]]).cross(points[t[2]] - points[t[0]]); // 2 x area
        for (int i = 0; i < 3; ++i)
            normals[t[i]] += n;
    }
    for (openvdb::Vec3d& n : normals) {
        const double length = n.length();
        n = length > 0 ? n / length : openvdb::Vec3d(0.0);
    }
    return normals;
}

bool
isFinite(const openvdb::Vec3d& v)
{
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

} // namespace

openvdb::Vec3d
transportNormal(const openvdb::Mat3d& A, const openvdb::Vec3d& n, bool inverse)
{
    const Eigen::Vector3d m = cofactorTimes(A, n, inverse);
    const double length = m.norm();
    if (!(length > 0) || !std::isfinite(length)) return openvdb::Vec3d(0.0);
    return openvdb::Vec3d(m[0], m[1], m[2]) / length;
}

MeshTransportResult
transportMesh(MeshDocument& mesh, const DeformationField& phi, const MeshTransportOptions& options)
{
    const bool inverse = options.inverse;
    const std::size_t n = mesh.vertexCount();
    if (options.attributes) {
        if (mesh.format() != MeshDocument::Format::Ply) {
            OPENVDB_THROW(openvdb::ValueError,
                          "per-vertex attributes can only be written to a PLY file (OBJ and STL "
                          "have no vertex properties)");
        }
        if (options.triangles.empty() && mesh.normals().size() != n) {
            OPENVDB_THROW(openvdb::ValueError,
                          "area_stretch needs the mesh's faces or per-vertex normals; the file "
                          "has neither");
        }
        for (const auto& t : options.triangles) {
            for (int32_t v : t) {
                if (v < 0 || std::size_t(v) >= n) {
                    OPENVDB_THROW(openvdb::ValueError, "transportMesh: triangle index "
                                                           << v << " out of range (" << n
                                                           << " vertices)");
                }
            }
        }
    }

    if (phi.dimension() == 2) {
        // A 2D deformation acts on its plane: a mesh (or OBJ curve) must lie in it.
        const double z0 = phi.worldBounds().min()[2];
        const double tolerance = PLANE_TOLERANCE * phi.worldBounds().extents().length();
        for (std::size_t i = 0; i < n; ++i) {
            if (std::abs(mesh.positions()[i][2] - z0) > tolerance) {
                OPENVDB_THROW(openvdb::ValueError, "the deformation is 2D (the plane z = "
                                                       << z0 << ") but the mesh is 3D (vertex " << i
                                                       << " has z = " << mesh.positions()[i][2]
                                                       << "); use a 3D deformation");
            }
        }
    }
    MeshTransportResult result;
    result.vertices = n;
    const std::vector<openvdb::Vec3d> before = mesh.positions();
    std::vector<openvdb::Vec3d> after = before;
    result.inverseFailures = phi.mapPoints(after, inverse, options.threaded);

    const openvdb::BBoxd& box = phi.worldBounds();
    const int dim = phi.dimension();
    for (const openvdb::Vec3d& p : before) {
        for (int a = 0; a < dim; ++a) {
            if (p[a] < box.min()[a] || p[a] > box.max()[a]) {
                ++result.outsideDomain;
                break;
            }
        }
    }
    for (std::size_t i = 0; i < n; ++i)
        result.maxDisplacement = std::max(result.maxDisplacement, (after[i] - before[i]).length());

    // Normals: the Jacobian at the anchor's preimage (forward: the anchor itself).
    std::vector<openvdb::Vec3d>& normals = mesh.normals();
    const std::vector<openvdb::Vec3d>& anchors = mesh.normalAnchors();
    std::vector<char> rewritten(normals.size(), 0);
    forEachIndex(normals.size(), options.threaded, [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const openvdb::Vec3d nrm = normals[i];
            if (!mesh.isNormalUsed(i) || !isFinite(nrm) || nrm.lengthSqr() == 0) continue;
            const openvdb::Vec3d x = inverse ? phi.inverse(anchors[i]).x : anchors[i];
            const openvdb::Vec3d m = transportNormal(phi.jacobian(x), nrm, inverse);
            if (m.lengthSqr() == 0) continue;
            normals[i] = m * nrm.length(); // the file's normals may not be unit: keep the length
            rewritten[i] = 1;
        }
    });
    for (char c : rewritten)
        result.normals += std::size_t(c);

    if (options.attributes) {
        const std::vector<openvdb::Vec3d> surfaceNormals =
            options.triangles.empty() ? mesh.normals() : vertexNormals(before, options.triangles);
        std::vector<float> det(n), stretch(n), displacement(n), residual;
        if (options.signedDistance) residual.resize(n);
        std::vector<char> folded(n, 0);
        forEachIndex(n, options.threaded, [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                // A = D phi at the source-space point of the vertex.
                const openvdb::Mat3d A = phi.jacobian(inverse ? after[i] : before[i]);
                const double detA = A.det();
                if (!(detA > 0)) folded[i] = 1;
                det[i] = float(inverse ? 1.0 / detA : detA);
                openvdb::Vec3d nrm = surfaceNormals[i];
                if (!isFinite(nrm)) nrm = openvdb::Vec3d(0.0);
                const double length = nrm.length();
                stretch[i] =
                    length > 0 ? float(cofactorTimes(A, nrm / length, inverse).norm()) : 0.0f;
                displacement[i] = float((after[i] - before[i]).length());
                if (options.signedDistance) {
                    residual[i] = float(std::abs(options.signedDistance(after[i])));
                }
            }
        });
        const auto fold = std::find(folded.begin(), folded.end(), char(1));
        if (fold != folded.end()) {
            OPENVDB_THROW(openvdb::ValueError, "the deformation folds at vertex "
                                                   << (fold - folded.begin())
                                                   << " (det D phi <= 0): det_jacobian "
                                                      "and area_stretch are undefined");
        }
        mesh.addVertexProperty(ATTRIBUTE_DET_JACOBIAN, std::move(det));
        mesh.addVertexProperty(ATTRIBUTE_AREA_STRETCH, std::move(stretch));
        mesh.addVertexProperty(ATTRIBUTE_DISPLACEMENT, std::move(displacement));
        result.added = {ATTRIBUTE_DET_JACOBIAN, ATTRIBUTE_AREA_STRETCH, ATTRIBUTE_DISPLACEMENT};
        if (options.signedDistance) {
            mesh.addVertexProperty(ATTRIBUTE_RESIDUAL, std::move(residual));
            result.added.push_back(ATTRIBUTE_RESIDUAL);
        }
    }
    mesh.positions() = after;
    return result;
}

} // namespace vdbmatch
