#pragma once
/// @file tick_budget.hpp
/// Does a field fit in a servo tick? measure_tick_budget(field) runs any
/// field (or any callable Probe -> force) over a scripted probe path, times
/// every call, counts allocations (when a counter is installed, see below)
/// and exceptions, and judges the result against the 1 kHz and 10 kHz
/// budgets. Offline code: it allocates; no other servo/ header, nor servo.hpp,
/// includes it.
///
/// The verdict: a field fits a rate when its p99 tick cost is at most
/// `share` of the period (default 0.25: the rest of the tick belongs to the
/// device, the safety chain and the scheduler), it allocated nothing and
/// threw nothing. The worst case is reported beside it, not judged: on a
/// shared machine it includes the process being preempted.
///
/// Allocations: give TickBudgetConfig::allocation_count a function that
/// returns the allocation calls made so far. One translation unit of a
/// program may define HAPTICFIELD_TICK_BUDGET_COUNT_NEW before including
/// this header: it then replaces the global operator new with the counting
/// one of rt/count_operator_new.hpp and the harness uses it by default
/// (examples/12_tick_budget.cpp).
///
///   auto report = hapticfield::offline::measure_tick_budget(field);
///   std::puts(report.summary().c_str());
///
/// A bench or a user with a path of their own (strokes over a mesh, pixel
/// positions on a picture) passes its probes instead:
/// measure_tick_budget(field, probes, config). TickBudgetConfig::clock
/// chooses wall time (the default, what the servo loop sees) or the
/// thread's CPU time (what the tick itself costs on a shared, loaded
/// machine).

#include <algorithm>
#include <atomic>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <exception>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/rt/allocation_count.hpp"

namespace hapticfield::offline {

/// Tick budgets [ns].
inline constexpr double budget_1khz_ns = 1e6;
inline constexpr double budget_10khz_ns = 1e5;

/// The scripted path: the probe strokes a circle of `radius` on the plane
/// z = 0 at `speed`, pressed `depth` below it, the depth breathing by half
/// over `breath_period` (so contact forces and textures vary), with the
/// velocity that motion has. normal_force and surface_normal stay zero: a
/// ContactField sets its own.
struct ProbePathConfig {
  glm::dvec3 centre{0.0};       ///< [m]
  double radius{0.02};          ///< [m]
  double speed{0.1};            ///< [m/s]
  double depth{0.002};          ///< mean depth below z = 0 [m]
  double breath_period{0.5};    ///< [s]
  double period{servo_period};  ///< tick period given to the field [s]
};

/// The probe of tick i on the path.
[[nodiscard]] inline Probe scripted_probe(const ProbePathConfig& c, std::uint64_t i) noexcept {
  Probe p;
  const double t = static_cast<double>(i) * c.period;
  const double w = c.radius > 0.0 ? c.speed / c.radius : 0.0;  // [rad/s]
  const double b = 2.0 * 3.14159265358979323846 / c.breath_period;
  const double z = -c.depth * (1.0 + 0.5 * std::sin(b * t));
  p.position = c.centre + glm::dvec3{c.radius * std::cos(w * t), c.radius * std::sin(w * t), z};
  p.velocity = {-c.speed * std::sin(w * t), c.speed * std::cos(w * t), -0.5 * c.depth * b * std::cos(b * t)};
  p.time = t;
  p.period = c.period;
  return p;
}

/// Returns the allocation calls made so far (any monotonic count).
using AllocationCount = std::int64_t (*)() noexcept;

namespace detail {
#ifdef HAPTICFIELD_TICK_BUDGET_COUNT_NEW
inline constexpr AllocationCount default_allocation_count = &rt::allocations_so_far;
#else
inline constexpr AllocationCount default_allocation_count = nullptr;
#endif
inline std::int64_t read_ns(clockid_t clock) noexcept {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
}  // namespace detail

/// What times a tick.
enum class TickClock : std::uint8_t {
  wall,        ///< CLOCK_MONOTONIC: includes time the thread was preempted
  thread_cpu,  ///< CLOCK_THREAD_CPUTIME_ID: the tick's own work only
};

struct TickBudgetConfig {
  std::uint64_t ticks{20000};  ///< timed ticks
  std::uint64_t warmup{1000};  ///< ticks run first, untimed (caches, lazy tables)
  ProbePathConfig path{};      ///< the scripted probe path
  double share{0.25};          ///< share of a period the field may take at p99 [-]
  AllocationCount allocation_count{detail::default_allocation_count};  ///< null: allocations not counted
  TickClock clock{TickClock::wall};                                    ///< what times a tick
};

struct TickBudgetReport {
  std::uint64_t ticks{0};
  double mean_ns{0.0};                                           ///< total time of an untimed pass / ticks
  double p50_ns{0.0}, p99_ns{0.0}, p999_ns{0.0}, worst_ns{0.0};  ///< per tick, clock overhead subtracted
  double clock_overhead_ns{0.0};  ///< median cost of reading the clock twice (subtracted)
  std::int64_t allocations{-1};   ///< during the timed ticks; -1: not counted
  std::uint64_t exceptions{0};    ///< ticks whose call threw (the tick then gives no force)
  std::uint64_t over_1khz{0};     ///< ticks above share x 1 ms
  std::uint64_t over_10khz{0};    ///< ticks above share x 0.1 ms
  double share{0.25};
  bool fits_1khz{false};
  bool fits_10khz{false};

