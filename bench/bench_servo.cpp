// bench_servo: the servo loop's timing on this machine and the per-tick cost
// of the device layer and the safety chain. Prints Markdown tables.
//
//   bench_servo [--seconds S] [--load N]   (default 10 s per loop, no load)
//   bench_servo --pacing [--seconds S] [--spin-margin US[,US...]] [--run-late]
//
// With --load N, N busy processes spin on the CPUs during a third table:
// each loop with and without SCHED_FIFO (RealTime::best_effort), with the
// periods longer than 4 ms counted as stalls and the CPU steal time the
// kernel reports for the run (/proc/stat), which is the host stalling this
// virtual machine rather than the loop overrunning.
//
// 1. ServoLoop (absolute deadlines, clock_nanosleep TIMER_ABSTIME) with the
//    simulated arm and a wall field, side by side with a relative-sleep loop
//    doing the same work (work; sleep_for(period)), as CHAI3D- and H3D-style
//    loops pace themselves. Same statistics code for both.
// With --pacing: ServoLoop paced by sleeping (today's default) against the
// hybrid mode (sleep to a spin margin before the deadline, then spin), at
// 1 and 10 kHz, idle and beside two busy processes, SCHED_FIFO where
// granted; periods longer than 4 periods are counted apart as stalls, and
// the loop thread's CPU time is the cost of the pacing.
//
// 2. Per-tick cost [ns], mean and worst, of ForceArm read+write (decode,
//    FK, velocity, J^T F, encode) over a loopback transport, of the safety
//    chain, and of a whole virtual-clock tick with the simulated arm; as a
//    fraction of the 1 kHz budget.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"
#include "tick_cost.hpp"

using namespace hapticfield;
using hapticfield::bench::Cost;
using hapticfield::bench::ForceArmLoopback;
using hapticfield::bench::measure;

namespace {

struct Wall {
  double stiffness{2000.0};
  glm::dvec3 force(const Probe& p) const noexcept {
    return p.position.z < 0.0 ? glm::dvec3{0.0, 0.0, -stiffness * p.position.z} : glm::dvec3{0.0};
  }
};

SimulatedArmConfig arm_config() {
  SimulatedArmConfig c;
  c.hand.path = HandPath::raster({0.0, 0.0, -0.005}, 0.06, 0.06, 8, 0.06);
  return c;
}

/// A simulated arm on the monotonic clock: what every timed loop here drives.
struct SteadyArm {
  SteadyClock clock;
  SimulatedArm arm{arm_config()};
  SimulatedTransport link{arm, [this] { return clock.now(); }};
  ForceArm device{link};
};

struct TimingRow {
  const char* name;
  std::uint64_t ticks;
  double seconds;
  LoopSnapshot s;
  double nominal_rate;
};

void print_timing(const TimingRow& r, const std::string& more = "") {
  const auto expected = static_cast<long long>(std::floor(r.seconds * r.nominal_rate));
  std::printf("| %-34s | %9.3f | %+8.4f %% | %7.4f | %7.4f | %7.4f | %7.3f | %6llu | %6lld |%s\n", r.name, r.s.rate,
              (r.s.rate / r.nominal_rate - 1.0) * 100.0, r.s.period_p50 * 1e3, r.s.period_p99 * 1e3,
              r.s.period_p999 * 1e3, r.s.period_max * 1e3, static_cast<unsigned long long>(r.s.missed_deadlines),
              std::max(0LL, expected - static_cast<long long>(r.ticks)), more.c_str());
}

TimingRow run_servo_loop(double seconds, double rate) {
  SteadyArm rig;
  SteadyClock& clock = rig.clock;
  LoopConfig c;
  c.rate = rate;
  ServoLoop<ForceArm, SteadyClock> loop(rig.device, clock, c);
  Wall wall;
  const std::int64_t t0 = clock.now();
  loop.run(wall, {.max_ticks = static_cast<std::uint64_t>(seconds * rate)});
  const double elapsed = static_cast<double>(clock.now() - t0) * 1e-9;
  return {"ServoLoop (absolute deadlines)", loop.statistics().ticks, elapsed, loop.statistics(), rate};
}

/// Asks SCHED_FIFO for the calling thread (as RealTime::best_effort does);
/// true when granted. restore_other() goes back to SCHED_OTHER.
bool fifo(int priority) {
  sched_param sp{};
  sp.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
}
void restore_other() {
  sched_param sp{};
  pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
}

/// Steal time of all CPUs so far [s] (the 8th field of /proc/stat's cpu line).
double steal_seconds() {
  std::FILE* f = std::fopen("/proc/stat", "r");
  if (!f) return 0.0;
  unsigned long long v[8]{};
  const int n = std::fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                            &v[6], &v[7]);
  std::fclose(f);
  return n == 8 ? static_cast<double>(v[7]) / static_cast<double>(sysconf(_SC_CLK_TCK)) : 0.0;
}

