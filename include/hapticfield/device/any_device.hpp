#pragma once
/// @file any_device.hpp
/// AnyDevice: a Device whose family is chosen at run time (the front door,
/// hapticfield/devices/open_device.hpp, returns one), so one ServoLoop or
/// MultiArmLoop type takes any arm.

#include <memory>
#include <type_traits>
#include <typeinfo>
#include <utility>

#include <glm/vec3.hpp>

#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"

namespace hapticfield {

/// Type-erased Device (move-only). Construction allocates once; read(),
/// write(), set_armed(), request_home() and clear_fault() are one virtual
/// call each and never allocate. A default constructed AnyDevice holds no
/// arm: every call returns Status::disconnected (a loop on it stops at once
/// with zero force).
class AnyDevice {
 public:
  AnyDevice() = default;

  /// Holds a device that owns everything it uses (moved in).
  template <Device D>
  requires(!std::is_same_v<std::remove_cvref_t<D>, AnyDevice>) explicit AnyDevice(D&& device)
      : model_(std::make_unique<Owned<std::remove_cvref_t<D>>>(std::forward<D>(device))) {}

  /// Holds `parts` (a device with what it refers to: its transport, a
  /// simulated twin) at a fixed address; `parts->device()` is the arm.
  template <class Parts>
  requires requires(Parts& p) {
    { p.device() } -> Device;
  }
  [[nodiscard]] static AnyDevice holding(std::unique_ptr<Parts> parts) {
    AnyDevice any;
    if (parts) any.model_ = std::make_unique<Held<Parts>>(std::move(parts));
    return any;
  }

  AnyDevice(AnyDevice&&) noexcept = default;
  AnyDevice& operator=(AnyDevice&&) noexcept = default;
  AnyDevice(const AnyDevice&) = delete;
  AnyDevice& operator=(const AnyDevice&) = delete;
  ~AnyDevice() = default;

  Status read(DeviceState& state) noexcept { return model_ ? model_->read(state) : Status::disconnected; }
  Status write(const glm::dvec3& force) noexcept { return model_ ? model_->write(force) : Status::disconnected; }
  Status set_armed(bool on) noexcept { return model_ ? model_->set_armed(on) : Status::disconnected; }
  Status request_home() noexcept { return model_ ? model_->request_home() : Status::disconnected; }
  /// Clears the device's latched fault; Status::unsupported on a family
  /// that has no such request.
  Status clear_fault() noexcept { return model_ ? model_->clear_fault() : Status::disconnected; }
  [[nodiscard]] const DeviceInfo& info() const noexcept { return model_ ? model_->info() : empty_info(); }

  /// True when an arm is held.
  [[nodiscard]] explicit operator bool() const noexcept { return static_cast<bool>(model_); }

  /// The held arm when it is of type D, else nullptr (its counters, its
  /// family's own calls).
  template <Device D>
  [[nodiscard]] D* target() noexcept {
    return model_ ? static_cast<D*>(model_->target(typeid(D))) : nullptr;
  }
  template <Device D>
  [[nodiscard]] const D* target() const noexcept {
    return model_ ? static_cast<const D*>(model_->target(typeid(D))) : nullptr;
  }

 private:
  static const DeviceInfo& empty_info() noexcept {
    static const DeviceInfo none{.name = "no device"};
    return none;
  }

  struct Concept {
    virtual ~Concept() = default;
    virtual Status read(DeviceState& state) noexcept = 0;
    virtual Status write(const glm::dvec3& force) noexcept = 0;
    virtual Status set_armed(bool on) noexcept = 0;
    virtual Status request_home() noexcept = 0;
    virtual Status clear_fault() noexcept = 0;
    [[nodiscard]] virtual const DeviceInfo& info() const noexcept = 0;
    [[nodiscard]] virtual void* target(const std::type_info& type) const noexcept = 0;
  };

  /// The calls on one device D, found through arm().
  template <class D, class Self>
  struct Calls : Concept {
    D& arm() noexcept { return static_cast<Self*>(this)->arm(); }
    const D& arm() const noexcept { return static_cast<const Self*>(this)->arm(); }
    Status read(DeviceState& state) noexcept final { return arm().read(state); }
    Status write(const glm::dvec3& force) noexcept final { return arm().write(force); }
    Status set_armed(bool on) noexcept final { return arm().set_armed(on); }
    Status request_home() noexcept final { return arm().request_home(); }
    Status clear_fault() noexcept final {
      if constexpr (requires(D & d) {
                      { d.clear_fault() } -> std::same_as<Status>;
                    })
        return arm().clear_fault();
      else
        return Status::unsupported;
    }
    [[nodiscard]] const DeviceInfo& info() const noexcept final { return arm().info(); }
    [[nodiscard]] void* target(const std::type_info& type) const noexcept final {
      return type == typeid(D) ? const_cast<D*>(&arm()) : nullptr;  // NOLINT(cppcoreguidelines-pro-type-const-cast)
    }
  };

  template <class D>
  struct Owned final : Calls<D, Owned<D>> {
    template <class E>
    explicit Owned(E&& e) : device(std::forward<E>(e)) {}
    D& arm() noexcept { return device; }
    const D& arm() const noexcept { return device; }
    D device;
  };

  template <class Parts>
  using DeviceOf = std::remove_cvref_t<decltype(std::declval<Parts&>().device())>;

  template <class Parts>
  struct Held final : Calls<DeviceOf<Parts>, Held<Parts>> {
    explicit Held(std::unique_ptr<Parts> p) : parts(std::move(p)), device(&parts->device()) {}
    DeviceOf<Parts>& arm() noexcept { return *device; }
    const DeviceOf<Parts>& arm() const noexcept { return *device; }
    std::unique_ptr<Parts> parts;
    DeviceOf<Parts>* device;
  };

  std::unique_ptr<Concept> model_;
};

static_assert(Device<AnyDevice>);

}  // namespace hapticfield
