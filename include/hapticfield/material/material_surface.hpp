#pragma once
/// @file material_surface.hpp
/// MaterialSurface: a proxy on any Shape (surface/proxy.hpp) whose
/// stiffness, damping and friction come from a material map
/// (material/material_map.hpp) read at the touched point's uv, plus texture
/// fields (any HapticField laid on the surface, e.g. through on_surface())
/// whose force the map's texture gain scales: F = Fc(k, b, mu_s, mu_k at
/// uv) + gain(uv) (Ft1 + Ft2 + ...), the contact composition of
/// core/contact.hpp.
///
/// When the material is read: each tick before the proxy moves, at the uv
/// where the proxy is held (the last tick's contact point): the friction
/// cone is tested where the proxy sticks, which is the material that holds
/// it, and the stiffness lags the touched point by one tick (1 ms at 1 kHz;
/// a slow stroke crosses a texel in hundreds of ticks). The first tick of a
/// contact reads it at the new contact point and its Fc is the spring and
/// damper of that material (no friction acts on a first tick).
///
/// A changed material reaches the servo loop without a lock: publish()
/// from one writer thread hands it over through a TripleBuffer
/// (rt/triple_buffer.hpp); the tick picks it up at its start, the proxy
/// keeps its place. touched_material() tells the vibration tap
/// (vibration/tap.hpp) the touched point's vibration id: the map's id
/// there, or with MaterialMaps::vibration left at per_primitive_material,
/// the touched triangle's own material (a mesh's per-triangle materials).

#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/field.hpp"
#include "hapticfield/core/live_field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/material/material_map.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "hapticfield/surface/shape.hpp"

namespace hapticfield::material {

/// MaterialMaps::vibration value meaning "the touched primitive's material".
inline constexpr std::uint32_t per_primitive_material = 0xFFFFFFFEu;

template <Shape S, HapticField... Textures>
class MaterialSurface {
 public:
  /// config: the proxy's offset, radius and stick_first (its stiffness,
  /// damping and friction come from the map). @throws std::invalid_argument
  /// as ProxyConstraint does.
  MaterialSurface(S shape, const ProxyConfig& config, MaterialMap map, Textures... textures)
      : proxy_(std::move(shape), config),
        materials_(std::make_unique<TripleBuffer<MaterialMap>>(std::make_unique<MaterialMap>(std::move(map)))),
        textures_(std::move(textures)...) {}

  /// Writer thread (one): the tick uses map from its next start on. The
  /// replaced map is destroyed here, never in a tick.
  void publish(MaterialMap map) { (void)materials_->publish(std::make_unique<MaterialMap>(std::move(map))); }

  /// F = Fc + gain (sum of textures) [N]; zero when not touching or for a
  /// non-finite position.
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    const MaterialMap* map = materials_->acquire();
    Probe on;
    if (!constraint_probe(probe, on)) {
      last_ = Contact{};
      held_ = false;
      return glm::dvec3{0.0};
    }
    if (map != nullptr && held_) apply(map->sample(held_uv_));
    last_ = proxy_.contact(on);
    if (!last_.touching) {
      held_ = false;
      return glm::dvec3{0.0};
    }
    if (map != nullptr && !held_) {  // first tick of a contact: the material where it touched
      apply(map->sample(last_.surface_uv));
      const double push =
          sample_.stiffness * last_.depth - sample_.damping * glm::dot(on.velocity, last_.normal);  // [N]
      last_.force = (push > 0.0 ? push : 0.0) * last_.normal;
    }
    held_ = true;
    held_uv_ = last_.surface_uv;
    if (map != nullptr) vibration_ = map->maps().vibration.at(last_.surface_uv);  // the point touched now
    tell_contact(on, last_);
    const glm::dvec3 t =
        std::apply([&on](auto&... part) { return (glm::dvec3{0.0} + ... + glm::dvec3(part.force(on))); }, textures_);
    const glm::dvec3 f = last_.force + sample_.texture_gain * t;
    return is_finite(f) ? f : glm::dvec3{0.0};
  }

  /// The proxy's look-ahead (core/field.hpp) on the probe force() would
  /// give it, with the material force() would give it first (the map's at
  /// the held point; a map published since is the next tick's alone);
  /// nothing changes.
  void anticipate(const Probe& next) const noexcept {
    Probe on;
    if (!constraint_probe(next, on)) return;
    const MaterialMap* map = materials_->held();
    if (map != nullptr && held_) {
      const MaterialSample s = map->sample(held_uv_);
      proxy_.anticipate(on, s.stiffness, s.damping, s.static_friction, s.dynamic_friction);
    } else {
      proxy_.anticipate(on);
    }
  }
  [[nodiscard]] bool looks_ahead() const noexcept { return proxy_.looks_ahead(); }

  void reset() noexcept {
    proxy_.reset();
    std::apply([](auto&... part) { (reset_if_stateful(part), ...); }, textures_);
    last_ = Contact{};
    held_ = false;
  }

  /// The contact of the last tick (Fc, normal, uv, primitive).
  [[nodiscard]] const Contact& last_contact() const noexcept { return last_; }
  /// The material the last touching tick's Fc was computed with (read
  /// where the proxy was held; its vibration id is touched_material()'s).
  [[nodiscard]] const MaterialSample& last_material() const noexcept { return sample_; }
  /// The vibration id of the touched point (see the file comment); 0 when not touching.
  [[nodiscard]] std::uint32_t touched_material() const noexcept {
    if (!last_.touching) return 0;
    return vibration_ == per_primitive_material ? last_.material : vibration_;
  }
  [[nodiscard]] const ProxyConstraint<S>& constraint() const noexcept { return proxy_; }
  template <std::size_t I>
  [[nodiscard]] auto& texture() noexcept {
    return std::get<I>(textures_);
  }

 private:
  void apply(const MaterialSample& s) noexcept {
    sample_ = s;
    (void)proxy_.set_material(s.stiffness, s.damping, s.static_friction, s.dynamic_friction);
  }

  ProxyConstraint<S> proxy_;
  std::unique_ptr<TripleBuffer<MaterialMap>> materials_;
  std::tuple<Textures...> textures_;
  Contact last_{};
  MaterialSample sample_{};
  std::uint32_t vibration_{0};  ///< the vibration id at the last contact point
  bool held_{false};            ///< the last tick touched: the proxy is held at held_uv_
  glm::dvec2 held_uv_{0.0};     ///< uv of the last contact point
};

/// material_surface(shape, config, map, textures...).
template <Shape S, HapticField... Textures>
[[nodiscard]] MaterialSurface<std::remove_cvref_t<S>, std::remove_cvref_t<Textures>...> material_surface(
    S&& shape, const ProxyConfig& config, MaterialMap map, Textures&&... textures) {
  return MaterialSurface<std::remove_cvref_t<S>, std::remove_cvref_t<Textures>...>(
      std::forward<S>(shape), config, std::move(map), std::forward<Textures>(textures)...);
}

}  // namespace hapticfield::material
