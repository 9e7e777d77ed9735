#pragma once
/// @file openhaptics_servo.hpp
/// OpenHapticsServo: our servo tick run inside HD's own scheduler callback,
/// with no tick of delay between the state and its force. It is a ServoLoop
/// (servo/loop.hpp), not a copy of one: the loop's run() runs on a small
/// stack of its own (a ucontext coroutine), and its clock's sleep hands
/// control back to HD, so each HD tick runs exactly one loop tick inside the
/// callback, between hdBeginFrame and hdEndFrame, with the loop's safety
/// chain, statistics, trusted-pose rule, stop and restart semantics as
/// they are. The clock reads HD ticks: one period per callback, plus the
/// real time the tick's work took, plus any lateness of the callback beyond
/// one period (the loop counts that as a missed deadline, as it would its
/// own).
///
/// A scheduler that stops calling (no callback for scheduler_timeout) ends
/// the run from the caller's thread: the callback is unscheduled, the loop
/// is stopped (its zero force cannot reach the arm then: HD is not calling;
/// the Touch drops force when its host stops commanding it, a vendor claim
/// never checked here) and run() throws DeviceError saying so.
///
/// Per tick: two context switches (swapcontext: a sigprocmask system call
/// each), no allocation, no lock. Never run on a real arm:
/// docs/arms-openhaptics.md.

#include <ucontext.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>

#include <glm/vec3.hpp>

#include "hapticfield/arms/openhaptics/openhaptics_device.hpp"
#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/loop.hpp"

// AddressSanitizer follows stack switches only when told (its fiber API).
#if defined(__SANITIZE_ADDRESS__)
#define HAPTICFIELD_ASAN_FIBERS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HAPTICFIELD_ASAN_FIBERS 1
#endif
#endif
#ifdef HAPTICFIELD_ASAN_FIBERS
#include <sanitizer/common_interface_defs.h>
#endif

namespace hapticfield {

class OpenHapticsServo {
 public:
  /// The clock the loop runs on inside the callback [ns]: see the file comment.
  class TickClock {
   public:
    [[nodiscard]] std::int64_t now() const noexcept { return base_ + (real() - resumed_at_); }
    /// Hands control back to HD until the next callback.
    void sleep_until(std::int64_t t) noexcept {
      target_ = t;
      owner_->yield_to_scheduler();
    }

   private:
    friend class OpenHapticsServo;
    /// Called as a callback resumes the loop: the time it wakes to.
    [[nodiscard]] std::int64_t real() const noexcept { return time_ ? time_() : steady_.now(); }
    void resume(std::int64_t period_ns, bool late_counts) noexcept {
      const std::int64_t real = this->real();
      std::int64_t late = 0;
      if (late_counts && last_resume_ >= 0) late = (real - last_resume_) - period_ns;
      base_ = (target_ > base_ ? target_ : base_) + (late > 0 ? late : 0);
      resumed_at_ = real;
      last_resume_ = real;
    }
    OpenHapticsServo* owner_{nullptr};
    SteadyClock steady_;
    TimeSource time_;  ///< the host's time [ns]; empty: CLOCK_MONOTONIC
    std::int64_t base_{0};
    std::int64_t target_{0};
    std::int64_t resumed_at_{0};
    std::int64_t last_resume_{-1};
  };

  /// The Device the loop sees: the arm's frame calls, live only inside
  /// the callback.
  class Frame {
   public:
    Status read(DeviceState& state) noexcept { return device_->read_frame(state, owner_->live_); }
    Status write(const glm::dvec3& force) noexcept { return device_->write_frame(force, owner_->live_); }
    Status set_armed(bool on) noexcept { return device_->set_armed(on); }
    Status request_home() noexcept { return device_->request_home(); }
    Status clear_fault() noexcept { return device_->clear_fault(); }
    [[nodiscard]] const DeviceInfo& info() const noexcept { return device_->info(); }

   private:
    friend class OpenHapticsServo;
    OpenHapticsDevice* device_{nullptr};
    OpenHapticsServo* owner_{nullptr};
  };

  static constexpr std::size_t stack_size = 512 * 1024;  ///< the loop's own stack [bytes]

