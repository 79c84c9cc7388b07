/// @file SurfaceNoise.h
/// @brief How noisy a surface's vertex positions are, for the Hessian smoothing of its signed
///        distance (ShapeFieldOptions::hessianSmoothingLength).
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
/// 4.6-7.4 x 10^-4 on its scans (Gaussian noise of 0.2% of the shape's diagonal).
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
/// the same amplitude and is barely smoothed (docs/numerics.md "Correlated noise").
constexpr double NOISE_SMOOTHING_LENGTH_FACTOR = 16.0;

template <> double surfaceNoise<2>(const Surface<2>& surface);
template <> double surfaceNoise<3>(const Surface<3>& surface);

} // namespace vdbmatch
