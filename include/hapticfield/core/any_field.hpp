#pragma once
/// @file any_field.hpp
/// AnyField: a HapticField whose concrete type is chosen at run time.

#include <memory>
#include <type_traits>
#include <utility>

#include "hapticfield/core/field.hpp"

namespace hapticfield {

/// Type-erased HapticField (move-only). Construction allocates once; force(),
/// reset() and anticipate() are a virtual call each and never allocate. A default
/// constructed AnyField is the zero field.
class AnyField {
 public:
  AnyField() = default;

  template <HapticField F>
  requires(!std::is_same_v<std::remove_cvref_t<F>, AnyField>)
      AnyField(F&& field)  // NOLINT(google-explicit-constructor): a field converts implicitly
      : model_(std::make_unique<Model<std::remove_cvref_t<F>>>(std::forward<F>(field))) {}

  AnyField(AnyField&&) noexcept = default;
  AnyField& operator=(AnyField&&) noexcept = default;
  AnyField(const AnyField&) = delete;
  AnyField& operator=(const AnyField&) = delete;
  ~AnyField() = default;

  /// Force on the HIP [N]; zero when empty.
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    return model_ ? model_->force(probe) : glm::dvec3{0.0};
  }

  /// Resets a stateful field; no effect on a stateless or empty one.
  void reset() noexcept {
    if (model_) model_->reset();
  }

  /// The held field's look-ahead (core/field.hpp), where it has one.
  void anticipate(const Probe& next) const noexcept {
    if (model_) model_->anticipate(next);
  }
  [[nodiscard]] bool looks_ahead() const noexcept { return model_ && model_->looks_ahead(); }

  /// True when a field is held.
  [[nodiscard]] explicit operator bool() const noexcept { return static_cast<bool>(model_); }

  /// The held field when it is of type F, else nullptr.
  template <HapticField F>
  [[nodiscard]] F* target() noexcept {
    auto* model = dynamic_cast<Model<F>*>(model_.get());
    return model ? &model->field : nullptr;
  }

 private:
  struct Concept {
    virtual ~Concept() = default;
    virtual glm::dvec3 force(const Probe& probe) noexcept = 0;
    virtual void reset() noexcept = 0;
    virtual void anticipate(const Probe& next) const noexcept = 0;
    virtual bool looks_ahead() const noexcept = 0;
  };

  template <class F>
  struct Model final : Concept {
    template <class G>
    explicit Model(G&& g) : field(std::forward<G>(g)) {}
    glm::dvec3 force(const Probe& probe) noexcept override { return field.force(probe); }
    void reset() noexcept override { reset_if_stateful(field); }
    void anticipate(const Probe& next) const noexcept override { anticipate_if_able(field, next); }
    bool looks_ahead() const noexcept override { return field_looks_ahead(field); }
    F field;
  };

  std::unique_ptr<Concept> model_;
};

static_assert(ResettableField<AnyField>);
static_assert(AnticipatingField<AnyField>);

}  // namespace hapticfield
