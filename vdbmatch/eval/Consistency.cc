/// @file Consistency.cc
#include "Consistency.h"

#include "ShapeDistance.h"

#include <vdbmatch/geometry/DistanceField.h>

#include <openvdb/Exceptions.h>
#include <openvdb/thread/Threading.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace vdbmatch {
namespace eval {

namespace {

using ConstAccessor = openvdb::tree::ValueAccessor<const openvdb::Vec3STree, /*IsSafe=*/false>;

/// Calls func(i) for i in [0, count), in parallel if @a threaded; checks the interrupter once per
/// range. Returns false if it fired (some i were skipped).
template <typename Func>
bool
forEachChecked(std::size_t count, bool threaded, openvdb::util::NullInterrupter* interrupter,
               const Func& func)
{
    std::atomic<bool> stopped{false};
    auto body = [&](const tbb::blocked_range<std::size_t>& range) {
        if (stopped.load(std::memory_order_relaxed)) return;
        if (interrupter && interrupter->wasInterrupted()) {
            stopped = true;
            if (threaded) openvdb::thread::cancelGroupExecution();
            return;
        }
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            func(i);
    };
    if (threaded) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), body);
    } else {
        /// Serial ranges of this many items, so the interrupter is still checked now and then.
        constexpr std::size_t SERIAL_CHUNK = 64;
        for (std::size_t b = 0; b < count && !stopped; b += SERIAL_CHUNK) {
            body(tbb::blocked_range<std::size_t>(b, std::min(count, b + SERIAL_CHUNK)));
        }
    }
    return !stopped;
}

/// A world point of a D-dimensional vertex; 2D points are put in the plane z of the grid.
template <int D>
openvdb::Vec3d
toWorld(const Vec<D>& p, double planeZ)
{
    openvdb::Vec3d w(0.0, 0.0, planeZ);
    for (int a = 0; a < D; ++a)
        w[a] = p[a];
    return w;
}

/// Mean and max of non-negative values, summed in order.
VertexError
summarize(const std::vector<double>& values)
{
    VertexError e;
    e.points = values.size();
    double sum = 0;
    for (double v : values) {
        sum += v;
        e.max = std::max(e.max, v);
    }
    e.mean = values.empty() ? 0.0 : sum / double(values.size());
    return e;
}

/// |b(a(x)) - x| over the vertices of a shape.
template <int D>
bool
compositionErrorOnShape(const DeformationField& a, const DeformationField& b,
                        const Surface<D>& shape, bool threaded,
                        openvdb::util::NullInterrupter* interrupter, VertexError& out)
{
    const double planeZ = a.worldBounds().min()[2];
    std::vector<double> values(shape.points.size(), 0.0);
    const bool complete = forEachChecked(values.size(), threaded, interrupter, [&](std::size_t i) {
        const openvdb::Vec3d x = toWorld<D>(shape.points[i], planeZ);
        values[i] = (b.apply(a.apply(x)) - x).length();
    });
    out = summarize(values);
    return complete;
}

/// |d(a(x))| over the vertices of a shape.
template <int D>
bool
residualOnShape(const DeformationField& a, const ShapeDistance<D>& d, const Surface<D>& shape,
                bool threaded, openvdb::util::NullInterrupter* interrupter, VertexError& out)
{
    const double planeZ = a.worldBounds().min()[2];
    std::vector<double> values(shape.points.size(), 0.0);
    const bool complete = forEachChecked(values.size(), threaded, interrupter, [&](std::size_t i) {
        values[i] = std::abs(d.signedDistance(a.apply(toWorld<D>(shape.points[i], planeZ))));
    });
    out = summarize(values);
    return complete;
}

/// Active voxel bounding box of a field's grid.
openvdb::CoordBBox
activeBox(const DeformationField& field)
{
    openvdb::CoordBBox box;
    field.grid().tree().evalActiveVoxelBoundingBox(box);
    return box;
}

