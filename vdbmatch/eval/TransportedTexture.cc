/// @file TransportedTexture.cc
/// @brief Painting M1 and carrying it, and the grid lines over Omega, by phi and psi o phi.
#include <vdbmatch/Parallel.h>
#include <vdbmatch/eval/TransportedTexture.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace vdbmatch {

namespace {

/// Breakpoints closer than this fraction of a voxel are merged.
constexpr double DUPLICATE_FRACTION = 1e-9;

void
requireDimension(const DeformationField& field, int dim, const char* caller, const char* role)
{
    if (field.dimension() != dim) {
        OPENVDB_THROW(openvdb::ValueError, std::string(caller) + ": " + role + " is a " +
                                               std::to_string(field.dimension()) +
                                               "D deformation, expected " + std::to_string(dim) +
                                               "D");
    }
}

openvdb::Vec2d
apply2D(const DeformationField& field, const openvdb::Vec2d& p)
{
    const openvdb::Vec3d q = field.apply(openvdb::Vec3d(p.x(), p.y(), 0.0));
    return openvdb::Vec2d(q.x(), q.y());
}

std::vector<ColoredPolyline2D>
mapLoops(const DeformationField& field, const std::vector<ColoredPolyline2D>& loops)
{
    std::vector<ColoredPolyline2D> out = loops;
    for (ColoredPolyline2D& loop : out)
        loop.points = applyToPolyline(field, loop.points);
    return out;
}

std::vector<std::vector<openvdb::Vec2d>>
mapLines(const DeformationField& field, const std::vector<std::vector<openvdb::Vec2d>>& lines)
{
    std::vector<std::vector<openvdb::Vec2d>> out(lines.size());
    detail::forEachIndex(lines.size(), /*threaded=*/true,
                         [&](std::size_t i) { out[i] = applyToPolyline(field, lines[i]); });
    return out;
}

} // namespace

std::vector<std::vector<std::int32_t>>
closedLoops(const Surface<2>& curve)
{
    const std::size_t n = curve.points.size();
    constexpr std::int32_t NONE = -1;
    std::vector<std::array<std::int32_t, 2>> neighbours(n, {NONE, NONE});
    std::vector<int> uses(n, 0);
    for (const auto& segment : curve.elements) {
        for (int e = 0; e < 2; ++e) {
            const std::int32_t v = segment[e];
            if (v < 0 || std::size_t(v) >= n) {
                OPENVDB_THROW(openvdb::ValueError, "closedLoops: segment index " +
                                                       std::to_string(v) + " is out of range");
            }
            if (uses[v] < 2) neighbours[v][uses[v]] = segment[1 - e];
            ++uses[v];
        }
    }
    for (std::size_t v = 0; v < n; ++v) {
        if (uses[v] != 2) {
            OPENVDB_THROW(openvdb::ValueError, "closedLoops: vertex " + std::to_string(v) +
                                                   " is used by " + std::to_string(uses[v]) +
                                                   " segments, expected 2 (a closed curve)");
        }
    }
    std::vector<std::vector<std::int32_t>> loops;
    std::vector<char> visited(n, 0);
    for (std::size_t start = 0; start < n; ++start) {
        if (visited[start]) continue;
        std::vector<std::int32_t> loop;
        std::int32_t previous = NONE, current = std::int32_t(start);
        do {
            visited[current] = 1;
            loop.push_back(current);
            const auto& nb = neighbours[current];
            const std::int32_t next = nb[0] != previous ? nb[0] : nb[1];
            previous = current;
            current = next;
        } while (current != std::int32_t(start) && !visited[current]);
        loops.push_back(std::move(loop));
    }
    return loops;
}

