/// @file TestBandWeight.cc
/// @brief eta: support [-1, 1], integral 1, C^1; eta_sigma scaling (subsec:symenergy).
#include <vdbmatch/geometry/BandWeight.h>

#include <gtest/gtest.h>

using namespace vdbmatch;

TEST(BandWeight, IntegralSupportAndSmoothness)
{
    for (Real sigma : {1.0, 0.25, 1.0 / 64}) {
        const BandWeight eta(sigma);
        // Simpson's rule over [-sigma, sigma] (eta is a polynomial there: exact up to rounding).
        const int n = 2000;
        const Real a = -sigma, step = 2 * sigma / n;
        Real s = eta(a) + eta(sigma);
        for (int i = 1; i < n; ++i)
            s += (i % 2 ? 4 : 2) * eta(a + i * step);
        EXPECT_NEAR(s * step / 3, 1.0, 1e-12);
        EXPECT_EQ(eta(1.0001 * sigma), 0.0);
        EXPECT_EQ(eta(-1.0001 * sigma), 0.0);
        EXPECT_GT(eta(0.999 * sigma), 0.0);
        EXPECT_FALSE(eta.inBand(sigma));
        EXPECT_TRUE(eta.inBand(0.5 * sigma));
        // derivative against central differences, and continuity of eta, eta' at the ends
        for (Real t : {-0.9, -0.3, 0.0, 0.2, 0.77}) {
            Real d;
            eta(t * sigma, d);
            const Real e = 1e-7 * sigma;
            EXPECT_NEAR(d, (eta(t * sigma + e) - eta(t * sigma - e)) / (2 * e),
                        1e-6 * (1 + std::abs(d)));
        }
        Real dEnd;
        EXPECT_NEAR(eta(sigma * (1 - 1e-9), dEnd), 0.0, 1e-12 / sigma);
        EXPECT_NEAR(dEnd, 0.0, 1e-7 / (sigma * sigma));
    }
}
