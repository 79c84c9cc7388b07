/// @file FuzzMeshDocument.cc
/// @brief libFuzzer target: the bytes are read by MeshDocument::read as a .ply file if they
/// start with "ply", else as .obj and as .stl; each document read is rendered unchanged, then
/// with moved positions and normals (and, for PLY, an added vertex property).
#include "FuzzCommon.h"

#include <vdbmatch/io/MeshDocument.h>

#include <cstring>
#include <vector>

namespace {

void
exercise(const std::string& path)
{
    vdbmatch::fuzz::expectNoCrash([&] {
        vdbmatch::MeshDocument doc = vdbmatch::MeshDocument::read(path);
        (void)doc.render();
        for (auto& p : doc.positions())
            p += openvdb::Vec3d(0.5, -0.25, 1.0);
        for (auto& n : doc.normals())
            n = -n;
        if (doc.format() == vdbmatch::MeshDocument::Format::Ply) {
            doc.addVertexProperty("fuzz_value", std::vector<float>(doc.vertexCount(), 1.5f));
        }
        (void)doc.render();
    });
}

} // namespace

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static vdbmatch::fuzz::ScratchFile obj("document", ".obj");
    static vdbmatch::fuzz::ScratchFile ply("document", ".ply");
    static vdbmatch::fuzz::ScratchFile stl("document", ".stl");
    if (size >= 3 && std::memcmp(data, "ply", 3) == 0) {
        exercise(ply.write(data, size));
    } else {
        exercise(obj.write(data, size));
        exercise(stl.write(data, size));
    }
    return 0;
}
