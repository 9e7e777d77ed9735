#pragma once
/// @file count_operator_new.hpp
/// Counting replacements of the global allocation functions: every form of
/// operator new (plain, array, nothrow) adds one to
/// rt::operator_new_calls (rt/allocation_count.hpp) and takes its memory
/// from malloc; every operator delete frees it. Include it in exactly one
/// translation unit of a program, never in a library: it defines the
/// program's operator new. ThreadSanitizer's runtime owns operator new and
/// refuses a replacement: a TSan build must not include it.

#include <cstddef>
#include <cstdlib>
#include <new>

#include "hapticfield/rt/allocation_count.hpp"

// g++ 12 warns that the replacement delete frees what the replacement new
// malloc'd, once both are inlined: that pairing is exactly what is intended.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

void* operator new(std::size_t size) {
  hapticfield::rt::operator_new_calls.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  hapticfield::rt::operator_new_calls.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
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
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
