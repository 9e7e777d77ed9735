#pragma once
// What the kernel says of the mapping that holds an address
// (/proc/self/smaps): the tests of the 2 MB page hint (rt/huge_pages.hpp).

#include <sys/mman.h>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace hapticfield::test {

/// The VmFlags line of the mapping that holds p (e.g. "rd wr mr mw me ac hg"),
/// or "" when /proc/self/smaps has none.
inline std::string vm_flags_of(const void* p) {
  const auto at = reinterpret_cast<std::uintptr_t>(p);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    unsigned long long lo = 0, hi = 0;
    if (std::sscanf(line.c_str(), "%llx-%llx ", &lo, &hi) == 2) {
      inside = at >= lo && at < hi;  // a mapping's first line: "start-end perms offset dev inode path"
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line.substr(8);
  }
  return "";
}

/// True when the mapping that holds p is marked for huge pages (madvise
/// MADV_HUGEPAGE: "hg" in its VmFlags).
inline bool marked_for_huge_pages(const void* p) {
  std::istringstream flags(vm_flags_of(p));
  std::string flag;
  while (flags >> flag)
    if (flag == "hg") return true;
  return false;
}

/// True when this kernel keeps the hint: a probe mapping given
/// madvise(MADV_HUGEPAGE) shows "hg" (no transparent huge pages, or a
/// sandbox that ignores madvise: false, and the page checks are skipped).
inline bool kernel_has_huge_pages() {
#if defined(MADV_HUGEPAGE)
  const std::size_t length = std::size_t{4} << 20;
  void* probe = mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (probe == MAP_FAILED) return false;
  const bool kept = madvise(probe, length, MADV_HUGEPAGE) == 0 && marked_for_huge_pages(probe);
  munmap(probe, length);
  return kept;
#else
  return false;
#endif
}

}  // namespace hapticfield::test
