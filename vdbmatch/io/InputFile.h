/// @file InputFile.h
/// @brief The checks every reader makes before opening an input file, and the whole-file read
///        of the text and mesh readers, with one wording of their errors.
#pragma once

#include <string>

namespace vdbmatch {

/// Throws openvdb::IoError "<where> does not exist" or "<where> is a directory".
void checkInputFile(const std::string& path, const std::string& where);

/// checkInputFile, then the whole file as bytes.
/// @throw openvdb::IoError if it is missing, a directory, or cannot be opened or read
std::string readInputFile(const std::string& path, const std::string& where);

} // namespace vdbmatch
