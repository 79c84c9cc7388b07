/// @file AtomicFile.h
/// @brief Writing a file without ever leaving a partial file at its path: write a temporary
///        file in the same directory, flush it to disk, rename it over the target.
///
/// A crash or an error leaves either the previous file or the complete new one (rename within a
/// directory is atomic on POSIX file systems); the temporary file is removed on failure.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace vdbmatch {

/// Writes @a path atomically through a stream.
/// @param path   file to create or replace
/// @param write  fills the stream (opened in binary mode); signature void(std::ostream&). It may
///               throw; the exception is reported as an IoError.
/// @throw openvdb::IoError naming @a path if the temporary file cannot be created, written,
///        flushed or renamed, or if @a write throws (the temporary file is removed)
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Writes @a path atomically with a writer that needs a file name (e.g. openvdb::io::File).
/// @param path       file to create or replace
/// @param writeTemp  writes the complete file at the given temporary path; signature
///                   void(const std::string& tempPath). It may throw.
/// @param caller     names the calling function in messages
/// @throw openvdb::IoError as writeFileAtomically, also if writeTemp leaves an empty file
void writeFileAtomicallyVia(const std::string& path,
                            const std::function<void(const std::string& tempPath)>& writeTemp,
                            const std::string& caller = "writeFileAtomically");

} // namespace vdbmatch
