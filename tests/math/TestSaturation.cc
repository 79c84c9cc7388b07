/// @file TestSaturation.cc
/// @brief The membrane saturation psi_s(w) = s log(1 + w/s) (math/Saturation.h): the identity at
///        s = 0 bit for bit, psi(0) = 0 and psi'(0) = 1 (small distortions cost what they cost in
///        the paper), below w, increasing and concave, the paper's W as s grows, and its
///        derivative against central differences.
#include <vdbmatch/math/Saturation.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace vdbmatch;

TEST(Saturation, ZeroIsThePapersDensityBitForBit)
{
    for (Real w : {0.0, 1e-300, 1e-9, 0.3, 7.0, 1e12}) {
        EXPECT_EQ(math::saturated(w, 0.0), w);
        EXPECT_EQ(math::saturatedSlope(w, 0.0), 1.0);
    }
}

TEST(Saturation, SmallDistortionsCostWhatTheyCostLargeOnesLogarithmically)
{
    for (Real s : {0.01, 0.1, 1.0}) {
        EXPECT_EQ(math::saturated(0.0, s), 0.0);
        EXPECT_EQ(math::saturatedSlope(0.0, s), 1.0);
        // psi(w) = w - w^2 / (2 s) + O(w^3): relative gap w / (2 s).
        const Real w = 1e-4 * s;
        EXPECT_NEAR(math::saturated(w, s), w, 1e-3 * w);
        Real previous = 0, previousSlope = 1;
        for (Real x = 0.01; x < 1e4; x *= 1.7) {
            const Real p = math::saturated(x, s), d = math::saturatedSlope(x, s);
            EXPECT_LT(p, x) << s << " " << x;             // below the paper's density
            EXPECT_GT(p, previous) << s << " " << x;      // increasing
            EXPECT_LT(d, previousSlope) << s << " " << x; // concave
            EXPECT_GT(d, 0.0);
            previous = p;
            previousSlope = d;
        }
        // Logarithmic growth: 10x the distortion energy adds s log(10) asymptotically.
        const Real big = 1e6 * s;
        EXPECT_NEAR(math::saturated(10 * big, s) - math::saturated(big, s), s * std::log(10.0),
                    1e-4 * s);
    }
}

TEST(Saturation, LargeSaturationTendsToThePapersDensity)
{
    const Real w = 0.7;
    Real previousGap = w;
    for (Real s : {1.0, 10.0, 100.0, 1000.0}) {
        const Real gap = w - math::saturated(w, s);
        EXPECT_GT(gap, 0.0);
        EXPECT_LT(gap, previousGap);
        EXPECT_NEAR(gap, w * w / (2 * s), 0.7 * w * w * w / (s * s)); // O(1/s)
        previousGap = gap;
    }
}

TEST(Saturation, SlopeIsTheDerivative)
{
    for (Real s : {0.03, 0.1, 2.0})
        for (Real w : {0.0, 0.002, 0.05, 0.4, 3.0, 40.0}) {
            const Real eps = 1e-6 * (s + w);
            const Real lo = std::max(w - eps, 0.0), hi = w + eps;
            const Real fd = (math::saturated(hi, s) - math::saturated(lo, s)) / (hi - lo);
            EXPECT_NEAR(math::saturatedSlope(w, s), fd, 1e-6) << s << " " << w;
        }
}
