/// @file Surface.h
/// @brief Closed polygonal surfaces (3D: triangles) and curves (2D: segments), the explicit form
///        of the input shapes, with their bounding box, placement in Omega and validity checks.
///
/// A Surface<3> is a triangle mesh, a Surface<2> a set of closed polylines stored as segments.
/// The space of the points is stated by whoever produces the surface: the readers of MeshIO.h
/// and SurfaceExtraction.h return world units (those of the input file or grid), the distance
/// functions of DistanceField.h expect Omega = (0,1)^D units. transformed() maps between the two
/// with a UnitBoxPlacement. Orientation is not required to be consistent: signs of distances are
/// computed from the topology (flood fill, crossing parity), not from the element order.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <openvdb/openvdb.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vdbmatch {

/// A closed surface (D = 3, triangles) or a set of closed curves (D = 2, segments).
template <int D> struct Surface
{
    static_assert(D == 2 || D == 3, "Surface: D must be 2 or 3");
    /// Vertex positions, in the space stated by the producer (world or Omega units).
    std::vector<Vec<D>> points;
    /// Triangles (D = 3) or segments (D = 2): indices into points.
    std::vector<std::array<int32_t, D>> elements;

    bool empty() const { return points.empty() || elements.empty(); }
};

/// Direction of transformed().
enum class PlacementDirection {
    WorldToUnit, ///< world units -> Omega (UnitBoxPlacement::toUnit)
    UnitToWorld  ///< Omega -> world units (UnitBoxPlacement::toWorld)
};

/// Bounding box of the points (z = 0 in 2D); an empty BBoxd if there are none.
template <int D> openvdb::BBoxd boundingBox(const Surface<D>& surface);

/// The surface with every point mapped by @a placement (2D: x and y of the 3D map at z = 0;
/// Omega's z coordinate is dropped). Elements are kept.
template <int D>
Surface<D> transformed(const Surface<D>& surface, const UnitBoxPlacement& placement,
                       PlacementDirection direction);

/// Checks that @a surface bounds a region:
/// - at least one element, all indices in range and no element repeating a vertex;
/// - finite coordinates;
/// - closed: 3D every undirected edge is shared by exactly two triangles; 2D every vertex is
///   used by exactly two segments;
/// - not degenerate: the bounding box has a positive extent in D directions.
/// @param what  names the surface in the message, e.g. "file 'a.obj'"
/// @throw openvdb::ValueError naming @a what and the first failed check
template <int D> void checkSurface(const Surface<D>& surface, const std::string& what);

/// Total length (2D) or area (3D) of the elements.
template <int D> double measure(const Surface<D>& surface);

/// Signed enclosed area (2D, positive for counter-clockwise curves) or signed enclosed volume
/// (3D, positive for outward-oriented triangles), by the divergence theorem.
template <int D> double signedVolume(const Surface<D>& surface);

template <> double measure<2>(const Surface<2>& surface);
template <> double measure<3>(const Surface<3>& surface);
template <> double signedVolume<2>(const Surface<2>& surface);
template <> double signedVolume<3>(const Surface<3>& surface);

extern template struct Surface<2>;
extern template struct Surface<3>;

} // namespace vdbmatch
