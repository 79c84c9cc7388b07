/// @file ConfigFile.h
/// @brief The --config file of `vdb_match match`: a JSON object with the keys of report.json's
///        "parameters", or a whole report.json; each key names the option it sets.
///
/// Reading is separate from applying (MatchCommand.cc applies each setting through the option
/// table, as the command line would) so that the reader can be fuzzed on its own
/// (fuzz/FuzzConfig.cc).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace vdbmatch {
namespace cli {

/// One setting of a --config file.
struct ConfigSetting
{
    std::string key;    ///< the report.json key, e.g. "cMatch"
    std::string option; ///< the option it sets, e.g. "--c-match"
    std::string value;  ///< the value as that option's text (a JSON number as written, a string)
};

/// The keys --config accepts and the option each sets, in report.json order ("sigmaFactor" is
/// accepted too, at its fixed value 2, and sets nothing).
const std::vector<std::pair<const char*, const char*>>& configKeys();

/// Largest --config file read (a report.json is a few KB).
constexpr std::size_t MAX_CONFIG_BYTES = 16u << 20;

/// The settings of the JSON text of a --config file, in the file's order.
/// @param path  names the file in messages
/// @throw openvdb::ValueError if the text is not a JSON object, its "parameters" (when present)
///        is not an object, a key is unknown (the message lists the known ones), a value is not a
///        number or a string, or sigmaFactor is not 2
std::vector<ConfigSetting> parseConfig(const std::string& text, const std::string& path);

/// Reads and parses a --config file.
/// @throw openvdb::IoError if it cannot be read or is larger than MAX_CONFIG_BYTES
/// @throw as parseConfig
std::vector<ConfigSetting> readConfig(const std::string& path);

} // namespace cli
} // namespace vdbmatch
