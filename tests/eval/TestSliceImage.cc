/// @file TestSliceImage.cc
/// @brief sampleSlice() and renderSlicePreview(): the documented channels with the right size
///        and finite values, an EXR that reads back with OpenImageIO, PNG previews that are not
///        blank, and the errors for bad planes.
#include "EvalFixture.h"

#include <vdbmatch/eval/SliceImage.h>
#include <vdbmatch/io/ImageIO.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <support/TestSurfaces.h>

using namespace vdbmatch;
using namespace vdbmatch::test;
namespace fs = std::filesystem;

namespace {

/// A scratch directory removed at the end of the test.
struct EvalScratchDir
{
    fs::path path;
    EvalScratchDir()
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        path = fs::temp_directory_path() /
               ("vdbmatch-" + std::string(info->test_suite_name()) + "-" + info->name());
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~EvalScratchDir() { fs::remove_all(path); }
};

void
expectFinite(const ImageChannels& img)
{
    for (float v : img.pixels)
        ASSERT_TRUE(std::isfinite(v));
}

} // namespace

TEST(SliceImage, ChannelsOf3DSliceRoundTripThroughExrAndPng)
{
    const Surface<3> m1 = toWorld(uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.25, 12, 24));
    const Surface<3> m2 = toWorld(uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.3, 12, 24));
    const int level = 4;
    const DeformationField phi = makeField<3>(level, forwardDisplacement<3>);
    const DeformationField psi = makeField<3>(level, inverseDisplacement<3>);
    eval::SliceOptions opts;
    opts.distanceLevel = 6;
    const eval::SliceImage slice = eval::sampleSlice<3>(phi, &psi, m1, m2, opts);

    // Default plane: z through the centre of M1's box; one pixel per voxel cell.
    EXPECT_EQ(slice.axis, 2);
    EXPECT_NEAR(slice.position, worldOffset(3)[2] + 0.5 * WORLD_SCALE, 1e-9);
    EXPECT_NEAR(slice.unitPosition, 0.5, 1e-9);
    EXPECT_EQ(slice.image.width, 1 << level);
    EXPECT_EQ(slice.image.height, 1 << level);
    const std::set<std::string> names(slice.image.names.begin(), slice.image.names.end());
    EXPECT_EQ(names, (std::set<std::string>{"d1", "d2", "displacement", "det", "residual",
                                            "inverse_error"}));
    expectFinite(slice.image);
    // The centre is inside both spheres; corners outside.
    const int c = slice.image.width / 2;
    const int d1 = slice.image.channelIndex("d1");
    EXPECT_LT(slice.image.at(c, c, d1), 0.0f);
    EXPECT_GT(slice.image.at(0, 0, d1), 0.0f);
    // d1 at the pixel (c, c), centred half a pixel off the sphere's centre in x and y: about
    // -(r1 - |offset|) (world), up to the faceting of the 12 x 24 UV sphere.
    const double offset = std::sqrt(2.0) * 0.5 * std::ldexp(1.0, -level);
    EXPECT_NEAR(slice.image.at(c, c, d1), -(0.25 - offset) * WORLD_SCALE, 0.03 * WORLD_SCALE);
    const int inv = slice.image.channelIndex("inverse_error");
    const int det = slice.image.channelIndex("det");
    for (int y = 0; y < slice.image.height; ++y) {
        for (int x = 0; x < slice.image.width; ++x) {
            EXPECT_LT(slice.image.at(x, y, inv), 0.02 * WORLD_SCALE);
            EXPECT_GT(slice.image.at(x, y, det), 0.5f);
        }
    }

    EvalScratchDir dir;
    const std::string exr = (dir.path / "slice.exr").string();
    writeExr(exr, slice.image, {{"vdbmatch:axis", "z"}, {"vdbmatch:units", "world"}});
    ImageAttributes attributes;
    const ImageChannels back = readImage(exr, &attributes);
    EXPECT_EQ(back.width, slice.image.width);
    EXPECT_EQ(back.height, slice.image.height);
    EXPECT_EQ(std::set<std::string>(back.names.begin(), back.names.end()), names);
    for (const std::string& name : slice.image.names) {
        const int a = slice.image.channelIndex(name), b = back.channelIndex(name);
        ASSERT_GE(b, 0);
        EXPECT_EQ(back.at(3, 5, b), slice.image.at(3, 5, a)) << name;
    }
    bool hasAxis = false;
    for (const auto& [key, value] : attributes)
        hasAxis = hasAxis || (key == "vdbmatch:axis" && value == "z");
    EXPECT_TRUE(hasAxis);

    for (const std::string& name : slice.image.names) {
        const Image8 preview = eval::renderSlicePreview(slice, name);
        const std::string png = (dir.path / ("slice." + name + ".png")).string();
        writePng(png, preview.width, preview.height, preview.rgb);
        ASSERT_TRUE(fs::exists(png));
        const ImageChannels pic = readImage(png);
        EXPECT_EQ(pic.width, preview.width);
        // Not blank: many distinct colours.
        std::set<int> colours;
        for (int y = 0; y < pic.height; y += 2) {
            for (int x = 0; x < pic.width; x += 2) {
                colours.insert(int(pic.at(x, y, 0) * 255) * 65536 +
                               int(pic.at(x, y, 1) * 255) * 256 + int(pic.at(x, y, 2) * 255));
            }
        }
        EXPECT_GT(colours.size(), 8u) << name;
    }
    EXPECT_THROW(eval::renderSlicePreview(slice, "nope"), openvdb::ValueError);
}

