/// @file TestSurfaceNoise.cc
/// @brief surfaceNoise(): a scanner's noise is measured, curvature and faceting are not, and the
///        measure follows the shape's scale and ignores the elements' orientation;
///        latticeSurfaceNoise(): noise correlated over a few vertices is read at its amplitude
///        where surfaceNoise() reads it low, and a smooth shape reads next to nothing.
#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/SurfaceNoise.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace vdbmatch;
using vdbmatch::test::correlatedNoise;
using vdbmatch::test::ellipseCurve;
using vdbmatch::test::uvSphere;

namespace {

/// Moves every point of @a s along its radial direction from @a centre by N(0, sigma), seeded.
template <int D>
Surface<D>
radialNoise(Surface<D> s, const Vec<D>& centre, double sigma, unsigned seed)
{
    std::mt19937 random(seed);
    std::normal_distribution<double> normal(0.0, sigma);
    for (Vec<D>& p : s.points)
        p += normal(random) * (p - centre).normalized();
    return s;
}

} // namespace

/// surfaceNoise() of @a clean is below 2% of sigma, and of @a clean with radial Gaussian noise
/// sigma (seeded) within [lo, hi] sigma.
template <int D>
void
expectNoiseFound(const Surface<D>& clean, const Vec<D>& centre, double sigma, double lo, double hi)
{
    const double cleanNoise = surfaceNoise(clean);
    const double noisy = surfaceNoise(radialNoise(clean, centre, sigma, 7));
    std::printf("%dD: noise %.3g clean, %.3g with sigma %.3g\n", D, cleanNoise, noisy, sigma);
    EXPECT_LT(cleanNoise, 0.02 * sigma);
    EXPECT_GT(noisy, lo * sigma);
    EXPECT_LT(noisy, hi * sigma);
}

TEST(SurfaceNoise, ScanNoiseIsMeasuredAndCurvatureIsNot)
{
    // A sphere of radius 1, edges about 0.04-0.08. The normal part of the umbrella vector alone
    // is e^2 / (4 R) ~ 1e-3 here, a tenth of the noise: its change cancels the curvature.
    // Gaussian noise sigma: r(v) has a standard deviation of about 1.2 sigma, median 0.8 sigma.
    const Vec<3> centre(0.2, -0.1, 0.3);
    expectNoiseFound<3>(uvSphere(centre, 1.0, 40, 80), centre, 0.01, 0.5, 1.2);
    // A polyline vertex has two neighbours: r(v) has a standard deviation of about 2.1 sigma.
    const Vec<2> middle(1.0, 2.0);
    expectNoiseFound<2>(ellipseCurve(middle, 1.0, 0.6, 600), middle, 0.004, 0.8, 2.5);
}

TEST(SurfaceNoise, RegularFacetsAreNotNoise)
{
    // The icosahedron and a 12-gon: every vertex alike, so the umbrella vectors are all the same
    // size along the normal (0.2 and 0.03 of the radius) and their change is zero.
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    Surface<3> ico;
    for (double a : {-1.0, 1.0})
        for (double b : {-t, t}) {
            ico.points.emplace_back(0, a, b);
            ico.points.emplace_back(a, b, 0);
            ico.points.emplace_back(b, 0, a);
        }
    // The 20 faces: the vertex triples at mutual distance 2 (the edge length).
    const int n = int(ico.points.size());
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
            for (int k = j + 1; k < n; ++k) {
                auto edge = [&](int p, int q) {
                    return std::abs((ico.points[p] - ico.points[q]).norm() - 2.0) < 1e-9;
                };
                if (edge(i, j) && edge(j, k) && edge(i, k)) ico.elements.push_back({i, j, k});
            }
    ASSERT_EQ(ico.elements.size(), 20u);
    EXPECT_LT(surfaceNoise(ico), 1e-12);
    EXPECT_LT(surfaceNoise(ellipseCurve(Vec<2>(0.3, 0.1), 1.0, 1.0, 12)), 1e-12);
    // The same with noise of 1% of the radius is seen.
    const double r = ico.points[0].norm();
    EXPECT_GT(surfaceNoise(radialNoise(ico, Vec<3>(0, 0, 0), 0.01 * r, 3)), 1e-3 * r);
}

TEST(SurfaceNoise, FollowsTheScaleAndIgnoresOrientation)
{
    const Vec<3> centre(0, 0, 0);
    const Surface<3> s = radialNoise(uvSphere(centre, 1.0, 20, 40), centre, 0.01, 5);
    const double base = surfaceNoise(s);
    Surface<3> scaled = s;
    for (Vec<3>& p : scaled.points)
        p = 2.5 * p + Vec<3>(3.0, -1.0, 0.5);
    EXPECT_NEAR(surfaceNoise(scaled), 2.5 * base, 1e-12 * base);
    // Every other triangle reversed: the vertex normal is a direction, not an orientation.
    Surface<3> flipped = s;
    for (std::size_t i = 0; i < flipped.elements.size(); i += 2)
        std::swap(flipped.elements[i][1], flipped.elements[i][2]);
    EXPECT_EQ(surfaceNoise(flipped), base);
}

TEST(SurfaceNoise, EmptyOrInvalidIsZero)
{
    EXPECT_EQ(surfaceNoise(Surface<3>()), 0.0);
    EXPECT_EQ(surfaceNoise(Surface<2>()), 0.0);
    Surface<2> bad = ellipseCurve(Vec<2>(0, 0), 1, 1, 8);
    bad.elements.push_back({0, 99});
    EXPECT_EQ(surfaceNoise(bad), 0.0);
}

