/// @file ImageBackend.h
/// @brief The OpenImageIO half of ImageIO.h, built as a module of its own
///        (libvdbmatch_image.so) that the library loads on the first picture it writes or reads.
///
/// OpenImageIO brings in some 250 shared libraries (codecs, OpenCV, GDAL, ...) whose loading
/// costs a command about 0.2 s before it does anything; most commands never touch an image.
/// The module exports one C function, vdbmatch_image_backend(), returning the table below.
/// ImageIO.cc checks the arguments, finds the module next to the object that holds the library
/// (libvdbmatch.so, or the executable it is linked into) and calls through the table.
#pragma once

#include <vdbmatch/io/ImageIO.h>

#include <cstdint>
#include <string>
#include <vector>

namespace vdbmatch {
namespace detail {

/// Version of the table layout; the library refuses a module with another one.
constexpr int IMAGE_BACKEND_VERSION = 1;

/// File name of the module (looked up next to the library, then by the dynamic loader's path).
constexpr const char* IMAGE_BACKEND_MODULE = "libvdbmatch_image.so";

/// The functions of ImageIO.h that need OpenImageIO, called with checked arguments; @a label
/// names the call in error messages (e.g. "writeExr('out.exr')").
struct ImageBackend
{
    int version;
    void (*writeExr)(const std::string& label, const std::string& path, const ImageChannels& image,
                     const ImageAttributes& attributes);
    void (*writePng)(const std::string& label, const std::string& path, int width, int height,
                     const std::vector<std::uint8_t>& rgb);
    ImageChannels (*readImage)(const std::string& label, const std::string& path,
                               ImageAttributes* attributes);
};

} // namespace detail
} // namespace vdbmatch

/// The module's entry point.
extern "C" const vdbmatch::detail::ImageBackend* vdbmatch_image_backend();
