/// @file Assert.h
/// @brief VDBMATCH_ASSERT: invariant checks, on in Debug builds and when VDBMATCH_ENABLE_ASSERTS is
/// set.
#pragma once

#if !defined(NDEBUG) || defined(VDBMATCH_ENABLE_ASSERTS)
#include <cassert>
#include <cstdio>
#include <cstdlib>
#define VDBMATCH_ASSERT(cond)                                                                      \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            std::fprintf(stderr, "%s:%d: assertion failed: %s\n", __FILE__, __LINE__, #cond);      \
            std::abort();                                                                          \
        }                                                                                          \
    } while (0)
#else
#define VDBMATCH_ASSERT(cond) ((void)0)
#endif
