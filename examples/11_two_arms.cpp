// two_arms: a teacher/student pair on one servo deadline. The teacher's hand
// draws a circle; the student's arm is pulled toward the teacher's handle by
// a spring (a haptic guidance field), on two simulated arms in one
// MultiArmLoop. Prints how closely the student follows and each arm's
// statistics; --fault stalls the student's link to show a fault zeroing one
// arm (--policy isolate) or both (--policy stop_all). --teacher and --student
// put any arm the device front door opens in either place.
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>

#include "common/cli.hpp"
#include "common/device_option.hpp"
#include "common/loop_thread.hpp"
#include "common/servo_options.hpp"
#include "common/stop_signal.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/devices/open_device.hpp"
#include "hapticfield/servo.hpp"

using namespace hapticfield;

namespace {

constexpr const char* usage_text =
    "usage: two_arms [--seconds S] [--stiffness K] [--policy isolate|stop_all] [--fault] [--clock wall|virtual]\n"
    "                [--teacher D] [--student D] [--list-devices]\n"
    "Two arms (simulated unless told otherwise) on one 1 kHz deadline: the teacher's hand draws a\n"
    "2 cm circle, the student's arm is pulled toward the teacher's handle by a spring.\n"
    "  --seconds S      run time [s], in [0.01, 60] (default 3)\n"
    "  --stiffness K    guidance spring [N/m], in (0, 500] (default 150)\n"
    "  --policy P       what a fault on one arm does: isolate (default: zero that arm) or\n"
    "                   stop_all (zero and latch both)\n"
    "  --fault          stall the student's link for 30 ms at 1 s: stale state latches it, its\n"
    "                   firmware watchdog trips; 0.5 s later the loop clears both and re-arms\n"
    "  --clock C        wall (default) or virtual: simulated time, as fast as the CPU allows, the\n"
    "                   same ticks and result whatever the machine's load (simulated arms only)\n"
    "  --teacher D      the teacher's arm: any device servo_demo opens (default sim, its scripted\n"
    "                   hand drawing the circle)\n"
    "  --student D      the student's arm (default: a simulated arm its hand rests on lightly)\n"
    "  --list-devices   one line per arm family: present, or why not; then exit\n"
    "  -h, --help       this text\n"
    "Ctrl-C or SIGTERM stops both arms through the loop's stop (zero force, then disarm).\n"
    "Exit status: 0 done, 1 failure, 2 usage error, 128 + N stopped by signal N.\n";

struct Arguments {
  double seconds{3.0};
  double stiffness{150.0};
  ArmFaultPolicy policy{ArmFaultPolicy::isolate};
  bool fault{false};
  bool virtual_clock{false};
  std::optional<DeviceSpec> teacher, student;  ///< none: the simulated arm
  bool list_devices{false};
};

/// The student's field: a spring toward where the teacher's handle is now
/// (read from the teacher's loop, which ticked just before in the same
/// thread), and nothing while the teacher's pose is not trusted (homing at
/// start-up or after a reboot, stale, latched).
template <ServoClock C>
using Guidance = GuidanceField<ServoLoop<AnyDevice, C>>;

/// The teacher feels nothing: its hand leads.
struct Free {
  glm::dvec3 force(const Probe&) const noexcept { return glm::dvec3{0.0}; }
};

/// One arm's statistics and, after a latch, what became of it: its reason,
/// when, whether force came back (a recovery counts only then) and when.
/// final_force: the arm's command on the last tick [N].
template <ServoClock C>
void print_arm(const char* name, const ServoLoop<AnyDevice, C>& arm, double final_force) {
  const LoopSnapshot s = arm.statistics();
  std::printf("%s: peak force %.2f N, latches %llu, recoveries %llu, force at the end %.2f N\n", name, s.peak_force,
              static_cast<unsigned long long>(s.latches), static_cast<unsigned long long>(s.recoveries), final_force);
  if (s.latches == 0) return;
  std::printf("  latched at %.3f s: %s\n", s.last_latch_time, safety_events::names(s.last_latch).c_str());
  if (const std::uint32_t held = arm.safety().latched())
    std::printf("  not recovered: still latched (%s), zero force until clear_fault()\n",
                safety_events::names(held).c_str());
  else if (s.recoveries > 0 && s.last_recovery_time >= s.last_latch_time)
    std::printf("  recovered: latch and device fault cleared, re-armed, force back at %.3f s through the soft start\n",
                s.last_recovery_time);
  else
    std::printf("  latch cleared, but no force has come back (the device or the field gives none)\n");
}

template <ServoClock C>
int run_on(const Arguments& o, C& clock) {
  const auto now = [&clock] { return clock.now(); };
  DeviceOptions teacher_options;
  teacher_options.now = now;
  teacher_options.hand.path = HandPath::circle({0.0, 0.0, 0.0}, 0.02, 0.3);  // 2 cm circle at 0.3 Hz
  AnyDevice teacher = open_device(o.teacher ? *o.teacher : parse_device_spec("sim"), teacher_options);
  AnyDevice student;
  if (o.student) {
    DeviceOptions student_options;
    student_options.now = now;
    student_options.hand.holding = false;  // a simulated student's hand rests lightly
    student = open_device(*o.student, student_options);
  } else {
    // The simulated student, its link a quarter period off the teacher's, which --fault stalls.
    struct Student {
      SimulatedArm arm;
      SimulatedTransport link;
      ForceArm force_arm;
      Student(const SimulatedArmConfig& c, const TimeSource& now) : arm(c), link(arm, now, 0.25), force_arm(link) {}
      ForceArm& device() noexcept { return force_arm; }
    };
    SimulatedArmConfig student_config;
    student_config.hand.holding = false;  // the student's hand rests lightly: the arm follows the guidance
    auto parts = std::make_unique<Student>(student_config, now);
    if (o.fault) parts->link.inject(LinkFault::stall, 1000, 30);
    student = AnyDevice::holding(std::move(parts));
  }
  LoopConfig config;
  config.recover_after = 0.5;  // a stall of the machine latches; re-arm through the soft start once fresh again
  if (std::is_same_v<C, VirtualClock>) config.realtime = RealTime::off;  // simulated time never sleeps
  MultiArmLoop<AnyDevice, 2, C> loop({&teacher, &student}, clock, config, o.policy);
  Free free;
  Guidance<C> guidance{&loop.arm(0), o.stiffness, 1.0};

  // The tracking error and the student's last command, recorded inside the
  // tick (no allocation, no I/O).
  struct Tracking {
    Guidance<C>* guidance;
    const ServoLoop<AnyDevice, C>* student;
    double sum_sq{0.0}, worst{0.0};
    long samples{0};
    double last_force{0.0};  // [N]
    glm::dvec3 force(const Probe& p) noexcept {
      last_force = glm::length(student->last_command());
      const double e = glm::length(guidance->leader->state().position - p.position);
      if (p.time > 0.5 && guidance->leader->trusted() && student->trusted()) {  // both driven, on real poses
        sum_sq += e * e;
        worst = std::fmax(worst, e);
        ++samples;
      }
      return guidance->force(p);
    }
  } tracking{&guidance, &loop.arm(1)};

  const auto ticks = static_cast<std::uint64_t>(std::llround(o.seconds * 1000.0));
  cli::StopOnSignal stop(loop);  // Ctrl-C: zero force and disarm both arms through the loop's stop
  const bool hardware = (o.teacher && !o.teacher->simulated) || (o.student && !o.student->simulated);
  if (hardware) cli::wait_for_operator();
  if (stop.caught()) {
    std::printf("stopped by signal %d before the loop started; no force was commanded\n", stop.caught());
    return stop.exit_status();
  }
  std::printf("two arms on one 1 kHz deadline for %.2f s (Ctrl-C stops)\n", o.seconds);
  std::fflush(stdout);
  loop.run({.max_ticks = ticks}, free, tracking);
  const LoopSnapshot s = loop.statistics();
  std::printf("%llu ticks at %.2f Hz, period p99 %.3f ms, max %.3f ms, late ticks %llu\n",
              static_cast<unsigned long long>(s.ticks), s.rate, s.period_p99 * 1e3, s.period_max * 1e3,
              static_cast<unsigned long long>(s.overruns));
  if (tracking.samples > 0)
    std::printf("student follows the teacher within %.2f mm rms, %.2f mm worst\n",
                1e3 * std::sqrt(tracking.sum_sq / static_cast<double>(tracking.samples)), 1e3 * tracking.worst);
  print_arm("teacher", loop.arm(0), 0.0);
  print_arm("student", loop.arm(1), tracking.last_force);
  if (stop.caught()) {
    std::printf("stopped by signal %d: zero force commanded to both arms, then both disarmed\n", stop.caught());
    return stop.exit_status();
  }
  return 0;
}

int run(const Arguments& o) {
  if (o.list_devices) return cli::print_device_list();
  if (o.virtual_clock) {
    VirtualClock clock;
    return run_on(o, clock);
  }
  SteadyClock clock;
  return run_on(o, clock);
}

}  // namespace

