// The live viewer's pieces (tools/view/): nice axis ticks, the servo ->
// viewer sample ring, the mouse as a device, the scene builder, the layout
// and the drawing (cursor at the probe, arrow along the force), and the
// viewer's tick path without allocation, the video player (the frame shown
// is the frame felt; pause, seek and rebuilds keep the video time) and the
// thread that destroys replaced fields. Timing runs on virtual or manual
// loop times.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/rt/spsc_ring.hpp"
#include "hapticfield/servo.hpp"
#include "view/mouse_device.hpp"
#include "view/scene.hpp"
#include "view/scope.hpp"
#include "view/video_player.hpp"
#include "view/view_frame.hpp"
#include "view/view_sample.hpp"
#include "view/window.hpp"

using namespace hapticfield;
using namespace hapticfield::view;

namespace {

/// 120 x 80 px, white on the left, black from column 60.
cv::Mat step_picture() {
  cv::Mat m(80, 120, CV_8UC3, cv::Scalar::all(255));
  m(cv::Rect(60, 0, 60, 80)).setTo(cv::Scalar::all(0));
  return m;
}

/// Frame k of a 40-frame clip (96 x 64 px): a white square on a dark
/// gradient, 2 px further right in each frame.
cv::Mat clip_frame(int k) {
  cv::Mat m(64, 96, CV_8UC3);
  for (int x = 0; x < 96; ++x)
    m.col(x).setTo(cv::Scalar::all(20 + x));
  cv::rectangle(m, cv::Rect(4 + 2 * k, 20, 12, 12), cv::Scalar::all(255), cv::FILLED);
  return m;
}

/// The clip as a lossless PNG sequence (25 fps: the fallback rate); its printf pattern.
std::string write_clip() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(HAPTICFIELD_TEST_TMP) / "view_clip";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (int k = 0; k < 40; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "%04d.png", k);
    REQUIRE(cv::imwrite((dir / name).string(), clip_frame(k)));
  }
  return (dir / "%04d.png").string();
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

TEST_CASE("the scope draws Fz: a push along z is its own red trace, below zero when it points down") {
  Scope scope({.window = 2.0, .min_range = 0.1});
  for (int i = 0; i <= 200; ++i)  // Fz = -0.6 N for 2 s, nothing along x or y: |F| = 0.6 N above zero
    scope.add({i * 0.01, {0, 0}, {0.0, 0.0, -0.6}});
  REQUIRE(scope.range() == Catch::Detail::Approx(1.0));
  cv::Mat canvas(230, 500, CV_8UC3, cv::Scalar(0, 0, 0));
  const cv::Rect area(0, 0, 500, 230);
  scope.draw(canvas, area);
  // the plot's box as Scope::draw lays it out: the force axis from +r at its top to -r at its bottom
  const int top = 26, bottom = 230 - 40, left = 62, right = 500 - 12;
  const auto y_of = [&](double f) { return top + static_cast<int>(std::lround((1.0 - f) / 2.0 * (bottom - top))); };
  const auto has = [&](int y, const cv::Scalar& colour) {
    for (int x = left + 20; x < right - 20; x += 10)
      for (int dy = -1; dy <= 1; ++dy)
        if (cv::norm(cv::Vec3d(canvas.at<cv::Vec3b>(y + dy, x)) - cv::Vec3d(colour[0], colour[1], colour[2])) < 40.0)
          return true;
    return false;
  };
  CHECK(std::string(scope_names[2]) == "Fz");
  CHECK(has(y_of(-0.6), scope_colours[2]));        // Fz, below zero
  CHECK_FALSE(has(y_of(0.6), scope_colours[2]));   // not where |F| is
  CHECK(has(y_of(0.6), scope_colours[3]));         // |F|
  CHECK_FALSE(has(y_of(-0.6), scope_colours[0]));  // Fx and Fy stay at zero
  CHECK(scope_value({0.1, 0.2, -0.3}, 2) == -0.3);
  CHECK(scope_value({0.0, 3.0, 4.0}, 3) == Catch::Detail::Approx(5.0));
}

