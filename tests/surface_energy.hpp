#pragma once
// The energy check of a haptic surface: a mass-damper HIP (the arm's moving
// mass and its physical damping) driven by a scripted hand (a spring-damper
// toward a target that taps and slides), the surface's force computed at
// the servo rate and held between ticks (zero-order hold), integrated at
// 100 sub-steps a tick. The surface with the arm's damping is passive when
// the work the surface does on the HIP never exceeds what the damping has
// dissipated: max over t of (integral Fc . v dt - integral b v^2 dt) <= 0
// (Colgate & Schenkel, "Passivity of a class of sampled-data systems",
// J. Robotic Systems 1997: passive iff b > k T / 2 for a sampled spring).
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"

namespace hapticfield::test {

struct EnergyRun {
  double excess{0.0};      ///< max over t of (surface work on the HIP - damping loss) [J]; <= 0: passive
  double dissipated{0.0};  ///< damping loss over the run [J]
  double max_force{0.0};   ///< largest |Fc| [N]
};

/// Taps (0 .. seconds/2: down to 3 mm below z = 0 and up, 2 per second)
/// then slides (3 mm deep, a 20 x 10 mm ellipse every 2 s) on a surface
/// whose top is near z = 0, at `rate` ticks per second.
template <class Field>
EnergyRun tap_and_slide(Field& field, double rate, double seconds, double mass = 0.1, double damping = 1.0) {
  constexpr double pi = 3.14159265358979323846;
  const double hand_k = 300.0, hand_b = 3.0;  // the hand: [N/m], [N s/m]
  const int substeps = 100;
  const double period = 1.0 / rate, dt = period / substeps;
  glm::dvec3 x{0.0, 0.0, 0.005}, v{0.0};
  EnergyRun run;
  double work = 0.0;
  const long ticks = std::lround(seconds * rate);
  for (long n = 0; n < ticks; ++n) {
    const double t = static_cast<double>(n) * period;
    Probe probe;
    probe.position = x;
    probe.velocity = v;
    probe.time = t;
    probe.period = period;
    const glm::dvec3 fc = field.force(probe);
    run.max_force = std::fmax(run.max_force, glm::length(fc));
    for (int k = 0; k < substeps; ++k) {
      const double ts = t + k * dt;
      glm::dvec3 target{0.0};
      if (ts < seconds / 2)
        target =
            glm::dvec3{0.004 * std::sin(2 * pi * 0.3 * ts), 0.0, 0.002 - 0.005 * (0.5 - 0.5 * std::cos(4 * pi * ts))};
      else
        target = glm::dvec3{0.02 * std::sin(pi * ts), 0.01 * std::cos(pi * ts) - 0.01, -0.003};
      const glm::dvec3 hand = hand_k * (target - x) - hand_b * v;
      const glm::dvec3 a = (hand + fc - damping * v) / mass;
      const glm::dvec3 v_next = v + dt * a;
      const glm::dvec3 v_mid = 0.5 * (v + v_next);
      work += glm::dot(fc, v_mid) * dt;
      run.dissipated += damping * glm::dot(v_mid, v_mid) * dt;
      v = v_next;
      x += dt * v_mid;
      run.excess = std::fmax(run.excess, work - run.dissipated);
    }
  }
  return run;
}

}  // namespace hapticfield::test