std::vector<openvdb::Vec2d>
applyToPolyline(const DeformationField& field, const std::vector<openvdb::Vec2d>& points)
{
    std::vector<openvdb::Vec2d> out(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        out[i] = apply2D(field, points[i]);
    return out;
}

std::vector<std::vector<openvdb::Vec2d>>
gridLines(const DeformationField& field, int cells, double extraSpacing)
{
    requireDimension(field, 2, "gridLines", "the field");
    if (cells < 1) {
        OPENVDB_THROW(openvdb::ValueError,
                      "gridLines: cells must be >= 1, got " + std::to_string(cells));
    }
    const openvdb::math::Transform& xform = field.grid().transform();
    const openvdb::BBoxd& omega = field.worldBounds();
    const double voxel = field.voxelSize();
    std::vector<std::vector<openvdb::Vec2d>> lines;
    // axis: the coordinate held constant; the line runs along the other one.
    for (int axis = 0; axis < 2; ++axis) {
        const int along = 1 - axis;
        const double lo = omega.min()[along], hi = omega.max()[along];
        for (int i = 0; i <= cells; ++i) {
            const double c = i == cells ? omega.max()[axis]
                                        : omega.min()[axis] +
                                              (omega.max()[axis] - omega.min()[axis]) * i / cells;
            openvdb::Vec3d probe(0.0);
            probe[axis] = c;
            probe[along] = lo;
            const openvdb::Vec3d index0 = xform.worldToIndex(probe);
            // Corners of the Kuhn triangles along the line (index space): the voxel edges
            // (integer index) and the diagonals t_axis = t_along of the cells, i.e. integer +
            // frac(index of c).
            const double fraction = index0[axis] - std::floor(index0[axis]);
            std::vector<double> ts{lo, hi}; // positions along the line, world
            const double first = std::floor(index0[along]);
            const int steps = int(std::ceil((hi - lo) / voxel)) + 2;
            for (int k = 0; k <= steps; ++k) {
                for (double offset : {0.0, fraction}) {
                    const double t = lo + (first + k + offset - index0[along]) * voxel;
                    if (t > lo && t < hi) ts.push_back(t);
                }
            }
            if (extraSpacing > 0.0) {
                const int samples = int(std::ceil((hi - lo) / extraSpacing));
                for (int k = 1; k < samples; ++k)
                    ts.push_back(lo + (hi - lo) * k / samples);
            }
            std::sort(ts.begin(), ts.end());
            std::vector<openvdb::Vec2d> line;
            line.reserve(ts.size());
            for (double t : ts) {
                if (!line.empty() && t - line.back()[along] <= DUPLICATE_FRACTION * voxel) {
                    continue;
                }
                openvdb::Vec2d p(0.0);
                p[axis] = c;
                p[along] = t;
                line.push_back(p);
            }
            lines.push_back(std::move(line));
        }
    }
    return lines;
}

TransportedSurface
transportSurface(const Surface<3>& m1, const SurfaceTexture& texture, const DeformationField& phi,
                 const DeformationField* psi)
{
    if (m1.points.empty()) {
        OPENVDB_THROW(openvdb::ValueError, "transportSurface: the source surface has no points");
    }
    requireDimension(phi, 3, "transportSurface", "phi");
    if (psi) requireDimension(*psi, 3, "transportSurface", "psi");

    TransportedSurface out;
    out.triangles.assign(m1.elements.begin(), m1.elements.end());
    const std::size_t n = m1.points.size();
    out.source.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec<3>& p = m1.points[i];
        out.source[i] = openvdb::Vec3d(p[0], p[1], p[2]);
    }
    out.colors = paintSurface(out.source, texture);
    out.deformed.resize(n);
    if (psi) out.roundtrip.resize(n);
    detail::forEachIndex(n, /*threaded=*/true, [&](std::size_t i) {
        out.deformed[i] = phi.apply(out.source[i]);
        if (psi) out.roundtrip[i] = psi->apply(out.deformed[i]);
    });
    return out;
}

TransportedCurve
transportCurve(const Surface<2>& m1, const CurveTexture& texture, const DeformationField& phi,
               const DeformationField* psi, int cells)
{
    requireDimension(phi, 2, "transportCurve", "phi");
    if (psi) requireDimension(*psi, 2, "transportCurve", "psi");
    if (cells < 1) {
        OPENVDB_THROW(openvdb::ValueError,
                      "transportCurve: cells must be >= 1, got " + std::to_string(cells));
    }
    const std::vector<std::vector<std::int32_t>> loops = closedLoops(m1);
    if (loops.empty()) {
        OPENVDB_THROW(openvdb::ValueError, "transportCurve: the source curve has no points");
    }

    // Paint all loops at once (one centre, arc length running on from loop to loop).
    std::vector<openvdb::Vec2d> ordered;
    ordered.reserve(m1.points.size());
    for (const auto& loop : loops) {
        for (std::int32_t v : loop)
            ordered.emplace_back(m1.points[v][0], m1.points[v][1]);
    }
    const std::vector<Rgb8> colors = paintCurve(ordered, texture);

    TransportedCurve out;
    std::size_t k = 0;
    for (const auto& loop : loops) {
        ColoredPolyline2D polyline;
        polyline.closed = true;
        polyline.points.assign(ordered.begin() + std::ptrdiff_t(k),
                               ordered.begin() + std::ptrdiff_t(k + loop.size()));
        polyline.colors.assign(colors.begin() + std::ptrdiff_t(k),
                               colors.begin() + std::ptrdiff_t(k + loop.size()));
        k += loop.size();
        out.source.push_back(std::move(polyline));
    }
    out.deformed = mapLoops(phi, out.source);
    if (psi) out.roundtrip = mapLoops(*psi, out.deformed);

    out.grid = gridLines(phi, cells);
    out.deformedGrid = mapLines(phi, out.grid);
    if (psi) {
        const auto fine = gridLines(phi, cells, psi->voxelSize() / ROUNDTRIP_SAMPLES_PER_VOXEL);
        out.roundtripGrid = mapLines(*psi, mapLines(phi, fine));
    }
    const openvdb::BBoxd& omega = phi.worldBounds();
    out.omegaMin = openvdb::Vec2d(omega.min().x(), omega.min().y());
    out.omegaMax = openvdb::Vec2d(omega.max().x(), omega.max().y());
    return out;
}

} // namespace vdbmatch
