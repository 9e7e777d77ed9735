// Tests of the tick-budget harness (servo/tick_budget.hpp): the scripted
// path, allocation and exception counting, and the verdict's rules. Timing
// figures are printed, never asserted (they depend on the machine).
#include <catch2/catch.hpp>

#include <cmath>
#include <ctime>
#include <iostream>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/servo/tick_budget.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;

namespace {
std::int64_t test_allocations() noexcept {
  return test::allocation_count.load();
}
offline::TickBudgetConfig small() {
  offline::TickBudgetConfig c;
  c.ticks = 2000;
  c.warmup = 100;
  if (test::allocations_counted) c.allocation_count = &test_allocations;
  return c;
}
}  // namespace

TEST_CASE("tick budget: the scripted path strokes a circle at the given speed, pressed into z = 0") {
  const offline::ProbePathConfig c;
  for (std::uint64_t i = 0; i < 2000; i += 97) {
    const Probe p = offline::scripted_probe(c, i);
    CHECK_THAT(std::hypot(p.position.x, p.position.y), WithinAbs(c.radius, 1e-12));
    CHECK_THAT(std::hypot(p.velocity.x, p.velocity.y), WithinAbs(c.speed, 1e-12));
    CHECK(p.position.z < 0.0);
    CHECK(p.time == static_cast<double>(i) * c.period);
  }
}

TEST_CASE("tick budget: a clean field counts no allocation and no exception") {
  auto field = contact(PlaneConstraint({}));
  const auto r = offline::measure_tick_budget(field, small());
  CHECK(r.ticks == 2000);
  CHECK(r.exceptions == 0);
  if (test::allocations_counted) CHECK(r.allocations == 0);
  CHECK(r.p50_ns <= r.p99_ns);
  CHECK(r.p99_ns <= r.worst_ns);
  std::cout << "contact(plane):\n" << r.summary();
}

TEST_CASE("tick budget: a field that allocates does not fit, whatever its speed") {
  if (!test::allocations_counted) return;  // ThreadSanitizer owns operator new
  struct Allocating {
    glm::dvec3 force(const Probe&) noexcept {
      std::vector<int> v(8);
      return glm::dvec3{static_cast<double>(v.size())};
    }
  } field;
  const auto r = offline::measure_tick_budget(field, small());
  CHECK(r.allocations == 2000);
  CHECK(r.allocations_per_tick() == 1.0);
  CHECK_FALSE(r.fits_1khz);
  CHECK_FALSE(r.fits_10khz);
  CHECK(r.summary().find("it allocates") != std::string::npos);
}

TEST_CASE("tick budget: a callable that throws is counted and does not fit") {
  long n = 0;
  auto throwing = [&n](const Probe&) -> glm::dvec3 {
    if (++n % 10 == 0) throw std::runtime_error("every tenth tick");
    return glm::dvec3{0.0};
  };
  const auto r = offline::measure_tick_budget(throwing, small());
  CHECK(r.exceptions == 200);
  CHECK_FALSE(r.fits_1khz);
  CHECK(r.summary().find("it throws") != std::string::npos);
}

TEST_CASE("tick budget: without a counter, allocations are reported as not counted") {
  auto c = small();
  c.allocation_count = nullptr;
  auto field = contact(PlaneConstraint({}));
  const auto r = offline::measure_tick_budget(field, c);
  CHECK(r.allocations == -1);
  CHECK(r.summary().find("not counted") != std::string::npos);
}

TEST_CASE("tick budget: the caller's own probes, warm-up along them, each timed pass over all of them in order") {
  std::vector<Probe> path(50);
  for (std::size_t i = 0; i < path.size(); ++i)
    path[i].position.x = static_cast<double>(i);
  std::vector<double> seen;
  auto recorder = [&seen](const Probe& p) noexcept {
    seen.push_back(p.position.x);
    return glm::dvec3{0.0};
  };
  auto c = small();
  c.warmup = 70;
  c.allocation_count = nullptr;  // the recorder allocates as it grows
  const auto r = offline::measure_tick_budget(recorder, path, c);
  CHECK(r.ticks == 50);
  REQUIRE(seen.size() == 2 * (70 + 50));  // warm-up and a pass, twice
  for (std::size_t i = 0; i < 70; ++i)
    CHECK(seen[i] == static_cast<double>(i % 50));  // the warm-up cycles through the path
  for (std::size_t i = 0; i < 50; ++i) {
    CHECK(seen[70 + i] == static_cast<double>(i));        // untimed pass
    CHECK(seen[120 + 70 + i] == static_cast<double>(i));  // timed pass
  }
  CHECK_THROWS_AS(offline::measure_tick_budget(recorder, std::span<const Probe>{}, c), std::invalid_argument);
}

TEST_CASE("tick budget: a tick body without a probe; the thread's CPU time leaves out a sleep that wall time counts") {
  int calls = 0;
  auto c = small();
  c.warmup = 3;
  c.allocation_count = nullptr;
  const auto counted = offline::measure_tick_cost(
      10, [&calls] { ++calls; }, c);
  CHECK(counted.ticks == 10);
  CHECK(calls == 2 * (3 + 10));

  // a tick that sleeps 2 ms: at least 2 ms of wall time, far less of CPU time (a bound, not a speed)
  const auto sleeper = [] {
    timespec ts{0, 2'000'000};
    while (nanosleep(&ts, &ts) != 0) {
    }
  };
  c.warmup = 0;
  c.clock = offline::TickClock::wall;
  const auto wall = offline::measure_tick_cost(5, sleeper, c);
  c.clock = offline::TickClock::thread_cpu;
  const auto cpu = offline::measure_tick_cost(5, sleeper, c);
  CHECK(wall.p50_ns >= 1.9e6);
  CHECK_FALSE(wall.fits_1khz);
  CHECK(cpu.p50_ns < 1e6);
  std::cout << "a 2 ms sleep: wall p50 " << wall.p50_ns << " ns, CPU p50 " << cpu.p50_ns << " ns\n";
}