/// Periods longer than 4 ms in a loop's histogram: stalls.
std::uint64_t stalls(const DurationHistogram& periods) {
  std::uint64_t n = 0;
  for (std::size_t i = 4000; i < DurationHistogram::bins; ++i)
    n += periods.bin(i);
  return n;
}

/// N processes that spin until killed.
struct BusyLoad {
  std::vector<pid_t> pids;
  explicit BusyLoad(int n) {
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        volatile unsigned long x = 0;
        for (;;)
          x = x + 1;
      }
      if (pid > 0) pids.push_back(pid);
    }
  }
  ~BusyLoad() {
    for (const pid_t pid : pids)
      kill(pid, SIGKILL);
    for (const pid_t pid : pids)
      waitpid(pid, nullptr, 0);
  }
};

TimingRow run_relative_sleep(double seconds, double rate, const char* name = "relative sleep (work; sleep_for(T))",
                             LoopStatistics* statistics = nullptr) {
  SteadyClock clock;
  SimulatedArm arm(arm_config());
  SimulatedTransport link(arm, [&clock] { return clock.now(); });
  ForceArm device(link);
  SafetyConfig sc;
  SafetyChain safety(sc, device.info().max_force);
  LoopStatistics own;
  LoopStatistics& stats = statistics ? *statistics : own;
  Wall wall;
  device.request_home();
  device.set_armed(true);
  DeviceState state;
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(1e9 / rate)));
  const std::int64_t t0 = clock.now();
  std::int64_t previous = t0, armed_at = -1;
  const auto ticks = static_cast<std::uint64_t>(seconds * rate);
  for (std::uint64_t i = 0; i < ticks; ++i) {
    const std::int64_t wake = clock.now();
    device.read(state);
    if (state.armed() && armed_at < 0) armed_at = wake;
    Probe p;
    p.position = state.position;
    p.velocity = state.velocity;
    SafetyInput in;
    in.force = wall.force(p);
    in.velocity = state.velocity;
    in.period = 1.0 / rate;
    in.time_since_armed = armed_at >= 0 ? static_cast<double>(wake - armed_at) * 1e-9 : -1.0;
    device.write(safety.process(in));
    const std::int64_t end = clock.now();
    stats.record(wake, wake - previous, 0, end - wake);
    previous = wake;
    std::this_thread::sleep_for(period);  // relative: every tick's latency adds up
  }
  const double elapsed = static_cast<double>(clock.now() - t0) * 1e-9;
  return {name, stats.snapshot().ticks, elapsed, stats.snapshot(), rate};
}

}  // namespace

