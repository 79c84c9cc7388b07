/// @file AnalyticShapes.h
/// @brief Exact signed distances, normals and principal curvatures of spheres (circles) and
/// ellipsoids (ellipses), and signed-distance FloatGrids sampled from them, for tests and
/// benchmarks.
///
/// Conventions as in the library: signed distances are negative inside (paper
/// [subsec:notation]); grid node ijk sits at ijk*h with h = 2^-level, so world space is Omega.
/// Principal curvatures are positive for convex shapes (they are the tangential eigenvalues of
/// D²d with the outer normal); at distance d from the surface the offset surface has curvatures
/// κ/(1 + κ d).
#pragma once

#include <vdbmatch/Types.h>

#include <Eigen/Core>
#include <openvdb/openvdb.h>

#include <functional>

namespace vdbmatch {
namespace test {

/// Default number of nodes added around [0, 2^level] on every side.
constexpr int DEFAULT_GRID_MARGIN = 3;
/// Background (inactive) value of the generated level sets, Omega units: far beyond any distance
/// in the unit box.
constexpr float SDF_BACKGROUND = 1.0e3f;

/// D-1 principal curvatures, ascending.
template <int D> using Curvatures = Eigen::Matrix<Real, D - 1, 1>;
/// Columns: an orthonormal basis of the tangent space n^⊥.
template <int D> using TangentBasis = Eigen::Matrix<Real, D, D - 1>;

/// An orthonormal basis of the plane (line) orthogonal to the unit vector n.
template <int D> TangentBasis<D> tangentBasis(const Vec<D>& n);

/// Curvatures of the offset surface at signed distance d: κ_i / (1 + κ_i d).
template <int D> Curvatures<D> offsetCurvatures(const Curvatures<D>& kappa, Real d);

/// Eigenvalues (ascending) of the symmetric matrix S restricted to n^⊥, i.e. of T^T S T with
/// T = tangentBasis(n / |n|).
template <int D> Curvatures<D> tangentialEigenvalues(const Mat<D>& S, const Vec<D>& n);

/// Sphere (D = 3) or circle (D = 2).
template <int D> class AnalyticSphere
{
public:
    AnalyticSphere(const Vec<D>& center, Real radius) : mCenter(center), mRadius(radius) {}

    const Vec<D>& center() const { return mCenter; }
    Real radius() const { return mRadius; }

    Real signedDistance(const Vec<D>& x) const { return (x - mCenter).norm() - mRadius; }
    /// Closest surface point (x != center).
    Vec<D> closestPoint(const Vec<D>& x) const;
    /// Outer unit normal at the surface point y.
    Vec<D> normal(const Vec<D>& y) const { return (y - mCenter).normalized(); }
    /// Principal curvatures at the surface point y: all 1/radius.
    Curvatures<D> principalCurvatures(const Vec<D>&) const
    {
        return Curvatures<D>::Constant(1.0 / mRadius);
    }
    /// The surface point in the given direction from the centre.
    Vec<D> surfacePoint(const Vec<D>& direction) const
    {
        return mCenter + mRadius * direction.normalized();
    }

private:
    Vec<D> mCenter;
    Real mRadius;
};

/// Axis-aligned ellipsoid (D = 3) or ellipse (D = 2) with the given semi-axes.
template <int D> class AnalyticEllipsoid
{
public:
    AnalyticEllipsoid(const Vec<D>& center, const Vec<D>& semiAxes)
        : mCenter(center), mSemiAxes(semiAxes)
    {
    }

    const Vec<D>& center() const { return mCenter; }
    const Vec<D>& semiAxes() const { return mSemiAxes; }

    /// Exact signed distance, through closestPoint().
    Real signedDistance(const Vec<D>& x) const;
    /// Exact closest surface point. The Lagrange condition y_i = a_i² x_i / (a_i² + t) with
    /// Σ (a_i x_i / (a_i² + t))² = 1 is solved by safeguarded Newton iteration; points on
    /// symmetry planes are handled by reduction to lower dimension (Eberly's method).
    Vec<D> closestPoint(const Vec<D>& x) const;
    /// Outer unit normal at the surface point y.
    Vec<D> normal(const Vec<D>& y) const;
    /// Principal curvatures at the surface point y: eigenvalues of
    /// P diag(1/a_i²) P / |diag(1/a_i²) (y - c)| on the tangent space.
    Curvatures<D> principalCurvatures(const Vec<D>& y) const;
    /// The surface point c + a ∘ u, u = direction / |direction|.
    Vec<D> surfacePoint(const Vec<D>& direction) const;

private:
    Vec<D> mCenter;
    Vec<D> mSemiAxes;
};

using AnalyticCircle = AnalyticSphere<2>;
using AnalyticEllipse = AnalyticEllipsoid<2>;

/// Signed-distance level set of @a sdf on the nodes ijk of [-margin, 2^level + margin]^D (k = 0
/// only for D = 2), node ijk at ijk*h, h = 2^-level. Nodes with |sdf| <= halfWidthVoxels*h are
/// active with the value sdf(ijk*h); all others are inactive ±SDF_BACKGROUND (default: all
/// active). Grid class level set, name "surface", background SDF_BACKGROUND.
/// @param sdf  called concurrently from several threads
template <int D>
openvdb::FloatGrid::Ptr createSdfGrid(int level, const std::function<Real(const Vec<D>&)>& sdf,
                                      int margin = DEFAULT_GRID_MARGIN, Real halfWidthVoxels = INF);

openvdb::FloatGrid::Ptr createSphereSdf(int level, const Vec<3>& center, Real radius,
                                        int margin = DEFAULT_GRID_MARGIN,
                                        Real halfWidthVoxels = INF);
openvdb::FloatGrid::Ptr createCircleSdf(int level, const Vec<2>& center, Real radius,
                                        int margin = DEFAULT_GRID_MARGIN,
                                        Real halfWidthVoxels = INF);
openvdb::FloatGrid::Ptr createEllipsoidSdf(int level, const Vec<3>& center, const Vec<3>& semiAxes,
                                           int margin = DEFAULT_GRID_MARGIN,
                                           Real halfWidthVoxels = INF);
openvdb::FloatGrid::Ptr createEllipseSdf(int level, const Vec<2>& center, const Vec<2>& semiAxes,
                                         int margin = DEFAULT_GRID_MARGIN,
                                         Real halfWidthVoxels = INF);

extern template class AnalyticSphere<2>;
extern template class AnalyticSphere<3>;
extern template class AnalyticEllipsoid<2>;
extern template class AnalyticEllipsoid<3>;

} // namespace test
} // namespace vdbmatch
