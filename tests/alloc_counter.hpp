#pragma once
// Counts global operator new calls so tests can prove a servo path does not
// allocate. Include from exactly one translation unit per test program: it
// includes the library's counting replacements of the global allocation
// functions (hapticfield/rt/count_operator_new.hpp).
//
// ThreadSanitizer's runtime owns operator new and refuses a replacement, so
// under TSan nothing is replaced, `allocations_counted` is false and tests
// that count skip themselves; every other build (plain, ASan + UBSan) counts.
#include <atomic>
#include <cstdint>

#include "hapticfield/rt/allocation_count.hpp"

#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define HAPTICFIELD_TEST_UNDER_TSAN 1
#endif
#endif
#if defined(__SANITIZE_THREAD__)
#define HAPTICFIELD_TEST_UNDER_TSAN 1
#endif

#ifndef HAPTICFIELD_TEST_UNDER_TSAN
#include "hapticfield/rt/count_operator_new.hpp"
#endif

namespace hapticfield::test {
/// The library's count (rt/allocation_count.hpp), under the tests' old name.
inline std::atomic<std::int64_t>& allocation_count = rt::operator_new_calls;
#ifdef HAPTICFIELD_TEST_UNDER_TSAN
inline constexpr bool allocations_counted = false;
#else
inline constexpr bool allocations_counted = true;
#endif

/// Number of operator new calls made while fn runs (on any thread).
template <class Fn>
long count_allocations(Fn&& fn) {
  const long before = allocation_count.load();
  fn();
  return allocation_count.load() - before;
}
}  // namespace hapticfield::test