/// The loops under N busy processes, with and without SCHED_FIFO.
void loaded_table(double seconds, int load) {
  std::printf("\n## Loop timing under load: %d busy processes on %ld CPUs, %.0f s per loop at 1 kHz\n\n", load,
              sysconf(_SC_NPROCESSORS_ONLN), seconds);
  std::printf(
      "| loop | mean rate [Hz] | vs nominal | p50 [ms] | p99 [ms] | p99.9 [ms] | max [ms] | missed | short |"
      " stalls > 4 ms | steal [ms] | latches |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  const auto extra = [](std::uint64_t stall_count, double steal, const std::string& latches) {
    char text[96];
    std::snprintf(text, sizeof text, " %6llu | %7.1f | %s |", static_cast<unsigned long long>(stall_count), steal * 1e3,
                  latches.c_str());
    return std::string(text);
  };
  for (const bool rt : {false, true}) {
    {
      BusyLoad busy(load);
      const double steal0 = steal_seconds();
      SteadyArm rig;
      SteadyClock& clock = rig.clock;
      LoopConfig c;
      c.realtime = rt ? RealTime::best_effort : RealTime::off;
      ServoLoop<ForceArm, SteadyClock> loop(rig.device, clock, c);
      Wall wall;
      const std::int64_t t0 = clock.now();
      loop.run(wall, {.max_ticks = static_cast<std::uint64_t>(seconds * 1000.0)});
      const double elapsed = static_cast<double>(clock.now() - t0) * 1e-9;
      const std::uint64_t latches = loop.statistics().latches;
      const char* name = rt ? "ServoLoop, best_effort (SCHED_FIFO)" : "ServoLoop, real time off";
      print_timing(
          {name, loop.statistics().ticks, elapsed, loop.statistics(), 1000.0},
          extra(stalls(loop.detailed_statistics().periods()), steal_seconds() - steal0, std::to_string(latches)));
    }
    {
      BusyLoad busy(load);
      const double steal0 = steal_seconds();
      const bool granted = rt && fifo(80);
      auto statistics = std::make_unique<LoopStatistics>();  // 240 KB of histograms: not on the stack
      const TimingRow r =
          run_relative_sleep(seconds, 1000.0,
                             rt ? (granted ? "relative sleep, SCHED_FIFO" : "relative sleep (FIFO refused)")
                                : "relative sleep, real time off",
                             statistics.get());
      if (granted) restore_other();
      print_timing(r, extra(stalls(statistics->periods()), steal_seconds() - steal0, "n/a"));
    }
  }
  std::printf(
      "\n(stalls: periods longer than 4 ms; steal: CPU time the hypervisor took from this virtual machine\n"
      "during the run, all CPUs; latches: times the watchdog zeroed the force and disarmed)\n");
}

/// CPU time of the calling thread [s].
double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

/// The 1-minute load average (/proc/loadavg), or -1.
double load_average() {
  std::FILE* f = std::fopen("/proc/loadavg", "r");
  if (!f) return -1.0;
  double v = -1.0;
  if (std::fscanf(f, "%lf", &v) != 1) v = -1.0;
  std::fclose(f);
  return v;
}

