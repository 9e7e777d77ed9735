#pragma once
/// @file video_field.hpp
/// VideoField: a video felt at 1 kHz (tangible video, "movie haptics").
///
/// A worker thread decodes frames, prepares them (gray, scene cuts,
/// denoising, the kernel's tables; see FramePreparer) and publishes the
/// window of the two frames that bracket the video time through a LiveField.
/// The servo thread maps its loop time to video time (PlaybackClock), and
/// blends the two frames' forces (FrameWindow): it never waits, locks or
/// allocates. A file decodes one frame ahead; when preparation lags, frames
/// whose successor is already due are dropped and counted, and windows are
/// published in order only, so the rendered field never goes back in time
/// (except by an explicit seek or loop, after which nothing is felt until
/// the worker publishes the new timeline's first window, which fades in
/// from zero: no frame of the old timeline). A live camera blends the previous
/// and the newest frame, one frame late.
///
/// Fades (the fade-in after a start, seek or loop, and the fade across a
/// scene cut) run on the loop's clock, not on video time: each begins at the
/// first tick that picks up its window and is over after the fade time T of loop time,
/// whether playback is paused, at a file's end or at any rate. In a file that
/// does not loop, a seek to or past the last frame's time feels the last
/// frame (when the source's frame count is right: a variable-rate file's is
/// an estimate).
///
/// Lockstep (set_lockstep(true)) is for loops on a simulated clock
/// (VirtualClock, offline evaluation): force() then waits, spinning with
/// yield, until the worker has published the window that covers the tick's
/// video time (or the stream ended, or the worker stopped), and the worker
/// drops no frame for lateness. The forces of a simulated run are then the
/// same on a slow and a fast machine. A real-time loop never sets it.
///
/// For a display (a viewer showing the frame under the probe), the worker
/// can keep copies of the newest decoded frames (VideoFieldConfig::
/// display_frames); display_frame(t) returns the newest kept frame at or
/// before video time t. It locks and copies on the worker's and the
/// caller's threads only: the servo path does not change.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/live_field.hpp"
#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/video/frame_preparer.hpp"
#include "hapticfield/video/frame_window.hpp"
#include "hapticfield/video/playback_clock.hpp"
#include "hapticfield/video/video_source.hpp"

namespace hapticfield {

/// A detected scene cut: the first frame of the new scene.
struct SceneCut {
  long frame = 0;     ///< index of the first frame of the new scene
  double time = 0.0;  ///< its timestamp [s of video time]
};

/// A decoded frame kept for display (see VideoField::display_frame).
struct DisplayFrame {
  long index = 0;     ///< frame index in the source
  double time = 0.0;  ///< its timestamp [s of video time]
  cv::Mat image;      ///< as decoded (BGR, 8-bit), never written again
};

inline constexpr int max_display_frames = 64;

/// One published window as a field: the probe's time is video time.
struct WindowField {
  FrameWindow window;
  PlaneMapping mapping;
  double gain = 1.0;        ///< force at a black/white edge [N]
  std::uint32_t epoch = 0;  ///< the playback epoch (seeks, loops) it was made for

  /// True when this is the window the worker publishes for video time t in
  /// epoch e: the next one comes out once t reaches t1 (see VideoField).
  [[nodiscard]] bool covers(double t, std::uint32_t e) const noexcept {
    return epoch == e && t >= window.t0 - 1e-9 && t < window.t1 - 1e-9;
  }

