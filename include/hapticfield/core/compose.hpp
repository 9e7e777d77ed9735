#pragma once
/// @file compose.hpp
/// Composition of fields: sum, scale, clamp. Each result is itself a field
/// whose force() is a direct, inlinable call on its parts.

#include <cmath>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// Sum of fields: F = F1 + F2 + ... (e.g. constraint + texture + friction).
template <HapticField... Fields>
class SumField {
 public:
  explicit SumField(Fields... fields) : fields_(std::move(fields)...) {}

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    return std::apply([&probe](auto&... f) { return (glm::dvec3{0.0} + ... + glm::dvec3(f.force(probe))); }, fields_);
  }

  void reset() noexcept {
    std::apply([](auto&... f) { (reset_if_stateful(f), ...); }, fields_);
  }

  /// Each part's look-ahead (core/field.hpp), where it has one.
  void anticipate(const Probe& next) const noexcept {
    std::apply([&next](const auto&... f) { (anticipate_if_able(f, next), ...); }, fields_);
  }
  [[nodiscard]] bool looks_ahead() const noexcept {
    return std::apply([](const auto&... f) { return (false || ... || field_looks_ahead(f)); }, fields_);
  }

  /// The i-th part.
  template <std::size_t I>
  [[nodiscard]] auto& part() noexcept {
    return std::get<I>(fields_);
  }

 private:
  std::tuple<Fields...> fields_;
};

/// A field scaled by a constant gain [dimensionless or N per unit].
template <HapticField Field>
class ScaledField {
 public:
  /// @throws std::invalid_argument when gain is not finite.
  ScaledField(Field field, double gain) : field_(std::move(field)), gain_(gain) {
    if (!std::isfinite(gain)) throw std::invalid_argument("ScaledField: gain must be finite");
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept { return gain_ * glm::dvec3(field_.force(probe)); }

  void reset() noexcept { reset_if_stateful(field_); }
  void anticipate(const Probe& next) const noexcept { anticipate_if_able(field_, next); }
  [[nodiscard]] bool looks_ahead() const noexcept { return field_looks_ahead(field_); }

  [[nodiscard]] Field& inner() noexcept { return field_; }

 private:
  Field field_;
  double gain_;
};

/// A field whose magnitude is clamped to a limit [N], keeping the direction;
/// a non-finite inner force becomes zero.
template <HapticField Field>
class ClampedField {
 public:
  /// @throws std::invalid_argument when limit is not finite and positive.
  ClampedField(Field field, double limit) : field_(std::move(field)), limit_(limit) {
    if (!std::isfinite(limit) || limit <= 0.0)
      throw std::invalid_argument("ClampedField: limit must be finite and positive [N]");
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    return clamp_magnitude(glm::dvec3(field_.force(probe)), limit_);
  }

  void reset() noexcept { reset_if_stateful(field_); }
  void anticipate(const Probe& next) const noexcept { anticipate_if_able(field_, next); }
  [[nodiscard]] bool looks_ahead() const noexcept { return field_looks_ahead(field_); }

  [[nodiscard]] Field& inner() noexcept { return field_; }

 private:
  Field field_;
  double limit_;
};

/// F1 + F2 + ...
template <HapticField... Fields>
[[nodiscard]] SumField<std::remove_cvref_t<Fields>...> sum(Fields&&... fields) {
  return SumField<std::remove_cvref_t<Fields>...>(std::forward<Fields>(fields)...);
}

/// gain * F
template <HapticField Field>
[[nodiscard]] ScaledField<std::remove_cvref_t<Field>> scale(Field&& field, double gain) {
  return ScaledField<std::remove_cvref_t<Field>>(std::forward<Field>(field), gain);
}

/// F with |F| <= limit [N]
template <HapticField Field>
[[nodiscard]] ClampedField<std::remove_cvref_t<Field>> clamp(Field&& field, double limit) {
  return ClampedField<std::remove_cvref_t<Field>>(std::forward<Field>(field), limit);
}

}  // namespace hapticfield
