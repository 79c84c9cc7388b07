/// @file BitmapFont.h
/// @brief A built-in 5x7 pixel bitmap font for labels in rendered pictures (colour-bar ticks,
///        titles, view names), so that pictures need no font files.
///
/// Coverage: digits, the letters A-Z (lower-case letters are drawn as upper case), space and
/// . , - + : ; = ( ) [ ] | / _ % * < > ! ? ' " # ^. Any other character is drawn as a hollow box.
/// Metrics, in font pixels (multiply by @a scale for image pixels): each glyph is 5 wide and 7
/// high, characters advance by 6, lines by 9.
#pragma once

#include <vdbmatch/render/Canvas.h>

#include <string>

namespace vdbmatch {

/// Width of one glyph, the horizontal advance and the glyph height, in font pixels.
constexpr int FONT_GLYPH_WIDTH = 5;
constexpr int FONT_ADVANCE = 6;
constexpr int FONT_GLYPH_HEIGHT = 7;

/// Width in image pixels of @a text drawn at integer @a scale (no trailing spacing).
int textWidth(const std::string& text, int scale);

/// Height in image pixels of one line of text drawn at @a scale.
inline int
textHeight(int scale)
{
    return FONT_GLYPH_HEIGHT * scale;
}

/// Draws @a text with its top-left corner at pixel (x, y), each font pixel a scale x scale block
/// of colour @a color; background pixels are left unchanged. Clipped to the image.
void drawText(Image8& image, int x, int y, const std::string& text, const Rgb8& color, int scale);

} // namespace vdbmatch
