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
/// Measured (docs/numerics.md "Noise-adaptive Hessian smoothing"): 0.5-19 x 10^-6 of the
/// bounding box diagonal on the accuracy benchmark's meshes and outlines and 4-6 x 10^-5 on
/// surfaces extracted from level sets, against 1.6-2.6 x 10^-3 on its scans (Gaussian noise of
/// 0.2% of the diagonal).
#pragma once

#include <vdbmatch/geometry/Surface.h>

namespace vdbmatch {

/// Median over the vertices of |r(v)| (see the file comment), in the surface's units;
/// 0 if no vertex has a neighbour. Deterministic, serial, O(vertices + elements).
/// @note Meant for closed surfaces (checkSurface); any element list is accepted.
template <int D> double surfaceNoise(const Surface<D>& surface);

/// Hessian smoothing length per unit of surfaceNoise() that match() uses by default
/// (MatchOptions::hessianSmoothingFromNoise): s = 4 e. On the benchmark's scans (e about 2e-3
/// in Omega units) s is about 1/128, so levels 4 and 5 get no pass, level 6 one, level 7 two
/// (ShapeFieldOptions::hessianSmoothingLength); on its noise-free inputs no level up to 10 gets
/// one.
constexpr double NOISE_SMOOTHING_LENGTH_FACTOR = 4.0;

template <> double surfaceNoise<2>(const Surface<2>& surface);
template <> double surfaceNoise<3>(const Surface<3>& surface);

} // namespace vdbmatch
