/// @file TestMatrixPlots.cc
/// @brief The heat map draws each cell in the colour of its value and refuses a bad order; the
///        scatter places its dots and refuses mismatched names.
#include <vdbmatch/render/ColorMap.h>
#include <vdbmatch/render/MatrixPlots.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

using namespace vdbmatch;

TEST(MatrixPlots, HeatMapCellsHaveTheColourOfTheirValues)
{
    eval::DistanceMatrix m;
    m.n = 2;
    m.d = {0, 3, 3, 0};
    const Image8 image = render::distanceHeatMap(m, {"a", "b"}, {1, 0}, "t");
    ASSERT_GT(image.width, 0);
    // Count the pixels of the colours of 0 and of the largest entry: two cells each.
    const Rgb8 zero = mapValue(0.0, 0.0, 3.0, ColorMapKind::Inferno);
    const Rgb8 top = mapValue(3.0, 0.0, 3.0, ColorMapKind::Inferno);
    int zeros = 0, tops = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            zeros += image.at(x, y) == zero;
            tops += image.at(x, y) == top;
        }
    EXPECT_GE(zeros, 2 * 3 * 3); // cells are at least 3 x 3 pixels
    EXPECT_GE(tops, 2 * 3 * 3);
    EXPECT_THROW(render::distanceHeatMap(m, {"a", "b"}, {0, 0}, "t"), openvdb::ValueError);
    EXPECT_THROW(render::distanceHeatMap(m, {"a"}, {0, 1}, "t"), openvdb::ValueError);
}

TEST(MatrixPlots, ScatterDrawsOneDotPerPoint)
{
    const std::vector<Vec<2>> p = {Vec<2>(0, 0), Vec<2>(1, 0), Vec<2>(0, 1)};
    const Image8 image = render::labelledScatter(p, {"a", "b", "c"}, "t");
    int coloured = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            const Rgb8 c = image.at(x, y);
            coloured += !(c[0] == c[1] && c[1] == c[2]); // not white, black or grey
        }
    EXPECT_GE(coloured, 3 * 20); // three dots of diameter 8
    EXPECT_THROW(render::labelledScatter(p, {"a"}, "t"), openvdb::ValueError);
}