  /// LoopConfig as for ServoLoop, except: the rate is the device's
  /// scheduler_rate, and RealTime is off (HD owns its thread's priority).
  /// host_time [ns] measures each tick's work and the callbacks' lateness
  /// (empty: CLOCK_MONOTONIC; tests give HD's tick count).
  /// @throws std::invalid_argument for a bad configuration.
  explicit OpenHapticsServo(OpenHapticsDevice& device, LoopConfig config = {}, TimeSource host_time = {})
      : device_(&device),
        frame_(make_frame(device)),
        loop_(frame_, clock_, adapt(config, device)),
        stack_(std::make_unique<char[]>(stack_size)) {
    clock_.owner_ = this;
    clock_.time_ = std::move(host_time);
    frame_.owner_ = this;
    period_ns_ = static_cast<std::int64_t>(1e9 / device.config().scheduler_rate + 0.5);
  }

  OpenHapticsServo(const OpenHapticsServo&) = delete;
  OpenHapticsServo& operator=(const OpenHapticsServo&) = delete;

  /// Runs a field, or a callback glm::dvec3(const TickInput&), inside HD's
  /// callback until request_stop(), the tick limit or a lost device.
  /// Blocks the calling thread.
  /// @throws as ServoLoop::run; DeviceError when the scheduler stopped
  ///         calling for scheduler_timeout.
  template <class F>
  StopReason run(F& field_or_callback, RunLimits limits = {},
                 std::chrono::milliseconds scheduler_timeout = std::chrono::milliseconds(250)) {
    limits.validate();
    body_ = [this, &field_or_callback, limits] { outcome_ = loop_.run(field_or_callback, limits); };
    error_ = nullptr;
    finished_.store(false, std::memory_order_release);
    abandoned_.store(false, std::memory_order_release);
    callbacks_.store(0, std::memory_order_release);
    started_ = false;
    clock_.last_resume_ = -1;
    getcontext(&loop_context_);
    loop_context_.uc_stack.ss_sp = stack_.get();
    loop_context_.uc_stack.ss_size = stack_size;
    loop_context_.uc_link = &return_context_;
    const auto address = reinterpret_cast<std::uintptr_t>(this);
    makecontext(&loop_context_, reinterpret_cast<void (*)()>(&OpenHapticsServo::entry), 2,
                static_cast<unsigned>(address >> 32), static_cast<unsigned>(address & 0xffffffffu));

    device_->set_direct(true);
    const hd::SchedulerHandle handle = device_->schedule(&OpenHapticsServo::hd_callback, this);
    if (handle == 0) {
      device_->set_direct(false);
      throw DeviceError("OpenHaptics: hdScheduleAsynchronous refused the servo callback: " + device_->last_error());
    }
    bool stalled = false;
    std::uint64_t seen = 0;
    auto since = std::chrono::steady_clock::now();
    while (!finished_.load(std::memory_order_acquire)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      const std::uint64_t n = callbacks_.load(std::memory_order_acquire);
      const auto now = std::chrono::steady_clock::now();
      if (n != seen) {
        seen = n;
        since = now;
      } else if (now - since > scheduler_timeout) {
        stalled = true;
        break;
      }
    }
    if (stalled) {
      // HD stopped calling: take the loop over on this thread and stop it
      // (its device calls do not reach HD now).
      abandoned_.store(true, std::memory_order_release);
      while (busy_.exchange(true, std::memory_order_acquire))
        std::this_thread::sleep_for(std::chrono::microseconds(100));
      loop_.request_stop();
      live_ = false;
      while (!finished_.load(std::memory_order_acquire)) {
        if (!started_) {  // never entered: nothing to unwind
          finished_.store(true, std::memory_order_release);
          break;
        }
        resume_loop();
      }
      busy_.store(false, std::memory_order_release);
    }
    device_->unschedule(handle);
    device_->set_direct(false);
    body_ = nullptr;
    if (error_) std::rethrow_exception(error_);
    if (stalled)
      throw DeviceError("OpenHaptics: the HD scheduler stopped calling the servo callback (none for " +
                        std::to_string(scheduler_timeout.count()) +
                        " ms); the run was stopped, and no further force is commanded");
    return outcome_;
  }

