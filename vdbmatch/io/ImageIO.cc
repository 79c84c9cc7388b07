/// @file ImageIO.cc
/// @brief EXR and PNG writing through OpenImageIO, with atomic rename; image reading.
#include "ImageIO.h"

#include <vdbmatch/io/AtomicFile.h>

#include <OpenImageIO/imageio.h>
#include <openvdb/Exceptions.h>

#include <algorithm>
#include <atomic>
#include <fcntl.h>
#include <filesystem>
#include <memory>
#include <set>
#include <system_error>
#include <unistd.h>

namespace vdbmatch {

namespace {

namespace fs = std::filesystem;

/// EXR header attributes that describe the image itself and cannot be set as strings.
const std::set<std::string> RESERVED_EXR_ATTRIBUTES = {
    "channels",  "compression",      "dataWindow",         "displayWindow",
    "lineOrder", "pixelAspectRatio", "screenWindowCenter", "screenWindowWidth",
};

std::string
quoted(const std::string& s)
{
    return "'" + s + "'";
}

/// Writes @a spec / @a data with OpenImageIO's writer for @a format ("openexr", "png") to
/// @a path atomically (writeFileAtomicallyVia: temporary file, flush, rename).
void
writeAtomically(const std::string& function, const std::string& path, const std::string& format,
                const OIIO::ImageSpec& spec, OIIO::TypeDesc dataType, const void* data)
{
    writeFileAtomicallyVia(
        path,
        [&](const std::string& temp) {
            std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(format);
            if (!out) {
                throw std::runtime_error("OpenImageIO has no " + format + " writer (" +
                                         OIIO::geterror() + ")");
            }
            if (!out->open(temp, spec)) throw std::runtime_error(out->geterror());
            if (!out->write_image(dataType, data)) {
                const std::string error = out->geterror();
                out->close();
                throw std::runtime_error(error);
            }
            if (!out->close()) throw std::runtime_error(out->geterror());
        },
        function);
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
    OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(image.names.size()),
                         OIIO::TypeDesc::FLOAT);
    spec.channelnames = image.names;
    spec.alpha_channel = -1;
    spec.attribute("compression", "zip");
    for (const auto& [name, value] : attributes) {
        if (name.empty()) OPENVDB_THROW(openvdb::ValueError, fn + ": empty attribute name");
        if (RESERVED_EXR_ATTRIBUTES.count(name)) {
            OPENVDB_THROW(openvdb::ValueError,
                          fn + ": attribute name " + quoted(name) + " is reserved by OpenEXR");
        }
        spec.attribute(name, value);
    }
    writeAtomically(fn, path, "openexr", spec, OIIO::TypeDesc::FLOAT, image.pixels.data());
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
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    writeAtomically(fn, path, "png", spec, OIIO::TypeDesc::UINT8, rgb.data());
}

ImageChannels
readImage(const std::string& path, ImageAttributes* attributes)
{
    const std::string fn = "readImage(" + quoted(path) + ")";
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) OPENVDB_THROW(openvdb::IoError, fn + ": cannot open: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    ImageChannels image;
    image.width = spec.width;
    image.height = spec.height;
    image.names = spec.channelnames;
    image.pixels.resize(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
        OPENVDB_THROW(openvdb::IoError, fn + ": cannot read the pixels: " + in->geterror());
    }
    if (attributes) {
        attributes->clear();
        for (const OIIO::ParamValue& p : spec.extra_attribs) {
            if (p.type() == OIIO::TypeDesc::STRING) {
                attributes->emplace_back(p.name().string(), p.get_string());
            }
        }
    }
    in->close();
    return image;
}

} // namespace vdbmatch
