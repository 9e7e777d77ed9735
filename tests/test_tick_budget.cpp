// Tests of the tick-budget harness (offline/tick_budget.hpp): the scripted
// path, allocation and exception counting, and the verdict's rules. Timing
// figures are printed, never asserted (they depend on the machine).
#include <catch2/catch.hpp>

#include <cmath>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/offline/tick_budget.hpp"

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
