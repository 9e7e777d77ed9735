#pragma once
// Counts global operator new calls so tests can prove a servo path does not
// allocate. Include from exactly one translation unit per test program (it
// replaces the global allocation functions).
//
// ThreadSanitizer's runtime owns operator new and refuses a replacement, so
// under TSan nothing is replaced, `allocations_counted` is false and tests
// that count skip themselves; every other build (plain, ASan + UBSan) counts.
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

// g++ 12 warns that the replacement delete frees what the replacement new
// malloc'd, once both are inlined: that pairing is exactly what is intended.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define HAPTICFIELD_TEST_UNDER_TSAN 1
#endif
#endif
#if defined(__SANITIZE_THREAD__)
#define HAPTICFIELD_TEST_UNDER_TSAN 1
#endif

namespace hapticfield::test {
inline std::atomic<long> allocation_count{0};
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

#ifndef HAPTICFIELD_TEST_UNDER_TSAN
void* operator new(std::size_t size) {
  hapticfield::test::allocation_count.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  hapticfield::test::allocation_count.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#endif  // HAPTICFIELD_TEST_UNDER_TSAN
