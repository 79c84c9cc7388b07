/// @file Canvas.h
/// @brief An 8-bit sRGB raster image (Image8) with the few 2D drawing primitives the preview and
///        the renderers share: filled rectangles, thick anti-aliasable segments, 2x2 box
///        downsampling and pasting.
///
/// Space and format: pixel (x, y) has its centre at (x + 0.5, y + 0.5) in "pixel coordinates";
/// x grows to the right, y grows downwards, row 0 is the top row. Pixels are stored interleaved
/// R, G, B, one byte each (sRGB-encoded), row after row: byte index 3 * (y * width + x) + c.
/// Drawing outside the image is clipped silently.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace vdbmatch {

/// An sRGB colour, one byte per channel (R, G, B).
using Rgb8 = std::array<std::uint8_t, 3>;

/// An 8-bit RGB image: width x height pixels, interleaved, row 0 at the top.
struct Image8
{
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgb; ///< size 3 * width * height

    Image8() = default;
    /// @throw openvdb::ValueError if a size is negative
    Image8(int w, int h, const Rgb8& fill);

    bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
    /// The colour of pixel (x, y); (x, y) must lie inside the image.
    Rgb8 at(int x, int y) const;
    /// Sets pixel (x, y) if it lies inside the image.
    void set(int x, int y, const Rgb8& c);
};

/// Fills the pixels x0 <= x < x1, y0 <= y < y1 (clipped) with @a c.
void fillRect(Image8& image, int x0, int y0, int x1, int y1, const Rgb8& c);

/// Draws the outline, one pixel wide, of the rectangle x0 <= x < x1, y0 <= y < y1.
void strokeRect(Image8& image, int x0, int y0, int x1, int y1, const Rgb8& c);

/// Draws a thick segment from (ax, ay) to (bx, by), in pixel coordinates, as a capsule of
/// diameter @a widthPx: every pixel whose centre lies within widthPx / 2 of the segment is set.
/// The colour is interpolated linearly (in sRGB bytes) from @a ca at a to @a cb at b. A width below
/// one pixel is drawn as a one-pixel-wide line (pixels within sqrt(2)/2 of the segment are not all
/// set; those within 0.5 are).
void drawSegment(Image8& image, double ax, double ay, double bx, double by, double widthPx,
                 const Rgb8& ca, const Rgb8& cb);

/// Every 2x2 block averaged into one pixel (box filter, in sRGB bytes, rounded): the image of a
/// 2x supersampled rendering. Odd sizes drop the last row / column.
Image8 downsample2x(const Image8& image);

/// Copies @a src into @a dst with its top-left corner at (x, y), clipped.
void paste(Image8& dst, const Image8& src, int x, int y);

} // namespace vdbmatch
