/// @file SurfaceNoise.h
/// @brief How noisy a surface is, read on its vertices (surfaceNoise) and on a lattice
///        (latticeSurfaceNoise), for the Hessian smoothing of its signed distance
///        (ShapeFieldOptions::hessianSmoothingLength; readNoise gives the length).
///
/// The shape operator S of eq:defSi comes from second differences of d, which amplify a vertex
/// noise of size e by 1/h^2: on a scan (noise ~0.2% of the shape's size) S at fine levels is as
/// much noise as curvature (docs/numerics.md "Hessian smoothing"). This measures e from the
/// surface alone, so that only noisy shapes are smoothed:
/// - the umbrella vector u(v) = v - mean of v's neighbours (the vertices sharing an edge with v)
///   is, on a smooth surface, about the curvature times the squared edge length along the
///   normal n(v) (the principal direction of the incident elements' normals, so that an
///   inconsistent orientation does not matter);
/// - r(v) = n(v).u(v) - mean over the neighbours w of n(w).u(w) (each n(w) turned to the side
///   of n(v)) cancels what varies smoothly (curvature, and the faceting of a regular mesh,
///   exactly) and keeps what does not (noise); tangential parts, from irregular sampling, are
///   left out;
/// - the noise is the median over the vertices of |r(v)|.
///
/// Measured (docs/numerics.md "Noise-adaptive Hessian smoothing"), in unit-box lengths after
/// match()'s placement: 0.04-1.4 x 10^-5 on the accuracy benchmark's noise-free meshes and
/// outlines, 5 x 10^-5 on the surfaces extracted from the bundled starfish level sets, against
/// 4.6-7.4 x 10^-4 on its scans (Gaussian noise of 0.2% of the shape's diagonal). Noise
/// correlated over a few vertices reads 3-9x lower on this measure; the lattice reading
/// (latticeSurfaceNoise) reads it at its amplitude (docs/numerics.md "Correlated noise: the
/// lattice reading").
#pragma once

#include <vdbmatch/geometry/Surface.h>

