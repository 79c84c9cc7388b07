/// @file TrilinearVsExact.cc
/// @brief How far a DCC's trilinear sampling of deformation.vdb and inverse.vdb is from the exact
/// piecewise-linear map and its exact inverse, over the vertices of a mesh (docs/apply.md).
///
/// Usage: vdbmatch_trilinear_vs_exact DEFORMATION.vdb MESH(.obj|.ply|.stl)
/// Prints, in world units and in voxels h: mean and max over the vertices x of
/// |x + u_trilinear(x) - phi(x)| and of |y + v_trilinear(y) - phi^-1(y)| at y = phi(x), where v is
/// the exact inverse at the nodes (makeInverseGrid), and the time to compute that grid.
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/InverseGrid.h>
#include <vdbmatch/io/MeshIO.h>

#include <openvdb/tools/Interpolation.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>

int
main(int argc, char** argv)
{
    using namespace vdbmatch;
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s DEFORMATION.vdb MESH\n", argv[0]);
        return 1;
    }
    try {
        openvdb::initialize();
        const DeformationField phi = DeformationField::read(argv[1]);
        const Surface<3> mesh = readMesh(argv[2]);
        const auto t0 = std::chrono::steady_clock::now();
        const InverseGridResult inverse = makeInverseGrid(phi, true);
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        openvdb::tools::GridSampler<openvdb::Vec3SGrid, openvdb::tools::BoxSampler> forward(
            phi.grid()),
            backward(*inverse.grid);
        double sumF = 0, maxF = 0, sumI = 0, maxI = 0;
        for (const auto& p : mesh.points) {
            const openvdb::Vec3d x(p[0], p[1], p[2]);
            const openvdb::Vec3d y = phi.apply(x);
            const double eF = (x + openvdb::Vec3d(forward.wsSample(x)) - y).length();
            const double eI = (y + openvdb::Vec3d(backward.wsSample(y)) - x).length();
            sumF += eF;
            maxF = std::max(maxF, eF);
            sumI += eI;
            maxI = std::max(maxI, eI);
        }
        const double n = double(mesh.points.size()), h = phi.voxelSize();
        std::printf("nodes %zu, voxel h %.6g, exact inverse grid %.2f s (%zu failures, max "
                    "residual %.3g)\n",
                    inverse.nodes, h, seconds, inverse.failures, inverse.maxResidual);
        std::printf("forward  trilinear vs exact: mean %.3g max %.3g world = %.4f h / %.3f h\n",
                    sumF / n, maxF, sumF / n / h, maxF / h);
        std::printf("inverse  trilinear vs exact: mean %.3g max %.3g world = %.4f h / %.3f h\n",
                    sumI / n, maxI, sumI / n / h, maxI / h);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
}
