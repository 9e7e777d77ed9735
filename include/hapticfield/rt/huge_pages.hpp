#pragma once
/// @file huge_pages.hpp
/// Large arrays that a servo tick reads at random (a mesh's tree) on 2 MB
/// pages: reserve_on_huge_pages() reserves a vector's storage and asks the
/// kernel to back it with transparent huge pages (madvise MADV_HUGEPAGE)
/// before anything is written to it; move_to_huge_pages() moves a filled
/// one there.
///
/// Why: a tick that walks a tree of hundreds of MB touches a new 4 KB page
/// at nearly every node, and each TLB miss is a page walk (in a virtual
/// machine, a two-level one) whose entries are cold too where the hand has
/// not been yet. With 2 MB pages the whole tree needs a few hundred TLB
/// entries. On the bench's 1M-triangle sheet in a shared VM, a first pass
/// over the mesh was 1.7-2.7x faster on the mean and 2.4-3.7x at p99 for a
/// point on 2 MB pages, 1.3-1.6x for balls (bench_surface, ticks of the two
/// alternated); later passes, with the page tables cached, within noise.
///
/// Only a hint: where the kernel has transparent huge pages off ("never"),
/// or the system is not Linux, the storage is an ordinary reservation.
/// Arrays under 4 MB are left alone (at most one 2 MB page would be used).
/// The hint belongs to the address range, not to the vector: once the
/// vector is freed, memory the allocator hands out again from that range
/// may get huge pages too (as with the kernel's "always" setting).

#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace hapticfield {

/// Bytes in one transparent huge page on x86-64 and most arm64 kernels.
inline constexpr std::size_t huge_page_bytes = std::size_t{2} << 20;

/// Reserves room for n elements in the empty vector v and, when that is 4 MB
/// or more, asks for its whole 2 MB pages to be huge ones. Call it before the
/// first write (push_back or resize up to n): pages already written stay
/// small, and a later reallocation (growing past n) loses the hint.
template <class T, class Allocator>
void reserve_on_huge_pages(std::vector<T, Allocator>& v, std::size_t n) {
  v.reserve(n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  const std::size_t bytes = v.capacity() * sizeof(T);
  if (bytes < 2 * huge_page_bytes) return;
  const auto begin = reinterpret_cast<std::uintptr_t>(v.data());
  const std::uintptr_t first = (begin + huge_page_bytes - 1) & ~(huge_page_bytes - 1);  // whole pages only
  const std::uintptr_t last = (begin + bytes) & ~(huge_page_bytes - 1);
  if (last > first) (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);  // a hint
#endif
}

/// Moves a filled vector of 4 MB or more into storage reserved as above
/// (one copy of its elements); a smaller one is left where it is.
template <class T, class Allocator>
void move_to_huge_pages(std::vector<T, Allocator>& v) {
  if (v.size() * sizeof(T) < 2 * huge_page_bytes) return;
  std::vector<T, Allocator> moved(v.get_allocator());
  reserve_on_huge_pages(moved, v.size());
  moved.assign(v.begin(), v.end());
  v.swap(moved);
}

}  // namespace hapticfield
