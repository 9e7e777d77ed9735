#pragma once
/// @file tick_cost.hpp
/// What the per-tick benches share: the cost of one tick body (through the
/// tick-budget harness), and a ForceArm loopback transport.

#include <cstdint>
#include <span>

#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/reports.hpp"
#include "hapticfield/servo/tick_budget.hpp"

namespace hapticfield::bench {

/// The cost of one call [ns]: the tick-budget harness's report (mean from
/// an untimed pass; p50, p99, p99.9 and worst timed call by call, the
/// clock's own cost subtracted).
using Cost = offline::TickBudgetReport;

/// n calls of tick(), untimed then timed one by one, through the harness
/// (servo/tick_budget.hpp), on wall time or on this thread's CPU time.
template <class Tick>
Cost measure(long n, Tick&& tick, offline::TickClock clock = offline::TickClock::wall) {
  offline::TickBudgetConfig config;
  config.warmup = 0;
  config.allocation_count = nullptr;
  config.clock = clock;
  return offline::measure_tick_cost(static_cast<std::uint64_t>(n), tick, config);
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
