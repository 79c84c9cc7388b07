/// @file Parallel.h
/// @brief forEachIndex: a TBB parallel loop over [0, count) that can also run serially (the
///        `threaded` flag every parallel function of vdbmatch takes).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

} // namespace detail
} // namespace vdbmatch
