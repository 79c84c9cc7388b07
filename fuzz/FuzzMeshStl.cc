/// @file FuzzMeshStl.cc
/// @brief libFuzzer target: the bytes are a .stl file given to readMesh (ascii or binary, as the
/// content says).
#include "FuzzCommon.h"

#include <vdbmatch/io/MeshIO.h>

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static vdbmatch::fuzz::ScratchFile file("mesh", ".stl");
    const std::string& path = file.write(data, size);
    vdbmatch::fuzz::expectNoCrash([&] { vdbmatch::readMesh(path); });
    return 0;
}
