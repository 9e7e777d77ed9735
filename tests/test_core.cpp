// Tests of the core: Probe, the HapticField concept, AnyField, composition,
// plane mapping.
#include <catch2/catch.hpp>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/rt/huge_pages.hpp"
#include "hapticfield/rt/latest_value.hpp"
#include "hapticfield/rt/spsc_ring.hpp"
#include "page_flags.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;

namespace {

struct Spring {  // F = -k x, k = 200 N/m
  glm::dvec3 force(const Probe& p) const noexcept { return -200.0 * p.position; }
};

struct Counter {  // stateful: counts ticks since reset
  int ticks = 0;
  glm::dvec3 force(const Probe&) noexcept { return glm::dvec3{static_cast<double>(++ticks), 0.0, 0.0}; }
  void reset() noexcept { ticks = 0; }
};

struct NotAField {
  glm::dvec3 force(const Probe&) { return glm::dvec3{0.0}; }  // not noexcept
};

Probe at(glm::dvec3 p) {
  Probe probe;
  probe.position = p;
  return probe;
}

}  // namespace

TEST_CASE("the HapticField concept demands a noexcept force(Probe)") {
  STATIC_REQUIRE(HapticField<Spring>);
  STATIC_REQUIRE(HapticField<ZeroField>);
  STATIC_REQUIRE(ResettableField<Counter>);
  STATIC_REQUIRE_FALSE(ResettableField<Spring>);
  STATIC_REQUIRE_FALSE(HapticField<NotAField>);
  STATIC_REQUIRE_FALSE(HapticField<int>);
}

TEST_CASE("Probe members start at zero with the nominal period") {
  const Probe p;
  CHECK(p.position == glm::dvec3{0.0});
  CHECK(p.velocity == glm::dvec3{0.0});
  CHECK(p.normal_force == 0.0);
  CHECK(p.surface_normal == glm::dvec3{0.0});  // no surface until a contact sets one
  CHECK(p.time == 0.0);
  CHECK(p.period == servo_period);
}

TEST_CASE("AnyField forwards force and reset, and is zero when empty") {
  AnyField empty;
  CHECK_FALSE(empty);
  CHECK(empty.force(Probe{}) == glm::dvec3{0.0});
  empty.reset();

  AnyField spring = Spring{};
  CHECK(spring.force(at({0.01, -0.02, 0.0})).x == Approx(-2.0));
  CHECK(spring.force(at({0.01, -0.02, 0.0})).y == Approx(4.0));
  CHECK(spring.target<Spring>() != nullptr);
  CHECK(spring.target<Counter>() == nullptr);

  AnyField counter = Counter{};
  (void)counter.force(Probe{});
  CHECK(counter.force(Probe{}).x == 2.0);
  counter.reset();
  CHECK(counter.force(Probe{}).x == 1.0);
}

TEST_CASE("sum, scale and clamp compose fields") {
  auto total = sum(Spring{}, Spring{}, ZeroField{});
  CHECK(total.force(at({0.01, 0.0, 0.0})).x == Approx(-4.0));

  auto scaled = scale(Spring{}, 0.5);
  CHECK(scaled.force(at({0.01, 0.0, 0.0})).x == Approx(-1.0));

  auto clamped = clamp(Spring{}, 1.5);
  const glm::dvec3 f = clamped.force(at({0.03, 0.04, 0.0}));  // 10 N before the clamp
  CHECK(glm::length(f) == Approx(1.5));
  CHECK(f.x / f.y == Approx(0.75));                               // direction kept
  CHECK(clamped.force(at({0.001, 0.0, 0.0})).x == Approx(-0.2));  // below the limit: unchanged

  auto stateful = sum(Counter{}, scale(Counter{}, 10.0));
  (void)stateful.force(Probe{});
  CHECK(stateful.force(Probe{}).x == 22.0);
  stateful.reset();
  CHECK(stateful.force(Probe{}).x == 11.0);
}