TEST(SliceImage, PlanesAndResolution)
{
    const Surface<3> m1 = toWorld(uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.25, 8, 16));
    const Surface<3> m2 = toWorld(uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.3, 8, 16));
    const DeformationField phi = makeField<3>(3, forwardDisplacement<3>);
    eval::SliceOptions opts;
    opts.distanceLevel = 5;
    opts.axis = 0;
    opts.unitPosition = 0.25;
    opts.resolution = 20;
    const eval::SliceImage s = eval::sampleSlice<3>(phi, nullptr, m1, m2, opts);
    EXPECT_EQ(s.image.width, 20);
    EXPECT_EQ(s.image.height, 20);
    EXPECT_EQ(s.image.names.size(), 5u);
    EXPECT_EQ(s.image.channelIndex("inverse_error"), -1);
    EXPECT_EQ(s.columnAxis, 1);
    EXPECT_EQ(s.rowAxis, 2);
    EXPECT_NEAR(s.position, worldOffset(3)[0] + 0.25 * WORLD_SCALE, 1e-9);
    expectFinite(s.image);

    eval::SliceOptions bad = opts;
    bad.unitPosition.reset();
    bad.position = 100.0;
    EXPECT_THROW(eval::sampleSlice<3>(phi, nullptr, m1, m2, bad), openvdb::ValueError);
    bad.unitPosition = 0.5;
    EXPECT_THROW(eval::sampleSlice<3>(phi, nullptr, m1, m2, bad), openvdb::ValueError);
    bad = opts;
    bad.unitPosition = 1.5;
    EXPECT_THROW(eval::sampleSlice<3>(phi, nullptr, m1, m2, bad), openvdb::ValueError);
    bad = opts;
    bad.axis = 3;
    EXPECT_THROW(eval::sampleSlice<3>(phi, nullptr, m1, m2, bad), openvdb::ValueError);
    bad = opts;
    bad.resolution = 1;
    EXPECT_THROW(eval::sampleSlice<3>(phi, nullptr, m1, m2, bad), openvdb::ValueError);
}

TEST(SliceImage, TwoDimensionalSliceIsThePlane)
{
    const Surface<2> m1 = toWorld(circle(Vec<2>(0.5, 0.5), 0.25, 128));
    const Surface<2> m2 = toWorld(circle(Vec<2>(0.5, 0.5), 0.3, 128));
    const DeformationField phi = makeField<2>(5, forwardDisplacement<2>);
    const DeformationField psi = makeField<2>(5, inverseDisplacement<2>);
    eval::SliceOptions opts;
    opts.resolution = 64;
    const eval::SliceImage s = eval::sampleSlice<2>(phi, &psi, m1, m2, opts);
    EXPECT_EQ(s.dim, 2);
    EXPECT_EQ(s.image.width, 64);
    EXPECT_EQ(s.image.height, 64);
    EXPECT_EQ(s.image.names.size(), 6u);
    expectFinite(s.image);
    // residual = d2(phi(x)) - d1(x): at a far corner phi = Id and |d2 - d1| ~ 0.05 * scale.
    const int r = s.image.channelIndex("residual");
    EXPECT_NEAR(std::abs(s.image.at(0, 0, r)), 0.05 * WORLD_SCALE, 0.02);

    eval::SliceOptions bad;
    bad.axis = 0;
    EXPECT_THROW(eval::sampleSlice<2>(phi, &psi, m1, m2, bad), openvdb::ValueError);
    bad = eval::SliceOptions();
    bad.position = 0.0;
    EXPECT_THROW(eval::sampleSlice<2>(phi, &psi, m1, m2, bad), openvdb::ValueError);
    const DeformationField phi3 = makeField<3>(2, zeroDisplacement<3>);
    EXPECT_THROW(eval::sampleSlice<2>(phi3, nullptr, m1, m2, opts), openvdb::ValueError);
}
