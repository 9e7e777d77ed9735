// The live viewer's pieces (examples/view/): nice axis ticks, the servo ->
// viewer sample ring, the mouse as a device, the scene builder, the layout
// and the drawing (cursor at the probe, arrow along the force), and the
// viewer's tick path without allocation. Timing runs on a virtual clock.
#include <catch2/catch.hpp>

#include <cmath>
#include <thread>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/servo.hpp"
#include "view/mouse_device.hpp"
#include "view/sample_ring.hpp"
#include "view/scene.hpp"
#include "view/scope.hpp"
#include "view/view_frame.hpp"

using namespace hapticfield;
using namespace hapticfield::view;

namespace {

/// 120 x 80 px, white on the left, black from column 60.
cv::Mat step_picture() {
  cv::Mat m(80, 120, CV_8UC3, cv::Scalar::all(255));
  m(cv::Rect(60, 0, 60, 80)).setTo(cv::Scalar::all(0));
  return m;
}

}  // namespace

TEST_CASE("nice_ticks: 1, 2 or 5 times a power of ten, covering the range") {
  CHECK(nice_ticks(-1.0, 1.0, 4) == std::vector<double>{-1.0, -0.5, 0.0, 0.5, 1.0});
  CHECK(nice_ticks(-5.0, 0.0, 5) == std::vector<double>{-5.0, -4.0, -3.0, -2.0, -1.0, 0.0});
  const std::vector<double> t = nice_ticks(0.0, 0.37, 5);  // raw step 0.074 -> 0.1
  REQUIRE(t.size() == 4);
  CHECK(t[3] == Catch::Detail::Approx(0.3));
  const std::vector<double> big = nice_ticks(-250.0, 250.0, 4);  // raw 125 -> 200
  CHECK(big == std::vector<double>{-200.0, 0.0, 200.0});
  CHECK(nice_ticks(1.0, 1.0).empty());
  CHECK(nice_ticks(2.0, 1.0).empty());
  CHECK(nice_ticks(0.0, std::nan("")).empty());
  CHECK(tick_label(0.5, 0.5) == "0.5");
  CHECK(tick_label(-2.0, 1.0) == "-2");
  CHECK(tick_label(0.25, 0.05) == "0.25");
}

TEST_CASE("Scope::range is a nice value above the largest force, and the window rolls") {
  Scope scope({.window = 2.0, .min_range = 0.1});
  CHECK(scope.range() == Catch::Detail::Approx(0.1));
  scope.add({0.0, {0, 0}, {0.3, 0.4, 0.0}});  // |F| = 0.5 N -> 0.55 -> 1
  CHECK(scope.range() == Catch::Detail::Approx(1.0));
  scope.add({1.0, {0, 0}, {1.5, 0.0, 0.0}});  // 1.65 -> 2
  CHECK(scope.range() == Catch::Detail::Approx(2.0));
  scope.add({3.5, {0, 0}, {0.0, 0.0, 0.0}});  // both older than 2 s: dropped
  CHECK(scope.samples().size() == 1);
  CHECK(scope.range() == Catch::Detail::Approx(0.1));
}

TEST_CASE("SampleRing: in order, a full ring drops and counts, two threads") {
  SampleRing<4> ring;
  for (int i = 0; i < 6; ++i)
    ring.push({static_cast<double>(i), {0, 0}, {0, 0, 0}});
  CHECK(ring.dropped() == 2);
  ViewSample s;
  for (int i = 0; i < 4; ++i) {
    REQUIRE(ring.pop(s));
    CHECK(s.t == i);
  }
  CHECK_FALSE(ring.pop(s));

  SampleRing<256> shared;
  constexpr int n = 100000;
  std::thread producer([&] {
    for (int i = 0; i < n; ++i)
      while (!shared.push({static_cast<double>(i), {i, -i}, {0, 0, 0}}))
        std::this_thread::yield();
  });
  int expected = 0;
  bool in_order = true;
  while (expected < n) {
    if (shared.pop(s)) {
      in_order = in_order && s.t == expected && s.pixel.x == expected && s.pixel.y == -expected;
      ++expected;
    }
  }
  producer.join();
  CHECK(in_order);
}

