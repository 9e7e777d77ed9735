#pragma once
/// @file tick_cost.hpp
/// What the per-tick benches share: the cost of one tick body measured two
/// ways, and a ForceArm loopback transport.

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/reports.hpp"
#include "hapticfield/servo/clock.hpp"

namespace hapticfield::bench {

/// The cost of one call [ns].
struct Cost {
  double mean_ns{0.0};                                           ///< from one untimed pass: total / n
  double p50_ns{0.0}, p99_ns{0.0}, p999_ns{0.0}, worst_ns{0.0};  ///< per call, timed one by one
};

/// Mean from an untimed pass of n calls; the per-call distribution from a
/// second pass that reads the clock around every call (that pass includes
/// the clock's own cost: time an empty body to know it).
template <class Tick>
Cost measure(long n, Tick&& tick) {
  SteadyClock clock;
  const std::int64_t t0 = clock.now();
  for (long i = 0; i < n; ++i)
    tick();
  Cost c;
  c.mean_ns = static_cast<double>(clock.now() - t0) / static_cast<double>(n);
  std::vector<std::int64_t> d(static_cast<std::size_t>(n));
  for (long i = 0; i < n; ++i) {
    const std::int64_t a = clock.now();
    tick();
    d[static_cast<std::size_t>(i)] = clock.now() - a;
  }
  std::sort(d.begin(), d.end());
  const auto at = [&](double q) {
    return static_cast<double>(d[static_cast<std::size_t>(q * static_cast<double>(n - 1))]);
  };
  c.p50_ns = at(0.5);
  c.p99_ns = at(0.99);
  c.p999_ns = at(0.999);
  c.worst_ns = static_cast<double>(d.back());
  return c;
}

/// Serves one pre-encoded state report per read, with a fresh sequence and
/// timestamp, and swallows writes: ForceArm's own cost without a simulation.
class ForceArmLoopback final : public Transport {
 public:
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int) noexcept override {
    if (served_) return Status::no_data;
    served_ = true;
    report_.sequence = ++sequence_;
    report_.timestamp_us += 1000;  // [us], one tick at 1 kHz
    report_.encoder[0] = static_cast<std::int32_t>(sequence_ % 200);
    size = protocol::encode(report_, buffer);
    return Status::ok;
  }
  Status write(std::span<const std::uint8_t> report) noexcept override {
    served_ = false;
    last_ = report[5];  // keeps the write from being optimised away
    return Status::ok;
  }
  Status get_feature(std::span<std::uint8_t>, std::size_t&) noexcept override { return Status::unsupported; }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::ok; }

 private:
  protocol::StateReport report_{};
  std::uint16_t sequence_{0};
  bool served_{false};
  volatile std::uint8_t last_{0};
};

}  // namespace hapticfield::bench
