// Vendor SDK arms loaded at run time (arms/openhaptics/, arms/dhd/) against
// stand-in libHD / libdhd built by the tests (tests/standins/): the
// documented constants pinned, the library seam's errors, every fault the
// stand-ins can raise, units and frames at the boundary, and the servo
// loop's stop, latch and restart semantics on both arms.
#include <catch2/catch.hpp>

#include <dlfcn.h>
#include <stdlib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "alloc_counter.hpp"
#include "child_process.hpp"
#include "device_suite.hpp"
#include "hapticfield/arms/dhd.hpp"
#include "hapticfield/arms/dynamic_library.hpp"
#include "hapticfield/arms/openhaptics.hpp"
#include "hapticfield/devices/open_device.hpp"
#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/loop.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "hapticfield/surface/shape.hpp"
#include "run_seed.hpp"

using namespace hapticfield;

namespace {

/// The stand-ins' control functions, from the same loaded copies the
/// adapters load (dlopen of the same path gives the same library).
struct HdStandin {
  DynamicLibrary lib = DynamicLibrary::open_first("HD stand-in", {HAPTICFIELD_STANDIN_HD});
  void (*step)(int) = lib.get<void (*)(int)>("hfstandin_hd_step");
  long (*ticks)() = lib.get<long (*)()>("hfstandin_hd_ticks");
  void (*last_force)(double*) = lib.get<void (*)(double*)>("hfstandin_hd_last_force");
  void (*position)(double*) = lib.get<void (*)(double*)>("hfstandin_hd_position");
  int (*shutdown_order_ok)() = lib.get<int (*)()>("hfstandin_hd_shutdown_order_ok");
  long (*frames_outside_callback)() = lib.get<long (*)()>("hfstandin_hd_frames_outside_callback");
  int (*initiated)() = lib.get<int (*)()>("hfstandin_hd_initiated");
  void (*inject)(const char*) = lib.get<void (*)(const char*)>("hfstandin_hd_inject");

  [[nodiscard]] glm::dvec3 force() const {
    glm::dvec3 f;
    last_force(&f.x);
    return f;
  }
  [[nodiscard]] glm::dvec3 position_mm() const {
    glm::dvec3 p;
    position(&p.x);
    return p;
  }
};
HdStandin& hd_standin() {
  static HdStandin s;
  return s;
}

struct DhdStandin {
  DynamicLibrary lib = DynamicLibrary::open_first("DHD stand-in", {HAPTICFIELD_STANDIN_DHD});
  void (*last_force)(double*) = lib.get<void (*)(double*)>("hfstandin_dhd_last_force");
  long (*expert_calls)() = lib.get<long (*)()>("hfstandin_dhd_expert_calls");
  int (*force_enabled)() = lib.get<int (*)()>("hfstandin_dhd_force_enabled");
  void (*position)(double*) = lib.get<void (*)(double*)>("hfstandin_dhd_position");
  void (*inject)(const char*) = lib.get<void (*)(const char*)>("hfstandin_dhd_inject");

  [[nodiscard]] glm::dvec3 force() const {
    glm::dvec3 f;
    last_force(&f.x);
    return f;
  }
};
DhdStandin& dhd_standin() {
  static DhdStandin s;
  return s;
}

/// Virtual time in which every loop period is one HD tick: the stand-in's
/// scheduler runs in lockstep, one tick per sleep, on the test's thread.
struct HdTickClock {
  VirtualClock virtual_time;
  [[nodiscard]] std::int64_t now() const noexcept { return virtual_time.now(); }
  void sleep_until(std::int64_t t) noexcept {
    hd_standin().step(1);
    virtual_time.sleep_until(t);
  }
};

OpenHapticsConfig hd_config() {
  OpenHapticsConfig c;
  c.library = HAPTICFIELD_STANDIN_HD;
  c.shutdown_wait_ms = 0;  // lockstep: no tick comes by itself
  return c;
}
DhdConfig dhd_config(VirtualClock& clock) {
  DhdConfig c;
  c.library = HAPTICFIELD_STANDIN_DHD;
  c.now = [&clock] { return clock.now(); };
  return c;
}
LoopConfig quiet_loop() {
  LoopConfig c;
  c.realtime = RealTime::off;
  return c;
}

/// A spring to a point 1 cm off the handle's path: force everywhere.
auto spring() {
  return [](const TickInput& in) { return -200.0 * (in.probe.position - glm::dvec3{0.0, 0.01, 0.0}); };
}

/// An environment variable set for a scope, then restored.
struct Env {
  Env(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) {
      had_ = true;
      old_ = old;
    }
    setenv(name, value, 1);
  }
  ~Env() {
    if (had_)
      setenv(name_, old_.c_str(), 1);
    else
      unsetenv(name_);
  }
  Env(const Env&) = delete;
  Env& operator=(const Env&) = delete;
  const char* name_;
  std::string old_;
  bool had_{false};
};

}  // namespace

