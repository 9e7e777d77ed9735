#pragma once
/// @file field.hpp
/// The Python-side field handle: a shared, type-erased HapticField, and the
/// helpers that turn numpy arrays into probes and back.

#include <hapticfield/core.hpp>
#include <hapticfield/kernels.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapticfield::python {

namespace py = pybind11;

/// N probes as numpy arrays (row-major) and the N x 3 forces [N] to write.
struct ProbeArrays {
  const double* positions = nullptr;        ///< N x 3 [m]
  const double* velocities = nullptr;       ///< N x 3 [m/s], or null: zero
  const double* normal_forces = nullptr;    ///< N [N], or null: zero
  const double* surface_normals = nullptr;  ///< N x 3, or null: none
  double* forces = nullptr;                 ///< N x 3 [N]
  py::ssize_t n = 0;
  double period = servo_period;  ///< [s] between consecutive probes
  double start_time = 0.0;       ///< time of the first probe [s]
};

/// Evaluates `field` at the probes in order, as consecutive ticks.
template <class F>
void evaluate(F& field, const ProbeArrays& a) noexcept {
  Probe probe;
  probe.period = a.period;
  const double *p = a.positions, *v = a.velocities, *nf = a.normal_forces, *sn = a.surface_normals;
  double* f = a.forces;
  for (py::ssize_t i = 0; i < a.n; ++i) {
    probe.position = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    if (v) probe.velocity = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
    if (nf) probe.normal_force = nf[i];
    if (sn) probe.surface_normal = {sn[3 * i], sn[3 * i + 1], sn[3 * i + 2]};
    probe.time = a.start_time + static_cast<double>(i) * a.period;
    const glm::dvec3 r = field.force(probe);
    f[3 * i] = r.x, f[3 * i + 1] = r.y, f[3 * i + 2] = r.z;
  }
}

/// The batch evaluator of a field of concrete type F held in an AnyField:
/// one type check a call instead of one virtual call a probe, and the
/// field's force() inlined into the loop.
template <class F>
void evaluate_as(AnyField& any, const ProbeArrays& a) noexcept {
  if (F* f = any.target<F>())
    evaluate(*f, a);
  else
    evaluate(any, a);
}

/// The one-thread-at-a-time rule for a field, enforced: every field built in Python has a guard, and a
/// field composed of others also holds theirs, so evaluating a composition takes its parts too.
struct FieldGuard {
  std::atomic<bool> busy{false};
  /// A video field's lockstep switch (VideoField::set_lockstep), empty for other fields: run_servo turns it
  /// on for a run on the virtual clock, so that each tick waits for its frame, and off after.
  std::function<void(bool)> lockstep;
  /// A simulator's own real-time thread (a MuJoCo scene's), empty for other fields: run_servo on the wall clock
  /// starts it (true) and stops it after the run (false).
  std::function<void(bool)> real_time;
};
using Guards = std::vector<std::shared_ptr<FieldGuard>>;

/// A field built in Python. Fields made of fields share their parts.
struct Field {
  std::shared_ptr<AnyField> impl;
  std::string description;
  /// Evaluates impl over arrays knowing its type (set by make_field; null: through AnyField).
  void (*batch)(AnyField&, const ProbeArrays&) noexcept = nullptr;
  /// Its own guard first, then those of every field it is made of, each once.
  Guards guards;
};

/// A fresh guard for a new field, followed by the guards of `parts` (each once).
inline Guards guards_of(const std::vector<const Field*>& parts = {}) {
  Guards g{std::make_shared<FieldGuard>()};
  for (const Field* part : parts)
    for (const auto& guard : part->guards)
      if (std::find(g.begin(), g.end(), guard) == g.end()) g.push_back(guard);
  return g;
}

/// Holds every guard of a field for the length of a call that evaluates it (forces, force, reset,
/// run_servo); throws RuntimeError, holding none, when another thread holds one of them.
class FieldUse {
 public:
  explicit FieldUse(const Field& field) : guards_(&field.guards) {
    for (std::size_t i = 0; i < guards_->size(); ++i) {
      bool free = false;
      if (!(*guards_)[i]->busy.compare_exchange_strong(free, true, std::memory_order_acquire)) {
        release(i);
        throw std::runtime_error(
            "field '" + field.description +
            "' is in use by another thread (a run_servo loop or a forces(), force() or reset() call): a field keeps "
            "state and is evaluated by one thread at a time; build a second field for the other thread (e.g. a "
            "second video_field on the same clip for a preview beside the loop), or wait for the first call to end");
      }
    }
  }
  ~FieldUse() { release(guards_->size()); }
  FieldUse(const FieldUse&) = delete;
  FieldUse& operator=(const FieldUse&) = delete;

 private:
  void release(std::size_t n) noexcept {
    for (std::size_t i = 0; i < n; ++i)
      (*guards_)[i]->busy.store(false, std::memory_order_release);
  }
  const Guards* guards_;
};

