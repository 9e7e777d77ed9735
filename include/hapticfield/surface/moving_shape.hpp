#pragma once
/// @file moving_shape.hpp
/// Shapes that move while the loop runs: MovingPose (a pose with its linear
/// and angular velocity at a time), PoseFeed (another thread publishes them,
/// the tick takes the newest without a lock) and Moving<S> (any Shape placed
/// by the newest pose, as Posed<S> by a fixed one).
///
/// Each tick the proxy (surface/proxy.hpp) calls advance(time): Moving<S>
/// swaps in the newest published MovingPose and extrapolates it to the
/// tick's time with its velocities (at most moving_max_extrapolation past
/// the snapshot, so a feed that stops stops the shape). The proxy then
/// carries its stored point with the shape's motion since the last tick
/// (carry(): the point keeps its place in the shape's frame) before its
/// usual constrained move toward the HIP. The move runs, in effect, in the
/// shape's frame, where the shape stands still: a proxy outside the shape
/// stays outside however fast the shape moves, a shape moving into a still
/// HIP pushes the proxy (and the hand) out, and a shape moving away leaves
/// it free. The damping acts on the HIP's velocity relative to the touched
/// surface point's, v - (v_lin + w x (p - origin)) (surface_velocity()).
///
/// Threads: one writer calls PoseFeed::publish (it allocates and may throw);
/// one reader, the servo thread, owns the Moving<S> (advance and the
/// queries: const or noexcept, no allocation, no lock).

#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/live_field.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/surface/posed_shape.hpp"
#include "hapticfield/surface/shape.hpp"

namespace hapticfield {

/// Longest a snapshot is extrapolated past its time stamp [s]: a shape whose
/// feed stops moves on for this long, then stands.
inline constexpr double moving_max_extrapolation = 0.1;

/// Where a shape is and how it moves, at one time.
struct MovingPose {
  Pose pose;                         ///< the shape's frame in the world at `time`
  glm::dvec3 linear_velocity{0.0};   ///< of the shape's origin (pose.translation), world frame [m/s]
  glm::dvec3 angular_velocity{0.0};  ///< world frame, right-handed [rad/s]
  double time{0.0};                  ///< on the loop's clock (Probe::time) [s]

  /// @throws std::invalid_argument for an invalid pose (Pose::validate) or
  ///         a non-finite velocity or time.
  void validate() const {
    pose.validate();
    if (!is_finite(linear_velocity) || !is_finite(angular_velocity))
      throw std::invalid_argument("MovingPose: the velocities must be finite [m/s, rad/s]");
    if (!std::isfinite(time)) throw std::invalid_argument("MovingPose: the time must be finite [s]");
  }

  /// The pose at time t: moved by the linear velocity and turned about the
  /// origin by the angular velocity (Rodrigues' formula for exp([w dt]x)),
  /// with dt = t - time clamped to [0, moving_max_extrapolation].
  [[nodiscard]] Pose at(double t) const noexcept {
    double dt = t - time;
    if (!(dt > 0.0)) return pose;  // earlier than the snapshot, or a non-finite t
    dt = std::fmin(dt, moving_max_extrapolation);
    Pose p = pose;
    p.translation += dt * linear_velocity;
    const double angle = glm::length(angular_velocity) * dt;  // [rad]
    if (angle > 0.0) {
      const glm::dvec3 k = angular_velocity / glm::length(angular_velocity);
      const double s = std::sin(angle), c = 1.0 - std::cos(angle);
      // R = I + s K + c K^2, K the cross-product matrix of k (column-major)
      const glm::dmat3 kx{glm::dvec3{0.0, k.z, -k.y}, glm::dvec3{-k.z, 0.0, k.x}, glm::dvec3{k.y, -k.x, 0.0}};
      const glm::dmat3 turn = glm::dmat3{1.0} + s * kx + c * (kx * kx);
      p.rotation = turn * pose.rotation;
    }
    return p;
  }

  /// The velocity of the shape's material point now at p (world) [m/s],
  /// with the shape at `now`: v_lin + w x (p - origin).
  [[nodiscard]] glm::dvec3 velocity_at(const Pose& now, const glm::dvec3& p) const noexcept {
    return linear_velocity + glm::cross(angular_velocity, p - now.translation);
  }
};

/// The hand-over of MovingPoses from one writer thread to one reader (the
/// servo thread), through a TripleBuffer: the writer's publish() allocates
/// until three snapshots circulate, then reuses them.
class PoseFeed {
 public:
  /// @throws std::invalid_argument as MovingPose::validate().
  explicit PoseFeed(const MovingPose& initial) : buffer_(checked(initial)) {}
  PoseFeed(const PoseFeed&) = delete;
  PoseFeed& operator=(const PoseFeed&) = delete;