TEST_CASE("HD constants have their documented values", "[vendor][openhaptics]") {
  // hdDefines.h / hdScheduler.h values (docs/arms-openhaptics.md): hand-written
  // copies in public code swap CONTINUE and DONE, give a priority of 500 or
  // a two-field HDErrorInfo, or NOMINAL_MAX_FORCE as 0x2604.
  STATIC_REQUIRE(hd::callback_done == 0);
  STATIC_REQUIRE(hd::callback_continue == 1);
  STATIC_REQUIRE(hd::wait_check_status == 0);
  STATIC_REQUIRE(hd::wait_infinite == 1);
  STATIC_REQUIRE(hd::min_scheduler_priority == 0);
  STATIC_REQUIRE(hd::max_scheduler_priority == 65535);
  STATIC_REQUIRE(hd::default_scheduler_priority == 32767);
  STATIC_REQUIRE(hd::invalid_handle == 0xFFFFFFFFu);
  STATIC_REQUIRE(hd::success == 0);
  STATIC_REQUIRE(sizeof(hd::ErrorInfo) == 12);
  STATIC_REQUIRE(sizeof(hd::Handle) == 4);
  STATIC_REQUIRE(sizeof(hd::Boolean) == 1);
  STATIC_REQUIRE(sizeof(hd::UShort) == 2);
  STATIC_REQUIRE(sizeof(hd::SchedulerHandle) == sizeof(unsigned long));
  STATIC_REQUIRE(hd::current_buttons == 0x2000);
  STATIC_REQUIRE(hd::current_safety_switch == 0x2001);
  STATIC_REQUIRE(hd::current_inkwell_switch == 0x2002);
  STATIC_REQUIRE(hd::current_position == 0x2050);
  STATIC_REQUIRE(hd::current_velocity == 0x2051);
  STATIC_REQUIRE(hd::current_transform == 0x2052);
  STATIC_REQUIRE(hd::current_angular_velocity == 0x2053);
  STATIC_REQUIRE(hd::current_jacobian == 0x2054);
  STATIC_REQUIRE(hd::current_joint_angles == 0x2100);
  STATIC_REQUIRE(hd::current_gimbal_angles == 0x2150);
  STATIC_REQUIRE(hd::current_position + hd::last_offset == 0x2250);
  STATIC_REQUIRE(hd::device_model_type == 0x2501);
  STATIC_REQUIRE(hd::device_serial_number == 0x2504);
  STATIC_REQUIRE(hd::max_workspace_dimensions == 0x2550);
  STATIC_REQUIRE(hd::usable_workspace_dimensions == 0x2551);
  STATIC_REQUIRE(hd::update_rate == 0x2600);
  STATIC_REQUIRE(hd::instantaneous_update_rate == 0x2601);
  STATIC_REQUIRE(hd::nominal_max_stiffness == 0x2602);
  STATIC_REQUIRE(hd::nominal_max_force == 0x2603);
  STATIC_REQUIRE(hd::nominal_max_continuous_force == 0x2604);
  STATIC_REQUIRE(hd::motor_temperature == 0x2605);
  STATIC_REQUIRE(hd::software_velocity_limit == 0x2606);
  STATIC_REQUIRE(hd::software_force_impulse_limit == 0x2607);
  STATIC_REQUIRE(hd::force_ramping_rate == 0x2608);
  STATIC_REQUIRE(hd::nominal_max_damping == 0x2609);
  STATIC_REQUIRE(hd::current_force == 0x2700);
  STATIC_REQUIRE(hd::current_torque == 0x2701);
  STATIC_REQUIRE(hd::current_joint_torque == 0x2703);
  STATIC_REQUIRE(hd::current_gimbal_torque == 0x2704);
  STATIC_REQUIRE(hd::last_force == 0x2800);
  STATIC_REQUIRE(hd::force_output == 0x4000);
  STATIC_REQUIRE(hd::max_force_clamping == 0x4001);
  STATIC_REQUIRE(hd::force_ramping == 0x4002);
  STATIC_REQUIRE(hd::software_force_limit == 0x4003);
  STATIC_REQUIRE(hd::one_frame_limit == 0x4004);
  STATIC_REQUIRE(hd::calibration_ok == 0x5000);
  STATIC_REQUIRE(hd::calibration_needs_update == 0x5001);
  STATIC_REQUIRE(hd::calibration_needs_manual_input == 0x5002);
  STATIC_REQUIRE(hd::invalid_enum == 0x100);
  STATIC_REQUIRE(hd::bad_handle == 0x104);
  STATIC_REQUIRE(hd::warm_motors == 0x200);
  STATIC_REQUIRE(hd::exceeded_max_force == 0x201);
  STATIC_REQUIRE(hd::exceeded_max_force_impulse == 0x202);
  STATIC_REQUIRE(hd::exceeded_max_velocity == 0x203);
  STATIC_REQUIRE(hd::force_error == 0x204);
  STATIC_REQUIRE(hd::device_fault == 0x300);
  STATIC_REQUIRE(hd::device_already_initiated == 0x301);
  STATIC_REQUIRE(hd::comm_error == 0x302);
  STATIC_REQUIRE(hd::timer_error == 0x304);
  STATIC_REQUIRE(hd::illegal_begin == 0x400);
  STATIC_REQUIRE(hd::scheduler_full == 0x501);
  STATIC_REQUIRE(hd::invalid_license == 0x600);
  CHECK(std::string(hd::library_name) == "libHD.so");
}

TEST_CASE("DHD constants have their documented values", "[vendor][dhd]") {
  STATIC_REQUIRE(dhd::ok == 0);
  STATIC_REQUIRE(dhd::failed == -1);
  STATIC_REQUIRE(dhd::timeguard == 1);
  STATIC_REQUIRE(dhd::motor_saturated == 2);
  STATIC_REQUIRE(dhd::no_error == 0);
  STATIC_REQUIRE(dhd::error == 1);
  STATIC_REQUIRE(dhd::error_com == 2);
  STATIC_REQUIRE(dhd::error_no_device_found == 5);
  STATIC_REQUIRE(dhd::error_timeout == 7);
  STATIC_REQUIRE(dhd::error_expert_mode_disabled == 9);
  STATIC_REQUIRE(dhd::error_device_not_ready == 12);
  STATIC_REQUIRE(dhd::error_device_in_use == 20);
  STATIC_REQUIRE(dhd::error_no_regulation == 22);
  STATIC_REQUIRE(dhd::device_omega3 == 33);
  STATIC_REQUIRE(dhd::device_falcon == 60);
  STATIC_REQUIRE(dhd::device_delta3 == 63);
  STATIC_REQUIRE(dhd::device_sigma7_right == 104);
  STATIC_REQUIRE(dhd::device_lambda7_right == 108);
  CHECK(std::string(dhd::library_names[0]) == "libdhd.so.3");
  CHECK(std::string(dhd::library_names[1]) == "libdhd.so");
}

