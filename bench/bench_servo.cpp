// bench_servo: the servo loop's timing on this machine and the per-tick cost
// of the device layer and the safety chain. Prints Markdown tables.
//
//   bench_servo [--seconds S]   (default 10 s per loop)
//
// 1. ServoLoop (absolute deadlines, clock_nanosleep TIMER_ABSTIME) with the
//    simulated arm and a wall field, side by side with a relative-sleep loop
//    doing the same work (work; sleep_for(period)), as CHAI3D- and H3D-style
//    loops pace themselves. Same statistics code for both.
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
#include <string>
#include <thread>
#include <vector>

#include "hapticfield/core.hpp"
#include "hapticfield/device.hpp"
#include "hapticfield/servo.hpp"

using namespace hapticfield;

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

struct TimingRow {
  const char* name;
  std::uint64_t ticks;
  double seconds;
  LoopSnapshot s;
  double nominal_rate;
};

void print_timing(const TimingRow& r) {
  const auto expected = static_cast<long long>(std::floor(r.seconds * r.nominal_rate));
  std::printf("| %-34s | %9.3f | %+8.4f %% | %7.4f | %7.4f | %7.4f | %7.3f | %6llu | %6lld |\n", r.name, r.s.rate,
              (r.s.rate / r.nominal_rate - 1.0) * 100.0, r.s.period_p50 * 1e3, r.s.period_p99 * 1e3,
              r.s.period_p999 * 1e3, r.s.period_max * 1e3, static_cast<unsigned long long>(r.s.missed_deadlines),
              std::max(0LL, expected - static_cast<long long>(r.ticks)));
}

TimingRow run_servo_loop(double seconds, double rate) {
  SteadyClock clock;
  SimulatedArm arm(arm_config());
  SimulatedTransport link(arm, [&clock] { return clock.now(); });
  ForceArm device(link);
  LoopConfig c;
  c.rate = rate;
  ServoLoop<ForceArm, SteadyClock> loop(device, clock, c);
  Wall wall;
  const std::int64_t t0 = clock.now();
  loop.run(wall, {.max_ticks = static_cast<std::uint64_t>(seconds * rate)});
  const double elapsed = static_cast<double>(clock.now() - t0) * 1e-9;
  return {"ServoLoop (absolute deadlines)", loop.statistics().ticks, elapsed, loop.statistics(), rate};
}

TimingRow run_relative_sleep(double seconds, double rate) {
  SteadyClock clock;
  SimulatedArm arm(arm_config());
  SimulatedTransport link(arm, [&clock] { return clock.now(); });
  ForceArm device(link);
  SafetyConfig sc;
  SafetyChain safety(sc, device.info().max_force);
  LoopStatistics stats;
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
  return {"relative sleep (work; sleep_for(T))", stats.snapshot().ticks, elapsed, stats.snapshot(), rate};
}

/// Serves one pre-encoded state report per read, with a fresh sequence and
/// timestamp, and swallows writes: ForceArm's own cost without a simulation.
class Loopback final : public Transport {
 public:
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int) noexcept override {
    if (served_) return Status::no_data;
    served_ = true;
    report_.sequence = ++sequence_;
    report_.timestamp_us += 1000;
    report_.encoder[0] = static_cast<std::int32_t>(sequence_ % 200);
    size = protocol::encode(report_, buffer);
    return Status::ok;
  }
  Status write(std::span<const std::uint8_t> r) noexcept override {
    served_ = false;
    last_ = r[5];
    return Status::ok;
  }
  Status get_feature(std::span<std::uint8_t>, std::size_t&) noexcept override { return Status::unsupported; }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::ok; }
  protocol::StateReport report_{};
  std::uint16_t sequence_{0};
  bool served_{false};
  volatile std::uint8_t last_{0};
};

struct Cost {
  double mean_ns{0.0};  ///< from one untimed pass: total / n
  double p50_ns{0.0}, p99_ns{0.0}, p999_ns{0.0}, worst_ns{0.0};  ///< per tick, timed one by one
};

/// Mean from an untimed pass; the per-tick distribution from a second pass
/// that reads the clock around every tick (its own overhead is reported by
/// the empty body and subtracted from the figures).
template <class Tick>
Cost measure(long n, Tick&& tick) {
  SteadyClock clock;
  const std::int64_t t0 = clock.now();
  for (long i = 0; i < n; ++i) tick();
  Cost c;
  c.mean_ns = static_cast<double>(clock.now() - t0) / static_cast<double>(n);
  std::vector<std::int64_t> d(static_cast<std::size_t>(n));
  for (long i = 0; i < n; ++i) {
    const std::int64_t a = clock.now();
    tick();
    d[static_cast<std::size_t>(i)] = clock.now() - a;
  }
  std::sort(d.begin(), d.end());
  const auto at = [&](double q) { return static_cast<double>(d[static_cast<std::size_t>(q * static_cast<double>(n - 1))]); };
  c.p50_ns = at(0.5);
  c.p99_ns = at(0.99);
  c.p999_ns = at(0.999);
  c.worst_ns = static_cast<double>(d.back());
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10.0;
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--seconds") == 0 && i + 1 < argc) seconds = std::atof(argv[++i]);
  if (!(seconds > 0.0)) {
    std::fprintf(stderr, "usage: bench_servo [--seconds S]\n");
    return 2;
  }

  std::printf("## Loop timing: %.0f s per loop at 1 kHz (simulated arm, wall field)\n\n", seconds);
  std::printf("| loop | mean rate [Hz] | vs nominal | p50 [ms] | p99 [ms] | p99.9 [ms] | max [ms] | missed | short |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  print_timing(run_servo_loop(seconds, 1000.0));
  print_timing(run_relative_sleep(seconds, 1000.0));
  std::printf("\n(missed: periods ServoLoop skipped after an overrun; short: ticks fewer than rate x elapsed time)\n\n");

  std::printf("\n## Loop timing: %.1f s per loop at 10 kHz\n\n", seconds / 5.0);
  std::printf("| loop | mean rate [Hz] | vs nominal | p50 [ms] | p99 [ms] | p99.9 [ms] | max [ms] | missed | short |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  print_timing(run_servo_loop(seconds / 5.0, 10000.0));
  print_timing(run_relative_sleep(seconds / 5.0, 10000.0));

  // ---- per-tick cost ----
  const long n = 1'000'000;
  const Cost empty = measure(n, [] {});

  Loopback loopback;
  ForceArmOptions fo;
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
  std::printf("| path | mean [ns] | p50 [ns] | p99 [ns] | p99.9 [ns] | worst [ns] | mean / 1 ms budget |\n"
              "|---|---:|---:|---:|---:|---:|---:|\n");
  const double overhead = empty.p50_ns;  // clock reads around one tick
  const auto row = [&](const char* name, const Cost& c, double sub) {
    std::printf("| %-50s | %6.0f | %6.0f | %6.0f | %7.0f | %9.0f | %.4f %% |\n", name, c.mean_ns, c.p50_ns - sub,
                c.p99_ns - sub, c.p999_ns - sub, c.worst_ns - sub, c.mean_ns / 1e6 * 100.0);
  };
  row("ForceArm read + write (loopback transport)", device_cost, overhead);
  row("SafetyChain::process (passivity on)", safety_cost, overhead);
  row("whole tick: device + safety + wall + simulated arm", full_cost, overhead);
  row("(empty body: clock-read overhead, not subtracted)", empty, 0.0);
  std::printf("\nPercentiles and worst have the empty body's median clock-read overhead subtracted; the worst\n"
              "case includes preemption by other processes (no real-time priority for this part).\n");
  return 0;
}
