/// @file DistanceMatrix.h
/// @brief What a collection's matrix of pairwise dissimilarities (e.g. the final energies of
///        `vdb_match batch --all-pairs`) is read with: the leaf order of an average-linkage
///        (UPGMA) hierarchical clustering, to show the matrix with similar shapes next to each
///        other, and classical multidimensional scaling to place the shapes in the plane.
///
/// A matrix is n x n, symmetric, zero on the diagonal; missing entries are NaN and count as
/// the largest finite entry (a pair that did not match is treated as far apart).
#pragma once

#include <vdbmatch/Types.h>

#include <vector>

namespace vdbmatch {
namespace eval {

/// n x n dissimilarities, row-major.
struct DistanceMatrix
{
    int n = 0;
    std::vector<double> d; ///< n * n entries, d[i * n + j]

    double at(int i, int j) const { return d[std::size_t(i) * std::size_t(n) + std::size_t(j)]; }
};

/// The matrix with NaN replaced by the largest finite entry, symmetrised ((d_ij + d_ji) / 2) and
/// with a zero diagonal.
/// @throw openvdb::ValueError if the size does not match n or an entry is negative or infinite
DistanceMatrix cleanedDistances(const DistanceMatrix& m);

/// The leaf order of average-linkage agglomerative clustering: at each step the two clusters
/// with the smallest mean pairwise distance merge (ties: the pair with the smallest indices),
/// and a merged cluster lists the cluster holding the smaller original index first. Every index
/// appears once; shapes in a tight group are contiguous.
std::vector<int> clusterOrder(const DistanceMatrix& m);

/// Classical (Torgerson) MDS in the plane: the two leading eigenvectors of
/// B = -1/2 J D^(2) J (D^(2) the squared distances, J the centring matrix), scaled by the square
/// roots of their eigenvalues (negative ones clamped to 0). Reproduces, up to a rigid motion,
/// any configuration of points in the plane from its Euclidean distances. Signs are fixed so that
/// the largest-magnitude coordinate of each axis is positive.
std::vector<Vec<2>> classicalMds(const DistanceMatrix& m);

} // namespace eval
} // namespace vdbmatch