TEST_CASE("DynamicLibrary: a missing library or symbol is one clear error", "[vendor]") {
  SECTION("every name tried is named, with the loader's reason") {
    try {
      (void)DynamicLibrary::open_first("Test SDK", {"libhapticfield-nonexistent.so", "/nonexistent/libx.so.3"});
      FAIL("loaded a library that does not exist");
    } catch (const LibraryError& e) {
      const std::string what = e.what();
      CHECK(what.find("Test SDK") != std::string::npos);
      CHECK(what.find("libhapticfield-nonexistent.so") != std::string::npos);
      CHECK(what.find("/nonexistent/libx.so.3") != std::string::npos);
      CHECK(what.find("installed") != std::string::npos);
    }
  }
  SECTION("the first name that loads is used") {
    const DynamicLibrary l = DynamicLibrary::open_first("x", {"/nonexistent/libx.so", HAPTICFIELD_STANDIN_DHD});
    CHECK(l.loaded());
    CHECK(l.name() == HAPTICFIELD_STANDIN_DHD);
    CHECK(l.find<int (*)()>("dhdGetDeviceCount") != nullptr);
    CHECK(l.find<int (*)()>("hdInitDevice") == nullptr);
  }
  SECTION("the override variable is the only name tried") {
    Env env("HAPTICFIELD_TEST_LIBRARY", "/nonexistent/override.so");
    try {
      (void)DynamicLibrary::open_first("x", {HAPTICFIELD_STANDIN_DHD}, "HAPTICFIELD_TEST_LIBRARY");
      FAIL("the override was ignored");
    } catch (const LibraryError& e) {
      CHECK(std::string(e.what()).find("/nonexistent/override.so (from HAPTICFIELD_TEST_LIBRARY)") !=
            std::string::npos);
    }
  }
  SECTION("a library without a documented symbol names the symbol") {
    OpenHapticsConfig c;
    c.library = HAPTICFIELD_STANDIN_DHD;  // a DHD library is no libHD
    CHECK_THROWS_WITH(OpenHapticsDevice(c), Catch::Contains("has no symbol hdInitDevice"));
    DhdConfig d;
    d.library = HAPTICFIELD_STANDIN_HD;
    CHECK_THROWS_WITH(DhdDevice(d), Catch::Contains("has no symbol dhdGetDeviceCount"));
  }
  SECTION("without the SDK the adapters say which library is missing") {
    unsetenv("HAPTICFIELD_HD_LIBRARY");
    unsetenv("HAPTICFIELD_DHD_LIBRARY");
    if (void* h = dlopen("libHD.so", RTLD_NOW | RTLD_NOLOAD)) {
      dlclose(h);
    } else if (void* real = dlopen("libHD.so", RTLD_NOW)) {
      dlclose(real);  // a machine with OpenHaptics installed: nothing to check
    } else {
      CHECK_THROWS_AS(OpenHapticsDevice(), LibraryError);
      CHECK_THROWS_WITH(OpenHapticsDevice(), Catch::Contains("libHD.so"));
    }
    if (void* real = dlopen("libdhd.so.3", RTLD_NOW)) {
      dlclose(real);
    } else {
      CHECK_THROWS_WITH(DhdDevice(), Catch::Contains("libdhd.so.3") && Catch::Contains("libdhd.so"));
    }
  }
}

TEST_CASE("OpenHaptics: start-up faults give one clear error", "[vendor][openhaptics]") {
  HdStandin& s = hd_standin();
  SECTION("no device") {
    Env env("HFSTANDIN_HD", "init_fails,lockstep");
    CHECK_THROWS_WITH(OpenHapticsDevice(hd_config()), Catch::Contains("hdInitDevice") &&
                                                          Catch::Contains("HD_DEVICE_FAULT (0x300)") &&
                                                          Catch::Contains("Touch_Setup"));
  }
  SECTION("calibration needed") {
    Env env("HFSTANDIN_HD", "calibration,lockstep");
    CHECK_THROWS_WITH(OpenHapticsDevice(hd_config()),
                      Catch::Contains("needs calibration") && Catch::Contains("NEEDS_MANUAL_INPUT"));
    CHECK(s.initiated() == 0);  // disabled again
  }
  SECTION("a device a crashed run left initiated is disabled and initialised again") {
    Env env("HFSTANDIN_HD", "already_initiated,lockstep");
    OpenHapticsDevice device(hd_config());
    CHECK(device.model() == "Stand-in Touch");
    CHECK(device.info().max_force == Approx(3.3));
    CHECK(device.info().continuous_force == Approx(0.88));
    CHECK(device.info().workspace_min.x == Approx(-0.080));  // mm to m
    CHECK(device.info().workspace_max.z == Approx(0.035));
  }
  SECTION("bad settings") {
    OpenHapticsConfig c = hd_config();
    c.scheduler_rate = 0.0;
    CHECK_THROWS_AS(OpenHapticsDevice(c), std::invalid_argument);
  }
  CHECK(s.initiated() == 0);
  CHECK(s.shutdown_order_ok() == 1);
}