TEST_CASE("the wheel: notches of the vertical wheel only, fractions from fine wheels") {
  const auto flags = [](int delta) { return static_cast<int>(static_cast<unsigned>(delta & 0xffff) << 16); };
  CHECK(wheel_notches(cv::EVENT_MOUSEWHEEL, flags(120)) == 1.0);                             // forward: in
  CHECK(wheel_notches(cv::EVENT_MOUSEWHEEL, flags(-120)) == -1.0);                           // back: out
  CHECK(wheel_notches(cv::EVENT_MOUSEWHEEL, flags(-240) | cv::EVENT_FLAG_CTRLKEY) == -2.0);  // modifiers ignored
  CHECK(wheel_notches(cv::EVENT_MOUSEWHEEL, flags(15)) == Catch::Detail::Approx(0.125));     // a touchpad's step
  CHECK(wheel_notches(cv::EVENT_MOUSEHWHEEL, flags(120)) == 0.0);                            // sideways: nothing
  CHECK(wheel_notches(cv::EVENT_MOUSEMOVE, flags(120)) == 0.0);
  CHECK(wheel_notches(cv::EVENT_LBUTTONDOWN, 0) == 0.0);
  // 35 notches in, then 35 out: back where it started, by exactly 35 mm each way at 1 mm a notch
  double depth = 0.0;
  for (int i = 0; i < 35; ++i)
    depth += wheel_notches(cv::EVENT_MOUSEWHEEL, flags(120));
  CHECK(depth == 35.0);
  for (int i = 0; i < 35; ++i)
    depth += wheel_notches(cv::EVENT_MOUSEWHEEL, flags(-120));
  CHECK(depth == 0.0);
}

TEST_CASE("the window's flags: fixed size, no toolbar, an OpenGL view under Qt with OpenGL (its wheel does not zoom)") {
  const int plain = cv::WINDOW_AUTOSIZE | cv::WINDOW_GUI_NORMAL;
  const std::string qt_gl =
      "  GUI:                           QT5\n    QT:                          YES (ver 5.15.8 )\n"
      "      QT OpenGL support:         YES (Qt5::OpenGL 5.15.8)\n    OpenGL support:              YES\n";
  const std::string qt_no_gl =
      "  GUI:                           QT5\n    QT:                          YES (ver 5.15.8 )\n"
      "      QT OpenGL support:         NO\n";
  const std::string gtk =
      "  GUI:                           GTK3\n    GTK+:                        YES (ver 3.24.37)\n"
      "    OpenGL support:              NO\n";
  CHECK(window_flags(qt_gl) == (plain | cv::WINDOW_OPENGL));
  CHECK(window_flags(qt_no_gl) == plain);
  CHECK(window_flags(gtk) == plain);
  CHECK(window_flags("") == plain);
  CHECK(qt_with_opengl(qt_gl));
  CHECK_FALSE(qt_with_opengl(gtk));
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
  rt::SpscRing<ViewSample, 8192> ring;

  // the real loop on a virtual clock, the tick as the viewer writes it
  ServoLoop<MouseDevice<VirtualClock>, VirtualClock> loop(mouse, clock);
  auto tick = [&](const TickInput& in) noexcept {
    (void)ring.try_push({in.probe.time, mapping.to_image(in.probe.position), loop.last_command()});
    return live.force(in.probe);
  };
  loop.run(tick, {.max_ticks = 1000});
  ViewSample last;
  int n = 0;
  while (const std::optional<ViewSample> s = ring.try_pop()) {
    last = *s;
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
      (void)ring.try_push({probe.time, mapping.to_image(probe.position), f});
      (void)mouse.write(f);
      if (i % 100 == 0) {
        while (ring.try_pop()) {
        }
      }
    }
  });
  CHECK(allocations == 0);
}