template <int D>
JacobianStats
jacobianStatsImpl(const DeformationField& field, bool threaded,
                  openvdb::util::NullInterrupter* interrupter, bool& complete)
{
    const openvdb::CoordBBox box = activeBox(field);
    const openvdb::Coord lo = box.min(), hi = box.max();
    const int nx = hi[0] - lo[0], ny = hi[1] - lo[1], nz = D == 3 ? hi[2] - lo[2] : 1;
    constexpr double INF_DET = std::numeric_limits<double>::infinity();
    JacobianStats total;
    if (nx <= 0 || ny <= 0 || nz <= 0) {
        complete = true;
        return total;
    }
    // One row of cells per (j, k); rows are combined in order.
    const std::size_t rows = std::size_t(ny) * std::size_t(nz);
    std::vector<JacobianStats> perRow(rows);
    complete = forEachChecked(rows, threaded, interrupter, [&](std::size_t r) {
        const int j = lo[1] + int(r % std::size_t(ny));
        const int k = lo[2] + int(r / std::size_t(ny));
        JacobianStats s;
        s.min = INF_DET;
        s.max = -INF_DET;
        double dets[6];
        for (int i = lo[0]; i < hi[0]; ++i) {
            const int n = field.cellDeterminants(openvdb::Coord(i, j, k), dets);
            for (int m = 0; m < n; ++m) {
                const double det = dets[m];
                s.min = std::min(s.min, det);
                s.max = std::max(s.max, det);
                ++s.simplices;
                if (det < DET_LOW_THRESHOLD) ++s.belowThreshold;
                if (det <= 0) ++s.nonPositive;
            }
        }
        perRow[r] = s;
    });
    total.min = INF_DET;
    total.max = -INF_DET;
    for (const JacobianStats& s : perRow) {
        if (!s.simplices) continue;
        total.min = std::min(total.min, s.min);
        total.max = std::max(total.max, s.max);
        total.simplices += s.simplices;
        total.belowThreshold += s.belowThreshold;
        total.nonPositive += s.nonPositive;
    }
    if (!total.simplices) total.min = total.max = 1;
    return total;
}

/// The error at one sample point; @a found is false if an inverse walk did not end.
struct PointError
{
    double error = 0;
    bool found = true;
};

/// An error over the regular points x = min + i spacing of @a field's Omega, one row of points
/// (along x) per task, rows combined in order.
/// @param pointError  PointError(const openvdb::Vec3d& x), called concurrently
/// @param failures    set to the number of points with found == false
/// @throw openvdb::ValueError naming @a caller if spacing is not positive and finite
template <typename PointFunc>
DomainError
errorOverDomainImpl(const char* caller, const DeformationField& field, double spacing,
                    bool threaded, openvdb::util::NullInterrupter* interrupter, bool& complete,
                    std::size_t& failures, const PointFunc& pointError)
{
    if (!(spacing > 0) || !std::isfinite(spacing)) {
        OPENVDB_THROW(openvdb::ValueError,
                      std::string(caller) + ": the spacing must be positive and finite");
    }
    /// Slack on the last point, relative to the spacing (float transforms).
    constexpr double LAST_POINT_SLACK = 1e-6;
    const int dim = field.dimension();
    const openvdb::BBoxd& bounds = field.worldBounds();
    std::array<std::size_t, 3> n{{1, 1, 1}};
    for (int a = 0; a < dim; ++a) {
        n[a] = std::size_t(std::floor(bounds.extents()[a] / spacing + LAST_POINT_SLACK)) + 1;
    }
    const std::size_t rows = n[1] * n[2];
    std::vector<double> sum2(rows, 0.0), rowMax(rows, 0.0);
    std::vector<std::size_t> rowFailures(rows, 0);
    complete = forEachChecked(rows, threaded, interrupter, [&](std::size_t r) {
        const std::size_t j = r % n[1], k = r / n[1];
        openvdb::Vec3d x = bounds.min();
        x[1] += double(j) * spacing;
        if (dim == 3) x[2] += double(k) * spacing;
        double s = 0, m = 0;
        std::size_t bad = 0;
        for (std::size_t i = 0; i < n[0]; ++i) {
            x[0] = bounds.min()[0] + double(i) * spacing;
            const PointError e = pointError(x);
            s += e.error * e.error;
            m = std::max(m, e.error);
            if (!e.found) ++bad;
        }
        sum2[r] = s;
        rowMax[r] = m;
        rowFailures[r] = bad;
    });
    DomainError out;
    out.points = rows * n[0];
    double s = 0;
    failures = 0;
    for (std::size_t r = 0; r < rows; ++r) {
        s += sum2[r];
        out.linf = std::max(out.linf, rowMax[r]);
        failures += rowFailures[r];
    }
    out.l2 = std::sqrt(s / double(out.points));
    return out;
}

DomainError
compositionErrorImpl(const DeformationField& phi, const DeformationField& psi, double spacing,
                     bool threaded, openvdb::util::NullInterrupter* interrupter, bool& complete)
{
    std::size_t failures = 0;
    return errorOverDomainImpl("compositionErrorOverDomain", phi, spacing, threaded, interrupter,
                               complete, failures, [&](const openvdb::Vec3d& x) {
                                   return PointError{(psi.apply(phi.apply(x)) - x).length(), true};
                               });
}