TEST_CASE("OpenHaptics: the loop runs on HD's ticks with mm to m and zero force at stop", "[vendor][openhaptics]") {
  Env env("HFSTANDIN_HD", "lockstep");
  HdStandin& s = hd_standin();
  HdTickClock clock;
  {
    OpenHapticsDevice device(hd_config());
    ServoLoop loop(device, clock, quiet_loop());
    auto f = spring();
    int checked = 0;
    auto check_units = [&](const TickInput& in) {
      if (in.read_status == Status::ok) {
        // The state is this tick's: HD's axes are ours, mm to m.
        const glm::dvec3 mm = s.position_mm();
        CHECK(glm::length(in.state.position - mm * 1e-3) < 1e-12);
        ++checked;
      }
      return f(in);
    };
    REQUIRE(loop.run(check_units, {.max_ticks = 1000}) == StopReason::tick_limit);
    CHECK(checked >= 998);
    const LoopSnapshot st = loop.statistics();
    CHECK(st.latches == 0);
    CHECK(st.peak_force > 1.0);      // force got through the soft start
    CHECK(loop.trusted() == false);  // stopped: nothing to steer by
    // The stop's zero reaches the arm on the next HD tick.
    s.step(1);
    CHECK(glm::length(s.force()) == 0.0);

    SECTION("a force reaches the arm on the next HD tick, unchanged") {
      int compared = 0;
      auto track = [&](const TickInput& in) {
        if (in.read_status == Status::ok && in.tick > 1) {  // the HD tick just run applied the last command
          CHECK(glm::length(s.force() - loop.last_command()) < 1e-12);
          ++compared;
        }
        return glm::dvec3{0.3, -0.2, 0.1};
      };
      loop.run(track, {.max_ticks = 300});
      CHECK(compared >= 297);
      CHECK(loop.last_command() == glm::dvec3{0.0});
      s.step(1);
      CHECK(glm::length(s.force()) == 0.0);
    }
    SECTION("a restart ramps up from zero (the soft start again)") {
      std::vector<double> first;
      auto watch = [&](const TickInput&) {
        if (first.size() < 20) first.push_back(glm::length(s.force()));
        return glm::dvec3{2.0, 0.0, 0.0};
      };
      loop.reset_statistics();
      loop.run(watch, {.max_ticks = 400});
      for (std::size_t i = 0; i < first.size(); ++i)
        CHECK(first[i] <= 1000.0 * 1e-3 * static_cast<double>(i + 1) + 1e-9);  // slew: 1000 N/s
      CHECK(loop.statistics().peak_force == Approx(2.0));
    }
  }
  CHECK(s.shutdown_order_ok() == 1);
  CHECK(s.frames_outside_callback() == 0);
  CHECK(s.initiated() == 0);
}

TEST_CASE("OpenHaptics: faults mid-run latch with zero force", "[vendor][openhaptics]") {
  HdStandin& s = hd_standin();
  HdTickClock clock;
  auto f = spring();
  SECTION("a device error (HD_COMM_ERROR) stops the run as a lost device") {
    Env env("HFSTANDIN_HD", "lockstep,device_error_at=500");
    OpenHapticsDevice device(hd_config());
    ServoLoop loop(device, clock, quiet_loop());
    CHECK(loop.run(f, {.max_ticks = 2000}) == StopReason::disconnected);
    CHECK(loop.safety().latched() & safety_events::disconnected);
    CHECK(device.last_error().find("HD_COMM_ERROR") != std::string::npos);
    s.step(1);
    CHECK(glm::length(s.force()) == 0.0);
  }
  SECTION("an impossible (non-finite) pose latches") {
    Env env("HFSTANDIN_HD", "lockstep,nan_at=500");
    OpenHapticsDevice device(hd_config());
    ServoLoop loop(device, clock, quiet_loop());
    CHECK(loop.run(f, {.max_ticks = 1000}) == StopReason::tick_limit);
    CHECK(loop.safety().latched() & safety_events::impossible_state);
    s.step(1);
    CHECK(glm::length(s.force()) == 0.0);
  }
  SECTION("HD_EXCEEDED_MAX_FORCE is a device fault: zero force until cleared") {
    Env env("HFSTANDIN_HD", "lockstep,exceeded_at=500");
    OpenHapticsDevice device(hd_config());
    ServoLoop loop(device, clock, quiet_loop());
    CHECK(loop.run(f, {.max_ticks = 1000}) == StopReason::tick_limit);
    CHECK(device.counters().guard_errors == 1);
    CHECK(loop.state().faulted());
    CHECK(glm::length(s.force()) == 0.0);
    CHECK(device.clear_fault() == Status::ok);
  }
  SECTION("a scheduler that stops calling latches the stale-state watchdog") {
    Env env("HFSTANDIN_HD", "lockstep,scheduler_stops_at=500");
    OpenHapticsDevice device(hd_config());
    ServoLoop loop(device, clock, quiet_loop());
    CHECK(loop.run(f, {.max_ticks = 1000}) == StopReason::tick_limit);
    CHECK(loop.safety().latched() & safety_events::stale_state);
    CHECK(loop.last_command() == glm::dvec3{0.0});
  }
  CHECK(s.shutdown_order_ok() == 1);
}

TEST_CASE("OpenHaptics: HD's own scheduler thread at 1 kHz, stopped from another thread", "[vendor][openhaptics]") {
  // The stand-in's scheduler runs on its own thread in real time here; the
  // checks hold whatever the machine's speed.
  HdStandin& s = hd_standin();
  SteadyClock clock;
  {
    OpenHapticsConfig c = hd_config();
    c.shutdown_wait_ms = 1000;  // the scheduler thread runs ticks by itself here
    OpenHapticsDevice device(c);
    LoopConfig lc = quiet_loop();
    lc.safety.watchdog_enabled = false;  // a loaded test machine may starve either thread
    ServoLoop loop(device, clock, lc);
    auto f = spring();
    std::thread stopper([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      loop.request_stop();  // as Ctrl-C does
    });
    CHECK(loop.run(f) == StopReason::requested);
    stopper.join();
    CHECK(device.scheduler_ticks() > 0);
  }  // the destructor waits for a tick that commands zero, then stops the scheduler
  CHECK(glm::length(s.force()) == 0.0);
  CHECK(s.shutdown_order_ok() == 1);
  CHECK(s.frames_outside_callback() == 0);
}

