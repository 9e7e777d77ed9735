#pragma once
/// @file statistics.hpp
/// Loop statistics recorded every tick and readable from any thread while
/// the loop runs: lock-free (relaxed atomics), fixed memory, no allocation
/// on the tick path.

#include <array>
#include <atomic>
#include <cstdint>

#include "hapticfield/servo/pacer.hpp"

namespace hapticfield {

/// Histogram of durations with 1 us bins up to 20 ms (plus overflow) and an
/// exact maximum. Percentiles are exact to the bin (+-0.5 us).
class DurationHistogram {
 public:
  static constexpr std::int64_t bin_ns = 1000;  ///< bin width [ns]
  static constexpr std::size_t bins = 20000;    ///< last bin collects overflow

  void record(std::int64_t ns) noexcept {
    if (ns < 0) ns = 0;
    const auto i = static_cast<std::size_t>(ns / bin_ns);
    counts_[i < bins ? i : bins - 1].fetch_add(1, std::memory_order_relaxed);
    count_.fetch_add(1, std::memory_order_relaxed);
    sum_.fetch_add(ns, std::memory_order_relaxed);
    std::int64_t m = max_.load(std::memory_order_relaxed);
    while (ns > m && !max_.compare_exchange_weak(m, ns, std::memory_order_relaxed)) {
    }
  }

  /// The p-quantile (0..1) [ns], bin centre; 0 when empty. Reads while
  /// another thread records see a consistent-enough snapshot.
  [[nodiscard]] std::int64_t percentile(double p) const noexcept {
    const std::uint64_t n = count_.load(std::memory_order_relaxed);
    if (n == 0) return 0;
    const auto rank = static_cast<std::uint64_t>(p * static_cast<double>(n - 1)) + 1;
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < bins; ++i) {
      seen += counts_[i].load(std::memory_order_relaxed);
      if (seen >= rank) {
        const std::int64_t centre = static_cast<std::int64_t>(i) * bin_ns + bin_ns / 2;
        const std::int64_t m = max();
        return centre < m ? centre : m;
      }
    }
    return max();
  }
  [[nodiscard]] std::int64_t max() const noexcept { return max_.load(std::memory_order_relaxed); }
  /// Count in bin i ([i, i+1) us; the last bin holds everything longer).
  [[nodiscard]] std::uint64_t bin(std::size_t i) const noexcept {
    return i < bins ? counts_[i].load(std::memory_order_relaxed) : 0;
  }
  [[nodiscard]] std::uint64_t count() const noexcept { return count_.load(std::memory_order_relaxed); }
  [[nodiscard]] double mean() const noexcept {
    const std::uint64_t n = count();
    return n ? static_cast<double>(sum_.load(std::memory_order_relaxed)) / static_cast<double>(n) : 0.0;
  }
  void reset() noexcept {
    for (auto& c : counts_)
      c.store(0, std::memory_order_relaxed);
    count_.store(0, std::memory_order_relaxed);
    sum_.store(0, std::memory_order_relaxed);
    max_.store(0, std::memory_order_relaxed);
  }

 private:
  std::array<std::atomic<std::uint32_t>, bins> counts_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> sum_{0};
  std::atomic<std::int64_t> max_{0};
};

