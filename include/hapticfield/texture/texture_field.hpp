#pragma once
/// @file texture_field.hpp
/// Texture forces Ft as HapticFields (Fritz & Barner 1996, sections 4-6):
/// a texture source (spatial, distance-driven, temporal or local-sphere)
/// followed by an optional per-component filter, silenced below a velocity
/// threshold and optionally scaled by the constraint force |Fc|. Compose
/// with a constraint and Friction through the core's contact(), which gives
/// the parts |Fc| and the surface normal of this tick (F = Fc + Ft + Ff):
///
///   auto field = contact(PlaneConstraint({...}),
///                        TextureField(SpatialSource(lattice), {...}),
///                        Friction({...}));
///
/// Also the flow texture (a vector field in free space with a mean shift and
/// viscous drag).

#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/surface_frame.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/texture/friction.hpp"
#include "hapticfield/texture/lattice.hpp"
#include "hapticfield/texture/noise.hpp"

namespace hapticfield::texture {

// --- sources ----------------------------------------------------------------

/// Something that yields a texture vector each tick (may keep state).
template <class S>
concept TextureSource = requires(S& s, const Probe& p) {
  { s.sample(p) }
  noexcept->std::convertible_to<glm::dvec3>;
};

/// Spatial sampling: the generator evaluated at the HIP position (repeatable
/// in space; the temporal frequency is spatial frequency x speed).
template <SpatialGenerator G>
class SpatialSource {
 public:
  explicit SpatialSource(G generator) : g_(std::move(generator)) {}
  [[nodiscard]] glm::dvec3 sample(const Probe& p) const noexcept { return g_(p.position); }
  [[nodiscard]] const G& generator() const noexcept { return g_; }

 private:
  G g_;
};

/// Distance sampling: the generator evaluated at (s, 0, 0), s the path length
/// travelled since reset [m] (a 1D texture that follows the stroke).
template <SpatialGenerator G>
class DistanceSource {
 public:
  explicit DistanceSource(G generator) : g_(std::move(generator)) {}
  [[nodiscard]] glm::dvec3 sample(const Probe& p) noexcept {
    if (!is_finite(p.position)) return glm::dvec3{0.0};
    if (started_) s_ += glm::length(p.position - last_);
    started_ = true;
    last_ = p.position;
    return g_(glm::dvec3{s_, 0.0, 0.0});
  }
  void reset() noexcept {
    started_ = false;
    s_ = 0.0;
  }
  [[nodiscard]] double distance() const noexcept { return s_; }

 private:
  G g_;
  glm::dvec3 last_{0.0};
  double s_{0.0};
  bool started_{false};
};

/// Temporal sampling (Siira & Pai, IROS 1996): a fresh noise sample every
/// tick, indexed by the tick count since reset (repeatable for a seed).
template <NoiseSource Noise>
class TemporalSource {
 public:
  TemporalSource(Noise noise, std::uint32_t seed) : noise_(std::move(noise)), seed_(seed) {}
  [[nodiscard]] glm::dvec3 sample(const Probe&) noexcept { return noise_.sample(seed_, Cell{tick_++, 0, 0}); }
  void reset() noexcept { tick_ = 0; }

 private:
  Noise noise_;
  std::uint32_t seed_;
  std::uint32_t tick_{0};
};

// --- per-component filters ---------------------------------------------------

/// A scalar filter: process(double) -> double, noexcept, with reset().
template <class F>
concept ScalarFilter = requires(F& f, double x) {
  { f.process(x) }
  noexcept->std::convertible_to<double>;
  { f.reset() }
  noexcept;
};

/// The identity filter.
struct NoFilter {
  [[nodiscard]] double process(double x) const noexcept { return x; }
  void reset() noexcept {}
};

/// Three copies of a scalar filter, one per vector component (x, y, z).
template <ScalarFilter F>
class PerComponent {
 public:
  PerComponent() = default;
  explicit PerComponent(const F& f) : f_{f, f, f} {}
  PerComponent(F fx, F fy, F fz) : f_{std::move(fx), std::move(fy), std::move(fz)} {}
  [[nodiscard]] glm::dvec3 process(const glm::dvec3& v) noexcept {
    return glm::dvec3{f_[0].process(v.x), f_[1].process(v.y), f_[2].process(v.z)};
  }
  void reset() noexcept {
    for (auto& f : f_)
      f.reset();
  }
  [[nodiscard]] F& component(std::size_t i) noexcept { return f_[i]; }

