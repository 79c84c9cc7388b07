/// @file TestScalingLimit.cc
/// @brief The scaling limit of thm:gammaconv: for a smooth phi with phi(M1) = M2, the directional
///        membrane and bending energies (eq:EdirMem, eq:EdirBend) approach the surface integrals
///        of eq:limitfunctional as sigma = 2h -> 0. The surface integrals are computed on a fine
///        triangulation (3D: subdivided icosahedron; 2D: fine polygon) of M1. Slow.
#include "energy/EnergyFixture.h"

#include <vdbmatch/kinematics/TangentialDerivative.h>
#include <vdbmatch/math/StoredEnergy.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

constexpr Real R0 = 0.2;     ///< radius of M1
constexpr Real SHEAR = 0.12; ///< strength of the smooth map below

/// A smooth map that is a pure translation-free shear-and-stretch near M1, identity far away:
/// phi(x) = x + SHEAR * bump(|x - c|) * (x_1 - c_1, 0.5 (x_0 - c_0), ...). M2 := phi(M1).
/// Its derivative is computed by central differences of the formula (step 1e-6).
template <int D> struct SmoothMap
{
    Vec<D> c = Vec<D>::Constant(0.5);
    static Real bump(Real r)
    {
        const Real R = 0.45;
        if (r >= R) return 0;
        const Real a = 1 - (r / R) * (r / R);
        return a * a * a;
    }
    Vec<D> operator()(const Vec<D>& x) const
    {
        const Vec<D> v = x - c;
        Vec<D> w = Vec<D>::Zero();
        w[0] = v[1];
        w[1] = 0.5 * v[0];
        if (D == 3) w[D - 1] = 0.3 * v[0];
        return x + SHEAR * bump(v.norm()) * w;
    }
    Mat<D> jacobian(const Vec<D>& x) const
    {
        Mat<D> J;
        const Real e = 1e-6;
        for (int k = 0; k < D; ++k) {
            Vec<D> a = x, b = x;
            a[k] += e;
            b[k] -= e;
            J.col(k) = ((*this)(a) - (*this)(b)) / (2 * e);
        }
        return J;
    }
};

/// Integrand of eq:limitfunctional at y in M1: W(D_tt phi) and W(Lambda[S1, S2(phi), D phi, ...]),
/// with n2 and S2 of M2 = phi(M1) computed from the map: n2 ~ cof(D phi) n1, shape operator of
/// the image surface from the pushed-forward second fundamental form.
template <int D>
std::array<Real, 2>
limitIntegrand(const SmoothMap<D>& phi, const Vec<D>& y, Real tau)
{
    const Vec<D> n1 = (y - phi.c).normalized();
    const Mat<D> A = phi.jacobian(y);
    const Vec<D> n2 = (math::cof(A) * n1).normalized();
    const Mat<D> P1 = math::projection<D>(n1), P2 = math::projection<D>(n2);
    // S1 = R(D^2 d1 + n1 n1) on the sphere: P1 / R0 + n1 n1 (eigenvalue floor tau).
    const Mat<D> S1 = std::max(1.0 / R0, tau) * P1 + n1 * n1.transpose();
    // Shape operator of M2 at phi(y): for tangent vectors a = A t, b = A s of M2,
    // II_2(a, b) = -<d n2 (a), b>. With the extension N(x) = n2(phi(x)) of n2 along M1,
    // dn2 (A t) = D N t, so the tangential matrix B2 with a^T B2 b = II_2 is
    // B2 = (A^+)^T (P1 D N^T P2 ...). We compute it as the symmetric tangential matrix K with
    // K (A t) = D N t for t tangent to M1, by least squares on a tangent basis.
    const Real e = 1e-5;
    Eigen::Matrix<Real, D, D - 1> T, Q;
    {
        // tangent basis of M1 at y
        Vec<D> a = Vec<D>::Zero();
        a[std::abs(n1[0]) < 0.9 ? 0 : 1] = 1;
        for (int k = 0; k < D - 1; ++k) {
            Vec<D> t = P1 * a;
            if constexpr (D == 3) {
                if (k == 1) t = n1.cross(T.col(0));
            }
            T.col(k) = t.normalized();
        }
    }
    for (int k = 0; k < D - 1; ++k) {
        // move along the sphere in direction T_k, evaluate N = normal of the image there
        auto N = [&](Real s) {
            const Vec<D> z = phi.c + R0 * (y - phi.c + s * T.col(k)).normalized();
            const Vec<D> m1 = (z - phi.c).normalized();
            return Vec<D>((math::cof(phi.jacobian(z)) * m1).normalized());
        };
        // d/ds of the point on the sphere is T_k at s = 0 (to first order), so D N T_k:
        Q.col(k) = (N(e) - N(-e)) / (2 * e);
    }
    // K maps A T_k to Q_k on the tangent plane of M2: K = Q (A T)^+ restricted, symmetrised.
    const Eigen::Matrix<Real, D, D - 1> AT = A * T;
    const Eigen::Matrix<Real, D - 1, D> ATpinv = (AT.transpose() * AT).inverse() * AT.transpose();
    Mat<D> K = P2 * Q * ATpinv * P2;
    K = 0.5 * (K + K.transpose());
    // S2 = R(K + n2 n2) with |eigenvalues| floored at tau.
    Eigen::SelfAdjointEigenSolver<Mat<D>> es(K + n2 * n2.transpose());
    const Vec<D> l = es.eigenvalues().cwiseAbs().cwiseMax(tau);
    const Mat<D> S2 = es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
    const Mat<D> Dtt = P2 * A * P1 + n2 * n1.transpose();
    const Mat<D> Lambda = kinematics::directBendingArgument<D>(A, S1, S2, n1, n2);
    return {math::W<D>(Dtt), math::W<D>(Lambda)};
}

