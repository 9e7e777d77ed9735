#pragma once
/// @file plots.hpp
/// Plots with axes, ticks, units and legends: the examples hand their data
/// to scripts/hapticfield_plots.py (matplotlib) when a Python 3 with
/// matplotlib is present, and draw their own simpler plots otherwise.
///
/// The interpreter: $HAPTICFIELD_PYTHON, else python3 on the PATH, else
/// /usr/bin/python3, the first that imports matplotlib. The script:
/// $HAPTICFIELD_PLOT_SCRIPT, else the installed copy
/// (<prefix>/share/hapticfield/hapticfield_plots.py, found from the
/// executable's place), else, for a run from the build tree, the source
/// tree's (common/share.hpp).

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <spawn.h>
#include <sys/wait.h>

#include "share.hpp"

extern char** environ;

namespace hapticfield::plots {

/// The script's exit status when the interpreter has no matplotlib.
inline constexpr int matplotlib_missing = 3;

namespace detail {

/// Runs argv (searched on the PATH) and returns its exit status; -1 when it
/// could not start or was killed.
inline int run(const std::vector<std::string>& args) {
  std::fflush(nullptr);  // our own output first
  std::vector<char*> argv;
  for (const std::string& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  pid_t done = 0;
  do
    done = waitpid(pid, &status, 0);
  while (done < 0 && errno == EINTR);
  if (done != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline std::string script_path() {
  if (const char* s = std::getenv("HAPTICFIELD_PLOT_SCRIPT"); s && *s) return s;
  return share::plot_script();
}

}  // namespace detail

/// Runs the plot script with args (e.g. {"servo", "--trace", ...}). Returns
/// true when it drew the plots; false, with the reason in why, when no
/// Python with matplotlib or no script was found, or the script failed.
inline bool matplotlib(const std::vector<std::string>& args, std::string& why) {
  const std::string script = detail::script_path();
  std::error_code ec;
  if (script.empty() || !std::filesystem::is_regular_file(script, ec)) {
    why = script.empty() ? "the plot script (share/hapticfield/hapticfield_plots.py) was not found"
                         : "the plot script " + script + " was not found";
    return false;
  }
  std::vector<std::string> pythons;
  if (const char* p = std::getenv("HAPTICFIELD_PYTHON"); p && *p) pythons.emplace_back(p);
  pythons.emplace_back("python3");
  pythons.emplace_back("/usr/bin/python3");
  for (const std::string& python : pythons) {
    std::vector<std::string> command{python, script, "--quiet-missing"};
    command.insert(command.end(), args.begin(), args.end());
    const int status = detail::run(command);
    if (status == 0) return true;
    // 3: this interpreter lacks matplotlib; -1 / 127: no such interpreter.
    if (status == matplotlib_missing || status == -1 || status == 127) continue;
    why = "the plot script failed (exit status " + std::to_string(status) + ")";
    return false;
  }
  why = "no python3 with matplotlib (Debian: python3-matplotlib)";
  return false;
}

}  // namespace hapticfield::plots
