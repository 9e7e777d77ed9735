// The servo loop from Python: a field built in Python, run in C++ on a
// simulated or real arm, with the GIL released for the whole run.
#include "field.hpp"

#include <hapticfield/devices/open_device.hpp>
#include <hapticfield/servo.hpp>

#include <pybind11/stl.h>

#include <dlfcn.h>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <tuple>
#include <vector>

namespace hapticfield::python {

namespace {

HandPath hand_path(const std::string& kind, const V3& centre, double size, double speed) {
  const glm::dvec3 c = glm3(centre);
  if (kind == "raster") return HandPath::raster(c, size, size, 8, speed);
  if (kind == "circle") return HandPath::circle(c, size / 2.0, speed);
  if (kind == "hold") return HandPath::hold(c);
  throw py::value_error("hand: unknown '" + kind + "' (choose raster, circle or hold)");
}

py::dict snapshot_dict(const LoopSnapshot& s) {
  py::dict d;
  d["ticks"] = s.ticks;
  d["missed_deadlines"] = s.missed_deadlines;
  d["overruns"] = s.overruns;
  d["safety_events"] = s.safety_events;
  d["latches"] = s.latches;
  d["last_latch"] = safety_events::names(s.last_latch);
  d["recoveries"] = s.recoveries;
  d["rate_hz"] = s.rate;
  d["period_mean_s"] = s.period_mean;
  d["period_p50_s"] = s.period_p50;
  d["period_p99_s"] = s.period_p99;
  d["period_p999_s"] = s.period_p999;
  d["period_max_s"] = s.period_max;
  d["wake_p99_s"] = s.wake_p99;
  d["compute_p50_s"] = s.compute_p50;
  d["compute_p99_s"] = s.compute_p99;
  d["compute_max_s"] = s.compute_max;
  d["peak_force_n"] = s.peak_force;
  d["look_aheads"] = s.look_aheads;            // ticks anticipated before their deadline (run_servo's anticipate)
  d["look_aheads_late"] = s.look_aheads_late;  // of those, run past the deadline
  return d;
}

/// An allocation counter preloaded into the process (python/tests/alloc/alloc_counter.c)
/// exports these: malloc and free calls made so far on the calling thread. Null without one.
using AllocationCount = unsigned long (*)();
AllocationCount counter_function(const char* name) {
  return reinterpret_cast<AllocationCount>(dlsym(RTLD_DEFAULT, name));
}
/// The counter's switch: starts (1) or stops (0) counting the calling thread, clearing its counts.
using CountHere = void (*)(int);

}  // namespace

/// A token that stops run_servo from any thread (ServoStop in Python).
struct StopToken {
  std::atomic<bool> requested{false};
  std::atomic<int> running{0};  ///< runs in progress that were given this token
};

namespace {

/// The interrupt a signal handler raised while a loop ran (a KeyboardInterrupt for Ctrl-C), held until
/// the loop has stopped and the result is built. Touched only with the GIL held.
struct PendingInterrupt {
  PyObject* type = nullptr;
  PyObject* value = nullptr;
  PyObject* traceback = nullptr;
  explicit operator bool() const noexcept { return type != nullptr; }
  /// Raises it again with `result` attached as its `result` attribute.
  [[noreturn]] void raise_with(const py::dict& result) {
    PyErr_NormalizeException(&type, &value, &traceback);
    if (value && PyObject_SetAttrString(value, "result", result.ptr()) != 0) PyErr_Clear();
    PyErr_Restore(type, value, traceback);
    type = value = traceback = nullptr;
    throw py::error_already_set();
  }
  ~PendingInterrupt() {
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(traceback);
  }
};

/// Runs `loop` on a thread of its own while the calling thread, the GIL released, watches every few ms for a
/// signal (Ctrl-C: Python's handler runs here, on the calling thread, the GIL taken for that moment only) and
/// for the token: either asks the loop to stop (zero force, disarm) at its next tick. The loop thread never
/// takes the GIL. Returns the loop's reason; the loop's own exception is rethrown here.
template <class Loop, class Callback>
StopReason run_watched(Loop& loop, Callback& callback, std::uint64_t ticks, StopToken* token,
                       PendingInterrupt& interrupt, long& loop_mallocs, long& loop_frees) {
  static const AllocationCount mallocs = counter_function("hapticfield_malloc_calls");
  static const AllocationCount frees = counter_function("hapticfield_free_calls");
  static const auto count_here = reinterpret_cast<CountHere>(dlsym(RTLD_DEFAULT, "hapticfield_count_here"));
  const bool counted = mallocs && frees && count_here;
  StopReason reason = StopReason::requested;
  std::exception_ptr error;
  std::mutex m;
  std::condition_variable ended;
  bool done = false;
  struct Running {  // StopToken::running for the length of the call
    StopToken* token;
    explicit Running(StopToken* t) noexcept : token(t) {
      if (token) token->running.fetch_add(1);
    }
    ~Running() {
      if (token) token->running.fetch_sub(1);
    }
  } running(token);
  {
    py::gil_scoped_release release;  // Python never runs inside a tick
    std::thread worker([&]() noexcept {
      // The loop thread is counted from here: the loop alone, not its setup.
      if (counted) count_here(1);
      try {
        reason = loop.run(callback, {.max_ticks = ticks});
      } catch (...) {
        error = std::current_exception();
      }
      if (counted) {
        loop_mallocs = static_cast<long>(mallocs()), loop_frees = static_cast<long>(frees());
        count_here(0);
      }
      {
        std::lock_guard<std::mutex> lock(m);
        done = true;
      }
      ended.notify_all();
    });
    bool stop_sent = false;
    std::unique_lock<std::mutex> lock(m);
    while (!ended.wait_for(lock, std::chrono::milliseconds(4), [&] { return done; })) {
      if (stop_sent) continue;
      if (token && token->requested.load()) {
        loop.request_stop();
        stop_sent = true;
        continue;
      }
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) {  // a handler raised: stop, and raise it once the loop has
          PyErr_Fetch(&interrupt.type, &interrupt.value, &interrupt.traceback);
          loop.request_stop();
          stop_sent = true;
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  if (error) std::rethrow_exception(error);
  return reason;
}

template <Device D, ServoClock C>
py::dict run_on(D& device, C& clock, Field& field, double seconds, double rate, RealTime realtime, bool anticipate,
                StopToken* token) {
  LoopConfig config;
  config.rate = rate;
  config.realtime = realtime;
  config.anticipate = anticipate;
  config.recover_after = 0.5;  // [s] fresh states before re-arming after a latch
  const auto ticks = static_cast<std::uint64_t>(std::llround(seconds * rate));
  std::vector<TraceRow> rows;
  rows.reserve(ticks + 8);  // the tick only fills reserved rows
  TracedDevice<D> traced(device, rows);
  ServoLoop<TracedDevice<D>, C> loop(traced, clock, config);
  std::shared_ptr<AnyField> f = field.impl;
  auto callback = [&](const TickInput& in) noexcept {
    traced.open(in);
    return f->force(in.probe);
  };
  if (token && token->requested.load()) loop.request_stop();  // a request made before the run ends it at once
  PendingInterrupt interrupt;
  long loop_mallocs = -1, loop_frees = -1;
  auto ahead = with_anticipation(callback, *f);  // a shape's proxy looks ahead before each deadline
  const StopReason reason = run_watched(loop, ahead, ticks, token, interrupt, loop_mallocs, loop_frees);
  const py::ssize_t n = static_cast<py::ssize_t>(rows.size());
  py::array_t<double> t(n);
  py::array_t<bool> homed(n), armed(n);
  auto position = matrix(n, 3), force = matrix(n, 3);
  for (py::ssize_t i = 0; i < n; ++i) {
    const TraceRow& r = rows[static_cast<std::size_t>(i)];
    t.mutable_at(i) = r.t;
    homed.mutable_at(i) = r.homed, armed.mutable_at(i) = r.armed;
    for (int k = 0; k < 3; ++k)
      position.mutable_at(i, k) = r.position[k], force.mutable_at(i, k) = r.force[k];
  }
  // The tick period histogram in 1 us bins: counts from the loop's own statistics.
  const DurationHistogram& periods = loop.detailed_statistics().periods();
  py::array_t<std::uint64_t> hist(static_cast<py::ssize_t>(DurationHistogram::bins));
  for (std::size_t i = 0; i < DurationHistogram::bins; ++i)
    hist.mutable_at(static_cast<py::ssize_t>(i)) = periods.bin(i);
  py::dict trace;
  trace["t"] = t;
  trace["position"] = position;
  trace["force"] = force;
  trace["homed"] = homed;
  trace["armed"] = armed;
  py::dict result;
  result["statistics"] = snapshot_dict(loop.statistics());
  result["trace"] = trace;
  result["period_histogram"] = hist;
  result["histogram_bin_s"] = DurationHistogram::bin_ns * 1e-9;
  result["nominal_period_s"] = loop.period();
  result["max_force_n"] = device.info().max_force;
  result["final_force"] = std::vector<double>{traced.last_written().x, traced.last_written().y,
                                              traced.last_written().z};  // what the arm was left with [N]
  if (loop_mallocs >= 0) {
    result["loop_allocations"] = loop_mallocs;
    result["loop_frees"] = loop_frees;
  } else {
    result["loop_allocations"] = py::none();
    result["loop_frees"] = py::none();
  }
  result["stop_reason"] = interrupt                            ? "interrupted"
                          : reason == StopReason::tick_limit   ? "tick_limit"
                          : reason == StopReason::disconnected ? "disconnected"
                                                               : "requested";
  if (interrupt) interrupt.raise_with(result);
  return result;
}

/// The arm `spec` names, opened through the front door on `clock`; a
/// simulated one held by the scripted hand.
template <ServoClock C>
py::dict run_device(const DeviceSpec& spec, C& clock, Field& field, double seconds, double rate, RealTime rt,
                    bool anticipate, const std::string& hand, const V3& hand_centre, double hand_size,
                    double hand_speed, StopToken* token) {
  DeviceOptions options;
  options.now = [&clock] { return clock.now(); };
  if (spec.simulated) {
    options.hand.path = hand_path(hand, hand_centre, hand_size, hand_speed);
    options.hand.path.validate();
  }
  AnyDevice arm = open_device(spec, options);
  return run_on(arm, clock, field, seconds, rate, rt, anticipate, token);
}

/// A device string checked by the front door; a bad one is a ValueError
/// naming it.
DeviceSpec device_spec(const std::string& device) {
  try {
    return parse_device_spec(device);
  } catch (const DeviceSpecError& e) {
    throw py::value_error(e.what());
  }
}

py::dict run_servo(Field& field, double seconds, double rate, const std::string& device, const std::string& hand,
                   const V3& hand_centre, double hand_size, double hand_speed, const std::string& realtime,
                   bool confirm_hardware, const std::optional<std::string>& clock_name,
                   const std::shared_ptr<StopToken>& stop, bool anticipate) {
  const DeviceSpec spec = device_spec(device);
  const bool real_arm = !spec.simulated;
  // The simulated arm runs on the virtual clock unless told otherwise: what a run renders is then the same on
  // any machine, however loaded. A real arm lives in real time.
  const std::string clock_kind = clock_name.value_or(real_arm ? "wall" : "virtual");
  if (clock_kind != "wall" && clock_kind != "virtual")
    throw py::value_error("clock: unknown '" + clock_kind + "' (choose wall or virtual)");
  const bool virtual_time = clock_kind == "virtual";
  if (virtual_time && real_arm)
    throw py::value_error(
        "clock: the virtual clock cannot drive a real arm, which moves in real time; use "
        "clock='wall' (the default for a real arm)");
  if (virtual_time && realtime != "off")
    throw py::value_error("realtime: '" + realtime +
                          "' is for the wall clock; a virtual run never sleeps and would "
                          "hold a CPU at real-time priority (use realtime='off' or clock='wall')");
  if (!(std::isfinite(seconds) && seconds > 0.0 && seconds <= 3600.0))
    throw py::value_error("seconds: must be within (0, 3600] [s]");
  if (!(std::isfinite(rate) && rate >= 1.0 && rate <= 10000.0))
    throw py::value_error("rate: must be within [1, 10000] [Hz]");
  if (std::llround(seconds * rate) < 1) throw py::value_error("seconds: gives no tick at this rate");
  RealTime rt = RealTime::off;
  if (realtime == "best_effort")
    rt = RealTime::best_effort;
  else if (realtime == "enforce")
    rt = RealTime::enforce;
  else if (realtime != "off")
    throw py::value_error("realtime: unknown '" + realtime + "' (choose off, best_effort or enforce)");
  const FieldUse use(field);  // for the whole run: no other thread evaluates the field or its parts meanwhile
  if (real_arm && !confirm_hardware)
    throw py::value_error("device " + device +
                          ": a real arm will move and push; pass confirm_hardware=True once the "
                          "handle is held and the workspace clear");
  if (virtual_time) {
    // Every video the field is made of waits for its frames at each tick for the run: the worker has no
    // real time to keep up with.
    struct Lockstep {
      const Guards& guards;
      explicit Lockstep(const Guards& g) : guards(g) {
        for (const auto& guard : guards)
          if (guard->lockstep) guard->lockstep(true);
      }
      ~Lockstep() {
        for (const auto& guard : guards)
          if (guard->lockstep) guard->lockstep(false);
      }
    } lockstep(field.guards);
    VirtualClock clock;
    return run_device(spec, clock, field, seconds, rate, rt, anticipate, hand, hand_centre, hand_size, hand_speed,
                      stop.get());
  }
  // Every simulator the field is made of (a MuJoCo scene) steps on its own thread in real time for the run.
  struct RealTimeSimulators {
    const Guards& guards;
    explicit RealTimeSimulators(const Guards& g) : guards(g) {
      for (const auto& guard : guards)
        if (guard->real_time) guard->real_time(true);
    }
    ~RealTimeSimulators() {
      for (const auto& guard : guards)
        if (guard->real_time) guard->real_time(false);
    }
  } simulators(field.guards);
  SteadyClock clock;
  return run_device(spec, clock, field, seconds, rate, rt, anticipate, hand, hand_centre, hand_size, hand_speed,
                    stop.get());
}

}  // namespace

void bind_servo(py::module_& m) {
  py::class_<StopToken, std::shared_ptr<StopToken>>(
      m, "ServoStop",
      "A token that stops run_servo from another thread: pass it as run_servo(..., stop=token) and call "
      "token.request() from any thread; the loop stops within a few ms (zero force, slew, disarm) and run_servo "
      "returns what it recorded with stop_reason 'requested'. A requested token stays requested, so it also ends "
      "any later run it is given before its first tick, until clear().")
      .def(py::init<>())
      .def(
          "request", [](StopToken& t) { t.requested.store(true); },
          "Asks every run given this token to stop (any thread; returns at once).")
      .def(
          "clear", [](StopToken& t) { t.requested.store(false); },
          "Withdraws the request, so that the token can be given to a new run.")
      .def_property_readonly(
          "requested", [](const StopToken& t) { return t.requested.load(); }, "True once request() was called.")
      .def_property_readonly(
          "running", [](const StopToken& t) { return t.running.load() > 0; },
          "True while a run given this token is in progress.");
  m.def("run_servo", &run_servo, py::arg("field"), py::arg("seconds") = 1.0, py::arg("rate") = 1000.0,
        py::arg("device") = "sim", py::arg("hand") = "raster", py::arg("hand_centre") = V3{0.0, 0.0, -0.008},
        py::arg("hand_size") = 0.06, py::arg("hand_speed") = 0.06, py::arg("realtime") = "off",
        py::arg("confirm_hardware") = false, py::arg("clock") = py::none(), py::arg("stop") = py::none(),
        py::arg("anticipate") = true,
        "Runs the 1 kHz servo loop (absolute deadlines, the safety chain) on a field for seconds [s] at rate [Hz] "
        "and returns a dict: statistics (rate, periods [s], deadlines, safety events, peak force [N], look_aheads and "
        "look_aheads_late: ticks anticipated, and run past their deadline), trace "
        "(one row a tick: t [s], position N x 3 [m], force N x 3 [N] as that tick commanded after the safety chain, "
        "homed and armed N booleans: the tick's device state, False before homing / arming), period_histogram "
        "(counts per histogram_bin_s), stop_reason, final_force (the last force written to the arm [N], the stop's "
        "zero after a stop), and loop_allocations / loop_frees (malloc / free calls on this "
        "thread while the loop ran, when an allocation counter is preloaded as in python/tests/test_alloc.py; None "
        "otherwise). device: any string the device front door opens (list_devices() names them and says which "
        "are present): sim, woody:GEN[:PRESET]:sim and inverse3:sim are simulated arms, held by a scripted hand "
        "(raster|circle|hold around hand_centre [m], hand_size [m], hand_speed [m/s]); hid[:VID:PID], "
        "serial:PATH, woody:GEN[:PRESET][:PATH] and inverse3:PATH are real arms "
        "(they need confirm_hardware=True). clock virtual (the default for a simulated arm): the loop runs on "
        "simulated time as "
        "fast as the CPU allows, with the same ticks, safety chain and trace as in real time, so a run renders "
        "the same forces on any machine (its timing statistics are nominal: every period exact, compute time 0); "
        "wall (the default for a real arm, the only choice there): real time, for timing studies and live interaction. "
        "realtime off|best_effort|enforce (SCHED_FIFO; wall clock only). The loop runs on a thread of its own, "
        "evaluating the field in C++, never taking the GIL; the calling thread waits with the GIL released. "
        "stop: a ServoStop token another thread can request() to end the run (stop_reason 'requested'). Ctrl-C "
        "(any exception a signal handler raises) stops the loop within a few ms with zero force and is then "
        "raised, the result attached as its `result` attribute (stop_reason 'interrupted'): "
        "`except KeyboardInterrupt as e: run = e.result`. anticipate (default True): before each deadline a "
        "shape's proxy runs the coming tick on a copy, on the last position moved one period by its velocity, "
        "so that the part of the mesh it reads is in cache when the tick runs (LoopConfig::anticipate); the "
        "forces are the same without it, only the tick's time differs.");
  m.def(
      "list_devices",
      [] {
        std::vector<std::tuple<std::string, bool, std::string>> out;
        for (const DeviceListing& listing : list_devices())
          out.emplace_back(listing.family, listing.present, listing.line);
        return out;
      },
      "Every arm family the device front door knows, one (family, present, line) tuple each: line says what strings "
      "it takes and that an arm is present, or why not (library not built in, no device found, permission "
      "denied). Probes only: nothing moves.");
}

}  // namespace hapticfield::python
