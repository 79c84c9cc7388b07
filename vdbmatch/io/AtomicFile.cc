/// @file AtomicFile.cc
/// @brief Atomic file writes: temporary file, fsync, rename.
#include "AtomicFile.h"

#include <vdbmatch/io/PathText.h>

#include <openvdb/openvdb.h>

#include <atomic>
#include <exception>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <unistd.h>

namespace vdbmatch {

namespace {

using detail::quoted;

} // namespace

void
writeFileAtomicallyVia(const std::string& path,
                       const std::function<void(const std::string& tempPath)>& writeTemp,
                       const std::string& caller)
{
    namespace fs = std::filesystem;
    static std::atomic<unsigned> sCounter{0};

    const fs::path target(path);
    if (target.filename().empty()) {
        OPENVDB_THROW(openvdb::IoError, caller + ": " + quoted(path) + " is not a file name");
    }
    const fs::path temp =
        target.parent_path() / ("." + target.filename().string() + ".tmp" +
                                std::to_string(::getpid()) + "-" + std::to_string(sCounter++));
    auto fail = [&](const std::string& what) {
        std::error_code ignored;
        fs::remove(temp, ignored);
        OPENVDB_THROW(openvdb::IoError, caller + ": cannot write " + quoted(path) + ": " + what);
    };

    try {
        writeTemp(temp.string());
    } catch (const std::exception& e) {
        fail(e.what());
    }
    // Flush to disk before the rename, so that a crash leaves the old file or the new one.
    const int fd = ::open(temp.c_str(), O_RDONLY);
    if (fd < 0) fail("the temporary file " + quoted(temp.string()) + " was not created");
    const bool synced = ::fsync(fd) == 0;
    ::close(fd);
    if (!synced) fail("cannot flush " + quoted(temp.string()) + " to disk");
    std::error_code sizeError;
    if (fs::file_size(temp, sizeError) == 0 || sizeError) fail("the temporary file is empty");

    std::error_code ec;
    fs::rename(temp, target, ec);
    if (ec) fail("cannot rename the temporary file (" + ec.message() + ")");
}

void
writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write)
{
    writeFileAtomicallyVia(
        path,
        [&](const std::string& tempPath) {
            std::ofstream out(tempPath, std::ios::binary | std::ios::trunc);
            if (!out) {
                OPENVDB_THROW(openvdb::IoError,
                              "cannot create the temporary file " + quoted(tempPath));
            }
            write(out);
            out.flush();
            if (!out) OPENVDB_THROW(openvdb::IoError, "the stream failed while writing");
            out.close();
            if (!out) OPENVDB_THROW(openvdb::IoError, "cannot close the temporary file");
        },
        "writeFileAtomically");
}

} // namespace vdbmatch