/// Sleep against hybrid pacing with each spin margin, same loop, same run
/// (see the file comment).
void pacing_table(double seconds, const std::vector<std::int64_t>& margins_ns, bool run_late) {
  std::string margins;
  for (const std::int64_t m : margins_ns)
    margins += (margins.empty() ? "" : ", ") + std::to_string(m / 1000);
  std::printf(
      "\n## Pacing: sleep (default) against hybrid (spin margin %s us, at most a fifth of the period), %.0f s "
      "per loop, SCHED_FIFO where granted; load average %.2f at the start\n\n",
      margins.c_str(), seconds, load_average());
  std::printf(
      "| rate, load | pacing | FIFO | mean rate [Hz] | p50 [ms] | p99 [ms] | p99.9 [ms] | max [ms] | max without "
      "stalls "
      "[ms] | stalls | missed | CPU [%% of a core] | steal [ms] |\n");
  std::printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<std::int64_t> modes{-1};  // -1: sleep
  modes.insert(modes.end(), margins_ns.begin(), margins_ns.end());
  struct Case {
    double rate;
    int load;
  };
  std::vector<OverrunPolicy> policies{OverrunPolicy::skip};
  if (run_late) policies.push_back(OverrunPolicy::run_next_late);
  for (const Case k : {Case{1000.0, 0}, Case{1000.0, 2}, Case{10000.0, 0}, Case{10000.0, 2}}) {
    std::int64_t previous = -2;
    for (const std::int64_t margin_ns : modes) {
      const bool hybrid = margin_ns >= 0;
      // at most a fifth of the period: the thread must sleep in every period
      const std::int64_t margin =
          hybrid ? std::min<std::int64_t>(margin_ns, static_cast<std::int64_t>(2e8 / k.rate)) : -1;
      if (margin == previous) continue;  // the same clamped margin: one row
      previous = margin;
      for (const OverrunPolicy policy : policies) {
        BusyLoad busy(k.load);
        const double steal0 = steal_seconds();
        SteadyArm rig;
        SteadyClock& clock = rig.clock;
        LoopConfig c;
        c.rate = k.rate;
        c.realtime = RealTime::best_effort;
        if (hybrid) c.pacing = {.mode = PacingMode::hybrid, .spin_margin_ns = margin};
        c.pacing.overrun = policy;
        ServoLoop<ForceArm, SteadyClock> loop(rig.device, clock, c);
        Wall wall;
        const double cpu0 = thread_cpu_seconds();
        const std::int64_t t0 = clock.now();
        loop.run(wall, {.max_ticks = static_cast<std::uint64_t>(seconds * k.rate)});
        const double elapsed = static_cast<double>(clock.now() - t0) * 1e-9;
        const double cpu = (thread_cpu_seconds() - cpu0) / elapsed;
        const LoopSnapshot s = loop.statistics();
        const DurationHistogram& periods = loop.detailed_statistics().periods();
        const auto stall_bin = static_cast<std::size_t>(4.0e6 / k.rate);  // [us]: 4 periods
        std::uint64_t stall_count = 0;
        std::size_t max_calm = 0;
        for (std::size_t i = 0; i < DurationHistogram::bins; ++i) {
          if (periods.bin(i) == 0) continue;
          if (i >= stall_bin)
            stall_count += periods.bin(i);
          else
            max_calm = i;
        }
        char name[48];
        std::snprintf(name, sizeof name, "%.0f kHz, %s", k.rate * 1e-3, k.load ? "2 busy processes" : "idle");
        char mode[48];
        if (hybrid)
          std::snprintf(mode, sizeof mode, "hybrid, %.0f us", static_cast<double>(margin) * 1e-3);
        else
          std::snprintf(mode, sizeof mode, "sleep");
        if (policy == OverrunPolicy::run_next_late) std::strcat(mode, ", run late");
        std::printf("| %s | %s | %s | %.3f | %.4f | %.4f | %.4f | %.3f | %.3f | %llu | %llu | %.1f | %.1f |\n", name,
                    mode, loop.realtime_granted() ? "yes" : "no", s.rate, s.period_p50 * 1e3, s.period_p99 * 1e3,
                    s.period_p999 * 1e3, s.period_max * 1e3, static_cast<double>(max_calm + 1) * 1e-3,
                    static_cast<unsigned long long>(stall_count), static_cast<unsigned long long>(s.missed_deadlines),
                    cpu * 100.0, (steal_seconds() - steal0) * 1e3);
      }
    }
  }
  std::printf("\nload average %.2f at the end\n", load_average());
  std::printf(
      "\n(stalls: periods longer than 4 periods, the host stalling this virtual machine; max without stalls:\n"
      "upper edge of the longest shorter period's 1 us bin; CPU: the loop thread's CPU time over the run's\n"
      "wall time, tick work included; steal: CPU time the hypervisor took during the run, all CPUs)\n");
}