  /// Force [N] at video time probe.time [s], `since_fade` [s] after the
  /// window's fade began (see FrameWindow::at).
  [[nodiscard]] glm::dvec3 force(const Probe& probe, double since_fade) const noexcept {
    if (!is_finite(probe.position)) return glm::dvec3{0.0};
    const glm::dvec2 px = mapping.to_image(probe.position);
    return gain * mapping.vector_to_device(window.at(probe.time, since_fade, px.x, px.y));
  }
};

struct VideoFieldConfig {
  PrepareConfig prepare{};
  PlaybackConfig playback{};       ///< a file's duration is filled in from the source when left infinite
  double fade = default_cut_fade;  ///< fade time across a cut [s], [0, 10]
  double gain = 1.0;               ///< force at a black/white edge [N], finite, >= 0
  /// Called on the worker thread before each frame is prepared (tests use
  /// it to make the worker slow); may be empty.
  std::function<void(long)> before_prepare{};
  /// How many of the newest decoded frames the worker keeps for
  /// display_frame(), in [0, 64]; 0 (the default) keeps none, copies nothing.
  int display_frames = 0;
};

/// Counters, readable from any thread.
struct VideoStatistics {
  long prepared = 0;           ///< frames prepared
  long dropped = 0;            ///< frames skipped because preparation lagged
  long bad = 0;                ///< frames that failed to decode
  long published = 0;          ///< windows handed to the servo thread
  long cuts = 0;               ///< scene cuts detected
  long stale = 0;              ///< ticks whose window was past its hold (the worker late): faded out, then zero
  bool ended = false;          ///< the stream ended (the last frame is held)
  bool variable_rate = false;  ///< the file's timestamps stray from k / fps (VideoSource::variable_rate())
  double video_time = 0.0;     ///< the servo thread's latest video time [s]
};

class VideoField {
 public:
  /// Starts the worker thread on `source`.
  /// @throws std::invalid_argument for a bad gain, fade, mask or playback
  ///         setting, frames smaller than the mask, or a start past the end
  ///         of a file (its duration from the source when the config leaves
  ///         it infinite).
  VideoField(std::unique_ptr<VideoSource> source, PlaneMapping mapping, VideoFieldConfig config)
      : state_(std::make_unique<State>(std::move(source), mapping, std::move(config))) {
    state_->worker = std::thread([s = state_.get()] { s->run(); });
  }
  VideoField(VideoField&&) noexcept = default;
  /// Stops and joins this field's worker first (a joinable thread must not
  /// be destroyed), then takes the other's.
  VideoField& operator=(VideoField&& other) noexcept {
    if (this != &other) {
      if (state_) state_->stop_and_join();
      state_ = std::move(other.state_);
    }
    return *this;
  }
  ~VideoField() {
    if (state_) state_->stop_and_join();
  }

  /// Force on the HIP [N] at the loop time probe.time [s]: servo thread only.
  /// In lockstep it first waits for the worker (see set_lockstep()).
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    if (!std::isfinite(probe.time)) return glm::dvec3{0.0};  // no time, no frame: zero, the clocks untouched
    State& s = *state_;
    const double t = s.clock.at(probe.time);
    const std::uint32_t epoch = s.clock.epoch();  // only at() changes it, on this thread
    s.video_time.store(t, std::memory_order_release);
    s.tick_epoch.store(epoch, std::memory_order_release);
    const WindowField* w = s.windows.acquire();
    if (s.lockstep.load(std::memory_order_relaxed) && !s.live_source) {
      // (a window of this epoch already past t: none will come, do not wait)
      while (!(w && (w->covers(t, epoch) || (w->epoch == epoch && t < w->window.t0))) && !s.idle(epoch)) {
        std::this_thread::yield();
        w = s.windows.acquire();
      }
    }
    // a file's window from before a seek or a loop belongs to the old
    // timeline: nothing is felt until the worker publishes the new one
    if (w && !s.live_source && w->epoch != epoch) w = nullptr;
    // The fade's own clock: loop time since the first tick that felt it
    // (a loop clock that goes back adds nothing).
    const double step = probe.time - s.last_tick_time;
    s.last_tick_time = probe.time;
    if (!w) {  // nothing to feel (a start, a seek, a loop): zero at once, nothing carried over
      s.presence = 0.0;
      s.carry_left = 0.0;
      s.last_force = glm::dvec3{0.0};
      return s.last_force;
    }
    const double fade = w->window.fade, half = 0.5 * fade;  // [s]
    // A window the worker is late with, past its hold, fades out over T/2
    // of loop time from its held frame (not a step to zero), and the force
    // comes back over T/2 when a window is due again (presence).
    const double stale_from = w->window.held_until();  // [s of video time]
    const bool stale = t > stale_from;
    if (stale) s.stale_ticks.store(s.stale_ticks.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (step > 0.0) s.carry_left = std::fmax(s.carry_left - step, 0.0);
    // A new fade: a new serial (a start, a seek, a cut), or a new epoch (a
    // live camera's frames after a seek or a new run fade in again too).
    if (!s.felt_a_fade || w->window.fade_serial != s.felt_fade_serial || w->epoch != s.felt_epoch) {
      // A cut that comes while the last fade still runs (cuts closer than
      // the fade time, as at a rate above 1) enters where that fade left the
      // force: from its fade-in at weight e, the old scene fades out from e;
      // from its first half, at the silent middle, and the scene before
      // last, which this window does not hold, goes on fading out as it
      // would have (its last felt force, as one vector; a force carried so
      // from an earlier cut goes on fading too). A cut that comes after a
      // silence (a window late past its hold, faded out) enters at the
      // silent middle too: the old scene is not felt again. Anything else
      // (a start, a seek, a loop, a new run) fades in from zero, as on the
      // first run: its silent half is the ramp, nothing is carried over.
      const bool same_run = s.felt_a_fade && w->window.before_cut && w->epoch == s.felt_epoch;
      double enter = 0.0;
      if (!same_run) {
        s.carry_left = 0.0;
        if (!stale) s.presence = 1.0;
      } else if (s.presence == 0.0) {
        enter = half;
        if (!stale) s.presence = 1.0;
      } else if (s.since_fade < fade) {
        enter = s.since_fade < half ? half : fade - s.since_fade;
        if (s.since_fade < half) {
          s.carry = s.last_force;
          s.carry_span = s.carry_left = half - s.since_fade;
        }
      }
      s.felt_a_fade = true;
      s.felt_fade_serial = w->window.fade_serial;
      s.felt_epoch = w->epoch;
      s.since_fade = enter;
    } else if (step > 0.0) {
      s.since_fade += step;
    }
    if (!(half > 0.0))
      s.presence = stale ? 0.0 : 1.0;
    else if (step > 0.0)
      s.presence = std::clamp(s.presence + (stale ? -step : step) / half, 0.0, 1.0);
    Probe on = probe;
    on.time = stale ? stale_from : t;
    glm::dvec3 f = s.presence * w->force(on, s.since_fade);
    if (s.carry_left > 0.0) f += (s.carry_left / s.carry_span) * s.carry;
    s.last_force = f;
    return f;
  }