/// |phi^{-1}(phi(x)) - x| over phi's Omega, each walk starting from the guess of
/// DeformationField::inverse(y) (two fixed-point iterates: a real walk, not a start at the
/// answer).
/// @note Deviation from issue 9's suggested warm start (the previous point of the row): with
///       stride 1 the sample points are grid nodes, so that walk runs along the image of a
///       voxel edge, i.e. inside a face of the deformed simplices, where DeformationField's walk
///       creeps by its nudge and runs out of steps (5127 of 258000 points on a 129^3 match,
///       1340 simplices per walk on average). The fixed-point guess costs two displacement
///       evaluations and walks 1.8 simplices on average there, none failing.
DomainError
inverseRoundTripImpl(const DeformationField& phi, double spacing, bool threaded,
                     openvdb::util::NullInterrupter* interrupter, bool& complete,
                     std::size_t& failures)
{
    return errorOverDomainImpl("inverseRoundTripOverDomain", phi, spacing, threaded, interrupter,
                               complete, failures, [&](const openvdb::Vec3d& x) {
                                   const DeformationField::InverseResult r =
                                       phi.inverse(phi.apply(x));
                                   return PointError{(r.x - x).length(), r.found};
                               });
}

/// |psi(y) - phi^{-1}(y)| over psi's Omega, each walk starting from psi(y).
DomainError
psiVsInverseImpl(const DeformationField& phi, const DeformationField& psi, double spacing,
                 bool threaded, openvdb::util::NullInterrupter* interrupter, bool& complete,
                 std::size_t& failures)
{
    return errorOverDomainImpl("psiVsInverseOverDomain", psi, spacing, threaded, interrupter,
                               complete, failures, [&](const openvdb::Vec3d& y) {
                                   const openvdb::Vec3d p = psi.apply(y);
                                   const DeformationField::InverseResult r = phi.inverse(y, p);
                                   return PointError{(p - r.x).length(), r.found};
                               });
}

/// |psi(y) - phi^{-1}(y)| over the vertices y of a shape, each walk starting from psi(y).
template <int D>
bool
psiVsInverseOnShape(const DeformationField& phi, const DeformationField& psi,
                    const Surface<D>& shape, bool threaded,
                    openvdb::util::NullInterrupter* interrupter, VertexError& out,
                    std::size_t& failures)
{
    const double planeZ = psi.worldBounds().min()[2];
    std::vector<double> values(shape.points.size(), 0.0);
    std::vector<unsigned char> found(shape.points.size(), 1);
    const bool complete = forEachChecked(values.size(), threaded, interrupter, [&](std::size_t i) {
        const openvdb::Vec3d y = toWorld<D>(shape.points[i], planeZ);
        const openvdb::Vec3d p = psi.apply(y);
        const DeformationField::InverseResult r = phi.inverse(y, p);
        values[i] = (p - r.x).length();
        found[i] = r.found ? 1 : 0;
    });
    out = summarize(values);
    failures = std::size_t(std::count(found.begin(), found.end(), 0));
    return complete;
}

} // namespace

DomainError
compositionErrorOverDomain(const DeformationField& phi, const DeformationField& psi, double spacing,
                           bool threaded, openvdb::util::NullInterrupter* interrupter)
{
    bool complete = true;
    return compositionErrorImpl(phi, psi, spacing, threaded, interrupter, complete);
}

DomainError
inverseRoundTripOverDomain(const DeformationField& phi, double spacing, std::size_t* failures,
                           bool threaded, openvdb::util::NullInterrupter* interrupter)
{
    bool complete = true;
    std::size_t bad = 0;
    const DomainError e = inverseRoundTripImpl(phi, spacing, threaded, interrupter, complete, bad);
    if (failures) *failures = bad;
    return e;
}

DomainError
psiVsInverseOverDomain(const DeformationField& phi, const DeformationField& psi, double spacing,
                       std::size_t* failures, bool threaded,
                       openvdb::util::NullInterrupter* interrupter)
{
    bool complete = true;
    std::size_t bad = 0;
    const DomainError e = psiVsInverseImpl(phi, psi, spacing, threaded, interrupter, complete, bad);
    if (failures) *failures = bad;
    return e;
}

JacobianStats
jacobianStats(const DeformationField& field, bool threaded,
              openvdb::util::NullInterrupter* interrupter)
{
    bool complete = true;
    return field.dimension() == 2 ? jacobianStatsImpl<2>(field, threaded, interrupter, complete)
                                  : jacobianStatsImpl<3>(field, threaded, interrupter, complete);
}

