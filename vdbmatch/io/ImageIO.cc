/// @file ImageIO.cc
/// @brief Argument checks of the picture functions, and the loader of the OpenImageIO module
///        (ImageBackend.h) that does the work.
#include "ImageIO.h"

#include <vdbmatch/io/ImageBackend.h>
#include <vdbmatch/io/PathText.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <dlfcn.h>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace vdbmatch {

namespace {

namespace fs = std::filesystem;

/// EXR header attributes that describe the image itself and cannot be set as strings.
const std::set<std::string> RESERVED_EXR_ATTRIBUTES = {
    "channels",  "compression",      "dataWindow",         "displayWindow",
    "lineOrder", "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth",
};

using detail::quoted;

/// The module, or why it could not be loaded.
struct LoadedBackend
{
    const detail::ImageBackend* table = nullptr;
    std::string error;
};

LoadedBackend
loadBackend()
{
    // Next to the object that holds this function (libvdbmatch.so, or the executable or Python
    // module the library was linked into statically), then by the loader's search path.
    std::vector<std::string> candidates;
    Dl_info info;
    if (dladdr(reinterpret_cast<void*>(&loadBackend), &info) && info.dli_fname) {
        std::error_code ec;
        const fs::path self = fs::canonical(info.dli_fname, ec);
        if (!ec) candidates.push_back((self.parent_path() / detail::IMAGE_BACKEND_MODULE).string());
    }
    candidates.push_back(detail::IMAGE_BACKEND_MODULE);
    LoadedBackend result;
    std::string tried;
    for (const std::string& path : candidates) {
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* e = dlerror();
            tried += std::string(tried.empty() ? "" : "; ") + (e ? e : path + ": not loadable");
            continue;
        }
        // Never closed: OpenImageIO keeps plugins and threads until the process exits.
        using Entry = const detail::ImageBackend* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, "vdbmatch_image_backend"));
        const detail::ImageBackend* table = entry ? entry() : nullptr;
        if (!table || table->version != detail::IMAGE_BACKEND_VERSION) {
            dlclose(handle);
            tried += std::string(tried.empty() ? "" : "; ") + path +
                     ": not a vdbmatch image module of this version";
            continue;
        }
        result.table = table;
        return result;
    }
    result.error = std::string("pictures need the OpenImageIO module ") +
                   detail::IMAGE_BACKEND_MODULE +
                   ", installed next to libvdbmatch, but it could not be loaded (" + tried + ")";
    return result;
}

const detail::ImageBackend&
backend()
{
    static const LoadedBackend loaded = loadBackend(); // thread-safe, once per process
    if (!loaded.table) OPENVDB_THROW(openvdb::IoError, loaded.error);
    return *loaded.table;
}

} // namespace

int
ImageChannels::channelIndex(const std::string& name) const
{
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

void
writeExr(const std::string& path, const ImageChannels& image, const ImageAttributes& attributes)
{
    const std::string fn = "writeExr(" + quoted(path) + ")";
    if (image.width <= 0 || image.height <= 0) {
        OPENVDB_THROW(openvdb::ValueError, fn + ": image size " + std::to_string(image.width) +
                                               " x " + std::to_string(image.height) +
                                               " is not positive");
    }
    if (image.names.empty()) OPENVDB_THROW(openvdb::ValueError, fn + ": no channels");
    std::set<std::string> seen;
    for (const std::string& name : image.names) {
        if (name.empty()) OPENVDB_THROW(openvdb::ValueError, fn + ": empty channel name");
        if (!seen.insert(name).second) {
            OPENVDB_THROW(openvdb::ValueError, fn + ": channel " + quoted(name) + " repeated");
        }
    }
    const size_t expected = static_cast<size_t>(image.width) * image.height * image.names.size();
    if (image.pixels.size() != expected) {
        OPENVDB_THROW(openvdb::ValueError, fn + ": " + std::to_string(image.pixels.size()) +
                                               " values given, expected width * height * "
                                               "channels = " +
                                               std::to_string(expected));
    }
    for (const auto& [name, value] : attributes) {
        if (name.empty()) OPENVDB_THROW(openvdb::ValueError, fn + ": empty attribute name");
        if (RESERVED_EXR_ATTRIBUTES.count(name)) {
            OPENVDB_THROW(openvdb::ValueError,
                          fn + ": attribute name " + quoted(name) + " is reserved by OpenEXR");
        }
    }
    backend().writeExr(fn, path, image, attributes);
}

void
writePng(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb)
{
    const std::string fn = "writePng(" + quoted(path) + ")";
    if (width <= 0 || height <= 0) {
        OPENVDB_THROW(openvdb::ValueError, fn + ": image size " + std::to_string(width) + " x " +
                                               std::to_string(height) + " is not positive");
    }
    const size_t expected = 3 * static_cast<size_t>(width) * height;
    if (rgb.size() != expected) {
        OPENVDB_THROW(openvdb::ValueError, fn + ": " + std::to_string(rgb.size()) +
                                               " bytes given, expected 3 * width * height = " +
                                               std::to_string(expected));
    }
    backend().writePng(fn, path, width, height, rgb);
}

ImageChannels
readImage(const std::string& path, ImageAttributes* attributes)
{
    return backend().readImage("readImage(" + quoted(path) + ")", path, attributes);
}

} // namespace vdbmatch