TEST_CASE("MouseDevice: the pointer's pixel on the plane, a filtered velocity, forces go nowhere") {
  const PlaneMapping mapping = PlaneMapping::fit(120, 80, 80.0);
  VirtualClock clock;
  MouseDevice<VirtualClock> mouse(mapping, clock);
  mouse.set_pixel(30.0, 20.0);
  DeviceState state;
  REQUIRE(mouse.read(state) == Status::ok);
  CHECK(state.valid);
  CHECK(state.armed());
  CHECK(state.homed());
  const glm::dvec3 p = mapping.to_device(glm::dvec2{30.0, 20.0});
  CHECK(state.position.x == Catch::Detail::Approx(p.x));
  CHECK(state.position.y == Catch::Detail::Approx(p.y));
  CHECK(state.position.z == 0.0);
  // moving right at 100 px/s for 0.5 s: the velocity settles to 100 px/s
  // in metres (time constant 20 ms, 25 of them)
  for (int i = 1; i <= 500; ++i) {
    clock.advance(1'000'000);  // 1 ms
    mouse.set_pixel(30.0 + 0.1 * i, 20.0);
    mouse.read(state);
  }
  const double expected = 100.0 / mapping.px_per_mm() * 1e-3;  // [m/s]
  CHECK(state.velocity.x == Catch::Detail::Approx(expected).epsilon(1e-3));
  CHECK(std::abs(state.velocity.y) < 1e-9);
  CHECK(mouse.write(glm::dvec3{1.0, 2.0, 3.0}) == Status::ok);
}

TEST_CASE("build_scene: the tangible field pushes toward the dark side with 1 N at a black/white edge") {
  const cv::Mat picture = step_picture();
  const PlaneMapping mapping = PlaneMapping::fit(picture.cols, picture.rows, 80.0);
  SceneConfig c;
  c.size = 9;
  c.border = Border::clamp;
  Scene scene = build_scene(picture, c, mapping);
  Probe probe;
  // at the edge (between columns 59 and 60) a black/white edge: |F| = gain
  probe.position = mapping.to_device(glm::dvec2{59.5, 40.0});
  const glm::dvec3 f = scene.field.force(probe);
  CHECK(f.x == Catch::Detail::Approx(1.0).epsilon(0.02));  // toward the black, +x
  CHECK(f.y == Catch::Detail::Approx(0.0).margin(1e-9));
  probe.position = mapping.to_device(glm::dvec2{20.0, 40.0});  // flat white
  CHECK(glm::length(scene.field.force(probe)) == Catch::Detail::Approx(0.0).margin(1e-12));
  CHECK(scene.label.find("prewitt 9 px") != std::string::npos);
  // denoise blurs the picture shown (and felt): OpenCV's blur is the oracle
  c.denoise_px = 2.0;
  Scene blurred = build_scene(picture, c, mapping);
  cv::Mat expected;
  cv::GaussianBlur(picture, expected, cv::Size(), 2.0);
  CHECK(cv::norm(blurred.underlay, expected, cv::NORM_INF) == 0.0);
  // a size a mask refuses is an exception (the viewer shows it and keeps the old field)
  c.mask = MaskKind::sobel;
  c.size = 33;
  CHECK_THROWS_AS(build_scene(picture, c, mapping), std::invalid_argument);
  CHECK(step_size(MaskKind::sobel, 31, 1) == 31);
  CHECK(step_size(MaskKind::prewitt, 17, -2) == 13);
  CHECK(step_size(MaskKind::roberts, 2, 5) == 2);
}

TEST_CASE("build_scene: normals need faces, and a face tints the picture by its normal") {
  const cv::Mat picture = step_picture();
  const PlaneMapping mapping = PlaneMapping::fit(picture.cols, picture.rows, 80.0);
  SceneConfig c;
  c.kind = FieldKind::normals;
  CHECK_THROWS_AS(build_scene(picture, c, mapping), std::invalid_argument);
  c.faces = {{{10, 10}, {50, 10}, {50, 50}, {10, 50}}};  // a square seen head-on
  c.focal_px = 100.0;
  Scene s = build_scene(picture, c, mapping);
  CHECK(s.underlay.size() == picture.size());
  CHECK(s.underlay.at<cv::Vec3b>(30, 30) != picture.at<cv::Vec3b>(30, 30));
  CHECK(s.underlay.at<cv::Vec3b>(70, 100) == picture.at<cv::Vec3b>(70, 100));
  c.kind = FieldKind::texture;
  Scene t = build_scene(picture, c, mapping);
  CHECK(t.label.find("texture") == 0);
  cv::Scalar mean, dev;
  cv::meanStdDev(t.underlay, mean, dev);
  CHECK(dev[0] > 5.0);  // a patch, not a flat colour
}

