/// @file PathText.h
/// @brief How the readers and writers name files in their messages and tell formats apart:
///        quoted('a.obj') and lowerExtension("A.OBJ") == ".obj".
#pragma once

#include <cctype>
#include <filesystem>
#include <string>

namespace vdbmatch {
namespace detail {

/// 'path', as every I/O message quotes a file name.
inline std::string
quoted(const std::string& s)
{
    return "'" + s + "'";
}

/// The extension of @a path with its dot, in lower case ("" if none).
inline std::string
lowerExtension(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext)
        c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

} // namespace detail
} // namespace vdbmatch