  /// Lockstep with a simulated clock, from any thread: while on, force()
  /// waits until the worker has published the window that covers the
  /// tick's video time (or the stream ended, the worker stopped or failed),
  /// and the worker never drops a frame for lateness. For loops on a
  /// VirtualClock only: a real-time loop would stall on a slow worker. A
  /// camera (a live source) is real time by nature: lockstep does nothing.
  void set_lockstep(bool on) noexcept { state_->lockstep.store(on); }
  [[nodiscard]] bool lockstep() const noexcept { return state_->lockstep.load(); }

  /// A new run from the configured start at the next tick (a new epoch: the
  /// worker seeks there); any thread. A tick whose loop time goes back (the
  /// loop's clock restarted) does the same by itself.
  void reset() noexcept { state_->clock.restart(); }

  /// Playback controls, from any thread.
  [[nodiscard]] PlaybackClock& playback() noexcept { return state_->clock; }

  [[nodiscard]] VideoStatistics statistics() const {
    const State& s = *state_;
    VideoStatistics v;
    v.prepared = s.prepared.load();
    v.dropped = s.dropped.load();
    v.bad = s.bad.load();
    v.published = s.published.load();
    v.cuts = s.cut_count.load();
    v.stale = s.stale_ticks.load();
    v.ended = s.ended.load();
    v.variable_rate = s.variable_rate.load();
    v.video_time = s.video_time.load();
    return v;
  }

  /// Every cut detected so far (not for the servo thread: it locks).
  [[nodiscard]] std::vector<SceneCut> cuts() const {
    std::lock_guard<std::mutex> lock(state_->cuts_mutex);
    return state_->cuts;
  }

  /// The newest frame kept for display whose time is at most `t` [s of video
  /// time] (VideoFieldConfig::display_frames); nullopt when none is (none
  /// kept, or none decoded yet since the start, a seek or a loop). Pass
  /// statistics().video_time to get the frame being felt. Not for the servo
  /// thread: it locks.
  [[nodiscard]] std::optional<DisplayFrame> display_frame(double t) const {
    std::lock_guard<std::mutex> lock(state_->display_mutex);
    const auto& kept = state_->display;
    for (auto it = kept.rbegin(); it != kept.rend(); ++it)
      if (it->time <= t + 1e-9) return *it;
    return std::nullopt;
  }

  /// The worker's error, if it stopped on one (empty otherwise).
  [[nodiscard]] std::string error() const {
    std::lock_guard<std::mutex> lock(state_->cuts_mutex);
    return state_->error;
  }