 private:
  std::array<F, 3> f_{};
};

// --- texture field ------------------------------------------------------------

struct TextureConfig {
  double gain{1.0};                     ///< force per texture unit [N] (or [N/N] when scaled by |Fc|)
  double velocity_threshold{1e-3};      ///< below this speed the texture is silent [m/s]
  bool scale_with_normal_force{false};  ///< Ft proportional to |Fc| (Probe::normal_force)
  glm::dvec3 axes{1.0, 1.0, 1.0};       ///< weights along (t1, t2, n) of the surface frame ({1,1,0}: tangential only)
};

/// Ft = gain (|Fc| if scaled) R (axes * filter(source(probe))), zero below
/// the velocity threshold (the source and filter do not advance while
/// silent) and for non-finite probe data.
///
/// R maps the texture's components to the surface frame (t1, t2, n) of the
/// probe's surface normal (core/surface_frame.hpp), so axes {1, 1, 0} keep
/// the texture in the tangent plane of a tilted plane too, and the
/// threshold applies to the tangential speed. A probe without a surface
/// normal uses the device frame (x, y, z), which is also the surface frame
/// of a surface with normal +z.
template <TextureSource Source, ScalarFilter Filter = NoFilter>
class TextureField {
 public:
  /// @throws std::invalid_argument for a non-finite gain or axes, or a
  ///         negative or non-finite velocity threshold.
  TextureField(Source source, const TextureConfig& params, Filter filter = Filter{})
      : source_(std::move(source)), filter_(filter), config_(params) {
    if (!std::isfinite(params.gain)) throw std::invalid_argument("TextureField: gain must be finite [N]");
    if (!std::isfinite(params.velocity_threshold) || params.velocity_threshold < 0.0)
      throw std::invalid_argument("TextureField: velocity_threshold must be finite and >= 0 [m/s]");
    if (!is_finite(params.axes)) throw std::invalid_argument("TextureField: axes must be finite");
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    if (!is_finite(probe.position) || !is_finite(probe.velocity) || !std::isfinite(probe.normal_force) ||
        !is_finite(probe.surface_normal))
      return glm::dvec3{0.0};
    const glm::dvec3 n = surface_normal_of(probe, glm::dvec3{0.0});
    const bool on_surface = n != glm::dvec3{0.0};
    const SurfaceFrame frame = on_surface ? surface_frame(n) : SurfaceFrame{};
    const glm::dvec3 v = on_surface ? frame.tangential(probe.velocity) : probe.velocity;  // [m/s]
    if (glm::length(v) < config_.velocity_threshold) return glm::dvec3{0.0};
    const glm::dvec3 raw = source_.sample(probe);
    const glm::dvec3 shaped = filter_.process(raw);
    const double scale = config_.scale_with_normal_force ? config_.gain * std::fabs(probe.normal_force) : config_.gain;
    const glm::dvec3 weighted = config_.axes * shaped;
    const glm::dvec3 f = scale * (on_surface ? frame.to_device(weighted) : weighted);
    return is_finite(f) ? f : glm::dvec3{0.0};
  }

  void reset() noexcept {
    reset_if_resettable(source_);
    filter_.reset();
  }

  [[nodiscard]] Source& source() noexcept { return source_; }
  [[nodiscard]] PerComponent<Filter>& filter() noexcept { return filter_; }

 private:
  template <class T>
  static void reset_if_resettable(T& t) noexcept {
    if constexpr (requires { t.reset(); }) t.reset();
  }

  Source source_;
  PerComponent<Filter> filter_;
  TextureConfig config_;
};

// --- flow textures --------------------------------------------------------------

struct FlowConfig {
  glm::dvec3 mean_shift{0.0};  ///< constant "active" force pushing the hand [N]
  double gain{1.0};            ///< force per unit of the vector lattice [N]
  double viscous{0.0};         ///< drag in the fluid [N s/m]
};

/// Flow texture (Fritz & Barner 1996, section 7): F = m + gain L(p) - b v,
/// with L a 3D vector-noise lattice (turbulence), m a mean shift that makes
/// the texture "active" (it pushes the hand) and b viscous drag. A flow is
/// felt in free space, in the device frame: add it with sum(), outside any
/// contact(), and it ignores the probe's contact data.
template <SpatialGenerator Lattice>
class FlowTexture {
 public:
  /// @throws std::invalid_argument for non-finite parameters or a negative
  ///         viscous coefficient.
  FlowTexture(Lattice lattice, const FlowConfig& p) : lattice_(std::move(lattice)), config_(p) {
    if (!is_finite(p.mean_shift) || !std::isfinite(p.gain))
      throw std::invalid_argument("FlowTexture: mean_shift [N] and gain [N] must be finite");
    if (!std::isfinite(p.viscous) || p.viscous < 0.0)
      throw std::invalid_argument("FlowTexture: viscous must be finite and >= 0 [N s/m]");
  }
  [[nodiscard]] glm::dvec3 force(const Probe& probe) const noexcept {
    if (!is_finite(probe.position) || !is_finite(probe.velocity)) return glm::dvec3{0.0};
    return config_.mean_shift + config_.gain * glm::dvec3(lattice_(probe.position)) - config_.viscous * probe.velocity;
  }

 private:
  Lattice lattice_;
  FlowConfig config_;
};

static_assert(HapticField<Friction>);
static_assert(HapticField<TextureField<TemporalSource<GaussianNoise>>>);
static_assert(ResettableField<TextureField<TemporalSource<GaussianNoise>>>);

}  // namespace hapticfield::texture
