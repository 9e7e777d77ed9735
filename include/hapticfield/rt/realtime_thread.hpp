#pragma once
/// @file realtime_thread.hpp
/// Real-time setup of the calling thread (Linux): SCHED_FIFO at a priority,
/// all memory locked (mlockall), 1 ns timer slack. request_realtime() asks
/// for all three and returns what was refused instead of printing it; the
/// caller decides whether to go on best-effort, to refuse, or to tell the
/// user (realtime_advice says how to grant the limits). Never in a tick.
/// Standard library and POSIX only (the ground floor).

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace hapticfield::rt {

/// What a real-time request got.
struct RealTimeGrant {
  std::string refused;        ///< what was refused, comma-separated ("" when all was granted)
  bool memory_locked{false};  ///< mlockall succeeded (release_realtime() undoes it)
  [[nodiscard]] bool granted() const noexcept { return refused.empty(); }
};

/// How a user grants what request_realtime() asks for.
inline constexpr const char* realtime_advice =
    "grant the user real-time limits (e.g. '@realtime - rtprio 95' and '- memlock unlimited' in "
    "/etc/security/limits.d/) or CAP_SYS_NICE and CAP_IPC_LOCK";

/// Asks for SCHED_FIFO at priority (1..99), mlockall and 1 ns timer slack
/// for the calling thread. Allocates (the refusal text); never throws but
/// std::bad_alloc.
[[nodiscard]] inline RealTimeGrant request_realtime(int priority) {
  RealTimeGrant grant;
  const auto refuse = [&](const std::string& what) { grant.refused += (grant.refused.empty() ? "" : ", ") + what; };
  sched_param sp{};
  sp.sched_priority = priority;
  if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp); e != 0)
    refuse("SCHED_FIFO priority " + std::to_string(priority) + " (" + std::strerror(e) + ")");
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
    refuse(std::string("mlockall (") + std::strerror(errno) + ")");
  else
    grant.memory_locked = true;
  if (prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) != 0)
    refuse(std::string("timer slack (") + std::strerror(errno) + ")");
  return grant;
}

/// Back to ordinary scheduling for the calling thread; unlocks memory when
/// memory_locked (what request_realtime() returned).
inline void release_realtime(bool memory_locked) noexcept {
  sched_param sp{};
  sp.sched_priority = 0;
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
  if (memory_locked) munlockall();
}

}  // namespace hapticfield::rt