  [[nodiscard]] double fps() const noexcept { return state_->fps; }
  [[nodiscard]] int width() const noexcept { return state_->width; }
  [[nodiscard]] int height() const noexcept { return state_->height; }

  /// Stops the worker (the field keeps its last window).
  void stop() { state_->stop_and_join(); }

 private:
  struct State {
    State(std::unique_ptr<VideoSource> src, PlaneMapping map, VideoFieldConfig cfg)
        : source(std::move(src)),
          mapping(map),
          config(std::move(cfg)),
          preparer(config.prepare),
          builder(config.fade),
          clock(playback_config(*source, config.playback)),
          fps(source->fps()),
          live_source(source->live()),
          width(source->width()),
          height(source->height()) {
      if (!std::isfinite(config.gain) || config.gain < 0.0)
        throw std::invalid_argument("VideoField: gain must be finite and non-negative [N]");
      if (config.display_frames < 0 || config.display_frames > max_display_frames)
        throw std::invalid_argument("VideoField: display_frames must be in [0, 64]");
      preparer.check_frame_size(width, height);
      video_time.store(config.playback.start);
    }

    /// The frame to seek to for video time t [s]: its slot's, or the last
    /// frame for a time at or past it (the end of a file).
    [[nodiscard]] long frame_at(double t) const noexcept {
      const auto index = static_cast<long>(std::floor(t * fps + 1e-9));
      const long count = source->frame_count();
      return count > 0 ? std::min(index, count - 1) : index;
    }

    static PlaybackConfig playback_config(const VideoSource& source, PlaybackConfig p) {
      if (!std::isfinite(p.duration) && !source.live()) p.duration = source.duration();
      if (source.live()) p.loop = false;
      return p;
    }

    void stop_and_join() {
      stop.store(true);
      if (worker.joinable()) worker.join();
    }

    /// Nothing more comes for epoch e: the worker is done (stopped, failed)
    /// or reached the end of the stream in that epoch.
    [[nodiscard]] bool idle(std::uint32_t e) const noexcept {
      return done.load(std::memory_order_acquire) || stop.load(std::memory_order_relaxed) ||
             ended_epoch.load(std::memory_order_acquire) == static_cast<std::int64_t>(e);
    }

    void publish(const FrameWindow& w, std::uint32_t epoch) {
      (void)windows.publish(std::make_unique<WindowField>(WindowField{w, mapping, config.gain, epoch}));
      published.fetch_add(1);
    }

    void record_cut(const VideoFrame& f) {
      cut_count.fetch_add(1);
      std::lock_guard<std::mutex> lock(cuts_mutex);
      cuts.push_back({f.index, f.time});
    }

    /// Keeps a copy of a decoded frame for display (worker thread).
    void keep_for_display(const cv::Mat& image, long index, double time) {
      if (config.display_frames == 0) return;
      DisplayFrame f{index, time, image.clone()};  // the source reuses `image`
      std::lock_guard<std::mutex> lock(display_mutex);
      display.push_back(std::move(f));
      while (static_cast<int>(display.size()) > config.display_frames)
        display.pop_front();
    }

    void forget_display() {
      std::lock_guard<std::mutex> lock(display_mutex);
      display.clear();
    }

    void run() noexcept {
      try {
        if (source->live())
          run_live();
        else
          run_file();
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(cuts_mutex);
        error = e.what();
      } catch (...) {
        std::lock_guard<std::mutex> lock(cuts_mutex);
        error = "unknown error";
      }
      ended.store(true);
      done.store(true, std::memory_order_release);
    }

