/// @file MeshTransport.h
/// @brief Carrying a mesh file through a deformation: every vertex moved by phi (or phi^{-1}),
///        normals by the cofactor of the Jacobian, everything else in the file kept; optional
///        per-vertex measures of the map as PLY properties.
///
/// Direction: a point x of the source space goes to phi(x) (forward), a point y of the target
/// space to phi^{-1}(y) (inverse, exact: DeformationField::inverse). Points outside the
/// deformation's domain Omega stay where they are (phi = Id there).
///
/// Normals: a surface normal n at a point x is carried to the image surface as
/// @f[ n' = \frac{\operatorname{cof} D\phi(x)\, n}{|\operatorname{cof} D\phi(x)\, n|}, @f]
/// the normal of the image of the tangent plane (cof A = det(A) A^{-T}: the paper's
/// eq:inversearea / Nanson's formula); for the inverse, A = D phi^{-1}(y) = D phi(x)^{-1} at
/// x = phi^{-1}(y), i.e. n' proportional to D phi(x)^T n. D phi is the Jacobian of the simplex
/// that contains the normal's anchor (MeshDocument::normalAnchors()). Zero and non-finite
/// normals, and OBJ normals no face uses, are kept as they are.
///
/// Per-vertex measures (MeshAttribute), for the vertex x and its image x' (PLY only):
/// - `det_jacobian`: det D phi(x) (forward) or det D phi^{-1}(x) = 1 / det D phi(x') (inverse);
/// - `area_stretch`: the surface area ratio |cof A n| of the map at the vertex, A its Jacobian
///   and n the unit area-weighted normal of the faces around the vertex (the file's normals if
///   it has no faces);
/// - `displacement`: |x' - x|, world units;
/// - `residual`: |d(x')| for a caller-given signed distance d of the shape x' should lie on
///   (the target M2 for phi, the source M1 for phi^{-1}), world units.
///
/// Units: world units of the mesh file and of the deformation grid (the inputs' world space).
/// @see paper eq:inversearea, DeformationField.h
#pragma once

#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/MeshDocument.h>

#include <openvdb/openvdb.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace vdbmatch {

/// Names of the per-vertex properties added by transportMesh.
constexpr const char* ATTRIBUTE_DET_JACOBIAN = "det_jacobian";
constexpr const char* ATTRIBUTE_AREA_STRETCH = "area_stretch";
constexpr const char* ATTRIBUTE_DISPLACEMENT = "displacement";
constexpr const char* ATTRIBUTE_RESIDUAL = "residual";

/// Options of transportMesh.
struct MeshTransportOptions
{
    /// Map by phi^{-1} instead of phi.
    bool inverse = false;
    /// Add det_jacobian, area_stretch and displacement as PLY vertex properties.
    bool attributes = false;
    /// If set (and attributes), also add `residual` = |signedDistance(x')|.
    /// Signature: double(const openvdb::Vec3d& xWorld); called concurrently.
    std::function<double(const openvdb::Vec3d&)> signedDistance;
    /// Faces of the mesh for the area-weighted normals of area_stretch, as triangles of vertex
    /// indices (readMesh of the same file); empty: use the file's per-vertex normals.
    std::vector<std::array<int32_t, 3>> triangles;
    bool threaded = true; ///< use TBB (the result does not depend on it)
};

/// What transportMesh did.
struct MeshTransportResult
{
    std::size_t vertices = 0;
    std::size_t normals = 0;         ///< normals rewritten
    std::size_t outsideDomain = 0;   ///< vertices outside Omega (left in place)
    std::size_t inverseFailures = 0; ///< inverse walks that did not end (DeformationField)
    std::vector<std::string> added;  ///< names of the properties added, in order
    double maxDisplacement = 0;      ///< max |x' - x|, world units
};

/// Moves the vertices and normals of @a mesh by phi or phi^{-1} (file comment), in place.
/// @throw openvdb::ValueError if phi is 2D and a vertex does not lie in its plane (within 1e-6
///        of Omega's diagonal), attributes are requested and the mesh is not a PLY file, the
///        properties already exist, or area_stretch has neither faces nor normals to use
MeshTransportResult transportMesh(MeshDocument& mesh, const DeformationField& phi,
                                  const MeshTransportOptions& options = MeshTransportOptions());

/// The cofactor-transported unit normal (file comment): cof(A) n / |cof(A) n| for the forward
/// map with A = D phi(x), or A^T n / |A^T n| (with the sign of det A) for the inverse at
/// x = phi^{-1}(y). A zero result stays zero.
openvdb::Vec3d transportNormal(const openvdb::Mat3d& A, const openvdb::Vec3d& n, bool inverse);

} // namespace vdbmatch