TEST_CASE("composition rejects bad parameters") {
  CHECK_THROWS_AS(scale(Spring{}, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  CHECK_THROWS_AS(clamp(Spring{}, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(clamp(Spring{}, -1.0), std::invalid_argument);
  CHECK_THROWS_AS(clamp(Spring{}, std::numeric_limits<double>::infinity()), std::invalid_argument);
}

TEST_CASE("clamp_magnitude keeps direction and zeroes non-finite input") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  CHECK(clamp_magnitude({nan, 0.0, 0.0}, 1.0) == glm::dvec3{0.0});
  CHECK(clamp_magnitude({inf, 0.0, 0.0}, 1.0) == glm::dvec3{0.0});
  CHECK(clamp_magnitude({1.0, 0.0, 0.0}, nan) == glm::dvec3{0.0});
  CHECK(clamp_magnitude({3.0, 4.0, 0.0}, 1.0).x == Approx(0.6));
  CHECK(clamp_magnitude({1e300, 1e300, 0.0}, 2.0).y == Approx(std::sqrt(2.0)));
}

TEST_CASE("PlaneMapping: the Kim & Kwon preset maps 100 mm to 640 px") {
  const PlaneMapping map = PlaneMapping::kim_kwon(640, 640);
  CHECK(map.px_per_mm() == 6.4);
  // the image centre sits at the device origin
  CHECK_THAT(map.to_image(glm::dvec3{0.0}).x, WithinAbs(319.5, 1e-12));
  // +50 mm along device x is the right edge (+320 px); +50 mm up is the top
  const glm::dvec2 right_top = map.to_image({0.05, 0.05, 0.0});
  CHECK_THAT(right_top.x, WithinAbs(639.5, 1e-9));
  CHECK_THAT(right_top.y, WithinAbs(-0.5, 1e-9));
  // round trip
  const glm::dvec3 back = map.to_device({12.25, 600.0});
  const glm::dvec2 again = map.to_image(back);
  CHECK_THAT(again.x, WithinAbs(12.25, 1e-9));
  CHECK_THAT(again.y, WithinAbs(600.0, 1e-9));
  // out-of-plane offsets do not move the image point
  CHECK_THAT(map.to_image({0.0, 0.0, 0.02}).x, WithinAbs(319.5, 1e-12));
  CHECK_THAT(map.height_above_plane({0.0, 0.0, 0.02}), WithinAbs(0.02, 1e-15));
  // image-axis vectors: image +y (down the picture) is device -y
  CHECK(map.vector_to_device({0.0, 1.0}) == glm::dvec3{0.0, -1.0, 0.0});
  CHECK(map.velocity_to_image({0.001, 0.0, 0.0}).x == Approx(6.4));
}

TEST_CASE("PlaneMapping rejects bad parameters") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(PlaneMapping(0.0), std::invalid_argument);
  CHECK_THROWS_AS(PlaneMapping(-1.0), std::invalid_argument);
  CHECK_THROWS_AS(PlaneMapping(nan), std::invalid_argument);
  CHECK_THROWS_AS(PlaneMapping(1.0, {nan, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(PlaneMapping(1.0, {0.0, 0.0}, {0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}),
                  std::invalid_argument);
  CHECK_THROWS_AS(PlaneMapping(1.0, {0.0, 0.0}, {0.0, 0.0, 0.0}, {2.0, 0.0, 0.0}, {0.0, 1.0, 0.0}),
                  std::invalid_argument);
  CHECK_THROWS_AS(PlaneMapping::fit(0, 10, 100.0), std::invalid_argument);
  CHECK_THROWS_AS(PlaneMapping::kim_kwon(-1, 10), std::invalid_argument);
}

TEST_CASE("force queries through AnyField and composition never allocate") {
  AnyField field = clamp(sum(Spring{}, Counter{}), 2.0);
  Probe probe = at({0.01, 0.0, 0.0});
  const auto allocations = test::count_allocations([&] {
    for (int i = 0; i < 1000; ++i) {
      probe.time = i * 1e-3;
      (void)field.force(probe);
    }
  });
  CHECK(allocations == 0);
}

TEST_CASE("the allocation counter itself sees allocations") {
  if (!test::allocations_counted) return;  // ThreadSanitizer build: see alloc_counter.hpp
  const auto allocations = test::count_allocations([] {
    static int* volatile keep = nullptr;
    keep = new int(3);
    delete keep;
  });
  CHECK(allocations == 1);
}

namespace {
struct Constant {  // a field that returns its own id as fx
  double id = 0.0;
  glm::dvec3 force(const Probe&) const noexcept { return glm::dvec3{id, 0.0, 0.0}; }
};
}  // namespace

TEST_CASE("LiveField: a writer replaces the field while the reader ticks, lock- and allocation-free") {
  LiveField<Constant> live;
  CHECK(live.force(Probe{}) == glm::dvec3{0.0});  // nothing published yet
  live.publish(Constant{1.0});
  CHECK(live.force(Probe{}).x == 1.0);
  live.publish(Constant{2.0});
  live.publish(Constant{3.0});  // the reader sees only the newest
  CHECK(live.force(Probe{}).x == 3.0);
  CHECK(live.force(Probe{}).x == 3.0);

  constexpr int published = 20000;
  std::atomic<bool> done{false};
  std::atomic<bool> reading{false};
  std::thread writer([&] {
    while (!reading.load())
      std::this_thread::yield();  // overlap the two threads
    for (int i = 4; i <= published; ++i)
      live.publish(Constant{static_cast<double>(i)});
    done = true;
  });
  double last = 3.0;
  bool monotonic = true;
  long reads = 0;
  reading = true;
  do {
    const double id = live.force(Probe{}).x;
    monotonic = monotonic && id >= last;
    last = id;
    ++reads;
  } while (!done.load());
  writer.join();
  CHECK(monotonic);
  CHECK(live.force(Probe{}).x == published);
  CHECK(reads > 0);

  // the reader's side alone never allocates
  live.publish(Constant{7.0});
  const long reader_allocations = test::count_allocations([&] {
    for (int i = 0; i < 1000; ++i)
      (void)live.force(Probe{});
  });
  CHECK(reader_allocations == 0);
  CHECK(live.force(Probe{}).x == 7.0);
}

TEST_CASE("LatestValue: the triple buffer over values, newest only, monotonic across threads") {
  LatestValue<long> value;
  CHECK(value.latest() == nullptr);  // nothing published yet
  constexpr long published = 20000;
  std::atomic<bool> done{false};
  std::atomic<bool> reading{false};
  std::thread writer([&] {
    while (!reading.load())
      std::this_thread::yield();
    for (long i = 1; i <= published; ++i)
      value.publish(i);
    done = true;
  });
  long last = 0;
  bool monotonic = true;
  reading = true;
  do {
    if (const long* v = value.latest()) {
      monotonic = monotonic && *v >= last;
      last = *v;
    }
  } while (!done.load());
  writer.join();
  CHECK(monotonic);
  REQUIRE(value.latest() != nullptr);
  CHECK(*value.latest() == published);
  const long allocations = test::count_allocations([&] {
    for (long i = 0; i < 1000; ++i) {
      value.publish(i);
      (void)value.latest();
    }
  });
  CHECK(allocations == 0);
}

TEST_CASE("SpscRing: in order, a full ring refuses and counts, two threads") {
  struct Sample {
    double t;
    int x, y;
  };
  rt::SpscRing<Sample, 4> ring;
  for (int i = 0; i < 6; ++i)
    (void)ring.try_push({static_cast<double>(i), 0, 0});
  CHECK(ring.rejected() == 2);
  CHECK(ring.size() == 4);
  for (int i = 0; i < 4; ++i) {
    const std::optional<Sample> s = ring.try_pop();
    REQUIRE(s);
    CHECK(s->t == i);
  }
  CHECK_FALSE(ring.try_pop());

  rt::SpscRing<Sample, 256> shared;
  constexpr int n = 100000;
  std::thread producer([&] {
    for (int i = 0; i < n; ++i)
      while (!shared.try_push({static_cast<double>(i), i, -i}))
        std::this_thread::yield();
  });
  int expected = 0;
  bool in_order = true;
  while (expected < n) {
    if (const std::optional<Sample> s = shared.try_pop()) {
      in_order = in_order && s->t == expected && s->x == expected && s->y == -expected;
      ++expected;
    }
  }
  producer.join();
  CHECK(in_order);
}

TEST_CASE("reserve_on_huge_pages: a large reservation's whole 2 MB pages are marked for huge pages", "[rt]") {
  if (!test::kernel_has_huge_pages()) {
    WARN("skipped: this kernel has no transparent huge pages");
    return;
  }
  std::vector<double> big;
  reserve_on_huge_pages(big, (std::size_t{16} << 20) / sizeof(double));  // 16 MB
  REQUIRE(big.capacity() >= (std::size_t{16} << 20) / sizeof(double));
  const auto begin = reinterpret_cast<std::uintptr_t>(big.data());
  const std::uintptr_t first = (begin + huge_page_bytes - 1) & ~(huge_page_bytes - 1);
  CHECK(test::marked_for_huge_pages(reinterpret_cast<const void*>(first)));
  CHECK(test::marked_for_huge_pages(reinterpret_cast<const void*>(first + 5 * huge_page_bytes)));
  big.resize(big.capacity(), 1.5);  // written after the hint: still the same storage
  CHECK(reinterpret_cast<std::uintptr_t>(big.data()) == begin);
  CHECK(big.back() == 1.5);

  // a filled vector is moved there whole, its elements unchanged
  std::vector<std::uint32_t> filled((std::size_t{6} << 20) / sizeof(std::uint32_t));
  for (std::size_t i = 0; i < filled.size(); ++i)
    filled[i] = static_cast<std::uint32_t>(i * 2654435761u);
  const std::vector<std::uint32_t> copy = filled;
  move_to_huge_pages(filled);
  CHECK(filled == copy);
  const auto moved = reinterpret_cast<std::uintptr_t>(filled.data());
  CHECK(test::marked_for_huge_pages(
      reinterpret_cast<const void*>((moved + huge_page_bytes - 1) & ~(huge_page_bytes - 1))));

  // under 4 MB: left where it is
  std::vector<std::uint32_t> small(1000, 7u);
  const std::uint32_t* before = small.data();
  move_to_huge_pages(small);
  CHECK(small.data() == before);
  CHECK(small.size() == 1000);
}