TEST_CASE("DHD frame: ours = (dhd y, dhd z, dhd x), a rotation", "[vendor][dhd]") {
  // x toward the operator, y right, z up (DHD) against x right, y up, z
  // toward the user (ours).
  CHECK(dhd_to_ours({1, 0, 0}) == glm::dvec3{0, 0, 1});  // toward the operator
  CHECK(dhd_to_ours({0, 1, 0}) == glm::dvec3{1, 0, 0});  // right
  CHECK(dhd_to_ours({0, 0, 1}) == glm::dvec3{0, 1, 0});  // up
  glm::dmat3 r;
  for (int i = 0; i < 3; ++i) {
    glm::dvec3 e{0.0};
    e[i] = 1.0;
    r[i] = dhd_to_ours(e);
  }
  CHECK(glm::determinant(r) == 1.0);
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int i = 0; i < 10000; ++i) {
    const glm::dvec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
    REQUIRE(ours_to_dhd(dhd_to_ours(a)) == a);
    REQUIRE(dhd_to_ours(a) == r * a);
    // lengths, dot and cross products kept: a proper rotation
    REQUIRE(glm::dot(dhd_to_ours(a), dhd_to_ours(b)) == Approx(glm::dot(a, b)).margin(1e-9));
    REQUIRE(glm::length(dhd_to_ours(glm::cross(a, b)) - glm::cross(dhd_to_ours(a), dhd_to_ours(b))) < 1e-9);
  }
}

TEST_CASE("DHD: start-up faults give one clear error", "[vendor][dhd]") {
  VirtualClock clock;
  SECTION("no device") {
    Env env("HFSTANDIN_DHD", "no_device");
    CHECK_THROWS_WITH(DhdDevice(dhd_config(clock)), Catch::Contains("no device found") && Catch::Contains("1451"));
  }
  SECTION("the device cannot be opened") {
    Env env("HFSTANDIN_DHD", "open_fails");
    CHECK_THROWS_WITH(DhdDevice(dhd_config(clock)),
                      Catch::Contains("dhdOpenID(0) failed") && Catch::Contains("device in use (error 20)"));
  }
  SECTION("an index beyond the count") {
    Env env("HFSTANDIN_DHD", "");
    DhdConfig c = dhd_config(clock);
    c.index = 3;
    CHECK_THROWS_WITH(DhdDevice(c), Catch::Contains("no device 3: 1 connected"));
  }
  SECTION("a Falcon through DHD gets its 8 N") {
    Env env("HFSTANDIN_DHD", "falcon");
    DhdDevice device(dhd_config(clock));
    CHECK(device.system_type() == dhd::device_falcon);
    CHECK(device.info().max_force == 8.0);
    CHECK(device.info().name == "Force Dimension stand-in falcon");
  }
}

TEST_CASE("DHD: the loop drives the arm in our frame; stop, latch and restart", "[vendor][dhd]") {
  DhdStandin& s = dhd_standin();
  VirtualClock clock;
  auto f = spring();
  SECTION("units and frame at the boundary, zero force at stop, no expert mode") {
    Env env("HFSTANDIN_DHD", "");
    DhdDevice device(dhd_config(clock));
    ServoLoop loop(device, clock, quiet_loop());
    int checked = 0;
    auto check_frame = [&](const TickInput& in) {
      if (in.read_status == Status::ok && in.tick > 300) {
        // the force commanded last tick is on the motors, in DHD's frame
        CHECK(glm::length(s.force() - ours_to_dhd(loop.last_command())) < 1e-12);
        ++checked;
      }
      return f(in);
    };
    REQUIRE(loop.run(check_frame, {.max_ticks = 1000}) == StopReason::tick_limit);
    CHECK(checked > 600);
    // The hand circles in DHD's y-z plane: ours x-y.
    CHECK(std::fabs(loop.state().position.z - 0.01) < 0.01);
    CHECK(loop.statistics().latches == 0);
    CHECK(glm::length(s.force()) == 0.0);
    CHECK(s.force_enabled() == 0);
    CHECK(s.expert_calls() == 0);  // velocity threshold and watchdog at their defaults

    SECTION("restart ramps up from zero") {
      std::vector<double> first;
      auto watch = [&](const TickInput&) {
        if (first.size() < 20) first.push_back(glm::length(s.force()));
        return glm::dvec3{2.0, 0.0, 0.0};
      };
      loop.run(watch, {.max_ticks = 400});
      for (std::size_t i = 0; i < first.size(); ++i)
        CHECK(first[i] <= 1e-3 * static_cast<double>(i + 1) * 1000.0 + 1e-9);
      CHECK(glm::length(s.force()) == 0.0);
    }
  }
  SECTION("a communication error mid-run stops the run as a lost device") {
    Env env("HFSTANDIN_DHD", "com_error_at=500");
    DhdDevice device(dhd_config(clock));
    ServoLoop loop(device, clock, quiet_loop());
    CHECK(loop.run(f, {.max_ticks = 2000}) == StopReason::disconnected);
    CHECK(loop.safety().latched() & safety_events::disconnected);
    CHECK(device.last_error().find("communication") != std::string::npos);
  }
  SECTION("an impossible pose latches") {
    Env env("HFSTANDIN_DHD", "nan_at=500");
    DhdDevice device(dhd_config(clock));
    ServoLoop loop(device, clock, quiet_loop());
    loop.run(f, {.max_ticks = 1000});
    CHECK(loop.safety().latched() & safety_events::impossible_state);
    CHECK(glm::length(s.force()) == 0.0);
  }
  SECTION("a saturated motor reaches the safety chain as a device fault") {
    Env env("HFSTANDIN_DHD", "saturate_above=1.0");
    DhdDevice device(dhd_config(clock));
    ServoLoop loop(device, clock, quiet_loop());
    bool faulted_seen = false;
    auto push = [&](const TickInput& in) {
      faulted_seen = faulted_seen || in.state.faulted();
      return glm::dvec3{3.0, 0.0, 0.0};
    };
    loop.run(push, {.max_ticks = 1000});
    CHECK(device.counters().saturations > 0);
    CHECK(faulted_seen);
    CHECK(s.expert_calls() == 0);
  }
  SECTION("velocity by differences when the SDK gives none") {
    Env env("HFSTANDIN_DHD", "no_velocity");
    DhdDevice device(dhd_config(clock));
    ServoLoop loop(device, clock, quiet_loop());
    loop.run(f, {.max_ticks = 200});
    // the hand moves at 2 pi 0.5 x 20 mm/s = 62.8 mm/s
    CHECK(glm::length(loop.state().velocity) == Approx(0.0628).epsilon(0.2));
  }
}

