// servo_callback: the two loop styles against the simulated arm.
//   1. loop.run(callback): a callback sees the whole TickInput (probe,
//      device state, read status) and returns a force.
//   2. read_once / write_once: the user owns the thread and its timing.
#include <cstdio>

#include "common/cli.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"

using namespace hapticfield;

namespace {

constexpr const char* usage =
    "usage: servo_callback\n"
    "Runs the two servo-loop styles (a callback; read_once / write_once) for 2 s + 1 s\n"
    "against the simulated arm and prints what each saw. Takes no options.\n"
    "  -h, --help   this text\n"
    "Exit status: 0 done, 1 failure, 2 usage error.\n";

int run() {
  SteadyClock clock;
  SimulatedArmConfig config;
  config.hand.path = HandPath::circle({0.0, 0.0, 0.0}, 0.02, 0.05);  // the hand draws a 2 cm circle
  SimulatedArm arm(config);
  SimulatedTransport link(arm, [&clock] { return clock.now(); });
  ForceArm device(link);
  ServoLoop loop(device, clock);

  // 1. A callback: a spring to the origin, stiffer while button 0 is held.
  auto spring = [](const TickInput& in) {
    const double k = (in.state.buttons & 1u) ? 80.0 : 40.0;  // [N/m]
    return -k * in.probe.position;
  };
  loop.run(spring, {.max_ticks = 2000});
  LoopSnapshot s = loop.statistics();
  std::printf("run(callback): %llu ticks at %.2f Hz, p99 period %.4f ms, peak %.2f N\n",
              static_cast<unsigned long long>(s.ticks), s.rate, s.period_p99 * 1e3, s.peak_force);

  // 2. Own the thread: sleep to absolute deadlines yourself. The first
  //    read_once() arms again and the force ramps up through the soft start.
  TickInput in;
  std::int64_t deadline = clock.now();
  for (int i = 0; i < 1000; ++i) {
    deadline += 1'000'000;
    clock.sleep_until(deadline);
    loop.read_once(in);
    loop.write_once(-40.0 * in.probe.position);
  }
  std::printf("read_once/write_once: handle at (%.1f, %.1f, %.1f) mm, last force %.2f N\n", in.probe.position.x * 1e3,
              in.probe.position.y * 1e3, in.probe.position.z * 1e3, glm::length(loop.last_command()));
  loop.write_once(glm::dvec3{0.0});
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return cli::main("servo_callback", usage, argc, argv, [](cli::Parser& p) {
    while (p.next())
      p.unknown();
    return run();
  });
}