TEST_CASE("the f key's cycle, the d key's steps and the labels, video included") {
  CHECK(next_kind(FieldKind::tangible, false, false) == FieldKind::texture);  // normals need faces
  CHECK(next_kind(FieldKind::tangible, true, false) == FieldKind::normals);
  CHECK(next_kind(FieldKind::texture, true, false) == FieldKind::tangible);  // video needs a video
  CHECK(next_kind(FieldKind::texture, false, true) == FieldKind::video);
  CHECK(next_kind(FieldKind::video, false, true) == FieldKind::tangible);
  SceneConfig c;
  next_denoise(c);
  CHECK(c.denoise_px == 1.0);
  CHECK(c.video_denoise == DenoiseMode::temporal);  // untouched by a still field
  c.kind = FieldKind::video;
  next_denoise(c);
  CHECK(c.video_denoise == DenoiseMode::spatial);
  next_denoise(c);
  next_denoise(c);
  CHECK(c.video_denoise == DenoiseMode::none);
  CHECK(c.denoise_px == 1.0);
  CHECK(scene_label(c) == "video: prewitt 17 px, border fade, denoise none, 1.00 N at an edge");
  CHECK_THROWS_AS(build_scene(step_picture(), c, PlaneMapping::fit(120, 80, 80.0)), std::invalid_argument);
}

TEST_CASE("VideoPlayer: the frame shown is the frame at the loop's video time; pause, seek and rebuilds") {
  const std::string clip = write_clip();
  const PlaneMapping mapping = PlaneMapping::fit(96, 64, 80.0);
  VideoPlayerConfig pc;
  pc.seek_step = 0.4;
  VideoPlayer player(clip, pc);
  CHECK(player.fps() == 25.0);
  CHECK(player.duration() == Catch::Detail::Approx(1.6));
  CHECK(cv::norm(player.frame(), clip_frame(0), cv::NORM_INF) == 0.0);  // the first view, before any field
  SceneConfig c;
  c.kind = FieldKind::video;
  c.size = 5;
  c.video_denoise = DenoiseMode::none;
  LiveField<AnyField> live(player.start(c, mapping));
  REQUIRE(player.playing());
  // The servo thread's part by hand: the live field at chosen loop times.
  Probe probe;
  probe.position = mapping.to_device(glm::dvec2{48.0, 40.0});
  const auto tick_at = [&](double loop_time) {
    probe.time = loop_time;
    (void)live.force(probe);
  };
  const auto shows = [&](int k) {
    const cv::Mat& shown = player.settle(std::chrono::milliseconds(2000));
    CAPTURE(k, player.time(), player.status().frame);
    CHECK(player.status().frame == k);
    CHECK(cv::norm(shown, clip_frame(k), cv::NORM_INF) == 0.0);
  };
  tick_at(10.0);  // the clock anchors: video time 0
  tick_at(10.5);
  CHECK(player.time() == Catch::Detail::Approx(0.5));
  shows(12);  // 0.5 s at 25 fps
  tick_at(10.61);
  shows(15);

  // pause: the video time stays where it was, whatever the loop's clock does
  CHECK(player.toggle_pause());
  tick_at(10.7);
  tick_at(13.0);
  CHECK(player.time() == Catch::Detail::Approx(0.61));
  CHECK(player.status().paused);
  shows(15);
  CHECK_FALSE(player.toggle_pause());
  tick_at(13.1);  // the loop takes up the resume here
  tick_at(13.2);
  CHECK(player.time() == Catch::Detail::Approx(0.71));

  // a rebuild (another mask, paused) starts at the current video time
  CHECK(player.toggle_pause());
  c.mask = MaskKind::sobel;
  c.size = 3;
  live.publish(player.start(c, mapping));
  CHECK(player.time() == Catch::Detail::Approx(0.71));  // before the new field's first tick
  tick_at(20.0);
  tick_at(21.0);
  CHECK(player.time() == Catch::Detail::Approx(0.71));  // still paused
  CHECK_FALSE(player.toggle_pause());
  tick_at(21.2);
  tick_at(21.4);
  CHECK(player.time() == Catch::Detail::Approx(0.91));
  shows(22);

  // seek: one step on, then clamped to the end and to 0 (applied at the next tick)
  CHECK(player.seek_by(1) == Catch::Detail::Approx(1.31));
  tick_at(21.4);
  CHECK(player.time() == Catch::Detail::Approx(1.31));
  shows(32);
  CHECK(player.seek_by(5) == Catch::Detail::Approx(1.6));
  tick_at(21.4);
  CHECK(player.time() == Catch::Detail::Approx(1.6));
  CHECK(player.seek_by(-10) == 0.0);
  tick_at(21.5);
  CHECK(player.time() == 0.0);
  shows(0);
  tick_at(21.7);
  shows(5);

  // a still field of the frame shown: the video stops there and starts there again
  const cv::Mat still = player.frame().clone();
  SceneConfig sc = c;
  sc.kind = FieldKind::tangible;
  Scene fresh = build_scene(still, sc, mapping);
  player.stop();
  live.publish(std::move(fresh.field));
  CHECK_FALSE(player.playing());
  tick_at(30.0);
  CHECK(player.time() == Catch::Detail::Approx(0.2));
  CHECK(player.seek_by(1) == Catch::Detail::Approx(0.6));  // remembered for the next start
  live.publish(player.start(c, mapping));
  tick_at(40.0);
  CHECK(player.time() == Catch::Detail::Approx(0.6));
  shows(15);
}

