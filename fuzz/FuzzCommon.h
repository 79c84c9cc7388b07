/// @file FuzzCommon.h
/// @brief Helpers shared by the libFuzzer targets: the readers take paths, so each input is
/// written to a per-process scratch file with the extension the reader dispatches on.
#pragma once

#include <openvdb/Exceptions.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <unistd.h>

namespace vdbmatch::fuzz {

/// A scratch file in $TMPDIR (else /dev/shm, else /tmp), named after the process id and a tag so
/// that parallel fuzzing jobs do not share it. Removed at exit.
class ScratchFile
{
public:
    /// @param tag        distinguishes several scratch files of one process
    /// @param extension  with the dot, e.g. ".ply"
    ScratchFile(const std::string& tag, const std::string& extension)
    {
        const char* dir = std::getenv("TMPDIR");
        std::string base =
            dir && *dir ? dir : (access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp");
        mPath = base + "/vdbmatch_fuzz_" + std::to_string(getpid()) + "_" + tag + extension;
    }
    ~ScratchFile() { std::remove(mPath.c_str()); }
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;

    /// Replaces the file's content with @a size bytes at @a data; returns the path.
    const std::string& write(const std::uint8_t* data, std::size_t size)
    {
        std::FILE* f = std::fopen(mPath.c_str(), "wb");
        if (!f) std::abort(); // the harness itself is broken: not a finding in the reader
        if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
        std::fclose(f);
        return mPath;
    }

    const std::string& path() const { return mPath; }

private:
    std::string mPath;
};

/// Runs @a f; the documented exceptions of the readers (openvdb::Exception for invalid input,
/// std::exception from validation) are expected outcomes, not findings. Anything else (a crash,
/// a sanitizer report, a hang, a huge allocation) is reported by libFuzzer.
template <typename F>
void
expectNoCrash(F&& f)
{
    try {
        f();
    } catch (const openvdb::Exception&) {
    } catch (const std::exception&) {
    }
}

} // namespace vdbmatch::fuzz
