#pragma once
/// @file playout.hpp
/// ContactPlayout: the audio side of the handoff. At the start of each
/// audio block it drains whatever the servo thread has pushed (never
/// waiting), keeps the last few hundred samples, and then gives, frame by
/// frame, the contact state at a play time that runs `delay` behind the
/// newest sample, linearly interpolated between the two ticks around it.
///
/// The play time advances by one audio frame per frame, nudged by at most
/// max_correction so that it follows the servo clock when the sound card's
/// clock drifts from it; a jump larger than `resync` (a loop restarted, the
/// audio thread stalled) re-seats it. When the play time passes the newest
/// sample the last state is held for `hold`, then the contact counts as
/// ended (ContactState::touching false): the sources fall silent rather
/// than wait for the servo thread.
///
/// Latency from a tick to the audio frames that render it is `delay` plus
/// where in the block the frame falls, plus whatever the sink buffers; pick
/// delay >= one audio block + two servo periods, so the play time stays
/// between received samples through a whole block (docs/vibration.md).

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "hapticfield/vibration/contact_sample.hpp"

namespace hapticfield::vibration {

struct PlayoutConfig {
  double sample_rate{48000.0};   ///< audio frames per second [Hz], 8000..192000
  double delay{0.008};           ///< play time behind the newest contact sample [s]
  double hold{0.02};             ///< keep the last state this long past the newest sample, then silence [s]
  double resync{0.1};            ///< re-seat the play time when it is off by more than this [s]
  double correction_time{0.5};   ///< time constant of the drift correction [s]
  double max_correction{0.005};  ///< largest relative change of the play rate [-]

  /// @throws std::invalid_argument naming the bad parameter.
  void validate() const {
    if (!(sample_rate >= 8000.0 && sample_rate <= 192000.0))
      throw std::invalid_argument("PlayoutConfig: sample_rate must be within [8000, 192000] [Hz]");
    if (!(delay > 0.0 && delay <= 1.0)) throw std::invalid_argument("PlayoutConfig: delay must be within (0, 1] [s]");
    if (!(hold >= 0.0 && hold <= 10.0)) throw std::invalid_argument("PlayoutConfig: hold must be within [0, 10] [s]");
    if (!(resync > delay && resync <= 100.0))
      throw std::invalid_argument("PlayoutConfig: resync must be within (delay, 100] [s]");
    if (!(correction_time > 0.0 && std::isfinite(correction_time)))
      throw std::invalid_argument("PlayoutConfig: correction_time must be > 0 [s]");
    if (!(max_correction >= 0.0 && max_correction <= 0.1))
      throw std::invalid_argument("PlayoutConfig: max_correction must be within [0, 0.1]");
  }
};

/// Counters of a playout (read on the audio thread, or after it stopped).
struct PlayoutStatistics {
  std::uint64_t frames{0};     ///< frames given
  std::uint64_t received{0};   ///< samples drained from the ring
  std::uint64_t held{0};       ///< frames past the newest sample (held or silent): the servo side was late
  std::uint64_t resyncs{0};    ///< times the play time was re-seated (a stall, a restarted loop)
  std::uint64_t discarded{0};  ///< samples older than the newest one (a restarted loop) or the history's capacity
};

/// Samples kept for interpolation (256 ms of a 1 kHz loop).
inline constexpr std::size_t playout_history = 256;

template <std::size_t N>
class ContactPlayout {
 public:
  /// @throws std::invalid_argument for a bad configuration.
  ContactPlayout(ContactRing<N>& ring, const PlayoutConfig& config) : ring_(&ring), config_(config) {
    config_.validate();
    frame_ = 1.0 / config_.sample_rate;
    step_ = frame_;
  }

  /// Starts a block: drains the ring and sets the play rate for the block.
  void begin_block() noexcept {
    while (const auto s = ring_->try_pop())
      add(*s);
    if (count_ == 0) return;
    const double target = newest().time - config_.delay;
    if (!started_ || std::fabs(target - play_) > config_.resync) {
      if (started_) ++stats_.resyncs;
      started_ = true;
      play_ = target;
      cursor_ = first_;
    }
    double c = (target - play_) / config_.correction_time;
    if (c > config_.max_correction) c = config_.max_correction;
    if (c < -config_.max_correction) c = -config_.max_correction;
    step_ = frame_ * (1.0 + c);
  }

  /// The contact state at the current play time; advances it by one frame.
  [[nodiscard]] ContactState next() noexcept {
    ++stats_.frames;
    ContactState out;
    if (!started_) return out;
    const double t = play_;
    play_ += step_;
    const std::uint64_t end = first_ + count_;
    if (cursor_ < first_) cursor_ = first_;
    while (cursor_ + 1 < end && at(cursor_ + 1).time <= t)
      ++cursor_;
    const ContactSample& a = at(cursor_);
    if (cursor_ + 1 >= end || t < a.time) {  // past the newest sample (or before the oldest)
      if (t >= a.time) {
        ++stats_.held;
        if (t - a.time > config_.hold) return out;
      }
      return state(a.speed, a.normal_force, a.material);
    }
    const ContactSample& b = at(cursor_ + 1);
    const double dt = b.time - a.time;
    const double w = dt > 0.0 ? (t - a.time) / dt : 1.0;
    return state(a.speed + w * (b.speed - a.speed), a.normal_force + w * (b.normal_force - a.normal_force), a.material);
  }

  [[nodiscard]] const PlayoutStatistics& statistics() const noexcept { return stats_; }
  [[nodiscard]] const PlayoutConfig& config() const noexcept { return config_; }
  /// The contact time being played [s] (servo clock).
  [[nodiscard]] double play_time() const noexcept { return play_; }

 private:
  static ContactState state(double speed, double force, std::uint32_t material) noexcept {
    return {speed, force, material, force > 0.0};
  }
  const ContactSample& at(std::uint64_t i) const noexcept { return history_[i % playout_history]; }
  const ContactSample& newest() const noexcept { return at(first_ + count_ - 1); }
  void add(const ContactSample& s) noexcept {
    ++stats_.received;
    if (!std::isfinite(s.time)) {
      ++stats_.discarded;
      return;
    }
    if (count_ > 0 && !(s.time > newest().time)) {
      if (s.time < newest().time - config_.resync) {  // the loop restarted: start over
        ++stats_.resyncs;
        count_ = 0;
        first_ = 0;
        cursor_ = 0;
        started_ = false;
      } else {
        ++stats_.discarded;
        return;
      }
    }
    if (count_ == playout_history) {
      ++first_;
      --count_;
      ++stats_.discarded;
    }
    history_[(first_ + count_) % playout_history] = s;
    ++count_;
  }

  ContactRing<N>* ring_;
  PlayoutConfig config_;
  std::array<ContactSample, playout_history> history_{};
  std::uint64_t first_{0};   // absolute index of the oldest kept sample
  std::uint64_t count_{0};   // samples kept
  std::uint64_t cursor_{0};  // absolute index of the sample at or before the play time
  double play_{0.0};         // [s]
  double frame_{0.0};        // [s]
  double step_{0.0};         // [s]
  bool started_{false};
  PlayoutStatistics stats_{};
};

}  // namespace hapticfield::vibration
