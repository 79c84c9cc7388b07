/// @file TextParsing.h
/// @brief What the text readers (OBJ, PLY, STL, point tables) share: the parse error
///        "<caller>: file '<path>', line n: <problem>", the whitespace tokenizer and strict
///        number parsing (the whole token, an optional leading '+', no locale).
#pragma once

#include <vdbmatch/io/PathText.h>

#include <openvdb/Exceptions.h>

#include <charconv>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace vdbmatch {
namespace detail {

/// Throws ValueError "<caller>: file '<path>'[, line n]: <problem>".
class ParseError
{
public:
    ParseError(std::string caller, std::string path)
        : mCaller(std::move(caller)), mPath(std::move(path))
    {
    }
    [[noreturn]] void operator()(const std::string& problem, std::size_t line = 0) const
    {
        std::string m = mCaller + ": file " + quoted(mPath);
        if (line > 0) m += ", line " + std::to_string(line);
        OPENVDB_THROW(openvdb::ValueError, m + ": " + problem);
    }
    const std::string& path() const { return mPath; }

private:
    std::string mCaller, mPath;
};

/// White space of the text formats (the C locale's, without a locale look-up).
inline bool
isSpace(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/// Splits a line into whitespace-separated tokens (views into the line's text).
inline void
tokenize(std::string_view line, std::vector<std::string_view>& out)
{
    out.clear();
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(line[i]))
            ++i;
        const std::size_t b = i;
        while (i < line.size() && !isSpace(line[i]))
            ++i;
        if (i > b) out.push_back(line.substr(b, i - b));
    }
}

/// The whole of @a s as a number (an optional leading '+'); false if anything is left over.
template <typename T>
inline bool
parseNumber(std::string_view s, T& v)
{
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

inline bool
parseDouble(std::string_view s, double& v)
{
    return parseNumber(s, v);
}

inline bool
parseInt(std::string_view s, int64_t& v)
{
    return parseNumber(s, v);
}

} // namespace detail
} // namespace vdbmatch
