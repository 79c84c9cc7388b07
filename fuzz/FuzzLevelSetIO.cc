/// @file FuzzLevelSetIO.cc
/// @brief libFuzzer target: the bytes are a .vdb file given to readLevelSet (default grid
/// selection and selection by name, which read the header, the grid descriptors and one grid)
/// and to readDeformation.
#include "FuzzCommon.h"

#include <vdbmatch/io/DeformationIO.h>
#include <vdbmatch/io/LevelSetIO.h>

#include <openvdb/openvdb.h>

extern "C" int
LLVMFuzzerInitialize(int*, char***)
{
    openvdb::initialize();
    return 0;
}

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static vdbmatch::fuzz::ScratchFile file("levelset", ".vdb");
    const std::string& path = file.write(data, size);
    vdbmatch::fuzz::expectNoCrash([&] { vdbmatch::readLevelSet(path); });
    // By name: the assets name their level set "surface"; the last byte picks another name
    // (missing grid / several grids of that name / wrong type paths).
    const char* names[] = {"surface", "displacement", "ls"};
    const std::string name = names[size > 0 ? data[size - 1] % 3 : 0];
    vdbmatch::fuzz::expectNoCrash([&] { vdbmatch::readLevelSet(path, name); });
    vdbmatch::fuzz::expectNoCrash([&] { vdbmatch::readDeformation(path); });
    return 0;
}
