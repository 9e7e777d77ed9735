#pragma once
/// @file multi_arm_loop.hpp
/// MultiArmLoop: N arms on one deadline (bimanual and teacher/student
/// setups). Each arm keeps its own field, safety chain, watchdog, latches
/// and statistics (it is a ServoLoop driven tick by tick); the loop adds one
/// Pacer and timing statistics for the shared deadline. A fault on one arm
/// zeroes that arm; with ArmFaultPolicy::stop_all it latches every arm.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "hapticfield/core/field.hpp"
#include "hapticfield/servo/loop.hpp"
#include "hapticfield/servo/pacer.hpp"
#include "hapticfield/servo/statistics.hpp"

namespace hapticfield {

/// What a latch on one arm does to the others.
enum class ArmFaultPolicy : std::uint8_t {
  isolate,   ///< only the faulted arm is zeroed and disarmed
  stop_all,  ///< every arm is zeroed, disarmed and latched (safety_events::other_arm)
};

template <Device D, std::size_t N, ServoClock C = SteadyClock>
class MultiArmLoop {
  static_assert(N >= 1, "MultiArmLoop needs at least one arm");

 public:
  /// @param devices  the arms, in the order their fields are passed to run()
  /// @param config   rate, real time and safety settings, the same for every arm
  /// @throws std::invalid_argument for a null device or a bad setting.
  MultiArmLoop(std::array<D*, N> devices, C& clock, LoopConfig config = {},
               ArmFaultPolicy policy = ArmFaultPolicy::isolate)
      : clock_(&clock), policy_(policy), stats_(std::make_unique<LoopStatistics>()) {
    for (std::size_t i = 0; i < N; ++i) {
      if (!devices[i]) throw std::invalid_argument("MultiArmLoop: device " + std::to_string(i) + " is null");
      arms_[i] = std::make_unique<ServoLoop<D, C>>(*devices[i], clock, config);
    }
  }

  /// Runs fields[i] on arm i until request_stop(), the tick limit, or (with
  /// stop_all) a disconnect of any arm; with isolate it returns
  /// disconnected once every arm is gone.
  /// @throws std::invalid_argument for max_ticks == 0; ServoError when an
  ///         arm has a latched fault (clear_fault(i) first).
  template <HapticField... Fields>
  requires(sizeof...(Fields) == N) StopReason run(RunLimits limits, Fields&... fields) {
    limits.validate();
    const std::int64_t start = clock_->now();
    for (auto& arm : arms_)
      arm->prepare_run(start);
    arms_[0]->apply_realtime();  // the policy of the calling thread, once
    struct Restore {
      ServoLoop<D, C>* arm;
      ~Restore() { arm->restore_realtime(); }
    } restore{arms_[0].get()};
    Pacer pacer(arms_[0]->period_ns_, arms_[0]->config_.pacing);
    pacer.start(clock_->now());
    std::array<TickInput, N> in{};
    const auto field_refs = std::forward_as_tuple(fields...);
    for (std::uint64_t tick = 0;; ++tick) {
      if (stop_.exchange(false, std::memory_order_acq_rel)) return stop_all(StopReason::requested);
      if (tick >= limits.max_ticks) return stop_all(StopReason::tick_limit);
      const std::int64_t deadline = pacer.deadline();
      std::int64_t wake = 0;
      if (tick > 0 && arms_[0]->config_.anticipate && (false || ... || field_looks_ahead(fields))) {
        wake = pacer.wait(*clock_, [this, &in, &field_refs]() noexcept {
          anticipate_arms(in, field_refs, std::make_index_sequence<N>{});
        });
        stats_->add_look_ahead(pacer.look_ahead());
      } else {
        wake = pacer.wait(*clock_);
      }
      tick_arms(in, field_refs, std::make_index_sequence<N>{});
      apply_policy();
      const std::int64_t end = clock_->now();
      stats_->record(wake, pacer.period_observed(), wake - deadline, end - wake);
      const std::int64_t skipped = pacer.finish(end);
      if (pacer.overran()) {
        stats_->add_missed(static_cast<std::uint64_t>(skipped));
        stats_->add_overrun();
      }
      std::size_t gone = 0;
      for (auto& arm : arms_) {
        arm->note_deadline(pacer.overran());
        gone += arm->disconnected_ ? 1 : 0;
      }
      if (gone == N || (gone > 0 && policy_ == ArmFaultPolicy::stop_all)) return stop_all(StopReason::disconnected);
    }
  }

  /// Asks run() to return after the current tick (any thread; as ServoLoop).
  void request_stop() noexcept { stop_.store(true, std::memory_order_release); }
  /// Clears arm i's latch at its next tick (any thread; as ServoLoop).
  void clear_fault(std::size_t i) noexcept {
    if (i < N) arms_[i]->clear_fault();
  }

  /// Arm i's own loop: safety chain, latches, statistics (force, events),
  /// last command and state.
  [[nodiscard]] const ServoLoop<D, C>& arm(std::size_t i) const { return *arms_.at(i); }
  /// Timing of the shared deadline (period, wake latency, compute of all
  /// arms together, overruns).
  [[nodiscard]] LoopSnapshot statistics() const noexcept { return stats_->snapshot(); }
  [[nodiscard]] ArmFaultPolicy policy() const noexcept { return policy_; }

 private:
  template <class Refs, std::size_t... I>
  void tick_arms(std::array<TickInput, N>& in, const Refs& refs, std::index_sequence<I...>) noexcept {
    (tick_arm(*arms_[I], in[I], std::get<I>(refs)), ...);
  }

  /// Each arm's field's look-ahead on its last HIP moved one period on
  /// (LoopConfig::anticipate of the first arm, which sets the shared
  /// timing, as ServoLoop).
  template <class Refs, std::size_t... I>
  void anticipate_arms(const std::array<TickInput, N>& in, const Refs& refs, std::index_sequence<I...>) const noexcept {
    (anticipate_arm(*arms_[I], in[I], std::get<I>(refs)), ...);
  }

  template <class F>
  static void anticipate_arm(const ServoLoop<D, C>& arm, const TickInput& in, const F& field) noexcept {
    anticipate_if_able(field, predicted_probe(in.probe, arm.period_));
  }

  template <class F>
  static void tick_arm(ServoLoop<D, C>& arm, TickInput& in, F& field) noexcept {
    arm.read_once(in);
    arm.write_once(glm::dvec3(field.force(in.probe)));
  }

  /// stop_all: a latch on any arm latches every other arm.
  void apply_policy() noexcept {
    if (policy_ != ArmFaultPolicy::stop_all) return;
    bool any = false;
    for (const auto& arm : arms_)
      any = any || arm->safety_.latched() != 0;
    if (!any) return;
    for (auto& arm : arms_)
      if (!arm->safety_.latched()) {
        arm->latch_fault(safety_events::other_arm);
        arm->device_->write(glm::dvec3{0.0});  // this tick's command already went out: zero it now
        arm->command_ = glm::dvec3{0.0};
      }
  }

  StopReason stop_all(StopReason reason) noexcept {
    for (auto& arm : arms_)
      arm->safe_stop();
    return reason;
  }

  C* clock_;
  ArmFaultPolicy policy_;
  std::array<std::unique_ptr<ServoLoop<D, C>>, N> arms_{};
  std::unique_ptr<LoopStatistics> stats_;
  std::atomic<bool> stop_{false};
};

}  // namespace hapticfield