TEST_CASE("ViewLayout and draw_view: the cursor at the probe, the arrow along the force") {
  const ViewLayout small = ViewLayout::for_picture(120, 80);
  CHECK(small.scale == 1.0);
  const ViewLayout big = ViewLayout::for_picture(1600, 900);
  CHECK(big.scale == Catch::Detail::Approx(0.5));
  CHECK(big.picture.width == 800);
  const glm::dvec2 back = big.to_picture(big.to_canvas({400.0, 300.0}).x, big.to_canvas({400.0, 300.0}).y);
  CHECK(back.x == Catch::Detail::Approx(400.0));
  CHECK(back.y == Catch::Detail::Approx(300.0));

  const cv::Mat picture(80, 120, CV_8UC3, cv::Scalar(90, 90, 90));
  Scope scope;
  ViewSample now{1.0, {40.0, 50.0}, {0.5, 0.0, 0.0}};  // 0.5 N along +x: 75 px to the right
  scope.add(now);
  cv::Mat canvas;
  draw_view(canvas, small, picture, scope, now, ViewStatus{});
  REQUIRE(canvas.size() == small.canvas);
  const cv::Point at = small.to_canvas(now.pixel);
  CHECK(canvas.at<cv::Vec3b>(at) == cv::Vec3b(255, 0, 255));
  const auto is_arrow = [&](cv::Point p) {
    const cv::Vec3b c = canvas.at<cv::Vec3b>(p);
    return c[0] < 60 && c[1] > 150 && c[2] > 200;  // orange-yellow
  };
  CHECK(is_arrow(at + cv::Point(40, 0)));
  CHECK_FALSE(is_arrow(at + cv::Point(-40, 0)));
  CHECK(canvas.at<cv::Vec3b>(at + cv::Point(-30, -30)) == cv::Vec3b(90, 90, 90));  // the picture itself
  // a force up (device +y) points up the picture
  now.force = {0.0, 0.3, 0.0};
  draw_view(canvas, small, picture, scope, now, ViewStatus{});
  CHECK(is_arrow(at + cv::Point(0, -30)));
  CHECK_FALSE(is_arrow(at + cv::Point(0, 30)));
}

TEST_CASE("the viewer's tick: mouse read, live field, sample push, command, without allocation") {
  const cv::Mat picture = step_picture();
  const PlaneMapping mapping = PlaneMapping::fit(picture.cols, picture.rows, 80.0);
  SceneConfig c;
  c.size = 9;
  LiveField<AnyField> live(build_scene(picture, c, mapping).field);
  VirtualClock clock;
  MouseDevice<VirtualClock> mouse(mapping, clock);
  mouse.set_pixel(59.5, 40.0);
  SampleRing<8192> ring;

  // the real loop on a virtual clock, the tick as the viewer writes it
  ServoLoop<MouseDevice<VirtualClock>, VirtualClock> loop(mouse, clock);
  auto tick = [&](const TickInput& in) noexcept {
    (void)ring.push({in.probe.time, mapping.to_image(in.probe.position), loop.last_command()});
    return live.force(in.probe);
  };
  loop.run(tick, {.max_ticks = 1000});
  ViewSample s, last;
  int n = 0;
  while (ring.pop(s)) {
    last = s;
    ++n;
  }
  CHECK(n == 1000);
  CHECK(last.pixel.x == Catch::Detail::Approx(59.5));
  CHECK(last.pixel.y == Catch::Detail::Approx(40.0));
  CHECK(last.force.x == Catch::Detail::Approx(1.0).epsilon(0.02));  // after the soft start, the edge's 1 N

  if (!test::allocations_counted) return;  // ThreadSanitizer build: see alloc_counter.hpp
  DeviceState state;
  Probe probe;
  const long allocations = test::count_allocations([&] {
    for (int i = 0; i < 2000; ++i) {
      clock.advance(1'000'000);
      mouse.read(state);
      probe.position = state.position;
      probe.velocity = state.velocity;
      const glm::dvec3 f = live.force(probe);
      (void)ring.push({probe.time, mapping.to_image(probe.position), f});
      (void)mouse.write(f);
      if (i % 100 == 0) {
        while (ring.pop(s)) {
        }
      }
    }
  });
  CHECK(allocations == 0);
}