    void run_file() {
      std::optional<FrameWindow> pending;
      // The servo thread stores a tick's video time, then its epoch: once
      // the worker sees an epoch, video_time is at least that tick's. It
      // starts from the clock's first epoch (0), so a seek made before it
      // runs is seen as one (and sought), not taken as where it began.
      std::uint32_t epoch = 0;
      bool end = false;
      bool have_frame = false;
      cv::Mat image;
      if (config.playback.start > 0.0) source->seek(frame_at(config.playback.start));
      while (!stop.load()) {
        if (const std::uint32_t e = tick_epoch.load(std::memory_order_acquire); e != epoch) {  // a seek or a loop
          epoch = e;
          const double t = video_time.load(std::memory_order_acquire);
          source->seek(frame_at(t));
          preparer.restart();
          builder.reset();
          pending.reset();
          forget_display();
          end = have_frame = false;
          ended.store(false);
        }
        const double t = video_time.load(std::memory_order_acquire);
        if (!pending && !end) {
          long index = 0;
          if (!source->read(image, index)) {
            end = true;
            bad.store(source->bad_frames());
            pending = builder.last();
            ended.store(true);
            if (!pending) ended_epoch.store(epoch, std::memory_order_release);
            continue;
          }
          bad.store(source->bad_frames());
          variable_rate.store(source->variable_rate());
          if (have_frame && !lockstep.load() && source->time_of(index + 1) <= t) {  // its successor is already due
            dropped.fetch_add(1);
            continue;
          }
          keep_for_display(image, index, source->time_of(index));
          if (config.before_prepare) config.before_prepare(index);
          std::shared_ptr<const VideoFrame> f = preparer.prepare(image, index, source->time_of(index));
          prepared.fetch_add(1);
          have_frame = true;
          if (f->cut) record_cut(*f);
          pending = builder.push(std::move(f));
          continue;
        }
        if (pending && t >= pending->t0 - 1e-9) {
          publish(*pending, epoch);
          pending.reset();
          if (end) ended_epoch.store(epoch, std::memory_order_release);  // the last window is out
          continue;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      }
    }

    void run_live() {
      cv::Mat image;
      const double period = 1.0 / fps;
      while (!stop.load()) {
        long index = 0;
        if (!source->read(image, index)) break;
        bad.store(source->bad_frames());
        if (config.before_prepare) config.before_prepare(index);
        const double now = video_time.load(std::memory_order_acquire);
        keep_for_display(image, index, now);
        std::shared_ptr<const VideoFrame> f = preparer.prepare(image, index, now);
        prepared.fetch_add(1);
        if (f->cut) record_cut(*f);
        publish(builder.push_live(std::move(f), now, period), tick_epoch.load(std::memory_order_acquire));
      }
    }

    std::unique_ptr<VideoSource> source;
    PlaneMapping mapping;
    VideoFieldConfig config;
    FramePreparer preparer;
    WindowBuilder builder;
    PlaybackClock clock;
    double fps;
    bool live_source;
    int width;
    int height;
    /// The windows, worker to servo thread; old ones come back to the worker.
    TripleBuffer<WindowField> windows;
    std::atomic<double> video_time{0.0};
    std::atomic<std::uint32_t> tick_epoch{0};   ///< the playback epoch of the latest tick
    std::atomic<std::int64_t> ended_epoch{-1};  ///< the epoch whose stream ended with nothing left to publish
    std::atomic<bool> lockstep{false};
    std::atomic<bool> variable_rate{false};
    std::atomic<bool> done{false};  ///< the worker returned (stopped or failed)
    std::atomic<bool> stop{false};
    std::atomic<bool> ended{false};
    std::atomic<long> prepared{0}, dropped{0}, bad{0}, published{0}, cut_count{0};
    std::atomic<long> stale_ticks{0};  ///< written by the servo thread only
    // servo-thread state: the fade being felt
    bool felt_a_fade = false;
    std::uint32_t felt_fade_serial = 0;  ///< FrameWindow::fade_serial of the fade felt last
    std::uint32_t felt_epoch = 0;        ///< the epoch of the window that began it
    double since_fade = 0.0;             ///< loop time since the first tick that felt it [s]
    double last_tick_time = std::numeric_limits<double>::quiet_NaN();  ///< the last finite loop time [s]
    /// How much of the window's force is felt, 0..1: it ramps over T/2 of
    /// loop time, down while the window is stale (past its hold), up again
    /// when one is due.
    double presence = 0.0;
    glm::dvec3 last_force{0.0};  ///< the force of the last tick [N]
    glm::dvec3 carry{0.0};       ///< the scene before last, as felt when a cut came in its fade-out [N]
    double carry_left = 0.0;     ///< loop time until the carried force is gone [s]
    double carry_span = 1.0;     ///< loop time it fades over [s]
    mutable std::mutex cuts_mutex;
    std::vector<SceneCut> cuts;
    std::string error;
    mutable std::mutex display_mutex;
    std::deque<DisplayFrame> display;  ///< oldest first
    std::thread worker;
  };

  std::unique_ptr<State> state_;
};

static_assert(HapticField<VideoField>);
static_assert(ResettableField<VideoField>);

}  // namespace hapticfield