  void request_stop() noexcept { loop_.request_stop(); }
  void clear_fault() noexcept { loop_.clear_fault(); }
  [[nodiscard]] LoopSnapshot statistics() const noexcept { return loop_.statistics(); }
  void reset_statistics() noexcept { loop_.reset_statistics(); }
  [[nodiscard]] const SafetyChain& safety() const noexcept { return loop_.safety(); }
  [[nodiscard]] glm::dvec3 last_command() const noexcept { return loop_.last_command(); }
  [[nodiscard]] const DeviceState& state() const noexcept { return loop_.state(); }
  [[nodiscard]] bool trusted() const noexcept { return loop_.trusted(); }
  [[nodiscard]] double period() const noexcept { return loop_.period(); }
  /// HD callbacks that ran a loop tick, this run.
  [[nodiscard]] std::uint64_t callbacks() const noexcept { return callbacks_.load(std::memory_order_acquire); }

 private:
  static Frame make_frame(OpenHapticsDevice& device) noexcept {
    Frame f;
    f.device_ = &device;
    return f;
  }
  static LoopConfig adapt(LoopConfig c, const OpenHapticsDevice& device) noexcept {
    c.rate = device.config().scheduler_rate;
    c.realtime = RealTime::off;
    c.anticipate = false;  // the HD scheduler owns the timing: no slack to look ahead in
    return c;
  }

  static void entry(unsigned high, unsigned low) noexcept {
    auto* self = reinterpret_cast<OpenHapticsServo*>((static_cast<std::uintptr_t>(high) << 32) | low);
#ifdef HAPTICFIELD_ASAN_FIBERS
    __sanitizer_finish_switch_fiber(nullptr, &self->caller_stack_, &self->caller_stack_size_);
#endif
    try {
      self->body_();
    } catch (...) {
      self->error_ = std::current_exception();
    }
    self->finished_.store(true, std::memory_order_release);
#ifdef HAPTICFIELD_ASAN_FIBERS
    __sanitizer_start_switch_fiber(nullptr, self->caller_stack_, self->caller_stack_size_);  // this stack ends
#endif
  }  // uc_link: back to whoever resumed the loop last

  /// From the loop's stack back to whoever resumed it.
  void yield_to_scheduler() noexcept {
#ifdef HAPTICFIELD_ASAN_FIBERS
    void* fake = nullptr;
    __sanitizer_start_switch_fiber(&fake, caller_stack_, caller_stack_size_);
    swapcontext(&loop_context_, &return_context_);
    __sanitizer_finish_switch_fiber(fake, &caller_stack_, &caller_stack_size_);
#else
    swapcontext(&loop_context_, &return_context_);
#endif
  }

  /// From the calling thread's stack into the loop's, until it yields.
  void resume_loop() noexcept {
#ifdef HAPTICFIELD_ASAN_FIBERS
    void* fake = nullptr;
    __sanitizer_start_switch_fiber(&fake, stack_.get(), stack_size);
    swapcontext(&return_context_, &loop_context_);
    __sanitizer_finish_switch_fiber(fake, nullptr, nullptr);
#else
    swapcontext(&return_context_, &loop_context_);
#endif
  }

  static hd::CallbackCode hd_callback(void* data) noexcept {
    auto& self = *static_cast<OpenHapticsServo*>(data);
    if (self.finished_.load(std::memory_order_acquire) || self.abandoned_.load(std::memory_order_acquire))
      return hd::callback_continue;
    if (self.busy_.exchange(true, std::memory_order_acquire)) return hd::callback_continue;
    self.live_ = true;
    self.clock_.resume(self.period_ns_, self.started_);
    self.started_ = true;
    self.resume_loop();  // one loop tick, then its sleep comes back here
    self.live_ = false;
    self.callbacks_.fetch_add(1, std::memory_order_release);
    self.busy_.store(false, std::memory_order_release);
    return hd::callback_continue;
  }

  OpenHapticsDevice* device_;
  Frame frame_;
  TickClock clock_;
  ServoLoop<Frame, TickClock> loop_;
  std::unique_ptr<char[]> stack_;
  ucontext_t loop_context_{};
  ucontext_t return_context_{};
  std::function<void()> body_;
  std::exception_ptr error_;
  StopReason outcome_{StopReason::requested};
  std::int64_t period_ns_{1'000'000};
  std::atomic<bool> finished_{false};
  std::atomic<bool> abandoned_{false};
  std::atomic<bool> busy_{false};
  std::atomic<std::uint64_t> callbacks_{0};
  bool started_{false};
  bool live_{false};
#ifdef HAPTICFIELD_ASAN_FIBERS
  const void* caller_stack_{nullptr};  ///< AddressSanitizer: the stack that resumed the loop
  std::size_t caller_stack_size_{0};
#endif
};

}  // namespace hapticfield
