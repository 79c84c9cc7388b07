/// @file FuzzPointTable.cc
/// @brief libFuzzer target: the bytes are read by PointTable::read as .csv and as .xyz, in 2D
/// and 3D; each table read is rendered unchanged and with moved positions.
#include "FuzzCommon.h"

#include <vdbmatch/io/PointTable.h>

namespace {

void
exercise(const std::string& path, int dimension)
{
    vdbmatch::fuzz::expectNoCrash([&] {
        vdbmatch::PointTable table = vdbmatch::PointTable::read(path, dimension);
        (void)table.render();
        for (auto& p : table.positions())
            p += openvdb::Vec3d(0.5, -0.25, 1.0);
        (void)table.render();
    });
}

} // namespace

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static vdbmatch::fuzz::ScratchFile csv("points", ".csv");
    static vdbmatch::fuzz::ScratchFile xyz("points", ".xyz");
    const std::string& csvPath = csv.write(data, size);
    const std::string& xyzPath = xyz.write(data, size);
    for (int dimension : {2, 3}) {
        exercise(csvPath, dimension);
        exercise(xyzPath, dimension);
    }
    return 0;
}
