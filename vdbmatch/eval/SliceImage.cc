/// @file SliceImage.cc
#include "SliceImage.h"

#include "ShapeDistance.h"

#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/render/Preview.h>

#include <openvdb/Exceptions.h>
#include <openvdb/thread/Threading.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <vector>

namespace vdbmatch {
namespace eval {

namespace {

const char* const AXIS_NAMES[] = {"x", "y", "z"};

/// Slices smaller than this many pixels on a side are refused (a picture needs two).
constexpr int MIN_SLICE_RESOLUTION = 2;

std::string
shortNumber(double x)
{
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.4g", x);
    return buf;
}

/// A title for the preview of @a channel.
std::string
channelTitle(const std::string& channel)
{
    if (channel == "inverse_error") return "|psi(phi(x)) - x|";
    if (channel == "residual") return "d2(phi(x)) - d1(x)";
    if (channel == "det") return "det D phi";
    if (channel == "displacement") return "|phi(x) - x|";
    if (channel == "d1") return "d1 (M1)";
    if (channel == "d2") return "d2 (M2)";
    return channel;
}

} // namespace

bool
isSignedChannel(const std::string& channel)
{
    return channel == "residual" || channel == "d1" || channel == "d2";
}

template <int D>
SliceImage
sampleSlice(const DeformationField& phi, const DeformationField* psi, const Surface<D>& m1,
            const Surface<D>& m2, const SliceOptions& options,
            openvdb::util::NullInterrupter* interrupter)
{
    if (phi.dimension() != D || (psi && psi->dimension() != D)) {
        OPENVDB_THROW(
            openvdb::ValueError,
            "sampleSlice: the deformation is " + std::to_string(phi.dimension()) + "D" +
                (psi ? ", the inverse " + std::to_string(psi->dimension()) + "D" : std::string()) +
                ", the shapes " + std::to_string(D) + "D");
    }
    SliceImage slice;
    slice.dim = D;
    const int axis = options.axis.value_or(2);
    if (axis < 0 || axis > 2) {
        OPENVDB_THROW(openvdb::ValueError, "sampleSlice: the axis must be x, y or z");
    }
    if (D == 2 && axis != 2) {
        OPENVDB_THROW(openvdb::ValueError,
                      "sampleSlice: a 2D deformation is sliced in its own plane (axis z), not "
                      "along " +
                          std::string(AXIS_NAMES[axis]));
    }
    if (options.position && options.unitPosition) {
        OPENVDB_THROW(openvdb::ValueError,
                      "sampleSlice: give the position in world or in unit coordinates, not both");
    }
    if (D == 2 && (options.position || options.unitPosition)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "sampleSlice: a 2D deformation has no slice position (it is its own plane)");
    }
    if (options.resolution != 0 &&
        (options.resolution < MIN_SLICE_RESOLUTION || options.resolution > MAX_SLICE_RESOLUTION)) {
        OPENVDB_THROW(openvdb::ValueError, "sampleSlice: the resolution must be in [" +
                                               std::to_string(MIN_SLICE_RESOLUTION) + ", " +
                                               std::to_string(MAX_SLICE_RESOLUTION) + "]");
    }
    checkSurface(m1, "M1 (source)");
    checkSurface(m2, "M2 (target)");
    const UnitBoxPlacement omega = domainPlacement(phi);
    checkShapeInDomain(m1, omega, "M1 (source)");
    checkShapeInDomain(m2, omega, "M2 (target)");
    const openvdb::BBoxd& bounds = phi.worldBounds();
    slice.domainSize = domainSize(phi);

    slice.axis = axis;
    slice.columnAxis = (axis + 1) % 3;
    slice.rowAxis = (axis + 2) % 3;
    if (D == 2) {
        slice.columnAxis = 0;
        slice.rowAxis = 1;
    }
    const double lo = bounds.min()[axis], hi = bounds.max()[axis];
    if (D == 2) {
        slice.position = lo;
        slice.unitPosition = 0;
    } else {
        if (options.position) {
            slice.position = *options.position;
        } else if (options.unitPosition) {
            const double t = *options.unitPosition;
            if (!(t >= 0 && t <= 1)) {
                OPENVDB_THROW(openvdb::ValueError,
                              "sampleSlice: the unit position must be in [0, 1], got " +
                                  shortNumber(t));
            }
            slice.position = lo + t * (hi - lo);
        } else {
            slice.position = boundingBox(m1).getCenter()[axis];
        }
        if (!(slice.position >= lo && slice.position <= hi)) {
            OPENVDB_THROW(openvdb::ValueError, "sampleSlice: the position " +
                                                   shortNumber(slice.position) + " along " +
                                                   AXIS_NAMES[axis] + " is outside the domain [" +
                                                   shortNumber(lo) + ", " + shortNumber(hi) + "]");
        }
        slice.unitPosition = hi > lo ? (slice.position - lo) / (hi - lo) : 0.0;
    }