namespace vdbmatch {

/// Median over the vertices of |r(v)| (see the file comment), in the surface's units;
/// 0 if no vertex has a neighbour. Deterministic, serial, O(E log E) for E edges.
/// @note Meant for closed surfaces (checkSurface); any element list is accepted.
template <int D> double surfaceNoise(const Surface<D>& surface);

/// Hessian smoothing length per unit of surfaceNoise() that match() uses by default
/// (MatchOptions::hessianNoiseFactor): s = 16 e. On the benchmark's 3D scans s is 0.0074-0.0094
/// of the unit box: no pass at levels 4 and 5, 0-1 at level 6, 2-3 at level 7
/// (ShapeFieldOptions::hessianSmoothingLength); on its noise-free inputs and the bundled level
/// sets no pass at any level match() accepts. Chosen on the benchmark's scans (3D and 2D, one
/// run each of 4 (2D only), 8 and 16, and about 14 and 28 with a first form of the measure;
/// docs/numerics.md). Noise correlated over a few vertices reads 3-9x lower than white noise of
/// the same amplitude; in 3D latticeSurfaceNoise() reads it (LATTICE_NOISE_SMOOTHING_FACTOR_3D).
constexpr double NOISE_SMOOTHING_LENGTH_FACTOR = 16.0;

/// Hessian smoothing length per unit of latticeSurfaceNoise() at LATTICE_NOISE_LEVEL that
/// match() uses by default in 3D (MatchOptions::hessianLatticeNoiseFactor; 2D: 0, off); each
/// shape's length is the larger of this one and NOISE_SMOOTHING_LENGTH_FACTOR's. The lattice
/// reads the benchmark's 3D scans at 2.5-2.7 x 10^-3 of the unit box, white or correlated over
/// a few vertices alike, and its noise-free meshes at 0.8-1.3 x 10^-4: with 3.5, noise of any
/// correlation gets a length from 0.008 up, which smooths from level 6 on as the white scans'
/// vertex noise did, and no noise-free input gets a pass (docs/numerics.md "Correlated
/// noise"). In 2D the noise-free outlines read 1.5-2.8 x 10^-4, too close to half a cell of
/// level 9 for this factor, and correlated noise was not measured there.
constexpr double LATTICE_NOISE_SMOOTHING_FACTOR_3D = 3.5;

/// The noise that a lattice of spacing h = 2^-level sees on the surface: the median over the
/// nodes within h of it of |H - S H| h^2 (H the Hessian of its signed distance by second
/// differences, S one [1,2,1]/4 pass along every axis, |.| the Frobenius norm), in the
/// surface's units, which must be Omega units (distanceBand). On a smooth surface H varies
/// over the curvature's scale and S barely changes it; noise the lattice resolves changes H
/// from node to node. Unlike surfaceNoise(), which compares a vertex with its neighbours and
/// reads noise correlated over a few vertices 3-9x low, this reads such noise at its
/// amplitude (docs/numerics.md "Correlated noise"); on a mesh much finer than h it misses
/// white vertex noise, which the lattice averages. 0 if no node has its whole stencil in the
/// band. Results do not depend on @a threaded.
/// @throw openvdb::ValueError as distanceBand (a surface that fails checkSurface, a level out
///        of range)
template <int D>
double latticeSurfaceNoise(const Surface<D>& surface, int level, bool threaded = true);

/// Level of the lattice reading match() takes (MatchOptions::hessianLatticeNoiseFactor):
/// h = 1/128, about three edges of the accuracy benchmark's 3D meshes.
constexpr int LATTICE_NOISE_LEVEL = 7;

/// A shape's noise readings and the Hessian smoothing length they give
/// (ShapeFieldOptions::hessianSmoothingLength), in the surface's units.
struct NoiseReading
{
    double vertex = 0;  ///< surfaceNoise()
    double lattice = 0; ///< latticeSurfaceNoise() at LATTICE_NOISE_LEVEL; 0 if not read
    double length = 0;  ///< max(vertexFactor * vertex, latticeFactor * lattice)
};

/// Largest ratio of the lattice reading to the vertex reading that white (independent,
/// per-vertex) noise gives: the accuracy benchmark's white 3D scans read 4.3-5.3, noise
/// correlated over about 2 and 4 edges 11-12 and 26-31 (docs/numerics.md "Correlated noise").
constexpr double WHITE_NOISE_LATTICE_RATIO = 6;

/// The part of a shape's lattice reading that its vertex reading does not account for as white
/// noise: sqrt(max(0, lattice^2 - (WHITE_NOISE_LATTICE_RATIO * vertex)^2)), in the reading's
/// units. About the lattice reading for noise correlated over a few vertices, 0 for white
/// noise, and at most the lattice reading of a noise-free shape (1e-4 of the box on the
/// benchmark's meshes). 0 when the lattice was not read.
double correlatedNoise(const NoiseReading& reading);

/// The readings of @a surface (Omega units) and its smoothing length: the larger of
/// @a vertexFactor times surfaceNoise() and @a latticeFactor times latticeSurfaceNoise() at
/// LATTICE_NOISE_LEVEL (read only when both factors are > 0). All zeros when vertexFactor is 0.
/// @throw openvdb::ValueError as latticeSurfaceNoise
template <int D>
NoiseReading readNoise(const Surface<D>& surface, double vertexFactor, double latticeFactor,
                       bool threaded = true);

template <> double surfaceNoise<2>(const Surface<2>& surface);
template <> double surfaceNoise<3>(const Surface<3>& surface);
template <> double latticeSurfaceNoise<2>(const Surface<2>&, int, bool);
template <> double latticeSurfaceNoise<3>(const Surface<3>&, int, bool);
template <> NoiseReading readNoise<2>(const Surface<2>&, double, double, bool);
template <> NoiseReading readNoise<3>(const Surface<3>&, double, double, bool);

} // namespace vdbmatch