/// Surface integrals over M1 of both integrands, on a fine triangulation.
template <int D>
std::array<Real, 2>
limitEnergies(const SmoothMap<D>& phi, Real tau)
{
    std::array<Real, 2> sum{0, 0};
    if constexpr (D == 2) {
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            const Real a0 = 2 * M_PI * i / n, a1 = 2 * M_PI * (i + 1) / n;
            const Vec<2> p0 = phi.c + R0 * Vec<2>(std::cos(a0), std::sin(a0));
            const Vec<2> p1 = phi.c + R0 * Vec<2>(std::cos(a1), std::sin(a1));
            const Vec<2> m = phi.c + R0 * (0.5 * (p0 + p1) - phi.c).normalized();
            const auto f = limitIntegrand<2>(phi, m, tau);
            const Real len = (p1 - p0).norm();
            sum[0] += len * f[0];
            sum[1] += len * f[1];
        }
    } else {
        // icosahedron subdivided 6 times, vertices on the sphere; centroid rule per triangle
        const Real t = (1 + std::sqrt(5.0)) / 2;
        std::vector<Vec<3>> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                 {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                 {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
        for (auto& p : v)
            p.normalize();
        std::vector<std::array<int, 3>> f = {
            {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
            {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
            {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
        for (int level = 0; level < 6; ++level) {
            std::map<std::pair<int, int>, int> mid;
            auto midpoint = [&](int a, int b) {
                auto key = std::make_pair(std::min(a, b), std::max(a, b));
                auto it = mid.find(key);
                if (it != mid.end()) return it->second;
                v.push_back((v[a] + v[b]).normalized());
                return mid[key] = int(v.size()) - 1;
            };
            std::vector<std::array<int, 3>> g;
            for (const auto& tri : f) {
                const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                          c = midpoint(tri[2], tri[0]);
                g.push_back({tri[0], a, c});
                g.push_back({tri[1], b, a});
                g.push_back({tri[2], c, b});
                g.push_back({a, b, c});
            }
            f.swap(g);
        }
        for (const auto& tri : f) {
            const Vec<3> p0 = phi.c + R0 * v[tri[0]], p1 = phi.c + R0 * v[tri[1]],
                         p2 = phi.c + R0 * v[tri[2]];
            const Vec<3> m = phi.c + R0 * ((p0 + p1 + p2) / 3 - phi.c).normalized();
            const Real area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
            const auto val = limitIntegrand<3>(phi, m, tau);
            sum[0] += area * val[0];
            sum[1] += area * val[1];
        }
    }
    return sum;
}

/// Signed distance to M2 = phi(M1): the closest point phi(c + R0 u), |u| = 1, found by
/// Gauss-Newton in tangent coordinates of u, started from the preimage of x (phi is close to the
/// identity, so the preimage, found by fixed-point iteration, also gives the sign).
template <int D>
openvdb::FloatGrid::Ptr
imageSdf(int level, const SmoothMap<D>& phi)
{
    const Real near = 8.0 / Real(1 << level); // the energy samples d2 only near M2
    return createSdfGrid<D>(level, [phi, near](const Vec<D>& x) {
        Vec<D> z = x;
        for (int it = 0; it < 100; ++it)
            z = z - (phi(z) - x);
        const Real approx = (z - phi.c).norm() - R0;
        if (std::abs(approx) > near) return approx; // far from M2: not a distance, never used
        Vec<D> u = (z - phi.c).normalized();
        auto point = [&](const Vec<D>& w) { return Vec<D>(phi(phi.c + R0 * w.normalized())); };
        for (int it = 0; it < 30; ++it) {
            Eigen::Matrix<Real, D, D - 1> T, J;
            {
                Vec<D> a = Vec<D>::Zero();
                a[std::abs(u[0]) < 0.9 ? 0 : 1] = 1;
                T.col(0) = (a - u * u.dot(a)).normalized();
                if constexpr (D == 3) T.col(1) = u.cross(Vec<3>(T.col(0)));
            }
            const Real e = 1e-7;
            for (int k = 0; k < D - 1; ++k)
                J.col(k) = (point(u + e * T.col(k)) - point(u - e * T.col(k))) / (2 * e);
            const Vec<D> r = point(u) - x;
            const Eigen::Matrix<Real, D - 1, 1> step =
                -(J.transpose() * J).ldlt().solve(J.transpose() * r);
            u = (u + T * step).normalized();
            if (step.norm() < 1e-13) break;
        }
        const Real dist = (point(u) - x).norm();
        return approx < 0 ? -dist : dist;
    });
}

template <int D>
void
checkScalingLimit(const std::vector<int>& levels)
{
    SmoothMap<D> phi;
    const EnergyParameters params = EnergyParameters::defaults(D);
    const auto limit = limitEnergies<D>(phi, params.tau);
    std::printf("%dD limit functional: membrane %.6g bending %.6g\n", D, limit[0], limit[1]);
    std::vector<Real> errMem, errBend;
    for (int level : levels) {
        // The directional band terms live where eta_sigma(d1) > 0: cells within R0 + sigma + h
        // of the centre suffice.
        const int n = 1 << level;
        const int reach = int(std::ceil((R0 + 2.0 * params.sigmaFactor / n + 1.0 / n) * n));
        openvdb::Coord lo(n / 2 - reach), hi(n / 2 + reach);
        const openvdb::CoordBBox cells(lo, hi);
        MatchingProblem<D> P(
            level,
            createSdfGrid<D>(level, [&](const Vec<D>& x) { return (x - phi.c).norm() - R0; }),
            imageSdf<D>(level, phi), params, EnergyKind::Directional, &cells);
        NodeVectors<D> u(D, P.lattice->nodeCount());
        for (std::size_t i = 0; i < P.lattice->nodeCount(); ++i) {
            const Vec<D> x = P.lattice->nodePosition(i);
            u.col(i) = phi(x) - x;
        }
        EnergyTerms t;
        P.energy->value(u, &t);
        const Real mem = t.mem[0] / params.cMem, bend = t.bend[0] / params.cBend;
        errMem.push_back(std::abs(mem - limit[0]) / limit[0]);
        errBend.push_back(std::abs(bend - limit[1]) / std::max(limit[1], 1e-3 * limit[0]));
        std::printf(
            "%dD level %d sigma=%.5f: E_mem %.6g (rel err %.3e)  E_bend %.6g (rel err %.3e)\n", D,
            level, P.energy->sigma(), mem, errMem.back(), bend, errBend.back());
    }
    for (std::size_t i = 1; i < levels.size(); ++i) {
        EXPECT_LT(errMem[i], errMem[i - 1]) << "membrane error must decrease with sigma, h";
        EXPECT_LT(errBend[i], errBend[i - 1]) << "bending error must decrease with sigma, h";
    }
    // O(sigma^2 + h^2): below 1% at the finest level of each study.
    EXPECT_LT(errMem.back(), 0.01);
    EXPECT_LT(errBend.back(), 0.01);
}

} // namespace

TEST(ScalingLimit, DirectionalMembraneAndBending3D)
{
    checkScalingLimit<3>({5, 6, 7});
}
TEST(ScalingLimit, DirectionalMembraneAndBending2D)
{
    checkScalingLimit<2>({5, 6, 7, 8});
}