TEST(LatticeSurfaceNoise, ReadsCorrelatedNoiseAtItsAmplitude)
{
    // A sphere of radius 0.25 in Omega, edges about 0.004: the lattice of level 7 (h = 1/128)
    // spans two of them, as on the accuracy benchmark's meshes (docs/numerics.md "Correlated
    // noise"). Noise of 0.0015, white and correlated over about 2 and 4 edges.
    const Vec<3> centre(0.5, 0.5, 0.5);
    const Surface<3> clean = uvSphere(centre, 0.25, 200, 400);
    const double sigma = 0.0015;
    const double cleanLattice = latticeSurfaceNoise(clean, LATTICE_NOISE_LEVEL);
    double vertex[3], lattice[3];
    const int passes[3] = {0, 2, 4};
    for (int i = 0; i < 3; ++i) {
        const Surface<3> noisy = correlatedNoise(clean, centre, sigma, passes[i], 11);
        vertex[i] = surfaceNoise(noisy);
        lattice[i] = latticeSurfaceNoise(noisy, LATTICE_NOISE_LEVEL);
        std::printf("%d passes: vertex %.3g, lattice %.3g (sigma %.3g)\n", passes[i], vertex[i],
                    lattice[i], sigma);
    }
    std::printf("clean: lattice %.3g\n", cleanLattice);
    // A smooth sphere reads next to nothing: its Hessian 1/r (I - n n^T) barely changes under
    // one pass.
    EXPECT_LT(cleanLattice, 0.05 * sigma);
    // The vertex reading falls with the correlation, 3-9x on the benchmark's scans ...
    EXPECT_LT(vertex[1], 0.6 * vertex[0]);
    EXPECT_LT(vertex[2], 0.25 * vertex[0]);
    // ... the lattice reading stays at the amplitude.
    for (int i = 0; i < 3; ++i) {
        EXPECT_GT(lattice[i], 0.7 * sigma) << passes[i] << " passes";
        EXPECT_LT(lattice[i], 2.0 * sigma) << passes[i] << " passes";
    }
    // correlatedNoise(), which sets the anchors' tolerance (MatchOptions::anchorNoiseFactor):
    // the part of the lattice reading beyond WHITE_NOISE_LATTICE_RATIO times the vertex
    // reading is none of white noise and nearly all of correlated noise.
    double correlated[3];
    for (int i = 0; i < 3; ++i) {
        NoiseReading r;
        r.vertex = vertex[i];
        r.lattice = lattice[i];
        correlated[i] = correlatedNoise(r);
        std::printf("%d passes: lattice / vertex %.3g, correlated %.3g\n", passes[i],
                    lattice[i] / vertex[i], correlated[i]);
    }
    EXPECT_EQ(correlated[0], 0.0);
    EXPECT_GT(correlated[2], 0.9 * lattice[2]);
    EXPECT_LE(correlated[2], lattice[2]);
    NoiseReading none;
    EXPECT_EQ(correlatedNoise(none), 0.0); // the lattice not read
}

TEST(LatticeSurfaceNoise, TwoDimensionsAndThreadCountIndependence)
{
    // An ellipse in Omega with 2000 points (spacing about 0.0015): noise correlated over about
    // 2 points is read within [0.3, 2] sigma, the clean curve below 5% of it; the value does not
    // depend on threading.
    const Vec<2> centre(0.5, 0.5);
    const Surface<2> clean = ellipseCurve(centre, 0.3, 0.2, 2000);
    const double sigma = 0.0015;
    const Surface<2> noisy = correlatedNoise(clean, centre, sigma, 2, 5);
    const double reading = latticeSurfaceNoise(noisy, LATTICE_NOISE_LEVEL, true);
    std::printf("2D: lattice %.3g clean, %.3g noisy\n",
                latticeSurfaceNoise(clean, LATTICE_NOISE_LEVEL), reading);
    EXPECT_LT(latticeSurfaceNoise(clean, LATTICE_NOISE_LEVEL), 0.05 * sigma);
    EXPECT_GT(reading, 0.3 * sigma);
    EXPECT_LT(reading, 2.0 * sigma);
    EXPECT_EQ(latticeSurfaceNoise(noisy, LATTICE_NOISE_LEVEL, false), reading);
    const Vec<3> middle(0.5, 0.5, 0.5);
    const Surface<3> sphere = correlatedNoise(uvSphere(middle, 0.2, 60, 120), middle, sigma, 0, 3);
    EXPECT_EQ(latticeSurfaceNoise(sphere, 6, false), latticeSurfaceNoise(sphere, 6, true));
}

TEST(LatticeSurfaceNoise, ReadNoiseTakesTheLargerLength)
{
    const Vec<3> centre(0.5, 0.5, 0.5);
    const Surface<3> s = correlatedNoise(uvSphere(centre, 0.25, 100, 200), centre, 0.002, 4, 9);
    const NoiseReading off = readNoise(s, 0.0, 3.0);
    EXPECT_EQ(off.vertex, 0.0);
    EXPECT_EQ(off.lattice, 0.0);
    EXPECT_EQ(off.length, 0.0);
    const NoiseReading vertexOnly = readNoise(s, 16.0, 0.0);
    EXPECT_EQ(vertexOnly.vertex, surfaceNoise(s));
    EXPECT_EQ(vertexOnly.lattice, 0.0);
    EXPECT_EQ(vertexOnly.length, 16.0 * vertexOnly.vertex);
    const NoiseReading both = readNoise(s, 16.0, 3.0);
    EXPECT_EQ(both.lattice, latticeSurfaceNoise(s, LATTICE_NOISE_LEVEL));
    EXPECT_EQ(both.length, std::max(16.0 * both.vertex, 3.0 * both.lattice));
    // Correlated noise: the lattice reading sets the length.
    EXPECT_GT(3.0 * both.lattice, 16.0 * both.vertex);
    EXPECT_THROW(latticeSurfaceNoise(s, 0), openvdb::ValueError);
}
