#pragma once
/// @file allocation_count.hpp
/// How many times a program has called the global operator new, to prove
/// that a servo path never allocates: read allocations_so_far() before and
/// after. The count moves only in a program that replaces the global
/// allocation functions with the counting ones of
/// rt/count_operator_new.hpp (in exactly one translation unit); elsewhere
/// it stays 0. Standard library only.

#include <atomic>
#include <cstdint>

namespace hapticfield::rt {

/// Calls of any global operator new so far (relaxed: a count, not a fence).
inline std::atomic<std::int64_t> operator_new_calls{0};

/// The count now; monotonic.
[[nodiscard]] inline std::int64_t allocations_so_far() noexcept {
  return operator_new_calls.load(std::memory_order_relaxed);
}

}  // namespace hapticfield::rt