/// A copy of the loop statistics at one moment (durations in seconds).
struct LoopSnapshot {
  std::uint64_t ticks{0};             ///< ticks run
  std::uint64_t missed_deadlines{0};  ///< periods skipped after overruns
  std::uint64_t overruns{0};          ///< ticks that ended after their deadline (a late wake is one)
  std::uint64_t safety_events{0};     ///< ticks on which the safety chain intervened
  std::uint64_t latches{0};           ///< times the watchdog latched (zero force, disarmed)
  std::uint32_t last_latch{0};        ///< safety_events bits of the most recent latch (0: none yet)
  double last_latch_time{-1.0};       ///< when the most recent latch happened [s since its run started]; -1: none
  /// Latches recovered from by LoopConfig::recover_after: counted only once
  /// force really came back (a non-zero command through the soft start).
  std::uint64_t recoveries{0};
  double last_recovery_time{-1.0};  ///< when force came back after the most recent recovery [s since its run started]
  double rate{0.0};                 ///< achieved rate [Hz] = (ticks - 1) / (last - first wake)
  double period_p50{0.0}, period_p99{0.0}, period_p999{0.0}, period_max{0.0};  ///< [s]
  double period_mean{0.0};                                                     ///< [s]
  double wake_p50{0.0}, wake_p99{0.0}, wake_max{0.0};                          ///< wake latency after the deadline [s]
  double compute_p50{0.0}, compute_p99{0.0}, compute_max{0.0}, compute_mean{0.0};  ///< tick work [s]
  double peak_force{0.0};                                                          ///< largest commanded |F| [N]
  /// The field's look-ahead (LoopConfig::anticipate): runs, runs a late
  /// wake skipped, runs that ended past the deadline, the longest [s].
  std::uint64_t look_aheads{0}, look_aheads_skipped{0}, look_aheads_late{0};
  double look_ahead_max{0.0};
};

/// Everything the loop records per tick.
class LoopStatistics {
 public:
  void record(std::int64_t wake, std::int64_t period, std::int64_t wake_latency, std::int64_t compute) noexcept {
    if (ticks_.load(std::memory_order_relaxed) == 0)
      first_wake_.store(wake, std::memory_order_relaxed);
    else
      period_.record(period);
    last_wake_.store(wake, std::memory_order_relaxed);
    wake_.record(wake_latency);
    compute_.record(compute);
    ticks_.fetch_add(1, std::memory_order_relaxed);
  }
  void add_missed(std::uint64_t n) noexcept { missed_.fetch_add(n, std::memory_order_relaxed); }
  void add_overrun() noexcept { overruns_.fetch_add(1, std::memory_order_relaxed); }
  /// A latch with its safety_events bits, at time t [s since the run started].
  void add_latch(std::uint32_t bits, double t = -1.0) noexcept {
    last_latch_.store(bits, std::memory_order_relaxed);
    last_latch_time_.store(t, std::memory_order_relaxed);
    latches_.fetch_add(1, std::memory_order_relaxed);
  }
  /// Force came back after a recovery, at time t [s since the run started].
  void add_recovery(double t = -1.0) noexcept {
    last_recovery_time_.store(t, std::memory_order_relaxed);
    recoveries_.fetch_add(1, std::memory_order_relaxed);
  }
  void add_safety_event() noexcept { safety_.fetch_add(1, std::memory_order_relaxed); }
  /// What the pacer did with the look-ahead before this tick.
  void add_look_ahead(const LookAhead& a) noexcept {
    if (a.skipped) look_aheads_skipped_.fetch_add(1, std::memory_order_relaxed);
    if (!a.ran) return;
    look_aheads_.fetch_add(1, std::memory_order_relaxed);
    if (a.late) look_aheads_late_.fetch_add(1, std::memory_order_relaxed);
    std::int64_t m = look_ahead_max_.load(std::memory_order_relaxed);
    while (a.took_ns > m && !look_ahead_max_.compare_exchange_weak(m, a.took_ns, std::memory_order_relaxed)) {
    }
  }
  void record_force(double magnitude) noexcept {
    double m = peak_force_.load(std::memory_order_relaxed);
    while (magnitude > m && !peak_force_.compare_exchange_weak(m, magnitude, std::memory_order_relaxed)) {
    }
  }