int main(int argc, char** argv) {
  return cli::main("two_arms", usage_text, argc, argv, [](cli::Parser& p) {
    Arguments o;
    while (p.next()) {
      if (p.is("--seconds"))
        o.seconds = p.real(cli::closed(0.01, 60.0));
      else if (p.is("--stiffness"))
        o.stiffness = p.real(cli::open_closed(0.0, 500.0));
      else if (p.is("--policy"))
        o.policy = p.choice<ArmFaultPolicy>(
            "fault policy", {{"isolate", ArmFaultPolicy::isolate}, {"stop_all", ArmFaultPolicy::stop_all}});
      else if (p.is("--fault"))
        o.fault = true;
      else if (p.is("--clock"))
        o.virtual_clock = cli::virtual_clock_option(p);
      else if (p.is("--teacher"))
        o.teacher = cli::device_option(p.value());
      else if (p.is("--student"))
        o.student = cli::device_option(p.value());
      else if (p.is("--list-devices"))
        o.list_devices = true;
      else
        p.unknown();
    }
    if (o.fault && o.student)
      throw cli::UsageError("--fault stalls the simulated student's own link: give no --student with it");
    if (o.teacher) cli::check_clock_fits_arm(o.virtual_clock, *o.teacher, "--teacher");
    if (o.student) cli::check_clock_fits_arm(o.virtual_clock, *o.student, "--student");
    p.finish();
    return run(o);
  });
}
