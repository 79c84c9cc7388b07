/// @file TransportedTexture.h
/// @brief A pattern painted on the source shape M1 and carried by the computed deformations: the
///        vertices of M1 are moved by phi (and by psi o phi when the reverse matching psi is
///        given) and keep the colours they got on M1, so the texture moves with the points; in
///        2D also the images of the lines of a regular grid over Omega.
///
/// The colours depend only on M1 (Texture.h: a pattern in a parametrization of M1, or colours
/// by position); phi(M1) and psi(phi(M1)) are drawn with the same per-vertex colours, as in the
/// paper's figures. Under exact symmetry psi o phi = Id and the round trip reproduces M1.
///
/// Grid lines (2D): the lines x = const and y = const at cells + 1 equally spaced positions
/// across Omega (the world box of phi's grid, boundary lines included). The deformation is
/// piecewise linear on the Kuhn triangles of its voxel grid (DeformationField.h), so its image
/// of a straight line is a polyline whose corners are the line's crossings with the voxel edges
/// and with the cells' diagonals: the lines are sampled exactly there (and at their ends), which
/// renders phi of the grid without approximation. For psi o phi, the corners of psi in
/// phi(line) are not computed: the lines are in addition sampled uniformly at a quarter of
/// psi's voxel size (ROUNDTRIP_SAMPLES_PER_VOXEL), an approximation far below a pixel.
///
/// Spaces: every position is in world units (those of the input shapes and of the deformation
/// grids); 2D shapes lie in the plane z = 0 and 2D points are (x, y).
/// Thread-safety: the functions are reentrant; the fields are only read.
/// @see paper fig:jump, fig:starfish, fig:dolphin
#pragma once

#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/render/Canvas.h>
#include <vdbmatch/render/Curves2D.h>
#include <vdbmatch/render/Texture.h>

#include <openvdb/Types.h>

#include <array>
#include <cstdint>
#include <vector>

namespace vdbmatch {

/// Default number of grid cells across Omega in each direction (cells + 1 lines each way).
constexpr int DEFAULT_GRID_CELLS = 24;
/// Uniform samples per voxel of psi along the grid lines of the round trip (see the file block).
constexpr int ROUNDTRIP_SAMPLES_PER_VOXEL = 4;

/// A textured triangle mesh M1 and its images; all point arrays share the triangles and colours.
struct TransportedSurface
{
    std::vector<std::array<std::int32_t, 3>> triangles;
    std::vector<openvdb::Vec3d> source;    ///< the vertices of M1, world
    std::vector<openvdb::Vec3d> deformed;  ///< phi(source), world
    std::vector<openvdb::Vec3d> roundtrip; ///< psi(phi(source)); empty without psi
    std::vector<Rgb8> colors;              ///< painted on M1, one per vertex
};

/// Paints @a m1 with @a texture and carries its vertices by @a phi and, if given, @a psi o phi.
/// @param m1   closed triangle mesh, world units (Shape::surface)
/// @param phi  the deformation matching M1 onto M2 (3D)
/// @param psi  the deformation matching M2 onto M1 (3D), or null
/// @throw openvdb::ValueError if m1 has no points, phi or psi is not 3D, or the texture is
///        invalid (paintSurface)
TransportedSurface transportSurface(const Surface<3>& m1, const SurfaceTexture& texture,
                                    const DeformationField& phi,
                                    const DeformationField* psi = nullptr);

/// A textured curve M1, its images, and the grid lines over Omega with their images.
struct TransportedCurve
{
    /// The closed loops of M1 in order along each loop, with their colours, world (x, y).
    std::vector<ColoredPolyline2D> source;
    std::vector<ColoredPolyline2D> deformed;                ///< phi of source, same colours
    std::vector<ColoredPolyline2D> roundtrip;               ///< psi(phi(source)); empty without psi
    std::vector<std::vector<openvdb::Vec2d>> grid;          ///< the straight lines (open)
    std::vector<std::vector<openvdb::Vec2d>> deformedGrid;  ///< phi of grid, exact
    std::vector<std::vector<openvdb::Vec2d>> roundtripGrid; ///< psi(phi(grid)); empty without psi
    openvdb::Vec2d omegaMin{0.0}, omegaMax{0.0}; ///< Omega of phi (world box of its grid)
};

/// Paints @a m1 with @a texture (the points of all loops in loop order, one centre for all) and
/// carries its vertices and the lines of a cells x cells grid over phi's Omega by @a phi and,
/// if given, @a psi o phi.
/// @param m1     closed curves, world units, z = 0 (Shape::curve)
/// @param phi    the deformation matching M1 onto M2 (2D)
/// @param psi    the deformation matching M2 onto M1 (2D), or null
/// @param cells  grid cells across Omega in each direction, >= 1
/// @throw openvdb::ValueError if m1 is not a set of closed loops (closedLoops), phi or psi is
///        not 2D, cells < 1, or the texture is invalid (paintCurve)
TransportedCurve transportCurve(const Surface<2>& m1, const CurveTexture& texture,
                                const DeformationField& phi, const DeformationField* psi = nullptr,
                                int cells = DEFAULT_GRID_CELLS);

/// The closed loops of a curve: vertex indices in order along each loop (each loop listed once,
/// starting at its lowest unvisited vertex; the last vertex joins the first).
/// @throw openvdb::ValueError if a vertex is not used by exactly two segments or an index is out
///        of range
std::vector<std::vector<std::int32_t>> closedLoops(const Surface<2>& curve);

/// The straight lines x = const and y = const of a cells x cells grid over the 2D field's Omega,
/// sampled at the corners of the field's image of them (see the file block), plus, if
/// @a extraSpacing > 0, uniformly every extraSpacing world units.
/// @throw openvdb::ValueError if the field is not 2D or cells < 1
std::vector<std::vector<openvdb::Vec2d>> gridLines(const DeformationField& field, int cells,
                                                   double extraSpacing = 0.0);

/// Maps every point of a 2D polyline by the 2D field (z = 0 in, x and y out).
std::vector<openvdb::Vec2d> applyToPolyline(const DeformationField& field,
                                            const std::vector<openvdb::Vec2d>& points);

} // namespace vdbmatch
