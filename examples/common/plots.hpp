#pragma once
/// @file plots.hpp
/// Plots with axes, ticks, units and legends: the examples hand their data
/// to scripts/hapticfield_plots.py (matplotlib) when a Python 3 with
/// matplotlib is present, and draw their own simpler plots otherwise.
///
/// The interpreter: $HAPTICFIELD_PYTHON, else python3 on the PATH, else
/// /usr/bin/python3, the first that imports matplotlib. The script:
/// $HAPTICFIELD_PLOT_SCRIPT, else the copy in the source tree.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

extern char** environ;

namespace hapticfield::plots {

namespace detail {

/// Runs argv (searched on the PATH) and returns its exit status; -1 when it
/// could not start. quiet: stdout and stderr go to /dev/null.
inline int run(const std::vector<std::string>& args, bool quiet) {
  std::fflush(nullptr);  // our own output first
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (quiet) {
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  }
  pid_t pid = 0;
  const int started = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (started != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline std::string script_path() {
  if (const char* s = std::getenv("HAPTICFIELD_PLOT_SCRIPT"); s && *s) return s;
#ifdef HAPTICFIELD_PLOT_SCRIPT
  return HAPTICFIELD_PLOT_SCRIPT;
#else
  return {};
#endif
}

}  // namespace detail

/// Runs the plot script with args (e.g. {"servo", "--trace", ...}). Returns
/// true when it drew the plots; false, with the reason in why, when no
/// Python with matplotlib or no script was found, or the script failed.
inline bool matplotlib(const std::vector<std::string>& args, std::string& why) {
  const std::string script = detail::script_path();
  std::error_code ec;
  if (script.empty() || !std::filesystem::is_regular_file(script, ec)) {
    why = "the plot script (scripts/hapticfield_plots.py) was not found";
    return false;
  }
  std::vector<std::string> pythons;
  if (const char* p = std::getenv("HAPTICFIELD_PYTHON"); p && *p) pythons.emplace_back(p);
  pythons.emplace_back("python3");
  pythons.emplace_back("/usr/bin/python3");
  for (const std::string& python : pythons) {
    if (detail::run({python, script, "--check"}, true) != 0) continue;
    std::vector<std::string> command{python, script};
    command.insert(command.end(), args.begin(), args.end());
    if (detail::run(command, false) == 0) return true;
    why = "the plot script failed";
    return false;
  }
  why = "no python3 with matplotlib (Debian: python3-matplotlib)";
  return false;
}

}  // namespace hapticfield::plots