template <int D>
ConsistencyReport
measureConsistency(const DeformationField& phi, const DeformationField& psi, const Surface<D>& m1,
                   const Surface<D>& m2, const ConsistencyOptions& options,
                   openvdb::util::NullInterrupter* interrupter)
{
    if (phi.dimension() != D || psi.dimension() != D) {
        OPENVDB_THROW(openvdb::ValueError, "measureConsistency: the deformations are " +
                                               std::to_string(phi.dimension()) + "D and " +
                                               std::to_string(psi.dimension()) + "D, the shapes " +
                                               std::to_string(D) + "D");
    }
    if (options.stride < 1) {
        OPENVDB_THROW(openvdb::ValueError, "measureConsistency: the stride must be >= 1");
    }
    checkSurface(m1, "M1 (source)");
    checkSurface(m2, "M2 (target)");
    const UnitBoxPlacement omega = domainPlacement(phi);
    checkShapeInDomain(m1, omega, "M1 (source)");
    checkShapeInDomain(m2, omega, "M2 (target)");

    ConsistencyReport report;
    report.dim = D;
    report.domainSize = domainSize(phi);
    const int level = std::max(deformationLevel(phi), deformationLevel(psi));
    report.distanceLevel =
        options.distanceLevel > 0 ? options.distanceLevel : defaultDistanceLevel(D, level);
    if (report.distanceLevel < MIN_DISTANCE_LEVEL || report.distanceLevel > MAX_DISTANCE_LEVEL) {
        OPENVDB_THROW(openvdb::ValueError, "measureConsistency: the distance level must be in [" +
                                               std::to_string(MIN_DISTANCE_LEVEL) + ", " +
                                               std::to_string(MAX_DISTANCE_LEVEL) + "]");
    }
    report.sampleSpacing = std::min(phi.voxelSize(), psi.voxelSize()) * options.stride;

    auto run = [&](bool ok) {
        if (!ok) report.interrupted = true;
        return ok;
    };
    const bool threaded = options.threaded;
    bool complete = true;
    report.psiPhiDomain =
        compositionErrorImpl(phi, psi, report.sampleSpacing, threaded, interrupter, complete);
    if (!run(complete)) return report;
    report.phiPsiDomain =
        compositionErrorImpl(psi, phi, report.sampleSpacing, threaded, interrupter, complete);
    if (!run(complete)) return report;
    if (!run(compositionErrorOnShape(phi, psi, m1, threaded, interrupter, report.psiPhiShape))) {
        return report;
    }
    if (!run(compositionErrorOnShape(psi, phi, m2, threaded, interrupter, report.phiPsiShape))) {
        return report;
    }
    report.inverseRoundTripDomain = inverseRoundTripImpl(
        phi, report.sampleSpacing, threaded, interrupter, complete, report.inverseFailures);
    if (!run(complete)) return report;
    std::size_t domainFailures = 0, shapeFailures = 0;
    report.psiVsInverseDomain = psiVsInverseImpl(phi, psi, report.sampleSpacing, threaded,
                                                 interrupter, complete, domainFailures);
    if (!run(complete)) return report;
    if (!run(psiVsInverseOnShape(phi, psi, m2, threaded, interrupter, report.psiVsInverseShape,
                                 shapeFailures))) {
        return report;
    }
    report.psiVsInverseFailures = domainFailures + shapeFailures;
    report.detPhi = jacobianStatsImpl<D>(phi, threaded, interrupter, complete);
    if (!run(complete)) return report;
    report.detPsi = jacobianStatsImpl<D>(psi, threaded, interrupter, complete);
    if (!run(complete)) return report;

    const ShapeDistance<D> d1(m1, omega, report.distanceLevel, threaded);
    if (interrupter && !run(!interrupter->wasInterrupted())) return report;
    const ShapeDistance<D> d2(m2, omega, report.distanceLevel, threaded);
    report.distanceVoxel = d1.voxelSize();
    if (!run(residualOnShape(phi, d2, m1, threaded, interrupter, report.residualPhi))) {
        return report;
    }
    run(residualOnShape(psi, d1, m2, threaded, interrupter, report.residualPsi));
    return report;
}

template ConsistencyReport measureConsistency<2>(const DeformationField&, const DeformationField&,
                                                 const Surface<2>&, const Surface<2>&,
                                                 const ConsistencyOptions&,
                                                 openvdb::util::NullInterrupter*);
template ConsistencyReport measureConsistency<3>(const DeformationField&, const DeformationField&,
                                                 const Surface<3>&, const Surface<3>&,
                                                 const ConsistencyOptions&,
                                                 openvdb::util::NullInterrupter*);

} // namespace eval
} // namespace vdbmatch