TEST_CASE("VideoPlayer: a missing video, a start past the end, a bad speed") {
  namespace fs = std::filesystem;
  const std::string clip = write_clip();
  CHECK_THROWS_AS(VideoPlayer((fs::path(HAPTICFIELD_TEST_TMP) / "no_such.avi").string(), {}), FileError);
  CHECK_THROWS_AS(VideoPlayer(clip, VideoPlayerConfig{.from = 2.0}), Error);
  CHECK_THROWS_AS(VideoPlayer(clip, VideoPlayerConfig{.speed = 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(VideoPlayer(clip, VideoPlayerConfig{.speed = 17.0}), std::invalid_argument);
  const VideoPlayer late(clip, VideoPlayerConfig{.from = 1.0});
  CHECK(late.expected_index() == 25);
}

namespace {
/// A field that records the thread that destroys it.
struct Witness {
  std::mutex* mutex;
  std::vector<std::thread::id>* destroyed_on;
  bool moved_from{false};
  Witness(std::mutex* m, std::vector<std::thread::id>* d) : mutex(m), destroyed_on(d) {}
  Witness(Witness&& o) noexcept : mutex(o.mutex), destroyed_on(o.destroyed_on) { o.moved_from = true; }
  Witness& operator=(Witness&&) = delete;
  ~Witness() {
    if (moved_from) return;
    std::lock_guard<std::mutex> lock(*mutex);
    destroyed_on->push_back(std::this_thread::get_id());
  }
  [[nodiscard]] glm::dvec3 force(const Probe& /*p*/) const noexcept { return glm::dvec3{1.0, 0.0, 0.0}; }
};
}  // namespace

TEST_CASE("LiveField destroys replaced fields on the publishing thread, never in the servo thread's tick") {
  // The viewer publishes a new VideoField (which joins its worker when
  // destroyed) while the loop runs: the old one must die on the viewer's
  // thread. Here the fields record who destroys them.
  std::mutex mutex;
  std::vector<std::thread::id> destroyed_on;
  {
    LiveField<AnyField> live(AnyField(Witness(&mutex, &destroyed_on)));
    std::atomic<bool> stop{false};
    std::atomic<long> ticks{0};
    std::thread servo([&] {
      Probe p;
      while (!stop.load()) {
        (void)live.force(p);
        ticks.fetch_add(1);
      }
    });
    for (int i = 0; i < 200; ++i) {
      live.publish(AnyField(Witness(&mutex, &destroyed_on)));
      const long seen = ticks.load();
      while (ticks.load() < seen + 3)  // the loop takes it up
        std::this_thread::yield();
    }
    stop.store(true);
    servo.join();
    std::lock_guard<std::mutex> lock(mutex);
    CHECK(destroyed_on.size() >= 190);  // all but the three in the buffer
    for (const std::thread::id id : destroyed_on)
      CHECK(id == std::this_thread::get_id());
  }
  CHECK(destroyed_on.size() == 201);  // the rest with the LiveField, here
}
