/// @file FuzzMeshObj.cc
/// @brief libFuzzer target: the bytes are a .obj file given to readMesh.
#include "FuzzCommon.h"

#include <vdbmatch/io/MeshIO.h>

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static vdbmatch::fuzz::ScratchFile file("mesh", ".obj");
    const std::string& path = file.write(data, size);
    vdbmatch::fuzz::expectNoCrash([&] { vdbmatch::readMesh(path); });
    return 0;
}
