/// @file ImageIO.h
/// @brief Writing pictures: multi-channel float OpenEXR images (field slices with named
///        channels and string metadata) and 8-bit RGB PNG images, both written atomically
///        through OpenImageIO; reading EXR images back.
///
/// Formats:
/// - EXR: 32-bit float channels, ZIP compression, scanline, one part. OpenEXR stores channels
///   sorted by name, so readers (and readExr()) may return them in another order than written:
///   identify channels by name. String attributes go into the header as string attributes.
/// - PNG: 8 bits per channel, RGB, sRGB-encoded, no alpha.
/// Pixel layout in memory: interleaved, row after row, row 0 = top row of the picture;
/// value index (y * width + x) * channelCount + c.
/// Atomic writes: the image goes to a temporary file in the destination directory, which is then
/// renamed over the destination, so that a reader never sees a partial file.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vdbmatch {

/// A float image with named channels.
struct ImageChannels
{
    int width = 0;
    int height = 0;
    std::vector<std::string> names; ///< channel names, e.g. {"phi1", "phi2"} or {"R", "G", "B"}
    std::vector<float> pixels; ///< size width * height * names.size(), interleaved, top row first

    /// Value of channel @a c at pixel (x, y).
    float at(int x, int y, int c) const
    {
        return pixels[(static_cast<size_t>(y) * width + x) * names.size() + c];
    }
    /// Index of the channel named @a name, or -1.
    int channelIndex(const std::string& name) const;
};

/// String attributes of an image header, (name, value) pairs.
using ImageAttributes = std::vector<std::pair<std::string, std::string>>;

/// Writes @a image as a float OpenEXR file at @a path, atomically, with @a attributes as string
/// attributes of the header (names such as "vdbmatch:source"; the reserved EXR names
/// "channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
/// "screenWindowCenter" and "screenWindowWidth" are rejected).
/// @throw openvdb::ValueError if the size is not positive, there are no channels, a channel name
///        is empty or repeated, the pixel count does not match, or an attribute name is empty or
///        reserved
/// @throw openvdb::IoError if the file cannot be written or renamed (no partial file is left)
void writeExr(const std::string& path, const ImageChannels& image,
              const ImageAttributes& attributes = {});

/// Writes an 8-bit RGB PNG of @a width x @a height pixels at @a path, atomically.
/// @param rgb  3 * width * height bytes, interleaved R, G, B, top row first
/// @throw openvdb::ValueError if the size is not positive or rgb has the wrong length
/// @throw openvdb::IoError if the file cannot be written or renamed
void writePng(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb);

/// Reads every channel of an image file (any format OpenImageIO reads) as floats, with the
/// string attributes of its header in @a attributes if given.
/// @throw openvdb::IoError if the file cannot be opened or read
ImageChannels readImage(const std::string& path, ImageAttributes* attributes = nullptr);

} // namespace vdbmatch
