/// @file FuzzConfig.cc
/// @brief libFuzzer target: the bytes are a `vdb_match match --config` file (JSON), given to
///        parseConfig (as text) and readConfig (as a file); every setting's value is then parsed
///        as the number or the word its option expects.
#include "FuzzCommon.h"

#include <ConfigFile.h>
#include <cerrno>
#include <cstdlib>

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static vdbmatch::fuzz::ScratchFile file("config", ".json");
    const std::string text(reinterpret_cast<const char*>(data), size);
    vdbmatch::fuzz::expectNoCrash([&] {
        for (const vdbmatch::cli::ConfigSetting& s : vdbmatch::cli::parseConfig(text, "fuzz")) {
            // What the options do with the text (parseDouble / parseInt in CliSupport.cc).
            errno = 0;
            char* end = nullptr;
            volatile double x = std::strtod(s.value.c_str(), &end);
            volatile long n = std::strtol(s.value.c_str(), &end, 10);
            (void)x;
            (void)n;
            if (s.key.empty() || s.option.rfind("--", 0) != 0) std::abort(); // a reader bug
        }
    });
    const std::string& path = file.write(data, size);
    vdbmatch::fuzz::expectNoCrash([&] { vdbmatch::cli::readConfig(path); });
    return 0;
}