TEST_CASE("Vendor arms: read and write allocate nothing", "[vendor]") {
  if (!test::allocations_counted) return;
  {
    Env env("HFSTANDIN_HD", "lockstep");
    OpenHapticsDevice device(hd_config());
    device.set_armed(true);
    DeviceState st;
    long n = 0;
    for (int i = 0; i < 1000; ++i) {
      hd_standin().step(1);  // the stand-in's tick allocates (it is not ours): counted apart
      n += test::count_allocations([&] {
        device.read(st);
        device.write({0.1, 0.2, 0.3});
      });
    }
    CHECK(n == 0);
  }
  {
    VirtualClock clock;
    Env env("HFSTANDIN_DHD", "");
    DhdDevice device(dhd_config(clock));
    device.set_armed(true);
    DeviceState st;
    const long n = test::count_allocations([&] {
      for (int i = 0; i < 1000; ++i) {
        clock.sleep_until(clock.now() + 1'000'000);
        device.read(st);
        device.write({0.1, 0.2, 0.3});
      }
    });
    CHECK(n == 0);
  }
}

namespace {
/// The host's time as HD's ticks count it [ns]: one period per tick.
std::int64_t hd_time() {
  return hd_standin().ticks() * 1'000'000;
}

/// HD's scheduler thread for the lockstep stand-in: ticks as fast as the
/// machine runs them (the loop's time is the HD tick count, so nothing
/// depends on the machine's speed).
struct HdSchedulerThread {
  std::atomic<bool> go{true};
  std::thread thread{[this] {
    while (go.load()) {
      hd_standin().step(1);
      std::this_thread::yield();
    }
  }};
  ~HdSchedulerThread() {
    go = false;
    thread.join();
  }
};
}  // namespace

TEST_CASE("OpenHapticsServo: our tick inside HD's callback, with the loop's semantics", "[vendor][openhaptics]") {
  Env env("HFSTANDIN_HD", "lockstep");
  HdStandin& s = hd_standin();
  {
    OpenHapticsDevice device(hd_config());
    OpenHapticsServo servo(device, quiet_loop(), hd_time);
    HdSchedulerThread scheduler;
    auto f = spring();
    int same_tick = 0;
    auto check = [&](const TickInput& in) {
      if (in.read_status == Status::ok) {
        // read inside this tick's frame: the arm's pose now, mm to m
        CHECK(glm::length(in.state.position - s.position_mm() * 1e-3) < 1e-12);
        // the last tick's force is on the arm, set in that tick's own frame
        CHECK(glm::length(s.force() - servo.last_command()) < 1e-12);
        ++same_tick;
      }
      return f(in);
    };
    REQUIRE(servo.run(check, {.max_ticks = 1000}) == StopReason::tick_limit);
    CHECK(same_tick == 1000);
    const LoopSnapshot st = servo.statistics();
    CHECK(st.ticks == 1000);
    CHECK(st.rate == Approx(1000.0));  // the loop's time is HD's ticks
    CHECK(st.missed_deadlines == 0);
    CHECK(st.latches == 0);
    CHECK(st.peak_force > 1.0);
    // The stop's zero was set in the last callback's frame: on the arm already.
    CHECK(glm::length(s.force()) == 0.0);

    SECTION("request_stop from another thread (as Ctrl-C does): zero force at once") {
      std::thread stopper([&] {
        while (servo.callbacks() < 500)
          std::this_thread::yield();
        servo.request_stop();
      });
      CHECK(servo.run(f) == StopReason::requested);
      stopper.join();
      CHECK(glm::length(s.force()) == 0.0);
    }
    SECTION("a field that looks ahead is not looked ahead here: HD's scheduler owns the timing") {
      ProxyConstraint floor(PlaneShape(PlaneShapeConfig{glm::dvec3{0.0, 0.0, -0.02}}), ProxyConfig{});
      static_assert(ProxyConstraint<PlaneShape>::looks_ahead());
      servo.reset_statistics();
      REQUIRE(servo.run(floor, {.max_ticks = 500}) == StopReason::tick_limit);
      const LoopSnapshot w = servo.statistics();
      CHECK(w.ticks == 500);
      CHECK(w.look_aheads == 0);
      CHECK(w.look_aheads_skipped == 0);
      CHECK(w.rate == Approx(1000.0));  // one HD callback a tick, no second wake
    }
    SECTION("a restart ramps up from zero") {
      std::vector<double> asked;
      auto watch = [&](const TickInput&) {
        if (asked.size() < 20) asked.push_back(glm::length(servo.last_command()));
        return glm::dvec3{2.0, 0.0, 0.0};
      };
      servo.run(watch, {.max_ticks = 400});
      for (std::size_t i = 0; i < asked.size(); ++i)
        CHECK(asked[i] <= 1e-3 * static_cast<double>(i) * 1000.0 + 1e-9);
      CHECK(glm::length(s.force()) == 0.0);
    }
    SECTION("a callback that throws: zero force, ServoError on the caller's thread") {
      int ticks = 0;
      auto bad = [&ticks](const TickInput&) -> glm::dvec3 {
        if (++ticks == 300) throw std::runtime_error("boom");
        return {1.0, 0.0, 0.0};
      };
      CHECK_THROWS_AS(servo.run(bad), ServoError);
      CHECK(glm::length(s.force()) == 0.0);
      CHECK(servo.safety().latched() & safety_events::callback_threw);
    }
  }
  CHECK(s.shutdown_order_ok() == 1);
  CHECK(s.frames_outside_callback() == 0);
}

