/// @file FuzzPolyline.cc
/// @brief libFuzzer target: the bytes are a .polyline file given to readPolyline.
#include "FuzzCommon.h"

#include <vdbmatch/io/MeshIO.h>

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static vdbmatch::fuzz::ScratchFile file("polyline", ".polyline");
    const std::string& path = file.write(data, size);
    vdbmatch::fuzz::expectNoCrash([&] { vdbmatch::readPolyline(path); });
    return 0;
}