  /// Writer thread: the reader uses `next` from its next tick on.
  /// @throws std::invalid_argument as MovingPose::validate() (nothing is
  ///         published then).
  void publish(const MovingPose& next) {
    next.validate();
    std::unique_ptr<MovingPose> slot = spare_ ? std::move(spare_) : std::make_unique<MovingPose>();
    *slot = next;
    spare_ = buffer_.publish(std::move(slot));
  }

  /// Reader thread: the newest snapshot (wait-free, no allocation).
  [[nodiscard]] const MovingPose& newest() noexcept { return *buffer_.acquire(); }

 private:
  static std::unique_ptr<MovingPose> checked(const MovingPose& p) {
    p.validate();
    return std::make_unique<MovingPose>(p);
  }

  TripleBuffer<MovingPose> buffer_;
  std::unique_ptr<MovingPose> spare_;  ///< a snapshot the reader gave back, for the next publish
};

/// Shape S placed in the world by the newest pose of a PoseFeed, answering
/// like Posed<S> (PosedQueries) with the pose of the last advance().
/// Move-only: one reader.
template <Shape S>
class Moving : public PosedQueries<Moving<S>, S> {
 public:
  /// A shape with its own feed, starting at `initial` (feed() for the writer).
  /// @throws std::invalid_argument as MovingPose::validate().
  Moving(S shape, const MovingPose& initial) : Moving(std::move(shape), std::make_shared<PoseFeed>(initial)) {}
  /// A shape moved by an existing feed.
  /// @throws std::invalid_argument for a null feed.
  Moving(S shape, std::shared_ptr<PoseFeed> feed) : shape_(std::move(shape)), feed_(std::move(feed)) {
    if (!feed_) throw std::invalid_argument("Moving: the pose feed must not be null");
    snapshot_ = feed_->newest();
    current_ = previous_ = snapshot_.at(snapshot_.time);
  }
  Moving(const Moving&) = delete;
  Moving& operator=(const Moving&) = delete;
  Moving(Moving&&) noexcept = default;
  Moving& operator=(Moving&&) noexcept = default;

  /// Servo thread, at the start of a tick at `time` [s]: takes the newest
  /// snapshot and the pose it gives at that time (the inner shape advances
  /// too, when it can). True when the shape moved since the last tick.
  bool advance(double time) noexcept {
    bool changed = false;
    if constexpr (requires(S & s) { s.advance(time); }) changed = shape_.advance(time);
    snapshot_ = feed_->newest();
    previous_ = current_;
    current_ = snapshot_.at(time);
    return changed || current_.rotation != previous_.rotation || current_.translation != previous_.translation;
  }

  /// Where the shape's motion since the last tick takes the world point p
  /// (it keeps its place in the shape's frame) [m].
  [[nodiscard]] glm::dvec3 carry(const glm::dvec3& p) const noexcept {
    return current_.point_to_world(previous_.point_to_local(p));
  }
  /// The velocity of the shape's surface at the world point p [m/s].
  [[nodiscard]] glm::dvec3 surface_velocity(const glm::dvec3& p) const noexcept {
    return snapshot_.velocity_at(current_, p);
  }

  [[nodiscard]] const S& shape() const noexcept { return shape_; }
  /// The pose of the last advance() (the first snapshot's before any).
  [[nodiscard]] const Pose& pose() const noexcept { return current_; }
  /// The pose of the advance() before it.
  [[nodiscard]] const Pose& previous_pose() const noexcept { return previous_; }
  /// The writer's end.
  [[nodiscard]] const std::shared_ptr<PoseFeed>& feed() const noexcept { return feed_; }

 private:
  S shape_;
  std::shared_ptr<PoseFeed> feed_;
  MovingPose snapshot_{};  ///< the newest snapshot at the last advance()
  Pose current_{};         ///< its pose at the last tick's time
  Pose previous_{};        ///< the pose of the tick before
};

static_assert(Shape<Moving<PlaneShape>>);
static_assert(Shape<Moving<SphereShape>>);

}  // namespace hapticfield
