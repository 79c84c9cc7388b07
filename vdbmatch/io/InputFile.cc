/// @file InputFile.cc
#include "InputFile.h"

#include <openvdb/Exceptions.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <system_error>

namespace vdbmatch {

void
checkInputFile(const std::string& path, const std::string& where)
{
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status))
        OPENVDB_THROW(openvdb::IoError, where + " does not exist");
    if (std::filesystem::is_directory(status))
        OPENVDB_THROW(openvdb::IoError, where + " is a directory");
}

std::string
readInputFile(const std::string& path, const std::string& where)
{
    checkInputFile(path, where);
    std::ifstream in(path, std::ios::binary);
    if (!in) OPENVDB_THROW(openvdb::IoError, where + " cannot be opened");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) OPENVDB_THROW(openvdb::IoError, where + " cannot be read");
    return bytes;
}

} // namespace vdbmatch