TEST_CASE("OpenHapticsServo: faults inside HD's callback", "[vendor][openhaptics]") {
  HdStandin& s = hd_standin();
  auto f = spring();
  SECTION("a device error ends the run as a lost device") {
    Env env("HFSTANDIN_HD", "lockstep,device_error_at=500");
    OpenHapticsDevice device(hd_config());
    OpenHapticsServo servo(device, quiet_loop(), hd_time);
    HdSchedulerThread scheduler;
    CHECK(servo.run(f, {.max_ticks = 3000}) == StopReason::disconnected);
    CHECK(servo.safety().latched() & safety_events::disconnected);
    CHECK(glm::length(s.force()) == 0.0);
  }
  SECTION("an impossible pose latches") {
    Env env("HFSTANDIN_HD", "lockstep,nan_at=500");
    OpenHapticsDevice device(hd_config());
    OpenHapticsServo servo(device, quiet_loop(), hd_time);
    HdSchedulerThread scheduler;
    servo.run(f, {.max_ticks = 1000});
    CHECK(servo.safety().latched() & safety_events::impossible_state);
    CHECK(glm::length(s.force()) == 0.0);
  }
  SECTION("a scheduler that stops calling ends the run with one clear error") {
    Env env("HFSTANDIN_HD", "lockstep,scheduler_stops_at=500");
    OpenHapticsDevice device(hd_config());
    OpenHapticsServo servo(device, quiet_loop(), hd_time);
    HdSchedulerThread scheduler;
    CHECK_THROWS_WITH(servo.run(f, {}, std::chrono::milliseconds(100)),
                      Catch::Contains("HD scheduler stopped calling"));
    CHECK(servo.last_command() == glm::dvec3{0.0});
    CHECK_FALSE(servo.trusted());
  }
  CHECK(s.shutdown_order_ok() == 1);
  CHECK(s.frames_outside_callback() == 0);
}

TEST_CASE("The front door opens openhaptics[:NAME] and dhd[:INDEX]", "[vendor]") {
  CHECK_THROWS_AS(parse_device_spec("dhd:x"), DeviceSpecError);
  CHECK_THROWS_AS(parse_device_spec("dhd:127"), DeviceSpecError);
  CHECK_THROWS_AS(parse_device_spec("openhaptics:"), DeviceSpecError);
  CHECK_FALSE(parse_device_spec("dhd:2").simulated);
  CHECK(parse_device_spec("openhaptics:Left Touch").args == "Left Touch");
  {
    Env library("HAPTICFIELD_HD_LIBRARY", HAPTICFIELD_STANDIN_HD);
    Env faults("HFSTANDIN_HD", "lockstep");
    AnyDevice touch = open_device("openhaptics");
    CHECK(touch.info().name == "OpenHaptics Stand-in Touch");
    CHECK(touch.target<OpenHapticsDevice>() != nullptr);
  }
  {
    Env library("HAPTICFIELD_DHD_LIBRARY", HAPTICFIELD_STANDIN_DHD);
    Env faults("HFSTANDIN_DHD", "");
    AnyDevice omega = open_device("dhd:0");
    CHECK(omega.info().name == "Force Dimension stand-in omega.3");
    CHECK_THROWS_WITH(open_device("dhd:1"), Catch::Contains("no device 1: 1 connected"));
    bool listed = false;
    for (const DeviceListing& l : list_devices())
      if (l.family == "dhd") {
        listed = true;
        CHECK(l.present);
        CHECK(l.line.find("1 device(s)") != std::string::npos);
      }
    CHECK(listed);
  }
}

#ifdef HAPTICFIELD_SERVO_DEMO
namespace {
namespace fs = std::filesystem;
/// What a stand-in wrote when the tool closed the arm ("" when it did not).
std::string report_value(const fs::path& report, const std::string& key) {
  const std::string text = testing::slurp(report);
  const std::size_t at = text.find(key + " ");
  if (at == std::string::npos) return "";
  return text.substr(at + key.size() + 1, text.find('\n', at) - at - key.size() - 1);
}
const fs::path tool_tmp = fs::path(HAPTICFIELD_TEST_TMP) / "vendor_arms";
}  // namespace