  [[nodiscard]] double allocations_per_tick() const noexcept {
    return allocations < 0 || ticks == 0 ? -1.0 : static_cast<double>(allocations) / static_cast<double>(ticks);
  }
  /// A few plain lines: the figures and the verdict at each rate.
  [[nodiscard]] std::string summary() const {
    char buf[768];
    const auto verdict = [&](bool fits, double budget, std::uint64_t over) {
      char v[200];
      if (fits)
        std::snprintf(v, sizeof v, "fits (p99 is %.1f%% of the %.0f us tick; %llu ticks above the %.0f%% share%s)",
                      100.0 * p99_ns / budget, budget * 1e-3, static_cast<unsigned long long>(over), 100.0 * share,
                      allocations < 0 ? "; allocations not counted" : "");
      else
        std::snprintf(v, sizeof v, "does NOT fit (%s)", reason(budget).c_str());
      return std::string(v);
    };
    std::snprintf(buf, sizeof buf,
                  "tick cost over %llu ticks: mean %.0f ns, p50 %.0f ns, p99 %.0f ns, p99.9 %.0f ns, worst %.0f ns\n"
                  "allocations per tick: %s; exceptions: %llu\n1 kHz: %s\n10 kHz: %s\n",
                  static_cast<unsigned long long>(ticks), mean_ns, p50_ns, p99_ns, p999_ns, worst_ns,
                  allocations_text().c_str(), static_cast<unsigned long long>(exceptions),
                  verdict(fits_1khz, budget_1khz_ns, over_1khz).c_str(),
                  verdict(fits_10khz, budget_10khz_ns, over_10khz).c_str());
    return buf;
  }

