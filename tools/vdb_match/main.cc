/// @file main.cc
/// @brief Entry point of the vdb_match command; everything else is in Cli.h.
#include "Cli.h"

#include <iostream>
#include <limits>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace {

/// glibc hands allocations above its mmap threshold (128 KiB at first, raised up to 32 MiB as
/// such blocks are freed) to mmap and trims the heap above 2x that threshold: every energy
/// evaluation and metric solve of a level then maps its work arrays afresh and faults their
/// pages in again, and concurrent page faults serialise the threads. Fixing the threshold at its
/// maximum and never trimming keeps the freed arrays for the next iteration: the metric solve of
/// the energy benchmark's 556k unknowns took 242 ms on 2 threads, 92 ms with these settings
/// (docs/performance.md). The process keeps at most its peak memory.
constexpr int MMAP_THRESHOLD_BYTES = 32 << 20;

void
tuneAllocator()
{
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES);
    mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
#endif
}

} // namespace

int
main(int argc, char** argv)
{
    tuneAllocator();
    return vdbmatch::cli::run(argc, argv, std::cout, std::cerr);
}