    const double extentC = bounds.extents()[slice.columnAxis];
    const double extentR = bounds.extents()[slice.rowAxis];
    slice.pixelSize = options.resolution > 0
                          ? std::max(extentC, extentR) / double(options.resolution)
                          : phi.voxelSize();
    const int width = std::max(1, int(std::lround(extentC / slice.pixelSize)));
    const int height = std::max(1, int(std::lround(extentR / slice.pixelSize)));
    if (width > MAX_SLICE_RESOLUTION || height > MAX_SLICE_RESOLUTION) {
        OPENVDB_THROW(openvdb::ValueError, "sampleSlice: the slice would be " +
                                               std::to_string(width) + " x " +
                                               std::to_string(height) + " pixels, too large");
    }
    slice.origin = bounds.min();
    slice.origin[axis] = slice.position;

    const int level = std::max(deformationLevel(phi), psi ? deformationLevel(*psi) : 0);
    const int distanceLevel =
        options.distanceLevel > 0 ? options.distanceLevel : defaultDistanceLevel(D, level);
    const ShapeDistance<D> d1(m1, omega, distanceLevel, options.threaded);
    const ShapeDistance<D> d2(m2, omega, distanceLevel, options.threaded);

    ImageChannels& img = slice.image;
    img.width = width;
    img.height = height;
    const int channelCount = psi ? 6 : 5;
    for (int c = 0; c < channelCount; ++c)
        img.names.push_back(SLICE_CHANNELS[c]);
    img.pixels.assign(std::size_t(width) * std::size_t(height) * std::size_t(channelCount), 0.0f);

    std::atomic<bool> stopped{false};
    auto rowsBody = [&](const tbb::blocked_range<int>& range) {
        if (stopped) return;
        if (interrupter && interrupter->wasInterrupted()) {
            stopped = true;
            if (options.threaded) openvdb::thread::cancelGroupExecution();
            return;
        }
        for (int r = range.begin(); r != range.end(); ++r) {
            for (int c = 0; c < width; ++c) {
                openvdb::Vec3d x = slice.origin;
                x[slice.columnAxis] += (c + 0.5) * slice.pixelSize;
                x[slice.rowAxis] += (height - r - 0.5) * slice.pixelSize;
                const double v1 = d1.signedDistance(x);
                const double v2 = d2.signedDistance(x);
                const openvdb::Vec3d y = phi.apply(x);
                float* px = &img.pixels[(std::size_t(r) * width + c) * channelCount];
                px[0] = float(v1);
                px[1] = float(v2);
                px[2] = float((y - x).length());
                px[3] = float(phi.jacobianDeterminant(x));
                px[4] = float(d2.signedDistance(y) - v1);
                if (psi) px[5] = float((psi->apply(y) - x).length());
            }
        }
    };
    if (options.threaded) {
        tbb::parallel_for(tbb::blocked_range<int>(0, height), rowsBody);
    } else {
        rowsBody(tbb::blocked_range<int>(0, height));
    }
    if (stopped) {
        OPENVDB_THROW(openvdb::RuntimeError, "sampleSlice: interrupted");
    }
    return slice;
}

Image8
renderSlicePreview(const SliceImage& slice, const std::string& channel)
{
    const ImageChannels& img = slice.image;
    const int c = img.channelIndex(channel);
    if (c < 0) {
        OPENVDB_THROW(openvdb::ValueError,
                      "renderSlicePreview: the slice has no channel '" + channel + "'");
    }
    const std::size_t n = std::size_t(img.width) * std::size_t(img.height);
    auto extract = [&](int k) {
        std::vector<float> v(n);
        for (std::size_t i = 0; i < n; ++i)
            v[i] = img.pixels[i * img.names.size() + std::size_t(k)];
        return v;
    };
    const std::vector<float> field = extract(c);
    const int c1 = img.channelIndex("d1"), c2 = img.channelIndex("d2");
    std::vector<float> f1, f2;
    PreviewOptions opts;
    if (c1 >= 0) {
        f1 = extract(c1);
        opts.contourFields.push_back(f1.data());
        opts.contourColors.push_back(SLICE_M1_COLOR);
    }
    if (c2 >= 0) {
        f2 = extract(c2);
        opts.contourFields.push_back(f2.data());
        opts.contourColors.push_back(SLICE_M2_COLOR);
    }
    const auto [lo, hi] = finiteRange(field.data(), n);
    if (isSignedChannel(channel)) {
        const float m = std::max(std::abs(lo), std::abs(hi));
        opts.lo = -m;
        opts.hi = m;
        opts.colorMap = ColorMapKind::Diverging;
    } else {
        opts.lo = lo;
        opts.hi = hi;
        opts.colorMap = ColorMapKind::Inferno;
    }
    std::string title = channelTitle(channel);
    if (channel != "det") title += " [world]";
    if (slice.dim == 3) {
        title += ", " + std::string(AXIS_NAMES[slice.axis]) + " = " + shortNumber(slice.position);
    }
    opts.title = title;
    return renderFieldPreview(field.data(), img.width, img.height, opts);
}

template SliceImage sampleSlice<2>(const DeformationField&, const DeformationField*,
                                   const Surface<2>&, const Surface<2>&, const SliceOptions&,
                                   openvdb::util::NullInterrupter*);
template SliceImage sampleSlice<3>(const DeformationField&, const DeformationField*,
                                   const Surface<3>&, const Surface<3>&, const SliceOptions&,
                                   openvdb::util::NullInterrupter*);

} // namespace eval
} // namespace vdbmatch