 private:
  [[nodiscard]] std::string allocations_text() const {
    if (allocations < 0) return "not counted";
    char t[32];
    std::snprintf(t, sizeof t, "%.3g", allocations_per_tick());
    return t;
  }
  [[nodiscard]] std::string reason(double budget) const {
    std::string r;
    if (p99_ns > share * budget)
      r += "p99 " + std::to_string(static_cast<long long>(p99_ns)) + " ns is above " +
           std::to_string(static_cast<int>(100.0 * share)) + "% of the tick";
    if (allocations > 0) r += (r.empty() ? "" : "; ") + std::string("it allocates");
    if (exceptions > 0) r += (r.empty() ? "" : "; ") + std::string("it throws");
    return r;
  }
};

namespace detail {
template <class F>
glm::dvec3 call_field(F& field, const Probe& p, std::uint64_t& exceptions) noexcept {
  if constexpr (requires { field.force(p); }) {
    if constexpr (noexcept(field.force(p))) {
      return glm::dvec3(field.force(p));
    } else {
      try {
        return glm::dvec3(field.force(p));
      } catch (...) {
        ++exceptions;
        return glm::dvec3{0.0};
      }
    }
  } else {
    if constexpr (std::is_nothrow_invocable_v<F&, const Probe&>) {
      return glm::dvec3(field(p));
    } else {
      try {
        return glm::dvec3(field(p));
      } catch (...) {
        ++exceptions;
        return glm::dvec3{0.0};
      }
    }
  }
}
}  // namespace detail

namespace detail {
template <class F>
void reset_if_possible(F& field) noexcept {
  if constexpr (requires { field.reset(); }) field.reset();
}
}  // namespace detail

/// Something the harness can time: a field (force(probe), noexcept or not)
/// or a callable Probe -> force.
template <class F>
concept TimedField = requires(F& f, const Probe& p) {
  glm::dvec3(f.force(p));
}
|| requires(F& f, const Probe& p) {
  glm::dvec3(f(p));
};

namespace detail {
/// The harness itself: warmup ticks on warmup_probe(i), then an untimed
/// and a timed pass of `ticks` ticks on probe_at(i).
template <class F, class ProbeAt, class WarmupProbe>
TickBudgetReport measure(F& field, std::uint64_t ticks, ProbeAt&& probe_at, WarmupProbe&& warmup_probe,
                         const TickBudgetConfig& config) {
  const clockid_t clock = config.clock == TickClock::thread_cpu ? CLOCK_THREAD_CPUTIME_ID : CLOCK_MONOTONIC;
  TickBudgetReport r;
  r.share = config.share;
  r.ticks = ticks;
  std::uint64_t exceptions = 0;
  volatile double sink = 0.0;
  std::vector<std::int64_t> d(r.ticks);
  std::vector<std::int64_t> empty(r.ticks);
  for (std::uint64_t i = 0; i < r.ticks; ++i) {  // the clock's own cost
    const std::int64_t a = read_ns(clock);
    empty[i] = read_ns(clock) - a;
  }
  const auto warm_up = [&] {
    reset_if_possible(field);
    for (std::uint64_t i = 0; i < config.warmup; ++i)
      sink = sink + call_field(field, warmup_probe(i), exceptions).x;
  };
  // untimed pass: the mean, allocations and exceptions
  warm_up();
  exceptions = 0;
  const std::int64_t before = config.allocation_count ? config.allocation_count() : 0;
  const std::int64_t t0 = read_ns(clock);
  for (std::uint64_t i = 0; i < r.ticks; ++i)
    sink = sink + call_field(field, probe_at(i), exceptions).x;
  const std::int64_t t1 = read_ns(clock);
  if (config.allocation_count) r.allocations = config.allocation_count() - before;
  r.exceptions = exceptions;
  r.mean_ns = static_cast<double>(t1 - t0) / static_cast<double>(r.ticks);
  // timed pass: one clock read around each tick
  warm_up();
  for (std::uint64_t i = 0; i < r.ticks; ++i) {
    const std::int64_t a = read_ns(clock);
    sink = sink + call_field(field, probe_at(i), exceptions).x;
    d[i] = read_ns(clock) - a;
  }
  (void)sink;
  std::sort(empty.begin(), empty.end());
  r.clock_overhead_ns = static_cast<double>(empty[empty.size() / 2]);
  for (auto& x : d)
    x = std::max<std::int64_t>(0, x - static_cast<std::int64_t>(r.clock_overhead_ns));
  for (const auto x : d) {
    r.over_1khz += static_cast<double>(x) > config.share * budget_1khz_ns;
    r.over_10khz += static_cast<double>(x) > config.share * budget_10khz_ns;
  }
  std::sort(d.begin(), d.end());
  const auto at = [&](double q) { return static_cast<double>(d[static_cast<std::size_t>(q * double(d.size() - 1))]); };
  r.p50_ns = at(0.5);
  r.p99_ns = at(0.99);
  r.p999_ns = at(0.999);
  r.worst_ns = static_cast<double>(d.back());
  const bool clean = r.allocations <= 0 && r.exceptions == 0;
  r.fits_1khz = clean && r.p99_ns <= config.share * budget_1khz_ns;
  r.fits_10khz = clean && r.p99_ns <= config.share * budget_10khz_ns;
  return r;
}
}  // namespace detail

/// Measures the field's tick cost over the caller's probes (a bench's own
/// path): config.warmup untimed ticks along them, then one untimed pass
/// (mean, allocations, exceptions) and one timed call by call.
/// config.ticks and config.path are not used. Stateful fields are reset
/// (when they can be) before each pass.
/// @throws std::invalid_argument when probes is empty.
template <TimedField F>
[[nodiscard]] TickBudgetReport measure_tick_budget(F& field, std::span<const Probe> probes,
                                                   const TickBudgetConfig& config) {
  if (probes.empty()) throw std::invalid_argument("measure_tick_budget: no probes");
  const auto at = [&](std::uint64_t i) -> const Probe& { return probes[i % probes.size()]; };
  return detail::measure(field, probes.size(), at, at, config);
}

/// Times a tick body that needs no probe (a device read and write, a safety
/// chain, a query on a picture): n calls of tick() after config.warmup
/// untimed ones, untimed then timed one by one, with the same figures.
template <class Tick>
requires std::invocable<Tick&>
[[nodiscard]] TickBudgetReport measure_tick_cost(std::uint64_t n, Tick&& tick, const TickBudgetConfig& config) {
  const Probe none{};
  const auto at = [&](std::uint64_t) -> const Probe& { return none; };
  auto body = [&](const Probe&) noexcept(std::is_nothrow_invocable_v<Tick&>) {
    tick();
    return glm::dvec3{0.0};
  };
  return detail::measure(body, n < 1 ? 1 : n, at, at, config);
}

/// Measures the field's tick cost over the scripted path (see the file
/// comment): config.ticks probes of config.path, after config.warmup ticks
/// from the path's start.
template <TimedField F>
[[nodiscard]] TickBudgetReport measure_tick_budget(F& field, const TickBudgetConfig& config = {}) {
  const std::uint64_t ticks = config.ticks < 1 ? 1 : config.ticks;
  std::vector<Probe> probes(ticks);
  for (std::uint64_t i = 0; i < ticks; ++i)
    probes[i] = scripted_probe(config.path, config.warmup + i);
  return detail::measure(
      field, ticks, [&](std::uint64_t i) -> const Probe& { return probes[i]; },
      [&](std::uint64_t i) { return scripted_probe(config.path, i); }, config);
}

}  // namespace hapticfield::offline

#ifdef HAPTICFIELD_TICK_BUDGET_COUNT_NEW
// This translation unit defines the program's counting operator new.
#include "hapticfield/rt/count_operator_new.hpp"
#endif