  [[nodiscard]] LoopSnapshot snapshot() const noexcept {
    LoopSnapshot s;
    constexpr double ns = 1e-9;
    s.ticks = ticks_.load(std::memory_order_relaxed);
    s.missed_deadlines = missed_.load(std::memory_order_relaxed);
    s.safety_events = safety_.load(std::memory_order_relaxed);
    s.overruns = overruns_.load(std::memory_order_relaxed);
    s.latches = latches_.load(std::memory_order_relaxed);
    s.last_latch = last_latch_.load(std::memory_order_relaxed);
    s.recoveries = recoveries_.load(std::memory_order_relaxed);
    s.last_latch_time = last_latch_time_.load(std::memory_order_relaxed);
    s.last_recovery_time = last_recovery_time_.load(std::memory_order_relaxed);
    const std::int64_t span = last_wake_.load(std::memory_order_relaxed) - first_wake_.load(std::memory_order_relaxed);
    s.rate = (s.ticks > 1 && span > 0) ? static_cast<double>(s.ticks - 1) / (static_cast<double>(span) * ns) : 0.0;
    s.period_p50 = period_.percentile(0.5) * ns;
    s.period_p99 = period_.percentile(0.99) * ns;
    s.period_p999 = period_.percentile(0.999) * ns;
    s.period_max = period_.max() * ns;
    s.period_mean = period_.mean() * ns;
    s.wake_p50 = wake_.percentile(0.5) * ns;
    s.wake_p99 = wake_.percentile(0.99) * ns;
    s.wake_max = wake_.max() * ns;
    s.compute_p50 = compute_.percentile(0.5) * ns;
    s.compute_p99 = compute_.percentile(0.99) * ns;
    s.compute_max = compute_.max() * ns;
    s.compute_mean = compute_.mean() * ns;
    s.peak_force = peak_force_.load(std::memory_order_relaxed);
    s.look_aheads = look_aheads_.load(std::memory_order_relaxed);
    s.look_aheads_skipped = look_aheads_skipped_.load(std::memory_order_relaxed);
    s.look_aheads_late = look_aheads_late_.load(std::memory_order_relaxed);
    s.look_ahead_max = static_cast<double>(look_ahead_max_.load(std::memory_order_relaxed)) * ns;
    return s;
  }

  [[nodiscard]] const DurationHistogram& periods() const noexcept { return period_; }
  [[nodiscard]] const DurationHistogram& wake_latencies() const noexcept { return wake_; }
  [[nodiscard]] const DurationHistogram& compute_times() const noexcept { return compute_; }

  void reset() noexcept {
    period_.reset();
    wake_.reset();
    compute_.reset();
    ticks_.store(0, std::memory_order_relaxed);
    missed_.store(0, std::memory_order_relaxed);
    safety_.store(0, std::memory_order_relaxed);
    overruns_.store(0, std::memory_order_relaxed);
    latches_.store(0, std::memory_order_relaxed);
    last_latch_.store(0, std::memory_order_relaxed);
    recoveries_.store(0, std::memory_order_relaxed);
    last_latch_time_.store(-1.0, std::memory_order_relaxed);
    last_recovery_time_.store(-1.0, std::memory_order_relaxed);
    peak_force_.store(0.0, std::memory_order_relaxed);
    look_aheads_.store(0, std::memory_order_relaxed);
    look_aheads_skipped_.store(0, std::memory_order_relaxed);
    look_aheads_late_.store(0, std::memory_order_relaxed);
    look_ahead_max_.store(0, std::memory_order_relaxed);
  }

 private:
  DurationHistogram period_;
  DurationHistogram wake_;
  DurationHistogram compute_;
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::uint64_t> missed_{0};
  std::atomic<std::uint64_t> safety_{0};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> latches_{0};
  std::atomic<std::uint32_t> last_latch_{0};
  std::atomic<std::uint64_t> recoveries_{0};
  std::atomic<double> last_latch_time_{-1.0};
  std::atomic<double> last_recovery_time_{-1.0};
  std::atomic<std::int64_t> first_wake_{0};
  std::atomic<std::int64_t> last_wake_{0};
  std::atomic<double> peak_force_{0.0};
  std::atomic<std::uint64_t> look_aheads_{0};
  std::atomic<std::uint64_t> look_aheads_skipped_{0};
  std::atomic<std::uint64_t> look_aheads_late_{0};
  std::atomic<std::int64_t> look_ahead_max_{0};
};

}  // namespace hapticfield
