/// @file ScratchBuffer.h
/// @brief ScratchBuffer: work arrays that a const, thread-safe method keeps between calls, so that
///        a descent does not allocate (and fault in) tens of MB at every iteration.
#pragma once

#include <mutex>
#include <utility>

namespace vdbmatch {
namespace detail {

/// Holds one T between calls and lends it to one caller at a time: a Lease takes the kept value
/// if no other lease has it (else it starts from an empty T), and gives it back when destroyed.
/// Concurrent callers are therefore safe; only the first one reuses the memory.
template <typename T> class ScratchBuffer
{
public:
    ScratchBuffer() = default;
    ScratchBuffer(const ScratchBuffer&) = delete;
    ScratchBuffer& operator=(const ScratchBuffer&) = delete;

    class Lease
    {
    public:
        explicit Lease(const ScratchBuffer& owner) : mOwner(owner)
        {
            std::unique_lock<std::mutex> lock(owner.mMutex, std::try_to_lock);
            if (lock.owns_lock() && !owner.mLent) {
                std::swap(mValue, owner.mValue);
                owner.mLent = true;
                mBorrowed = true;
            }
        }
        ~Lease()
        {
            if (!mBorrowed) return;
            std::lock_guard<std::mutex> lock(mOwner.mMutex);
            std::swap(mValue, mOwner.mValue);
            mOwner.mLent = false;
        }
        Lease(const Lease&) = delete;
        Lease& operator=(const Lease&) = delete;

        T& operator*() { return mValue; }
        T* operator->() { return &mValue; }
        /// True if this lease holds the kept value (false: a fresh one, another lease has it).
        bool reused() const { return mBorrowed; }

    private:
        const ScratchBuffer& mOwner;
        T mValue{};
        bool mBorrowed = false;
    };

private:
    mutable std::mutex mMutex;
    mutable T mValue{};
    mutable bool mLent = false;
};

} // namespace detail
} // namespace vdbmatch
