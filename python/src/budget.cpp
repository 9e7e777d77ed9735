// hapticfield.tick_budget(field, ...): does a field fit in a servo tick? The
// tick-budget harness (servo/tick_budget.hpp) run on a field built in
// Python. Allocations are counted when the process has the allocation
// counter preloaded (python/tests/alloc/alloc_counter.c), else reported as
// None.
#include "field.hpp"

#include <hapticfield/servo/tick_budget.hpp>

#include <dlfcn.h>

#include <cmath>
#include <cstdint>
#include <memory>

namespace hapticfield::python {

namespace {

using CounterRead = unsigned long (*)();
using CounterSwitch = void (*)(int);

/// The preloaded counter's functions, or null without one.
CounterRead counter_read() {
  static const auto f = reinterpret_cast<CounterRead>(dlsym(RTLD_DEFAULT, "hapticfield_malloc_calls"));
  return f;
}
CounterSwitch counter_switch() {
  static const auto f = reinterpret_cast<CounterSwitch>(dlsym(RTLD_DEFAULT, "hapticfield_count_here"));
  return f;
}
std::int64_t preloaded_allocations() noexcept {
  return static_cast<std::int64_t>(counter_read()());
}

py::dict tick_budget(Field& field, std::uint64_t ticks, double speed, double radius, double depth, double period,
                     double share) {
  if (ticks < 1 || ticks > 100'000'000) throw py::value_error("tick_budget: ticks must be within 1..1e8");
  if (!(std::isfinite(speed) && speed >= 0.0) || !(std::isfinite(radius) && radius > 0.0) ||
      !(std::isfinite(depth) && depth >= 0.0))
    throw py::value_error("tick_budget: speed [m/s] and depth [m] must be >= 0, radius [m] > 0");
  if (!(std::isfinite(period) && period > 0.0 && period <= 1.0))
    throw py::value_error("tick_budget: period must be within (0, 1] [s]");
  if (!(std::isfinite(share) && share > 0.0 && share <= 1.0))
    throw py::value_error("tick_budget: share must be within (0, 1]");
  offline::TickBudgetConfig c;
  c.ticks = ticks;
  c.path.speed = speed;
  c.path.radius = radius;
  c.path.depth = depth;
  c.path.period = period;
  c.share = share;
  const bool counted = counter_read() && counter_switch();
  c.allocation_count = counted ? &preloaded_allocations : nullptr;
  std::shared_ptr<AnyField> f = field.impl;
  offline::TickBudgetReport r;
  {
    py::gil_scoped_release release;  // the field is C++ throughout
    if (counted) counter_switch()(1);
    r = offline::measure_tick_budget(*f, c);
    if (counted) counter_switch()(0);
  }
  py::dict d;
  d["ticks"] = r.ticks;
  d["mean_ns"] = r.mean_ns;
  d["p50_ns"] = r.p50_ns;
  d["p99_ns"] = r.p99_ns;
  d["p999_ns"] = r.p999_ns;
  d["worst_ns"] = r.worst_ns;
  d["allocations"] = r.allocations < 0 ? py::object(py::none()) : py::object(py::int_(r.allocations));
  d["allocations_per_tick"] =
      r.allocations < 0 ? py::object(py::none()) : py::object(py::float_(r.allocations_per_tick()));
  d["exceptions"] = r.exceptions;
  d["fits_1khz"] = r.fits_1khz;
  d["fits_10khz"] = r.fits_10khz;
  d["summary"] = r.summary();
  return d;
}

}  // namespace

void bind_budget(py::module_& m) {
  m.def("tick_budget", &tick_budget, py::arg("field"), py::arg("ticks") = 20000, py::arg("speed") = 0.1,
        py::arg("radius") = 0.02, py::arg("depth") = 0.002, py::arg("period") = servo_period, py::arg("share") = 0.25,
        "Does the field fit in a servo tick? Runs it over a scripted path (a circle of radius [m] at speed [m/s], "
        "pressed depth [m] into the plane z = 0, ticks period [s] apart) and returns a dict: mean_ns, p50_ns, p99_ns, "
        "p999_ns, worst_ns, allocations and allocations_per_tick (None unless the allocation counter is "
        "preloaded), exceptions, fits_1khz, fits_10khz (p99 at most share of the period, no allocation, no "
        "exception) and summary (the same in words). The GIL is released while it runs.");
}

}  // namespace hapticfield::python