/// A part held by a composed field: forwards to the shared field.
struct SharedField {
  std::shared_ptr<AnyField> field;
  glm::dvec3 force(const Probe& probe) noexcept { return field->force(probe); }
  void reset() noexcept { field->reset(); }
  void anticipate(const Probe& next) const noexcept { field->anticipate(next); }
  [[nodiscard]] bool looks_ahead() const noexcept { return field->looks_ahead(); }
};

/// F = sum of the parts; the vector is filled at construction only.
struct FieldSum {
  std::vector<SharedField> parts;
  glm::dvec3 force(const Probe& probe) noexcept {
    glm::dvec3 f{0.0};
    for (auto& p : parts)
      f += p.force(probe);
    return f;
  }
  void reset() noexcept {
    for (auto& p : parts)
      p.reset();
  }
  void anticipate(const Probe& next) const noexcept {
    for (const auto& p : parts)
      p.anticipate(next);
  }
  [[nodiscard]] bool looks_ahead() const noexcept {
    for (const auto& p : parts)
      if (p.looks_ahead()) return true;
    return false;
  }
};

/// A field of its own (parts empty) or one made of `parts`, whose guards it takes when evaluated.
template <HapticField F>
Field make_field(F&& f, std::string description, const std::vector<const Field*>& parts = {}) {
  using T = std::remove_cvref_t<F>;
  return Field{std::make_shared<AnyField>(std::forward<F>(f)), std::move(description), &evaluate_as<T>,
               guards_of(parts)};
}

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// Checks an N x cols array (cols = 0: a 1-D array of N) and returns N.
inline py::ssize_t rows_of(const Array& a, py::ssize_t cols, const char* what) {
  if (cols == 0) {
    if (a.ndim() != 1) throw py::value_error(std::string(what) + ": expected a 1-D array");
    return a.shape(0);
  }
  if (a.ndim() != 2 || a.shape(1) != cols)
    throw py::value_error(
        std::string(what) + ": expected an N x " + std::to_string(cols) + " array, got shape " +
        std::string(py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()))))));
  return a.shape(0);
}

/// The option called `name` among `options`; a ValueError naming them all otherwise.
template <class E>
inline E choose(const std::string& what, const std::string& name, const std::map<std::string, E>& options) {
  const auto it = options.find(name);
  if (it != options.end()) return it->second;
  std::string names;
  for (const auto& [k, v] : options)
    names += (names.empty() ? "" : ", ") + k;
  throw py::value_error(what + ": unknown '" + name + "' (choose " + names + ")");
}

/// The gray weights called `name` (paper, bt601).
GrayWeights gray_weights(const std::string& name);

/// Mask, border and tangible options as tangible_forces() takes them (image.cpp).
MaskKind mask_kind(const std::string& name);
Border border_kind(const std::string& name);
TangibleConfig tangible_options(const std::string& mask, std::optional<int> size, const std::string& border,
                                double sigma);
/// A picture as the bindings take it: a path, or a numpy array read with `channels` ("rgb" or "bgr") and white
/// level `levels` (required for float arrays); see picture_argument_doc (image.cpp).
GrayImage gray_from(const py::object& image, GrayWeights weights, const std::string& channels,
                    std::optional<double> levels);
/// What every docstring that takes a picture says about it.
inline constexpr const char* picture_argument_doc =
    "image: a path (any format OpenCV reads; 16-bit files are scaled by 255/65535) or a numpy array, H x W gray or "
    "H x W x 3 / x 4 colour (alpha ignored). channels='rgb' (default: numpy, PIL, imageio order) or 'bgr' (cv2.imread "
    "order) names a colour array's channel order. White level: 255 for uint8 and other integer arrays, 65535 for "
    "uint16 (as 16-bit files); a float or bool array needs levels= (its white level: 1.0 for a picture in [0, 1], 255 "
    "for [0, 255]) and is refused without it; levels= overrides the white level of any array.";
/// The picture centred on the origin at px_per_mm [px/mm] (default Kim & Kwon's 6.4) or fitted so that its
/// longer side spans workspace_mm [mm].
PlaneMapping mapping_for(int width, int height, std::optional<double> px_per_mm, std::optional<double> workspace_mm);

using V3 = std::array<double, 3>;
inline glm::dvec3 glm3(const V3& a) {
  return {a[0], a[1], a[2]};
}

/// An N x 3 (or N x cols) result array.
inline py::array_t<double> matrix(py::ssize_t n, py::ssize_t cols) {
  return py::array_t<double>({n, cols});
}

void bind_core(py::module_& m);
void bind_image(py::module_& m);
void bind_texture(py::module_& m);
void bind_servo(py::module_& m);
void bind_video(py::module_& m);
void bind_budget(py::module_& m);
void bind_surface(py::module_& m);
void bind_relief_map(py::module_& m);
void bind_mujoco(py::module_& m);

}  // namespace hapticfield::python
