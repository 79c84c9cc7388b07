/// @file main.cc
/// @brief Entry point of the vdb_match command; everything else is in Cli.h.
#include "Cli.h"

#include <iostream>

int
main(int argc, char** argv)
{
    return vdbmatch::cli::run(argc, argv, std::cout, std::cerr);
}