TEST_CASE("servo_demo --device openhaptics and dhd against the stand-ins, as a user runs it", "[vendor][cli]") {
  fs::create_directories(tool_tmp);
  const fs::path report = tool_tmp / "report.txt";
  Env report_to("HFSTANDIN_REPORT", report.c_str());
  const std::string dhd_folder = fs::path(HAPTICFIELD_STANDIN_DHD).parent_path().string();
  struct Arm {
    const char* device;
    const char* variable;  // how the tool finds the stand-in
    std::string value;
    const char* faults;
    const char* device_error;
  };
  const Arm arms[] = {
      {"openhaptics", "HAPTICFIELD_HD_LIBRARY", HAPTICFIELD_STANDIN_HD, "HFSTANDIN_HD", "device_error_at=300"},
      // the documented name, found through the loader's search path
      {"dhd", "LD_LIBRARY_PATH", dhd_folder, "HFSTANDIN_DHD", "com_error_at=300"},
  };
  for (const Arm& arm : arms) {
    INFO(arm.device);
    Env library(arm.variable, arm.value.c_str());
    SECTION(std::string(arm.device) + ": a run ends with zero force") {
      Env faults(arm.faults, "");
      fs::remove(report);
      testing::Child tool(HAPTICFIELD_SERVO_DEMO, {"--device", arm.device, "--field", "spring", "--seconds", "1"},
                          tool_tmp, std::string(arm.device) + "_run");
      REQUIRE(tool.wait());
      INFO(tool.out() << tool.err());
      CHECK(tool.status() == 0);
      CHECK(tool.out().find("1000 ticks") != std::string::npos);
      CHECK(report_value(report, "last_force") == "0 0 0");
      if (std::string(arm.device) == "openhaptics") {
        CHECK(report_value(report, "shutdown_order") == "ok");
        CHECK(report_value(report, "frames_outside_callback") == "0");
      } else {
        CHECK(report_value(report, "force_enabled") == "0");
        CHECK(report_value(report, "expert_calls") == "0");
      }
    }
    SECTION(std::string(arm.device) + ": Ctrl-C gives zero force") {
      Env faults(arm.faults, "");
      fs::remove(report);
      testing::Child tool(HAPTICFIELD_SERVO_DEMO, {"--device", arm.device, "--field", "spring", "--seconds", "60"},
                          tool_tmp, std::string(arm.device) + "_sigint");
      // the prompt comes once the tool's Ctrl-C handler is in place
      REQUIRE(tool.wait_for_output("Press Enter"));
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      tool.signal(SIGINT);
      REQUIRE(tool.wait());
      INFO(tool.out() << tool.err());
      CHECK(tool.killed_by() == 0);
      CHECK(tool.out().find("stopped by signal") != std::string::npos);
      CHECK(report_value(report, "last_force") == "0 0 0");
    }
    SECTION(std::string(arm.device) + ": a device error mid-run latches, zero force, exit 1") {
      Env faults(arm.faults, arm.device_error);
      fs::remove(report);
      testing::Child tool(HAPTICFIELD_SERVO_DEMO, {"--device", arm.device, "--field", "spring", "--seconds", "5"},
                          tool_tmp, std::string(arm.device) + "_error");
      REQUIRE(tool.wait());
      INFO(tool.out() << tool.err());
      CHECK(tool.status() == 1);
      CHECK(tool.out().find("the device disconnected; zero force was commanded") != std::string::npos);
      CHECK(report_value(report, "last_force") == "0 0 0");
    }
  }
  SECTION("without the SDK: one line on stderr, exit 1") {
    for (const char* device : {"openhaptics", "dhd"}) {
      testing::Child tool(HAPTICFIELD_SERVO_DEMO, {"--device", device}, tool_tmp, std::string(device) + "_missing");
      REQUIRE(tool.wait());
      CHECK(tool.status() == 1);
      const std::string err = tool.err();
      CHECK(std::count(err.begin(), err.end(), '\n') == 1);
      CHECK(err.find("cannot load") != std::string::npos);
    }
  }
}
#endif

// ---- the device suite every family passes, on the stand-ins ----

namespace {

/// An OpenHaptics arm on the lockstep stand-in: HD's scheduler runs one
/// tick before each read (a loop period is one HD tick).
class HdTwin {
  struct OnHdTicks {
    OpenHapticsDevice arm;
    Status read(DeviceState& s) noexcept {
      hd_standin().step(1);
      return arm.read(s);
    }
    Status write(const glm::dvec3& f) noexcept { return arm.write(f); }
    Status set_armed(bool on) noexcept { return arm.set_armed(on); }
    Status request_home() noexcept { return arm.request_home(); }
    Status clear_fault() noexcept { return arm.clear_fault(); }
    [[nodiscard]] const DeviceInfo& info() const noexcept { return arm.info(); }
  };
  struct Parts {
    OnHdTicks ticks{OpenHapticsDevice(hd_config())};
    OnHdTicks& device() noexcept { return ticks; }
  };

 public:
  explicit HdTwin(VirtualClock&) : env_("HFSTANDIN_HD", "lockstep"), device_(AnyDevice::holding(make())) {}
  AnyDevice& device() noexcept { return device_; }
  [[nodiscard]] double effort() const { return glm::length(hd_standin().force()); }
  void lose() { hd_standin().inject("lose"); }
  void send_impossible() { hd_standin().inject("impossible"); }

 private:
  static std::unique_ptr<Parts> make() { return std::make_unique<Parts>(); }
  Env env_;
  AnyDevice device_;
};

/// A Force Dimension arm on the DHD stand-in, on the loop's clock.
class DhdTwin {
 public:
  explicit DhdTwin(VirtualClock& clock)
      : env_("HFSTANDIN_DHD", ""), library_("HAPTICFIELD_DHD_LIBRARY", HAPTICFIELD_STANDIN_DHD) {
    DeviceOptions options;
    options.now = [&clock] { return clock.now(); };
    device_ = open_device("dhd:0", options);
  }
  AnyDevice& device() noexcept { return device_; }
  [[nodiscard]] double effort() const { return glm::length(dhd_standin().force()); }
  void lose() { dhd_standin().inject("lose"); }
  void send_impossible() { dhd_standin().inject("impossible"); }

 private:
  Env env_;
  Env library_;
  AnyDevice device_;
};

}  // namespace

HAPTICFIELD_DEVICE_SUITE(HdTwin, "device suite, openhaptics (stand-in libHD)")
HAPTICFIELD_DEVICE_SUITE(DhdTwin, "device suite, dhd (stand-in libdhd)")