int main(int argc, char** argv) {
  double seconds = 10.0;
  int load = 0;
  bool pacing = false;
  bool run_late = false;
  std::vector<std::int64_t> margins_ns{100'000};
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--seconds") == 0 && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else if (std::strcmp(argv[i], "--load") == 0 && i + 1 < argc)
      load = std::atoi(argv[++i]);
    else if (std::strcmp(argv[i], "--pacing") == 0)
      pacing = true;
    else if (std::strcmp(argv[i], "--run-late") == 0)
      run_late = true;
    else if (std::strcmp(argv[i], "--spin-margin") == 0 && i + 1 < argc) {
      margins_ns.clear();
      for (std::string list = argv[++i]; !list.empty();) {
        const std::size_t comma = list.find(',');
        const std::string item = list.substr(0, comma);
        char* end = nullptr;
        const double us = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !(us >= 0.0 && us <= 1000.0)) {
          std::fprintf(stderr, "bench_servo: --spin-margin values must be within [0, 1000] [us]\n");
          return 2;
        }
        margins_ns.push_back(static_cast<std::int64_t>(us * 1e3));
        list = comma == std::string::npos ? "" : list.substr(comma + 1);
      }
    } else if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      std::printf(
          "usage: bench_servo [--seconds S] [--load N] [--pacing [--spin-margin US[,US...]] [--run-late]]\n"
          "  --seconds S  time per loop [s] (default 10)\n"
          "  --load N     also time the loops under N busy processes (default 0: skip)\n"
          "  --pacing     sleep against hybrid pacing only, idle and loaded, 1 and 10 kHz\n"
          "  --spin-margin US[,US...]  hybrid pacing's spin margins [us], one row each (default 100)\n"
          "  --run-late   each row again with OverrunPolicy::run_next_late (the tick after an overrun runs late)\n");
      return 0;
    } else {
      std::fprintf(stderr, "bench_servo: unknown or incomplete option '%s' (--help shows the usage)\n", argv[i]);
      return 2;
    }
  }
  if (!(seconds > 0.0 && seconds <= 600.0) || load < 0 || load > 64) {
    std::fprintf(stderr, "bench_servo: --seconds must be in (0, 600] and --load in 0..64\n");
    return 2;
  }
  if (margins_ns.empty()) {
    std::fprintf(stderr, "bench_servo: --spin-margin needs at least one value [us]\n");
    return 2;
  }
  if (pacing) {
    pacing_table(seconds, margins_ns, run_late);
    return 0;
  }
  if (load > 0) {
    loaded_table(seconds, load);
    return 0;
  }

  std::printf("## Loop timing: %.0f s per loop at 1 kHz (simulated arm, wall field)\n\n", seconds);
  std::printf(
      "| loop | mean rate [Hz] | vs nominal | p50 [ms] | p99 [ms] | p99.9 [ms] | max [ms] | missed | short |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  print_timing(run_servo_loop(seconds, 1000.0));
  print_timing(run_relative_sleep(seconds, 1000.0));
  std::printf(
      "\n(missed: periods ServoLoop skipped after an overrun; short: ticks fewer than rate x elapsed time)\n\n");

  std::printf("\n## Loop timing: %.1f s per loop at 10 kHz\n\n", seconds / 5.0);
  std::printf(
      "| loop | mean rate [Hz] | vs nominal | p50 [ms] | p99 [ms] | p99.9 [ms] | max [ms] | missed | short |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  print_timing(run_servo_loop(seconds / 5.0, 10000.0));
  print_timing(run_relative_sleep(seconds / 5.0, 10000.0));

  // ---- per-tick cost ----
  const long n = 1'000'000;
  const Cost empty = measure(n, [] {});

  ForceArmLoopback loopback;
  ForceArmConfig fo;
  fo.query_device = false;
  ForceArm device(loopback, fo);
  DeviceState state;
  glm::dvec3 f{0.1, 0.2, 0.3};
  const Cost device_cost = measure(n, [&] {
    device.read(state);
    device.write(f);
  });

  SafetyConfig sc;
  sc.passivity_enabled = true;
  SafetyChain chain(sc, 3.3);
  SafetyInput in;
  in.time_since_armed = 1.0;
  long k = 0;
  const Cost safety_cost = measure(n, [&] {
    in.force = {std::sin(k * 1e-3), 1.0, -0.5};
    in.velocity = {0.01, -0.02, 0.0};
    ++k;
    f = chain.process(in);
  });

  VirtualClock vclock;
  SimulatedArm arm(arm_config());
  SimulatedTransport link(arm, [&vclock] { return vclock.now(); });
  ForceArm sim_device(link);
  LoopConfig lc;
  lc.realtime = RealTime::off;
  ServoLoop<ForceArm, VirtualClock> loop(sim_device, vclock, lc);
  Wall wall;
  TickInput tick_in;
  const Cost full_cost = measure(n / 4, [&] {
    vclock.advance(1'000'000);
    loop.read_once(tick_in);
    loop.write_once(wall.force(tick_in.probe));
  });

  std::printf("\n## Per-tick cost (%ld ticks each)\n\n", n);
  std::printf(
      "| path | mean [ns] | p50 [ns] | p99 [ns] | p99.9 [ns] | worst [ns] | mean / 1 ms budget |\n"
      "|---|---:|---:|---:|---:|---:|---:|\n");
  const auto row = [&](const char* name, const Cost& c) {
    std::printf("| %-50s | %6.0f | %6.0f | %6.0f | %7.0f | %9.0f | %.4f %% |\n", name, c.mean_ns, c.p50_ns, c.p99_ns,
                c.p999_ns, c.worst_ns, c.mean_ns / 1e6 * 100.0);
  };
  row("ForceArm read + write (loopback transport)", device_cost);
  row("SafetyChain::process (passivity on)", safety_cost);
  row("whole tick: device + safety + wall + simulated arm", full_cost);
  row("(empty body: what is left after the clock's cost)", empty);
  std::printf(
      "\nMeasured by the tick-budget harness (servo/tick_budget.hpp): percentiles and worst have the median\n"
      "cost of a clock read pair (%.0f ns) subtracted; the worst case includes preemption by other processes\n"
      "(no real-time priority for this part).\n",
      empty.clock_overhead_ns);

  // ---- simulated time: ServoLoop::run on VirtualClock, as fast as the CPU allows ----
  constexpr int repeats = 5;
  constexpr std::uint64_t simulated_ticks = 60'000;  // 60 s at 1 kHz
  double mean_speed = 0.0, worst_speed = 1e300;
  for (int r = 0; r < repeats; ++r) {
    VirtualClock clock;
    SimulatedArm run_arm(arm_config());
    SimulatedTransport run_link(run_arm, [&clock] { return clock.now(); });
    ForceArm run_device(run_link);
    ServoLoop<ForceArm, VirtualClock> run_loop(run_device, clock, lc);
    Wall run_wall;
    const auto t0 = std::chrono::steady_clock::now();
    run_loop.run(run_wall, {.max_ticks = simulated_ticks});
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double speed = static_cast<double>(simulated_ticks) * 1e-3 / wall_s;  // simulated s per wall s
    mean_speed += speed / repeats;
    worst_speed = std::min(worst_speed, speed);
  }
  // The ceiling: one whole tick (device + safety + field + arm) at its mean cost measured above.
  const double ceiling = 1e9 / full_cost.mean_ns * 1e-3;  // simulated s per wall s
  std::printf("\n## Simulated time: ServoLoop::run on VirtualClock (60 s of the simulated arm, %d runs)\n\n", repeats);
  std::printf(
      "| loop | mean [simulated s / wall s] | worst | ceiling (1 / whole tick) | mean / ceiling |\n"
      "|---|---:|---:|---:|---:|\n");
  std::printf("| simulated arm, wall field | %.0f | %.0f | %.0f | %.2f |\n", mean_speed, worst_speed, ceiling,
              mean_speed / ceiling);
  return 0;
}
