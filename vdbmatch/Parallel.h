/// @file Parallel.h
/// @brief forEachIndex: a TBB parallel loop over [0, count), and invokeBoth: two tasks side by
///        side, both of which can also run serially (the `threaded` flag every parallel
///        function of vdbmatch takes).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <cstddef>

namespace vdbmatch {
namespace detail {

/// Calls func(i) for i in [0, count): in parallel with TBB if @a threaded, else in order.
template <typename Func>
void
forEachIndex(std::size_t count, bool threaded, const Func& func)
{
    if (threaded) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const auto& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i)
                func(i);
        });
    } else {
        for (std::size_t i = 0; i != count; ++i)
            func(i);
    }
}

/// Calls first() and second(): side by side with TBB if @a threaded, else in that order.
template <typename First, typename Second>
void
invokeBoth(bool threaded, const First& first, const Second& second)
{
    if (threaded) {
        tbb::parallel_invoke(first, second);
    } else {
        first();
        second();
    }
}

} // namespace detail
} // namespace vdbmatch
