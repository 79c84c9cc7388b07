/// @file ImageBackendOiio.cc
/// @brief The module libvdbmatch_image.so: EXR and PNG writing through OpenImageIO with atomic
///        rename, and image reading (ImageBackend.h). The arguments were checked by ImageIO.cc.
#include <vdbmatch/io/AtomicFile.h>
#include <vdbmatch/io/ImageBackend.h>

#include <OpenImageIO/imageio.h>
#include <openvdb/Exceptions.h>

#include <memory>
#include <stdexcept>

namespace vdbmatch {
namespace {

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

void
writeExrOiio(const std::string& label, const std::string& path, const ImageChannels& image,
             const ImageAttributes& attributes)
{
    OIIO::ImageSpec spec(image.width, image.height, static_cast<int>(image.names.size()),
                         OIIO::TypeDesc::FLOAT);
    spec.channelnames = image.names;
    spec.alpha_channel = -1;
    spec.attribute("compression", "zip");
    for (const auto& [name, value] : attributes)
        spec.attribute(name, value);
    writeAtomically(label, path, "openexr", spec, OIIO::TypeDesc::FLOAT, image.pixels.data());
}

void
writePngOiio(const std::string& label, const std::string& path, int width, int height,
             const std::vector<std::uint8_t>& rgb)
{
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    writeAtomically(label, path, "png", spec, OIIO::TypeDesc::UINT8, rgb.data());
}

ImageChannels
readImageOiio(const std::string& label, const std::string& path, ImageAttributes* attributes)
{
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) OPENVDB_THROW(openvdb::IoError, label + ": cannot open: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    ImageChannels image;
    image.width = spec.width;
    image.height = spec.height;
    image.names = spec.channelnames;
    image.pixels.resize(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
        OPENVDB_THROW(openvdb::IoError, label + ": cannot read the pixels: " + in->geterror());
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

const detail::ImageBackend BACKEND = {detail::IMAGE_BACKEND_VERSION, &writeExrOiio, &writePngOiio,
                                      &readImageOiio};

} // namespace
} // namespace vdbmatch

extern "C" __attribute__((visibility("default"))) const vdbmatch::detail::ImageBackend*
vdbmatch_image_backend()
{
    return &vdbmatch::BACKEND;
}
