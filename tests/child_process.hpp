#pragma once
// A command-line tool run as a child process for the tests: stdin a pipe
// (optionally carrying one Enter for the operator's prompt), stdout and
// stderr to files, every wait bounded.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace hapticfield::testing {

namespace fs = std::filesystem;

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Starts `tool args...` with the given file actions (destroyed here) and
/// returns its pid; a failed spawn fails the test.
inline pid_t spawn_tool(const std::string& tool, const std::vector<std::string>& args,
                        posix_spawn_file_actions_t& actions) {
  std::vector<std::string> text{tool};
  text.insert(text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : text)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  REQUIRE(spawned == 0);
  return pid;
}

/// A tool running as a child: stdin a pipe that carries one Enter (the
/// operator's go-ahead), stdout and stderr to files.
class Child {
 public:
  /// press_enter false: the prompt waits (the pipe stays open, empty).
  /// stdout and stderr go to folder/name.out and .err.
  Child(const std::string& tool, const std::vector<std::string>& args, const fs::path& folder, const std::string& name,
        bool press_enter = true) {
    fs::create_directories(folder);
    out_ = folder / (name + ".out");
    err_ = folder / (name + ".err");
    int in[2];
    REQUIRE(::pipe(in) == 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
    posix_spawn_file_actions_addclose(&actions, in[1]);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_ = spawn_tool(tool, args, actions);
    ::close(in[0]);
    if (press_enter) enter(in[1]);  // Enter at the prompt; the pipe stays open
    stdin_ = in[1];
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  ~Child() {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (stdin_ >= 0) ::close(stdin_);
  }

  void signal(int s) const { REQUIRE(::kill(pid_, s) == 0); }

  /// Writes one Enter to the child's stdin; a child that has already
  /// exited (a tool that answers --help at once) has closed its end: the
  /// write then fails with EPIPE, and the SIGPIPE it raises, held back
  /// for this thread, is taken off here instead of ending the test.
  static void enter(int fd) {
    sigset_t pipe_signal, before;
    sigemptyset(&pipe_signal);
    sigaddset(&pipe_signal, SIGPIPE);
    ::pthread_sigmask(SIG_BLOCK, &pipe_signal, &before);
    if (::write(fd, "\n", 1) < 0 && errno == EPIPE) {
      const timespec now{0, 0};
      (void)::sigtimedwait(&pipe_signal, nullptr, &now);
    }
    ::pthread_sigmask(SIG_SETMASK, &before, nullptr);
  }

  /// Waits for the child to end (bounded); false if it had to be killed.
  bool wait(std::chrono::seconds patience = std::chrono::seconds(60)) {
    const auto give_up = std::chrono::steady_clock::now() + patience;
    while (::waitpid(pid_, &raw_, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > give_up) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &raw_, 0);
        exited_ = true;
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    exited_ = true;
    return true;
  }
  /// Waits (bounded) until the child's stdout holds `text`; false when it
  /// ended or the time ran out without it.
  bool wait_for_output(const std::string& text, std::chrono::seconds patience = std::chrono::seconds(60)) {
    const auto give_up = std::chrono::steady_clock::now() + patience;
    while (alive() && std::chrono::steady_clock::now() < give_up) {
      if (out().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return out().find(text) != std::string::npos;
  }
  /// True while the child has not ended (it may be waiting at the prompt).
  [[nodiscard]] bool alive() {
    if (exited_) return false;
    if (::waitpid(pid_, &raw_, WNOHANG) == 0) return true;
    exited_ = true;
    return false;
  }
  [[nodiscard]] bool exited_normally() const { return exited_ && WIFEXITED(raw_); }
  [[nodiscard]] int status() const { return WIFEXITED(raw_) ? WEXITSTATUS(raw_) : -1; }
  [[nodiscard]] int killed_by() const { return WIFSIGNALED(raw_) ? WTERMSIG(raw_) : 0; }
  [[nodiscard]] std::string out() const { return slurp(out_); }
  [[nodiscard]] std::string err() const { return slurp(err_); }

 private:
  pid_t pid_{-1};
  int stdin_{-1};
  int raw_{0};
  bool exited_{false};
  fs::path out_, err_;
};

}  // namespace hapticfield::testing
