#include <vdbmatch/Parallel.h>
#include <vdbmatch/geometry/NearestPoints.h>
#include <vdbmatch/geometry/RigidLimbs.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <sstream>
#include <utility>

namespace vdbmatch {

namespace {

constexpr double FAR = std::numeric_limits<double>::infinity();
constexpr double DEGREES = 180.0 / 3.14159265358979323846;
/// The geodesic distance's chords span up to this many edges (chordGraph).
constexpr int CHORD_RINGS = 3;
/// Fits from different starts this close to the closest (relative to it, or to the tolerance
/// if larger) count as equally close.
constexpr double START_TIE = 0.1;
/// A rigid segment turns about its joint: the fit may move the joint vertex of each shape by at
/// most this times J (step 6).
constexpr double SEGMENT_JOINT_SLACK = 0.1;
/// A rigid segment's vertices are nearer its tip than this times the shape's J (step 6).
constexpr double SEGMENT_REACH = 1.5;

/// Each vertex's share of the surface's measure: 1/D of each element's length or area.
template <int D>
std::vector<double>
vertexShares(const Surface<D>& s)
{
    std::vector<double> w(s.points.size(), 0.0);
    for (const auto& e : s.elements) {
        double m;
        if constexpr (D == 2) {
            m = (s.points[std::size_t(e[1])] - s.points[std::size_t(e[0])]).norm();
        } else {
            const Vec<3> p = s.points[std::size_t(e[0])];
            m = 0.5 *
                (s.points[std::size_t(e[1])] - p).cross(s.points[std::size_t(e[2])] - p).norm();
        }
        for (int k = 0; k < D; ++k)
            w[std::size_t(e[k])] += m / D;
    }
    return w;
}

/// The graph of the geodesic distance: each vertex joined to the vertices within CHORD_RINGS
/// edges of it, by the straight distance. Chords over a few edges follow the surface as edges
/// do, but do not add up a noisy surface's zigzag: on the benchmark's 2D scans (noise of 0.2%
/// of the shape's diagonal) paths along the edges are about 1.5x longer than on the noise-free
/// outline, over three edges about 1.06x.
template <int D>
std::vector<std::vector<std::pair<std::size_t, double>>>
chordGraph(const Surface<D>& s)
{
    const std::size_t n = s.points.size();
    std::vector<std::vector<std::size_t>> next(n);
    for (const auto& e : s.elements) {
        for (int k = 0; k < D; ++k) {
            const std::size_t i = std::size_t(e[k]), j = std::size_t(e[(k + 1) % D]);
            next[i].push_back(j);
            next[j].push_back(i);
        }
    }
    for (auto& v : next) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
    }
    std::vector<std::vector<std::pair<std::size_t, double>>> graph(n);
    std::vector<int> seen(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        std::vector<std::size_t> ring = {i}, reached;
        seen[i] = int(i);
        for (int r = 0; r < CHORD_RINGS; ++r) {
            std::vector<std::size_t> outer;
            for (std::size_t v : ring) {
                for (std::size_t w : next[v]) {
                    if (seen[w] == int(i)) continue;
                    seen[w] = int(i);
                    outer.push_back(w);
                    reached.push_back(w);
                }
            }
            ring.swap(outer);
        }
        std::sort(reached.begin(), reached.end());
        for (std::size_t w : reached)
            graph[i].push_back({w, (s.points[i] - s.points[w]).norm()});
    }
    return graph;
}

/// Geodesic distance over @a graph (chordGraph) from vertex @a from (Dijkstra).
std::vector<double>
geodesicDistance(const std::vector<std::vector<std::pair<std::size_t, double>>>& graph,
                 std::size_t from)
{
    std::vector<double> g(graph.size(), FAR);
    using Item = std::pair<double, std::size_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    g[from] = 0;
    queue.push({0.0, from});
    while (!queue.empty()) {
        const auto [d, i] = queue.top();
        queue.pop();
        if (d > g[i]) continue;
        for (const auto& [j, w] : graph[i]) {
            const double dj = d + w;
            if (dj < g[j]) {
                g[j] = dj;
                queue.push({dj, j});
            }
        }
    }
    return g;
}

template <int D>
std::size_t
nearestVertex(const Surface<D>& s, const Vec<D>& x)
{
    std::size_t best = 0;
    double bestD = FAR;
    for (std::size_t i = 0; i < s.points.size(); ++i) {
        const double d = (s.points[i] - x).squaredNorm();
        if (d < bestD) {
            bestD = d;
            best = i;
        }
    }
    return best;
}

/// Weighted centroid and principal direction of the points @a idx, oriented towards @a tip.
template <int D>
void
principalAxis(const Surface<D>& s, const std::vector<double>& w,
              const std::vector<std::size_t>& idx, const Vec<D>& tip, Vec<D>& centre, Vec<D>& axis)
{
    double total = 0;
    centre.setZero();
    for (std::size_t i : idx) {
        centre += w[i] * s.points[i];
        total += w[i];
    }
    centre /= total;
    Mat<D> cov = Mat<D>::Zero();
    for (std::size_t i : idx) {
        const Vec<D> d = s.points[i] - centre;
        cov += w[i] * d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Mat<D>> eig(cov);
    axis = eig.eigenvectors().col(D - 1).normalized();
    if ((tip - centre).dot(axis) < 0) axis = -axis;
}

/// The rotation by @a radians about the unit vector @a axis (2D: about the plane's normal; the
/// axis is not used).
template <int D>
Mat<D>
turnAbout(const Vec<D>& axis, double radians)
{
    if constexpr (D == 2) {
        (void)axis;
        Mat<2> r;
        r << std::cos(radians), -std::sin(radians), std::sin(radians), std::cos(radians);
        return r;
    } else {
        return Eigen::AngleAxis<Real>(radians, axis).toRotationMatrix();
    }
}

/// The least rotation taking the unit vector @a a to the unit vector @a b (3D: about a x b;
/// opposite vectors: about an axis normal to a).
template <int D>
Mat<D>
leastRotation(const Vec<D>& a, const Vec<D>& b)
{
    if constexpr (D == 2) {
        return turnAbout<2>(a, std::atan2(a[0] * b[1] - a[1] * b[0], a.dot(b)));
    } else {
        const double c = a.dot(b);
        Vec<3> k = a.cross(b);
        double s = k.norm();
        if (s < 1e-12) {
            if (c > 0) return Mat<3>::Identity();
            // Half a turn about any axis normal to a.
            k = a.cross(std::abs(a[0]) < 0.9 ? Vec<3>::UnitX() : Vec<3>::UnitY()).normalized();
            return 2.0 * k * k.transpose() - Mat<3>::Identity();
        }
        k /= s;
        Mat<3> K;
        K << 0, -k[2], k[1], k[2], 0, -k[0], -k[1], k[0], 0;
        const double angle = std::atan2(s, c);
        return Mat<3>::Identity() + std::sin(angle) * K + (1 - std::cos(angle)) * K * K;
    }
}

template <int D>
double
rotationAngle(const Mat<D>& r)
{
    if constexpr (D == 2) {
        return std::abs(std::atan2(r(1, 0), r(0, 0))) * DEGREES;
    } else {
        return std::acos(std::clamp(0.5 * (r.trace() - 1.0), -1.0, 1.0)) * DEGREES;
    }
}

/// Farthest-point samples of the vertices @a idx, the first the one nearest @a start.
template <int D>
std::vector<std::size_t>
farthestSamples(const Surface<D>& s, const std::vector<std::size_t>& idx, const Vec<D>& start,
                std::size_t count)
{
    std::vector<std::size_t> out;
    if (idx.empty() || count == 0) return out;
    std::size_t first = 0;
    double best = FAR;
    for (std::size_t k = 0; k < idx.size(); ++k) {
        const double d = (s.points[idx[k]] - start).squaredNorm();
        if (d < best) {
            best = d;
            first = k;
        }
    }
    std::vector<double> dist(idx.size(), FAR);
    std::size_t current = first;
    for (std::size_t n = 0; n < std::min(count, idx.size()); ++n) {
        out.push_back(idx[current]);
        std::size_t far = 0;
        double farD = -1;
        for (std::size_t k = 0; k < idx.size(); ++k) {
            dist[k] = std::min(dist[k], (s.points[idx[k]] - s.points[idx[current]]).squaredNorm());
            if (dist[k] > farD) {
                farD = dist[k];
                far = k;
            }
        }
        current = far;
    }
    return out;
}

template <int D>
void
checkPoints(const std::vector<Vec<D>>& points, const char* what)
{
    for (const Vec<D>& p : points) {
        if (!p.allFinite()) {
            OPENVDB_THROW(openvdb::ValueError,
                          "findRigidLimbs: a point of " << what << " is not finite");
        }
    }
}

} // namespace

template <int D>
RigidLimbs<D>
findRigidLimbs(const Surface<D>& unitSource, const Surface<D>& unitTarget,
               const std::vector<Vec<D>>& sourceTips, const std::vector<Vec<D>>& targetTips,
               const std::vector<Vec<D>>& still, const RigidLimbOptions& opts)
{
    checkSurface(unitSource, "source");
    checkSurface(unitTarget, "target");
    if (sourceTips.size() != targetTips.size()) {
        OPENVDB_THROW(openvdb::ValueError, "findRigidLimbs: " << sourceTips.size()
                                                              << " source tips against "
                                                              << targetTips.size());
    }
    checkPoints(sourceTips, "the source tips");
    checkPoints(targetTips, "the target tips");
    checkPoints(still, "the still points");
    const bool ok =
        opts.minMotion >= 0 && std::isfinite(opts.minMotion) && opts.reach > 0 && opts.reach <= 1 &&
        opts.targetReach >= opts.reach && opts.targetReach <= 1 && opts.trim > 0 &&
        opts.trim <= 1 && opts.iterations >= 1 && opts.starts >= 1 && opts.maxResidual >= 0 &&
        std::isfinite(opts.maxResidual) && opts.count >= 2 &&
        (opts.segmentTo == 0 ||
         (opts.segmentFrom >= 0 && opts.segmentFrom < opts.segmentTo && opts.segmentTo <= 1)) &&
        opts.segmentMinAngle >= 0 && std::isfinite(opts.segmentMinAngle) &&
        opts.segmentMaxTipMotion >= 0 && std::isfinite(opts.segmentMaxTipMotion);
    if (!ok) {
        OPENVDB_THROW(
            openvdb::ValueError,
            "findRigidLimbs: options out of range (minMotion >= 0, 0 < reach <= "
            "targetReach <= 1, 0 < trim <= 1, iterations >= 1, starts >= 1, maxResidual >= 0, "
            "count >= 2, segmentTo = 0 or 0 <= segmentFrom < segmentTo <= 1, segmentMinAngle >= 0, "
            "segmentMaxTipMotion >= 0)");
    }
    RigidLimbs<D> out;
    if (still.empty()) return out;
    const std::vector<double> w1 = vertexShares(unitSource), w2 = vertexShares(unitTarget);
    std::vector<std::size_t> still1, still2;
    for (const Vec<D>& p : still) {
        still1.push_back(nearestVertex(unitSource, p));
        still2.push_back(nearestVertex(unitTarget, p));
    }
    // Steps 3 to 5 for one part of a limb: r1, r2 its vertices on each shape, fit1, fit2 the
    // closest points its fit may pair them with, tip1, tip2 where its samples start; held only
    // when it fits and turned by at least minAngle degrees.
    auto fitPart = [&](RigidLimb<D>& limb, const std::vector<std::size_t>& r1,
                       const std::vector<std::size_t>& r2, const std::vector<std::size_t>& fit1,
                       const std::vector<std::size_t>& fit2, const Vec<D>& tip1, const Vec<D>& tip2,
                       double minAngle, const Vec<D>* joint1, const Vec<D>* joint2) {
        limb.sourceVertices = r1.size();
        limb.targetVertices = r2.size();
        if (r1.size() < opts.minVertices || r2.size() < opts.minVertices) {
            std::ostringstream s;
            s << "the limb has too few vertices (" << r1.size() << " and " << r2.size() << ")";
            limb.reason = s.str();
            return;
        }
        Vec<D> c1, u1, c2, u2;
        principalAxis(unitSource, w1, r1, tip1, c1, u1);
        principalAxis(unitTarget, w2, r2, tip2, c2, u2);
        // Trimmed closest points, both ways at once: the pairs are M1's limb with its closest
        // points on M2 and M2's limb with its closest points on M1, so that the fit of M2 onto
        // M1 is the inverse motion. From each of `starts` rotations (the least rotation between
        // the axes, turned about them in equal steps: the inverses of the starts the other way
        // round), the one that ends closest.
        const std::size_t n1 = r1.size(), n = n1 + r2.size();
        std::vector<Vec<D>> px(n), py(n);
        std::vector<double> pw(n), dist(n);
        for (std::size_t a = 0; a < n1; ++a) {
            px[a] = unitSource.points[r1[a]];
            pw[a] = w1[r1[a]];
        }
        for (std::size_t b = n1; b < n; ++b) {
            py[b] = unitTarget.points[r2[b - n1]];
            pw[b] = w2[r2[b - n1]];
        }
        auto pointsOf = [](const Surface<D>& m, const std::vector<std::size_t>& idx) {
            std::vector<Vec<D>> p;
            p.reserve(idx.size());
            for (std::size_t i : idx)
                p.push_back(m.points[i]);
            return p;
        };
        const NearestPoints<D> tree1(pointsOf(unitSource, fit1)), tree2(pointsOf(unitTarget, fit2));
        auto fit = [&](Mat<D>& R, Vec<D>& t) {
            double residual = FAR;
            for (int it = 0; it < opts.iterations; ++it) {
                detail::forEachIndex(n, opts.threaded, [&](std::size_t a) {
                    const bool forward = a < n1;
                    const Vec<D> y =
                        forward ? Vec<D>(R * px[a] + t) : Vec<D>(R.transpose() * (py[a] - t));
                    const auto [j, d] = (forward ? tree2 : tree1).nearest(y);
                    (forward ? py[a] : px[a]) =
                        forward ? unitTarget.points[fit2[j]] : unitSource.points[fit1[j]];
                    dist[a] = std::sqrt(d);
                });
                std::vector<double> sorted = dist;
                const std::size_t cut = std::min(n - 1, std::size_t(opts.trim * double(n)));
                std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(cut),
                                 sorted.end());
                const double limit = sorted[cut];
                double total = 0, sum = 0;
                Vec<D> mx = Vec<D>::Zero(), my = Vec<D>::Zero();
                for (std::size_t a = 0; a < n; ++a) {
                    if (dist[a] > limit) continue;
                    total += pw[a];
                    sum += pw[a] * dist[a];
                    mx += pw[a] * px[a];
                    my += pw[a] * py[a];
                }
                residual = sum / total;
                mx /= total;
                my /= total;
                Mat<D> H = Mat<D>::Zero();
                for (std::size_t a = 0; a < n; ++a) {
                    if (dist[a] > limit) continue;
                    H += pw[a] * (px[a] - mx) * (py[a] - my).transpose();
                }
                Eigen::JacobiSVD<Mat<D>> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
                Mat<D> fix = Mat<D>::Identity();
                fix(D - 1, D - 1) =
                    (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
                R = svd.matrixV() * fix * svd.matrixU().transpose();
                t = my - R * mx;
            }
            return residual;
        };
        const Mat<D> axes = leastRotation<D>(u1, u2);
        std::vector<Mat<D>> Rs(std::size_t(opts.starts));
        std::vector<Vec<D>> ts(Rs.size());
        std::vector<double> rs(Rs.size());
        for (std::size_t start = 0; start < Rs.size(); ++start) {
            Rs[start] =
                turnAbout<D>(u2, 360.0 * double(start) / double(Rs.size()) / DEGREES) * axes;
            ts[start] = c2 - Rs[start] * c1;
            rs[start] = fit(Rs[start], ts[start]);
        }
        // Of the fits as close as the closest, to START_TIE of it or of the tolerance, the least
        // turned from the axes (a flattened limb fits as well half a turn about its axis).
        const double closest = *std::min_element(rs.begin(), rs.end());
        std::size_t chosen = 0;
        double least = FAR;
        for (std::size_t start = 0; start < Rs.size(); ++start) {
            const double turn = rotationAngle<D>(Rs[start] * axes.transpose());
            if (rs[start] <= closest + START_TIE * std::max(closest, opts.maxResidual) &&
                turn < least) {
                least = turn;
                chosen = start;
            }
        }
        const Mat<D> R = Rs[chosen];
        const Vec<D> t = ts[chosen];
        const double residual = rs[chosen];
        limb.residual = residual;
        Mat<D> rotation = R;
        if constexpr (D == 3) {
            // The axis of both limbs in M1's frame, the same either way round.
            const Vec<D> u = (u1 + R.transpose() * u2).normalized();
            rotation = leastRotation<D>(u, (R * u).normalized());
            limb.axialTurn = rotationAngle<D>(R * rotation.transpose());
        }
        limb.rotation = rotation;
        // The pivot halfway between M1's centroid and where (R, t) takes M2's back, and its
        // image: either way round the same pair of points.
        limb.sourceCentre = 0.5 * (c1 + R.transpose() * (c2 - t));
        limb.targetCentre = R * limb.sourceCentre + t;
        limb.angle = rotationAngle<D>(rotation);
        if (!(residual <= opts.maxResidual)) {
            std::ostringstream s;
            s << "not rigid: the fit leaves " << residual << " > " << opts.maxResidual
              << " (unit box)";
            limb.reason = s.str();
            return;
        }
        if (!(limb.angle >= minAngle)) {
            std::ostringstream s;
            s << "turned by " << limb.angle << " < " << minAngle << " degrees";
            limb.reason = s.str();
            return;
        }
        if (joint1) {
            // A segment turns about its joint, which stays: where the map takes each shape's
            // joint vertex is near it, or the fit found another motion (a band of a limb fits
            // itself half a turn round).
            const double slip = std::max((limb.map(*joint1) - *joint1).norm(),
                                         (limb.inverse(*joint2) - *joint2).norm());
            if (!(slip <= SEGMENT_JOINT_SLACK * limb.joint())) {
                std::ostringstream s;
                s << "the joint does not stay: the fit moves it by " << slip << " > "
                  << SEGMENT_JOINT_SLACK << " J = " << SEGMENT_JOINT_SLACK * limb.joint()
                  << " (unit box)";
                limb.reason = s.str();
                return;
            }
        }
        limb.used = true;
        const std::size_t targetCount = opts.count / 2;
        for (std::size_t i : farthestSamples(unitSource, r1, tip1, opts.count - targetCount)) {
            const Vec<D> q = limb.map(unitSource.points[i]);
            if (!((q.array() > 0).all() && (q.array() < 1).all())) continue; // off Omega
            out.source.push_back(unitSource.points[i]);
            out.target.push_back(q);
        }
        for (std::size_t i : farthestSamples(unitTarget, r2, tip2, targetCount)) {
            const Vec<D> p = limb.inverse(unitTarget.points[i]);
            if (!((p.array() > 0).all() && (p.array() < 1).all())) continue; // off Omega
            out.source.push_back(p);
            out.target.push_back(unitTarget.points[i]);
        }
    };
    std::vector<std::vector<std::pair<std::size_t, double>>> graph1, graph2; // when needed
    const bool segments = opts.segmentTo > 0;
    // The geodesic distances from each tip on each shape, when needed.
    std::vector<std::vector<double>> geodesics1(sourceTips.size()), geodesics2(sourceTips.size());
    const auto computeGeodesics = [&](std::size_t k) {
        if (!geodesics1[k].empty()) return;
        if (graph1.empty()) {
            detail::invokeBoth(
                opts.threaded, [&] { graph1 = chordGraph(unitSource); },
                [&] { graph2 = chordGraph(unitTarget); });
        }
        detail::invokeBoth(
            opts.threaded,
            [&] {
                geodesics1[k] = geodesicDistance(graph1, nearestVertex(unitSource, sourceTips[k]));
            },
            [&] {
                geodesics2[k] = geodesicDistance(graph2, nearestVertex(unitTarget, targetTips[k]));
            });
    };
    for (std::size_t k = 0; k < sourceTips.size(); ++k) {
        const double motion = (sourceTips[k] - targetTips[k]).norm();
        const bool moved = motion > opts.minMotion;
        if (!moved && !(segments && motion <= opts.segmentMaxTipMotion)) continue;
        computeGeodesics(k);
        const std::vector<double>&g1 = geodesics1[k], &g2 = geodesics2[k];
        double j1 = FAR, j2 = FAR;
        for (std::size_t i : still1)
            j1 = std::min(j1, g1[i]);
        for (std::size_t i : still2)
            j2 = std::min(j2, g2[i]);
        RigidLimb<D> limb;
        limb.extremity = k;
        limb.sourceJoint = j1;
        limb.targetJoint = j2;
        const double joint = limb.joint();
        if (!std::isfinite(joint)) {
            if (moved) {
                limb.reason = "no still point is connected to the tip";
                out.limbs.push_back(limb);
            }
            continue;
        }
        // The vertices of each shape with g < to * J.
        const auto within = [joint](const std::vector<double>& g, double to) {
            std::vector<std::size_t> idx;
            for (std::size_t i = 0; i < g.size(); ++i)
                if (g[i] < to * joint) idx.push_back(i);
            return idx;
        };
        if (moved) {
            fitPart(limb, within(g1, opts.reach), within(g2, opts.reach),
                    within(g1, opts.targetReach), within(g2, opts.targetReach), sourceTips[k],
                    targetTips[k], 0.0, nullptr, nullptr);
            out.limbs.push_back(limb);
            continue;
        }
        // Step 6: the segment next to the joint of a limb whose tip stayed.
        const auto jointVertex = [](const std::vector<double>& g,
                                    const std::vector<std::size_t>& at) {
            std::size_t best = at.front();
            for (std::size_t i : at)
                if (g[i] < g[best]) best = i;
            return best;
        };
        const Vec<D> p1 = unitSource.points[jointVertex(g1, still1)],
                     p2 = unitTarget.points[jointVertex(g2, still2)];
        // The segment on each shape: the vertices between segmentFrom and segmentTo of the way
        // from the tip to the joint vertex, of those nearer this tip than any other (the inner
        // side of a thigh meets the other thigh's at the crotch) and than SEGMENT_REACH times
        // the shape's own J (a tip next to the still part has no segment). Not g < J: the tip
        // lies to one side of a foot, and the joint's geodesic distance follows a scan's
        // noise, so that bound cuts the two shapes' segments unlike.
        for (std::size_t j = 0; j < sourceTips.size(); ++j)
            computeGeodesics(j);
        const auto segmentOf = [&](const Surface<D>& m,
                                   const std::vector<std::vector<double>>& geodesics,
                                   double ownJoint, const Vec<D>& tip, const Vec<D>& p) {
            std::vector<std::size_t> idx;
            const std::vector<double>& g = geodesics[k];
            const Vec<D> axis = p - tip;
            const double length2 = axis.squaredNorm();
            if (!(length2 > 0)) return idx;
            for (std::size_t i = 0; i < g.size(); ++i) {
                const double along = (m.points[i] - tip).dot(axis) / length2;
                if (!(along >= opts.segmentFrom && along < opts.segmentTo &&
                      g[i] < SEGMENT_REACH * ownJoint))
                    continue;
                bool nearest = true;
                for (std::size_t j = 0; j < geodesics.size() && nearest; ++j)
                    nearest = j == k || g[i] <= geodesics[j][i];
                if (nearest) idx.push_back(i);
            }
            return idx;
        };
        const Vec<D> tip1 = unitSource.points[nearestVertex(unitSource, sourceTips[k])],
                     tip2 = unitTarget.points[nearestVertex(unitTarget, targetTips[k])];
        const std::vector<std::size_t> s1 = segmentOf(unitSource, geodesics1, j1, tip1, p1),
                                       s2 = segmentOf(unitTarget, geodesics2, j2, tip2, p2);
        // A segment too small to fit (a tip next to the still part: a hand hanging by the
        // body) is no limb and is not reported.
        if (s1.size() < opts.minVertices || s2.size() < opts.minVertices) continue;
        RigidLimb<D> segment;
        segment.extremity = k;
        segment.segment = true;
        segment.sourceJoint = j1;
        segment.targetJoint = j2;
        fitPart(segment, s1, s2, s1, s2, tip1, tip2, opts.segmentMinAngle, &p1, &p2);
        // One that fitted but barely turned is a limb that stayed, and not reported.
        if (segment.used || !(segment.residual <= opts.maxResidual) ||
            segment.angle >= opts.segmentMinAngle)
            out.limbs.push_back(segment);
    }
    return out;
}

template RigidLimbs<2> findRigidLimbs<2>(const Surface<2>&, const Surface<2>&,
                                         const std::vector<Vec<2>>&, const std::vector<Vec<2>>&,
                                         const std::vector<Vec<2>>&, const RigidLimbOptions&);
template RigidLimbs<3> findRigidLimbs<3>(const Surface<3>&, const Surface<3>&,
                                         const std::vector<Vec<3>>&, const std::vector<Vec<3>>&,
                                         const std::vector<Vec<3>>&, const RigidLimbOptions&);

} // namespace vdbmatch
