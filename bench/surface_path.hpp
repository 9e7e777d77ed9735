#pragma once
/// @file surface_path.hpp
/// What the surface benches share (bench_surface, bench_embree): the scripted
/// HIP path over a mesh and the tick-budget settings they time it with.

#include <hapticfield/core/probe.hpp>
#include <hapticfield/servo/tick_budget.hpp>

#include <cmath>
#include <random>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

namespace hapticfield::bench {

/// A HIP sliding over the surface 2 mm deep at up to 0.2 m/s, with taps and
/// a bounded random wobble (1 mm), one probe per 1 ms tick, within 0.6
/// half_extent [m] of the centre; the same path on every run (seeded).
inline std::vector<Probe> sliding_path(long ticks, double half_extent) {
  std::vector<Probe> path;
  std::mt19937 rng(17);
  std::normal_distribution<double> g(0.0, 2e-5);
  glm::dvec3 wobble{0.0};
  for (long i = 0; i < ticks; ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    wobble += glm::dvec3{g(rng), g(rng), g(rng)};
    wobble = glm::clamp(wobble, glm::dvec3{-1e-3}, glm::dvec3{1e-3});
    Probe p;
    p.position = glm::dvec3{0.6 * half_extent * std::sin(0.5 * t), 0.6 * half_extent * std::sin(0.31 * t),
                            0.002 - 0.004 * (0.5 + 0.5 * std::sin(3.0 * t))} +
                 wobble;
    p.velocity = glm::dvec3{0.1, 0.05, 0.0};
    p.time = t;
    path.push_back(p);
  }
  return path;
}

/// The tick-budget harness (servo/tick_budget.hpp) on this thread's CPU
/// time (CLOCK_THREAD_CPUTIME_ID): time the scheduler gives to other
/// processes is not counted, so a shared, loaded machine still measures the
/// work of the tick. No warm-up: the path is timed as scripted, once
/// untimed and once call by call.
inline offline::TickBudgetConfig thread_cpu_budget() {
  offline::TickBudgetConfig c;
  c.warmup = 0;
  c.allocation_count = nullptr;
  c.clock = offline::TickClock::thread_cpu;
  return c;
}

}  // namespace hapticfield::bench
