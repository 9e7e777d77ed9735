#pragma once
/// @file share.hpp
/// Where the tools find their files (the example picture, the plot script):
/// installed, in <prefix>/share/hapticfield, found from the executable's own
/// place (<prefix>/bin/../share/hapticfield), so an installed tree works
/// wherever it is installed or moved to and never reads the source tree.
/// Run from the build tree (the executable is where the build put it) they
/// are read from the source tree instead.
///
/// Compile definitions (examples/CMakeLists.txt):
///   HAPTICFIELD_SHARE_FROM_BIN  the share directory relative to the executable's directory
///                               (or absolute when the install layout is)
///   HAPTICFIELD_BUILD_BIN_DIR   the executable's directory in the build tree
///   HAPTICFIELD_SOURCE_ROOT     the source tree, read only from the build tree

#include <filesystem>
#include <string>
#include <system_error>

namespace hapticfield::share {

/// The running program's directory (/proc/self/exe), empty when unknown.
inline std::filesystem::path executable_dir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path{} : exe.parent_path();
}

/// True when the program runs from the directory the build wrote it to.
inline bool in_build_tree() {
#ifdef HAPTICFIELD_BUILD_BIN_DIR
  std::error_code ec;
  const std::filesystem::path here = executable_dir();
  return !here.empty() && std::filesystem::equivalent(here, HAPTICFIELD_BUILD_BIN_DIR, ec);
#else
  return false;
#endif
}

/// The installed file share/hapticfield/<installed> next to the executable's
/// bin/; from the build tree, <source tree>/<in_source>. Empty when neither
/// exists.
inline std::string find(const std::string& installed, const std::string& in_source) {
  std::error_code ec;
#ifdef HAPTICFIELD_SHARE_FROM_BIN
  if (const std::filesystem::path bin = executable_dir(); !bin.empty()) {
    const std::filesystem::path p = (bin / HAPTICFIELD_SHARE_FROM_BIN / installed).lexically_normal();
    if (std::filesystem::is_regular_file(p, ec)) return p.string();
  }
#endif
#ifdef HAPTICFIELD_SOURCE_ROOT
  if (in_build_tree()) {
    const std::filesystem::path p = std::filesystem::path(HAPTICFIELD_SOURCE_ROOT) / in_source;
    if (std::filesystem::is_regular_file(p, ec)) return p.string();
  }
#endif
  (void)in_source;
  return {};
}

/// The example picture (examples/data/coffee.png; share/hapticfield/data/coffee.png).
inline std::string example_picture() {
  return find("data/coffee.png", "examples/data/coffee.png");
}

/// The plot script (scripts/hapticfield_plots.py; share/hapticfield/hapticfield_plots.py).
inline std::string plot_script() {
  return find("hapticfield_plots.py", "scripts/hapticfield_plots.py");
}

}  // namespace hapticfield::share
