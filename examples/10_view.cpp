// hapticfield_view: a live window showing what the arm feels. The picture
// (or the field's own underlay: normals faces, a texture patch) with the
// probe as a cursor and the force as an arrow, the loop's rate, jitter,
// missed deadlines and safety events, and a rolling scope of Fx, Fy, Fz, |F|.
// The probe follows the mouse (forces shown, not felt), the simulated arm's
// scripted hand, or a real arm. The servo loop runs on its own thread and
// never waits for drawing: ticks hand samples to the window through a
// lock-free ring, the window hands new fields to the loop through a
// LiveField. --screenshot draws the same view off-screen (no display).
// A video is felt through a VideoField, and the window shows the frame
// being felt (the newest decoded frame at the loop's video time).
// --shape shows a mesh or a height map in a 3D view (our own software
// renderer, view/mesh_render.hpp) with the proxy, the HIP and the force.
//
//   hapticfield_view SOURCE [--field tangible|video|normals|texture] [field options]
//       [--device mouse|sim|hid[:VID:PID]|...] [--list-devices] [--screenshot OUT.png --seconds S]
//   hapticfield_view --shape FILE [--height-mm H] [--radius MM] [--view YAW,PITCH] [--distance MM]
//       [same probe options]
#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/highgui.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.hpp"
#include "common/device_option.hpp"
#include "common/loop_thread.hpp"
#include "common/picture.hpp"
#include "common/servo_options.hpp"
#include "common/stop_signal.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/device/device_error.hpp"
#include "hapticfield/image.hpp"
#include "hapticfield/io/mesh_read.hpp"
#include "hapticfield/rt/spsc_ring.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"
#include "hapticfield/video.hpp"
#include "view/mouse_device.hpp"
#include "view/orbit_camera.hpp"
#include "view/scene.hpp"
#include "view/scene3d.hpp"
#include "view/scope.hpp"
#include "view/video_player.hpp"
#include "view/view_frame.hpp"
#include "view/view_options.hpp"
#include "view/view_sample.hpp"
#include "view/window.hpp"
#if HAPTICFIELD_EXAMPLE_SHAPES
#include "view/shape_scene.hpp"
#endif

using namespace hapticfield;
using namespace hapticfield::view;

namespace {

constexpr const char* usage_text =
    "usage: hapticfield_view SOURCE [options]\n"
    "A live window showing what the arm feels: the picture under the probe, the probe as a\n"
    "cursor, the force as an arrow, a rolling scope of Fx, Fy, Fz, |F| and the loop's timing and\n"
    "safety events. The servo loop runs on its own thread and never waits for drawing.\n"
    "  SOURCE               a picture file (any format OpenCV reads), or a video file or an\n"
    "                       image sequence (a printf pattern such as frames/%04d.png)\n"
    "  --field F            tangible (the default for a picture), video (the default for a\n"
    "                       video; a video only), normals or texture (of the frame shown)\n"
    "tangible pictures and video:\n"
    "  --mask M             prewitt (default), sobel, scharr, roberts, gauss or emboss\n"
    "  --size M             mask size [px]: odd 3..129 (sobel 3..31, scharr 3, roberts 2)\n"
    "  --border B           suspend, clamp, reflect or fade (default)\n"
    "  --denoise SIGMA|D    a picture: blur it first, sigma [px] in [0, 20] (default 0: none);\n"
    "                       video: none, temporal (default), spatial or both (compression noise)\n"
    "  --gain N             force at a black/white edge [N], in [0, 10] (default 1)\n"
    "video only:\n"
    "  --speed R            playback rate [video s per s], in (0, 16] (default 1)\n"
    "  --from S             start at video time S [s], in [0, the video's length] (default 0)\n"
    "  --loop               start again at 0 after the end (default: hold the last frame)\n"
    "  --fade-ms MS         fade out and in across a scene cut [ms], in [0, 10000] (default 100)\n"
    "  --max-mpx N          largest picture, video frame or height map accepted [megapixels],\n"
    "                       in (0, 1e6] (default 100), checked before decoding\n"
    "normals from a picture (Kim & Kwon):\n"
    "  --face CORNERS       \"x1,y1 x2,y2 x3,y3 x4,y4\" [px] around a planar face; repeat per face\n"
    "  --focal F            focal length [px] in [1, 1e6] (default: a 60 degree field of view)\n"
    "stochastic texture:\n"
    "  --grain MM           Gaussian lattice spacing [mm], in [0.1, 50] (default 2)\n"
    "  --texture-gain N     force per texture unit [N], in [0, 5] (default 0.5)\n"
    "a shape in 3D (instead of SOURCE; felt through a proxy, k = 1500 N/m):\n"
    "  --shape FILE         a mesh (.stl, .obj, .gltf, .glb) or a height map picture (white high),\n"
    "                       scaled so its footprint spans 80 mm, its top 1 mm below the start\n"
    "                       (a mesh file of at most 512 MB, a height map of at least 2 x 2 px)\n"
    "  --max-triangles N    most triangles a mesh may make, counted before it is read, in\n"
    "                       1..20000000 (default 20000000); a height map: --max-mpx\n"
    "  --height-mm H        a height map's height of white over black [mm], in (0, 100] (default 4)\n"
    "  --radius MM          the tool's radius [mm], in [0, 50] (default 0: a point, drawn as a dot);\n"
    "                       > 0 a ball centred on the HIP, felt against the mesh and drawn as a\n"
    "                       shaded ball of that radius at the proxy (on a height map, each cell\n"
    "                       is two flat triangles for the ball)\n"
    "  --view YAW,PITCH     the camera's orbit [degrees]: yaw in [-180, 180] about y (up), pitch in\n"
    "                       [-89, 89] (default 25,30; 0,0 looks from +z, the user's side)\n"
    "  --distance MM        the camera's distance from the shape's centre [mm], in [1, 1e5]\n"
    "                       (default: the shape fills about 70 % of the view's height)\n"
    "probe and loop:\n"
    "  --device D           mouse (default: forces shown, not felt), sim (the simulated arm's\n"
    "                       scripted hand raster-scans the picture), hid[:VID:PID] (a real arm), or any\n"
    "                       arm servo_demo opens (servo_demo --help lists every family)\n"
    "  --list-devices       one line per arm family: present, or why not; then exit\n"
    "  --start X,Y          the mouse probe's position before the pointer moves [px]\n"
    "                       (default: the picture's centre); a shape's HIP starts 5 mm above its top\n"
    "  --rate HZ            servo rate [Hz], in [1, 10000] (default 1000)\n"
    "  --realtime R         off, best_effort (default) or enforce\n"
    "  --seconds S          stop after S [s], in (0, 3600] (window: default until q or Esc)\n"
    "  --screenshot OUT.png draw the view off-screen after --seconds and write it; no window\n"
    "  --shots DIR          where the s key saves screenshots (default: the current folder)\n"
    "  -h, --help           this text\n"
    "Keys: f field, m mask, + / - size (texture: grain), b border, d denoise, space pause and\n"
    "resume, [ ] seek -5 s / +5 s (the video field), s screenshot, q or Esc quit.\n"
    "A shape: the mouse moves the HIP in the view plane, the wheel or [ ] push it in and out\n"
    "(1 mm a notch; the wheel moves the probe only, it does not zoom the window), right-drag\n"
    "or j l i k orbit, + - zoom, r resets the view, s screenshot, q or Esc quit.\n"
    "Ctrl-C or SIGTERM stops the loop through its stop (zero force, then disarm).\n"
    "Exit status: 0 done, 1 bad input or failure, 2 usage error, 128 + N stopped by signal N.\n";

struct Arguments {
  std::string source;
  SceneConfig scene;
  bool kind_given{false};
  bool blur_given{false};  ///< --denoise with a sigma above 0 (pictures)
  VideoPlayerConfig video;
  std::vector<std::string> video_only;           ///< the video-only options given
  std::uint64_t max_pixels{default_max_pixels};  ///< largest picture or frame decoded [px]
  std::string device{"mouse"};
  std::optional<DeviceSpec> arm;  ///< the arm --device names (none: the mouse)
  bool list_devices{false};       ///< --list-devices: say which arms are present, then exit
  std::optional<glm::dvec2> start;
  double rate{1000.0};
  RealTime realtime{RealTime::best_effort};
  std::optional<double> seconds;
  std::string screenshot;
  std::string shots{"."};
  // a shape in 3D
  std::string shape;
  std::size_t max_triangles{io::default_max_mesh_triangles};  ///< a mesh's most triangles
  std::vector<std::string> shape_only;                        ///< the shape-only options given
  double height_mm{4.0};
  double radius_mm{0.0};  ///< the tool's radius [mm]
  ViewOptions view;       ///< the camera's start (r in the window returns to it)
};

[[noreturn]] void usage(const std::string& error) {
  throw cli::UsageError(error);
}

std::optional<DenoiseMode> denoise_mode(const std::string& v) {
  for (const DenoiseMode m : {DenoiseMode::none, DenoiseMode::temporal, DenoiseMode::spatial, DenoiseMode::both})
    if (v == to_string(m)) return m;
  return std::nullopt;
}

/// A still picture (else a video): by the name's ending, or by the file's
/// first bytes when a picture decoder knows them.
bool is_still_picture(const std::string& path) {
  if (path.find('%') != std::string::npos) return false;  // an image sequence, whatever its files are
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".jpe", ".bmp", ".dib", ".tif", ".tiff", ".webp", ".pgm", ".ppm",
                        ".pbm", ".pnm", ".pxm",  ".pfm", ".sr",  ".ras", ".exr", ".hdr",  ".pic",  ".jp2"})
    if (ext == e) return true;
  try {
    return std::filesystem::is_regular_file(path) && cv::haveImageReader(path);
  } catch (const std::exception&) {
    return false;
  }
}

/// The status panel's name of the device: the simulated arm says so.
std::string device_label(const Arguments& o, const std::string& name) {
  return o.arm && o.arm->simulated ? "simulated arm (no real device)" : name;
}

/// "x1,y1 x2,y2 x3,y3 x4,y4": four finite corners.
std::vector<glm::dvec2> parse_face(const std::string& text) {
  std::istringstream in(text);
  std::vector<glm::dvec2> corners;
  std::string pair;
  while (in >> pair) {
    const auto [x, y] = cli::parse_pair(pair, "--face", cli::closed(-1e6, 1e6));
    corners.emplace_back(x, y);
  }
  if (corners.size() != 4)
    usage("--face expects 4 corners \"x1,y1 x2,y2 x3,y3 x4,y4\", got " + std::to_string(corners.size()));
  return corners;
}

Arguments parse(cli::Parser& p) {
  Arguments o;
  bool size_given = false;
  cli::Input source("SOURCE");
  while (p.next()) {
    if (o.view.take(p)) continue;  // --view, --distance
    if (p.is("--field")) {
      o.scene.kind = p.choice<FieldKind>("field", {{"tangible", FieldKind::tangible},
                                                   {"video", FieldKind::video},
                                                   {"normals", FieldKind::normals},
                                                   {"texture", FieldKind::texture}});
      o.kind_given = true;
    } else if (p.is("--mask")) {
      o.scene.mask = p.named("mask", mask_kinds);
    } else if (p.is("--size")) {
      o.scene.size = static_cast<int>(p.integer(2, 129));
      size_given = true;
    } else if (p.is("--border")) {
      o.scene.border = p.named("border", border_kinds);
    } else if (p.is("--denoise")) {
      const std::string v = p.value();
      if (const auto mode = denoise_mode(v)) {
        o.scene.video_denoise = *mode;
        if (*mode != DenoiseMode::none) o.video_only.push_back("--denoise " + v);
      } else {
        double sigma = 0.0;
        try {
          sigma = cli::parse_real(v, "--denoise");
        } catch (const cli::UsageError&) {
          usage("--denoise expects a blur sigma [px] or a video's none, temporal, spatial or both, got '" + v + "'");
        }
        if (!cli::closed(0.0, 20.0).contains(sigma)) usage("--denoise must be in [0, 20] px, got '" + v + "'");
        o.scene.denoise_px = sigma;
        o.blur_given = o.blur_given || sigma > 0.0;
      }
    } else if (p.is("--speed")) {
      o.video.speed = p.real(cli::open_closed(0.0, max_playback_rate));
      o.video_only.emplace_back("--speed");
    } else if (p.is("--from")) {
      o.video.from = p.real(cli::closed(0.0, 1e6));
      o.video_only.emplace_back("--from");
    } else if (p.is("--loop")) {
      o.video.loop = true;
      o.video_only.emplace_back("--loop");
    } else if (p.is("--fade-ms")) {
      o.video.fade = p.real(cli::closed(0.0, 10000.0)) * 1e-3;
      o.video_only.emplace_back("--fade-ms");
    } else if (p.is("--max-mpx")) {
      o.max_pixels = p.megapixels();
      o.video.max_pixels = o.max_pixels;
    } else if (p.is("--gain")) {
      o.scene.gain = p.real(cli::closed(0.0, 10.0));
    } else if (p.is("--face")) {
      o.scene.faces.push_back(parse_face(p.value()));
    } else if (p.is("--focal")) {
      o.scene.focal_px = p.real(cli::closed(1.0, 1e6));
    } else if (p.is("--grain")) {
      o.scene.grain_mm = p.real(cli::closed(0.1, 50.0));
    } else if (p.is("--texture-gain")) {
      o.scene.texture_gain = p.real(cli::closed(0.0, 5.0));
    } else if (p.is("--device")) {
      o.device = p.value();
      o.arm.reset();
      if (o.device != "mouse") o.arm = cli::device_option(o.device);
    } else if (p.is("--list-devices")) {
      o.list_devices = true;
    } else if (p.is("--start")) {
      const auto [x, y] = p.pair(cli::closed(-1e6, 1e6));
      o.start = glm::dvec2{x, y};
    } else if (p.is("--rate")) {
      o.rate = p.real(cli::closed(min_servo_rate, max_servo_rate));
    } else if (p.is("--realtime")) {
      o.realtime = cli::realtime_option(p);
    } else if (p.is("--seconds")) {
      o.seconds = p.real(cli::open_closed(0.0, 3600.0));
    } else if (p.is("--screenshot")) {
      o.screenshot = p.output_file();
    } else if (p.is("--shots")) {
      o.shots = p.output_dir();
    } else if (p.is("--shape")) {
      o.shape = p.value();
    } else if (p.is("--max-triangles")) {
      o.max_triangles = static_cast<std::size_t>(p.integer(1, static_cast<long long>(io::default_max_mesh_triangles)));
      o.shape_only.push_back("--max-triangles");
    } else if (p.is("--radius")) {
      o.radius_mm = p.real(cli::closed(0.0, proxy_max_radius * 1e3));
      o.shape_only.push_back("--radius");
    } else if (p.is("--height-mm")) {
      o.height_mm = p.real(cli::open_closed(0.0, 100.0));
    } else {
      p.input_or_unknown(source);
    }
  }
  o.source = source.value();
  if (o.list_devices) {
    p.finish();
    return o;
  }
  if (!o.shape.empty()) {
    if (!o.source.empty()) usage("give SOURCE or --shape, not both ('" + o.source + "' and --shape " + o.shape + ")");
    if (o.kind_given) usage("--field is for a picture or a video; --shape is felt through its proxy");
    if (o.start) usage("--start is a picture's pixel; a shape's HIP starts 5 mm above its top");
    if (!o.video_only.empty()) usage(o.video_only.front() + " is for a video, not --shape");
  }
  if (o.source.empty() && o.shape.empty()) usage("missing SOURCE (a picture or a video file) or --shape FILE");
  if (o.shape.empty() && !o.shape_only.empty()) usage(o.shape_only.front() + " is for --shape FILE (a mesh)");
  if (!o.screenshot.empty() && !o.seconds) usage("--screenshot needs --seconds (how long the loop runs first)");
  if (o.seconds) cli::check_at_least_one_tick(*o.seconds, o.rate);
  const SizeRange r = size_range(o.scene.mask);
  if (!size_given)
    o.scene.size = std::clamp(o.scene.size, r.lo, r.hi);
  else if (o.scene.size < r.lo || o.scene.size > r.hi || (r.step == 2 && o.scene.size % 2 == 0))
    usage(std::string("--size ") + std::to_string(o.scene.size) + " does not suit mask " + to_string(o.scene.mask) +
          " (" + (r.lo == r.hi ? std::to_string(r.lo) : "odd " + std::to_string(r.lo) + ".." + std::to_string(r.hi)) +
          ")");
  if (o.scene.kind == FieldKind::normals && o.scene.faces.empty()) usage("--field normals needs at least one --face");
  p.finish();  // output paths, before any work
  return o;
}

/// The live field as a part of a composition (the LiveField stays put).
struct LiveRef {
  LiveField<AnyField>* live;
  glm::dvec3 force(const Probe& p) noexcept { return live->force(p); }
  void reset() noexcept { live->reset(); }
};

/// What the window thread shares with the mouse callback.
struct Pointer {
  const ViewLayout* layout{nullptr};
  std::function<void(glm::dvec2)> moved;
  cv::Size picture;
};

void on_mouse(int event, int x, int y, int /*flags*/, void* user) {
  auto* p = static_cast<Pointer*>(user);
  if (event != cv::EVENT_MOUSEMOVE || !p->moved) return;
  glm::dvec2 px = p->layout->to_picture(x, y);
  px.x = std::clamp(px.x, 0.0, p->picture.width - 1.0);
  px.y = std::clamp(px.y, 0.0, p->picture.height - 1.0);
  p->moved(px);
}

constexpr const char* window_title = "hapticfield_view";

/// Runs the loop on its own thread and the view on this one.
/// `picture` is the still picture, or for a video (`video` set) its first
/// frame shown.
/// How a run ended, on stdout: a disconnect, a signal, and the loop's
/// figures. Returns whether the device disconnected.
bool report_run(StopReason outcome, const cli::StopOnSignal& stop, const LoopSnapshot& s) {
  const bool disconnected = outcome == StopReason::disconnected;
  if (disconnected) std::printf("the device disconnected; zero force was commanded\n");
  if (stop.caught()) std::printf("stopped by signal %d: zero force commanded, then the arm disarmed\n", stop.caught());
  std::printf(
      "%llu ticks at %.2f Hz, period p50 %.4f / p99 %.4f / max %.4f ms, late ticks %llu, missed deadlines "
      "%llu, safety events %llu (ticks whose force the safety chain clamped, slowed, damped or zeroed), latches "
      "%llu\n",
      static_cast<unsigned long long>(s.ticks), s.rate, s.period_p50 * 1e3, s.period_p99 * 1e3, s.period_max * 1e3,
      static_cast<unsigned long long>(s.overruns), static_cast<unsigned long long>(s.missed_deadlines),
      static_cast<unsigned long long>(s.safety_events), static_cast<unsigned long long>(s.latches));
  return disconnected;
}

/// The end of a run in the window: the loop stopped and its thread joined,
/// the last samples taken (drain()), the window closed, the run reported
/// (from `figures`, which drain() brings up to date). Returns whether the
/// device disconnected.
template <class Loop, class Drain>
bool end_run(Loop& loop, cli::LoopThread& servo, Drain& drain, bool window, const cli::StopOnSignal& stop,
             const LoopSnapshot& figures) {
  loop.request_stop();
  servo.join();
  drain();
  if (window) cv::destroyAllWindows();
  return report_run(servo.outcome(), stop, figures);
}

/// 's' in the window: the picture shown, saved as DIR/hapticfield_view_N.png.
/// Returns the line that tells the user.
std::string save_shot(const std::string& dir, int number, const cv::Mat& canvas) {
  const std::string path =
      (std::filesystem::path(dir) / ("hapticfield_view_" + std::to_string(number) + ".png")).string();
  return cv::imwrite(path, canvas) ? "saved " + path : "cannot write " + path;
}

template <Device D, HapticField F>
int run_view(const Arguments& o, D& device, F& field, LiveField<AnyField>& live, const cv::Mat& picture,
             VideoPlayer* video, Scene& scene, SceneConfig cfg, const PlaneMapping& mapping, SteadyClock& clock,
             bool hardware, std::function<void(glm::dvec2)> mouse_moved) {
  LoopConfig config;
  config.rate = o.rate;
  config.realtime = o.realtime;
  config.recover_after = 0.5;  // re-arm through the soft start after a stall
  ServoLoop<D, SteadyClock> loop(device, clock, config);
  cli::StopOnSignal stop(loop);  // Ctrl-C: zero force and disarm through the loop's stop
  rt::SpscRing<ViewSample, 8192> ring;

  if (hardware) cli::wait_for_operator();
  if (stop.caught()) return stop.exit_status();
  std::printf("%s on %s (Ctrl-C stops; so do q and Esc in the window)\n", o.source.c_str(), device.info().name.c_str());
  std::fflush(stdout);

  // the tick: tell the viewer where the probe is and what was commanded
  auto tick = [&](const TickInput& in) noexcept {
    (void)ring.try_push({in.probe.time, mapping.to_image(in.probe.position), loop.last_command()});
    return field.force(in.probe);
  };
  const std::uint64_t ticks = o.seconds ? static_cast<std::uint64_t>(std::llround(*o.seconds * o.rate)) : no_tick_limit;
  cli::LoopThread servo(loop, tick, {.max_ticks = ticks});

  const ViewLayout layout = ViewLayout::for_picture(picture.cols, picture.rows);
  Scope scope;
  ViewSample now{};
  now.pixel = o.start ? *o.start : glm::dvec2{picture.cols / 2.0, picture.rows / 2.0};
  ViewStatus status;
  status.source = std::filesystem::path(o.source).filename().string();
  status.device = device_label(o, device.info().name);
  status.field = scene.label;
  const bool window = o.screenshot.empty();
  double note_until = 0.0;  // [s of loop time]
  const auto drain = [&] {
    while (const std::optional<ViewSample> s = ring.try_pop()) {
      scope.add(*s);
      now = *s;
    }
    status.loop = loop.statistics();
    status.latched = loop.safety().latched() != 0;
    status.latch_bits = loop.safety().latched();
    status.dropped = ring.rejected();
    if (video) {  // the frame being felt, and where the video is
      if (video->playing()) scene.underlay = video->frame();
      const VideoStatus v = video->status();
      status.video = true;
      status.video_time = v.time;
      status.video_duration = v.duration;
      status.video_frame = v.frame;
      status.frames_dropped = v.dropped;
      status.scene_cuts = v.cuts;
      status.paused = v.paused;
      if (!v.error.empty()) {  // the worker stopped: the last window is held
        status.note = "video: " + v.error;
        note_until = now.t + 3.0;
      }
    }
  };
  cv::Mat canvas;
  Pointer pointer{&layout, std::move(mouse_moved), picture.size()};
  int shot = 0;
  // Fields are built here, on the viewer's thread, and handed to the loop,
  // which picks them up on its next tick; the LiveField destroys replaced
  // ones here too (a VideoField joins its worker when destroyed).
  const auto rebuild = [&](const SceneConfig& next) {
    try {
      if (next.kind == FieldKind::video) {  // a new VideoField at the current video time
        live.publish(video->start(next, mapping));
        scene.underlay = video->frame();
        scene.label = scene_label(next);
      } else {  // a still field of the picture, or of the video frame shown now
        Scene fresh = build_scene(video ? video->frame() : picture, next, mapping);
        if (video) video->stop();
        live.publish(std::move(fresh.field));
        scene.underlay = std::move(fresh.underlay);
        scene.label = fresh.label;
      }
      status.field = scene.label;
      cfg = next;
    } catch (const std::exception& e) {
      status.note = e.what();
      note_until = now.t + 3.0;
    }
  };
  const auto say = [&](const std::string& text) {
    status.note = text;
    note_until = now.t + 3.0;
  };

  std::optional<ViewWindow> shown;  // the wheel does nothing here (a picture has no depth)
  if (window) shown.emplace(window_title, on_mouse, &pointer);
  while (!servo.done()) {
    drain();
    if (!window) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    if (now.t > note_until) status.note.clear();
    draw_view(canvas, layout, scene.underlay, scope, now, status);
    shown->show(canvas);
    const int key = cv::waitKey(15) & 0xff;
    if (cv::getWindowProperty(window_title, cv::WND_PROP_VISIBLE) < 1.0) break;  // closed by the user
    SceneConfig next = cfg;
    switch (key) {
      case 'q':
      case 27:
        loop.request_stop();
        break;
      case 'f':
        next.kind = next_kind(next.kind, !next.faces.empty(), video != nullptr);
        rebuild(next);
        break;
      case 'm': {
        next.mask = static_cast<MaskKind>((static_cast<int>(next.mask) + 1) % 6);
        const SizeRange r = size_range(next.mask);
        next.size = std::clamp(next.size | (r.step == 2 ? 1 : 0), r.lo, r.hi);
        rebuild(next);
        break;
      }
      case '+':
      case '=':
      case '-': {
        const int steps = key == '-' ? -1 : 1;
        if (next.kind == FieldKind::texture)
          next.grain_mm = std::clamp(next.grain_mm * (steps > 0 ? 1.5 : 1 / 1.5), 0.1, 50.0);
        else
          next.size = step_size(next.mask, next.size, steps * std::max(1, next.size / 8));
        rebuild(next);
        break;
      }
      case 'b':
        next.border = static_cast<Border>((static_cast<int>(next.border) + 1) % 4);
        rebuild(next);
        break;
      case 'd':
        next_denoise(next);
        rebuild(next);
        break;
      case ' ':
        if (!video)
          say("a still picture: nothing to pause");
        else if (!video->playing())
          say("a still of the video: f to the video field to play");
        else
          say(video->toggle_pause() ? "paused" : "playing");
        break;
      case '[':
      case ']':
        if (!video) {
          say("a still picture: nothing to seek");
        } else if (!video->playing()) {
          say("a still of the video: f to the video field to seek");
        } else {
          char text[64];
          std::snprintf(text, sizeof text, "seek to %.2f s", video->seek_by(key == '[' ? -1 : 1));
          say(text);
        }
        break;
      case 's': {
        say(save_shot(o.shots, ++shot, canvas));
        break;
      }
      default:
        break;
    }
  }
  const bool disconnected = end_run(loop, servo, drain, window, stop, status.loop);
  if (video) {
    if (video->playing()) (void)video->settle(std::chrono::milliseconds(1000));  // the last tick's frame
    drain();
    std::printf("video: %.6f s of %.2f s, frame %ld shown, %ld frames dropped, %ld scene cuts%s\n", status.video_time,
                status.video_duration, status.video_frame, status.frames_dropped, status.scene_cuts,
                status.paused ? ", paused" : "");
  }
  if (!o.screenshot.empty()) {
    status.note.clear();
    draw_view(canvas, layout, scene.underlay, scope, now, status);
    if (!cv::imwrite(o.screenshot, canvas)) throw FileError("--screenshot: cannot write '" + o.screenshot + "'");
    const cv::Point at = layout.to_canvas(now.pixel);
    std::printf("screenshot: %s, probe at %.2f,%.2f px of the picture (%d,%d on the screenshot)\n",
                o.screenshot.c_str(), now.pixel.x, now.pixel.y, at.x, at.y);
  }
  // A run cut short by the device is a failure (exit 1), after the report above.
  if (disconnected) throw DeviceError("the device disconnected during the run; zero force was commanded");
  return stop.caught() ? stop.exit_status() : 0;
}

// ---- a shape in 3D (--shape) ------------------------------------------------

#if HAPTICFIELD_EXAMPLE_SHAPES

/// What the window thread shares with the mouse callback in the 3D view.
struct ShapePointer {
  const ViewLayout* layout{nullptr};
  OrbitCamera* camera{nullptr};
  MouseDevice<SteadyClock>* mouse{nullptr};  ///< null: an arm moves the HIP
  glm::dvec3 hip{0.0};                       ///< where the mouse put the HIP [m]
  cv::Point drag{-1, -1};                    ///< right-drag start (canvas px)
  double drag_yaw{0.0}, drag_pitch{0.0};     ///< the camera's angles then [rad]
};

constexpr double degree = std::numbers::pi / 180.0;
constexpr double push_step = 1e-3;  ///< one wheel notch or [ ] key [m]

void push_hip(ShapePointer& p, double steps) {
  if (!p.mouse) return;
  p.hip += steps * push_step * p.camera->forward();
  p.mouse->set_position(p.hip);
}

void on_shape_mouse(int event, int x, int y, int flags, void* user) {
  auto* p = static_cast<ShapePointer*>(user);
  if (event == cv::EVENT_RBUTTONDOWN) {
    p->drag = {x, y};
    p->drag_yaw = p->camera->yaw;
    p->drag_pitch = p->camera->pitch;
    return;
  }
  if (event == cv::EVENT_RBUTTONUP) {
    p->drag = {-1, -1};
    return;
  }
  if (event == cv::EVENT_MOUSEMOVE && (flags & cv::EVENT_FLAG_RBUTTON) && p->drag.x >= 0) {  // orbit
    p->camera->yaw = p->drag_yaw - (x - p->drag.x) * 0.5 * degree;
    p->camera->pitch =
        std::clamp(p->drag_pitch + (y - p->drag.y) * 0.5 * degree, -OrbitCamera::max_pitch, OrbitCamera::max_pitch);
    return;
  }
  if (event == cv::EVENT_MOUSEWHEEL) {  // the probe's depth, and nothing else (see view/window.hpp)
    push_hip(*p, wheel_notches(event, flags));
    return;
  }
  if (event != cv::EVENT_MOUSEMOVE || !p->mouse) return;
  // the HIP moves in the view plane: same depth, under the pointer
  const glm::dvec2 px = p->layout->to_picture(x, y) + glm::dvec2{0.5};
  const double depth = std::max(1e-3, p->camera->project(p->hip).depth);
  p->hip = p->camera->unproject(
      glm::dvec2{std::clamp(px.x, 0.0, p->camera->width * 1.0), std::clamp(px.y, 0.0, p->camera->height * 1.0)}, depth);
  p->mouse->set_position(p->hip);
}

/// The loop on its own thread, the 3D view on this one.
template <Device D, class Field>
int run_shape_view(const Arguments& o, D& device, Field& field, const ShapeScene& scene, SteadyClock& clock,
                   bool hardware, MouseDevice<SteadyClock>* mouse, const glm::dvec3& start) {
  LoopConfig config;
  config.rate = o.rate;
  config.realtime = o.realtime;
  config.recover_after = 0.5;
  ServoLoop<D, SteadyClock> loop(device, clock, config);
  cli::StopOnSignal stop(loop);
  rt::SpscRing<Sample3d, 8192> ring;
  if (hardware) cli::wait_for_operator();
  if (stop.caught()) return stop.exit_status();
  std::printf("%s on %s (Ctrl-C stops; so do q and Esc in the window)\n", o.shape.c_str(),
              device_label(o, device.info().name).c_str());
  std::fflush(stdout);

  auto tick = [&](const TickInput& in) noexcept {
    // an arm's pose before it is armed is not to be felt: the proxy starts
    // (from above the shape) once it is
    glm::dvec3 f{0.0};
    if (in.trusted && in.state.armed())
      f = field.force(in.probe);
    else
      field.reset();
    (void)ring.try_push(
        {in.probe.time, in.probe.position, field.proxy(), loop.last_command(), field.last_contact().touching});
    return f;
  };
  auto ahead = with_anticipation(tick, field);  // the proxy's look-ahead before each deadline
  const std::uint64_t ticks = o.seconds ? static_cast<std::uint64_t>(std::llround(*o.seconds * o.rate)) : no_tick_limit;
  cli::LoopThread servo(loop, ahead, {.max_ticks = ticks});

  OrbitCamera camera;
  const auto reset_view = [&] {
    camera.frame(scene.centre, scene.radius);
    o.view.aim(camera);
  };
  reset_view();
  const ViewLayout layout = ViewLayout::for_picture(camera.width, camera.height);
  Scope scope;
  Sample3d now;
  now.hip = now.proxy = start;
  ViewStatus status;
  status.source = scene.label;
  status.device = device_label(o, device.info().name);
  char field_text[80];
  if (o.radius_mm > 0.0)
    std::snprintf(field_text, sizeof field_text, "proxy (god-object), k 1500 N/m, ball r %.3g mm", o.radius_mm);
  else
    std::snprintf(field_text, sizeof field_text, "proxy (god-object), k 1500 N/m");
  status.field = field_text;
  status.keys = {"mouse: HIP in the view plane; wheel or [ ]:", "push it in / out 1 mm; right-drag or j l i k:",
                 "orbit; + - zoom, r reset, s shot, q quit"};
  const bool window = o.screenshot.empty();
  double note_until = 0.0;
  double frame_ms = 0.0;
  const auto drain = [&] {
    while (const std::optional<Sample3d> s = ring.try_pop()) {
      scope.add(ViewSample{s->t, glm::dvec2{0.0}, s->force});
      now = *s;
    }
    status.loop = loop.statistics();
    status.latched = loop.safety().latched() != 0;
    status.latch_bits = loop.safety().latched();
    status.dropped = ring.rejected();
    char text[160];
    std::snprintf(text, sizeof text, "depth %.2f mm   3D frame %.1f ms",
                  now.touching ? glm::length(now.proxy - now.hip) * 1e3 : 0.0, frame_ms);
    status.probe_line = text;
  };
  RenderTarget target;
  cv::Mat canvas;
  ViewDrawConfig draw;
  draw.probe_marks = false;
  Scene3dConfig look;
  look.tip_radius = o.radius_mm * 1e-3;
  Scene3dMarks marks;
  const auto draw_frame = [&] {
    const auto t0 = std::chrono::steady_clock::now();
    marks = draw_scene3d(target, scene.display, camera, now, look);
    frame_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    draw_view(canvas, layout, target.image, scope, ViewSample{now.t, glm::dvec2{0.0}, now.force}, status, draw);
  };
  ShapePointer pointer{&layout, &camera, mouse, start};
  int shot = 0;
  std::optional<ViewWindow> shown;
  if (window) shown.emplace(window_title, on_shape_mouse, &pointer);
  while (!servo.done()) {
    drain();
    if (!window) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    if (now.t > note_until) status.note.clear();
    draw_frame();
    shown->show(canvas);
    const int key = cv::waitKey(10) & 0xff;
    if (cv::getWindowProperty(window_title, cv::WND_PROP_VISIBLE) < 1.0) break;
    switch (key) {
      case 'q':
      case 27:
        loop.request_stop();
        break;
      case '[':
      case ']':
        if (mouse)
          push_hip(pointer, key == '[' ? 1.0 : -1.0);
        else
          status.note = "an arm moves the HIP here", note_until = now.t + 3.0;
        break;
      case 'j':
      case 'l':
        camera.yaw += (key == 'j' ? 10.0 : -10.0) * degree;
        break;
      case 'i':
      case 'k':
        camera.pitch = std::clamp(camera.pitch + (key == 'i' ? 10.0 : -10.0) * degree, -OrbitCamera::max_pitch,
                                  OrbitCamera::max_pitch);
        break;
      case '+':
      case '=':
      case '-':
        camera.distance *= key == '-' ? 1.2 : 1.0 / 1.2;
        break;
      case 'r':
        reset_view();
        break;
      case 's': {
        status.note = save_shot(o.shots, ++shot, canvas);
        note_until = now.t + 3.0;
        break;
      }
      default:
        break;
    }
  }
  const bool disconnected = end_run(loop, servo, drain, window, stop, status.loop);
  if (!o.screenshot.empty()) {
    draw_frame();  // once to time it, then with the time shown
    drain();
    draw_frame();
    if (!cv::imwrite(o.screenshot, canvas)) throw FileError("--screenshot: cannot write '" + o.screenshot + "'");
    const cv::Point off = layout.picture.tl();
    std::printf(
        "screenshot: %s, proxy at %d,%d and HIP at %d,%d (on the screenshot), %s; %zu triangles drawn in %.1f ms\n",
        o.screenshot.c_str(), marks.proxy.x + off.x, marks.proxy.y + off.y, marks.hip.x + off.x, marks.hip.y + off.y,
        now.touching ? "touching" : "not touching", marks.stats.drawn, frame_ms);
    if (o.radius_mm > 0.0)
      std::printf("screenshot: the tool's ball (r %.6g mm) centred %.3f mm from the eye, covering %zu px\n",
                  o.radius_mm, glm::dot(now.proxy - camera.eye(), camera.forward()) * 1e3, marks.ball_pixels);
  }
  if (disconnected) throw DeviceError("the device disconnected during the run; zero force was commanded");
  return stop.caught() ? stop.exit_status() : 0;
}

/// The shape's proxy against the mouse, the simulated arm or a real arm.
template <class Field>
int run_shape_with(const Arguments& o, const ShapeScene& scene, Field& field) {
  SteadyClock clock;
  const auto now = [&clock] { return clock.now(); };
  // the mouse: 5 mm above the top (the tool's ball: its lowest point)
  const glm::dvec3 start = scene.top + glm::dvec3{0.0, 0.0, 0.005 + o.radius_mm * 1e-3};
  if (o.device == "mouse") {
    MouseDevice<SteadyClock> mouse(PlaneMapping::fit(800, 600, 80.0), clock);
    mouse.set_position(start);
    return run_shape_view(o, mouse, field, scene, clock, false, &mouse, start);
  }
  // a simulated arm's hand aims 8 mm below the shape's top and raster-scans
  // 70 % of its footprint (the handle overshoots the first corner as the hand
  // catches it; past a height map's edge below its top it would be under the sheet)
  DeviceOptions options;
  options.now = now;
  const glm::vec3 extent = scene.display.hi - scene.display.lo;
  options.hand.path = HandPath::raster(glm::dvec3{scene.centre.x, scene.centre.y, scene.top.z - 0.008}, extent.x * 0.7,
                                       extent.y * 0.7, 8, 0.06);
  AnyDevice device = open_device(*o.arm, options);
  return run_shape_view(o, device, field, scene, clock, !o.arm->simulated, nullptr, start);
}

int run_shape(const Arguments& o) {
  if (o.screenshot.empty() && !std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY"))
    throw Error(
        "no display (DISPLAY is not set): run it on a desktop, or draw off-screen with --screenshot OUT.png "
        "--seconds S");
  ShapeSceneConfig config;
  config.height_mm = o.height_mm;
  config.max_pixels = o.max_pixels;
  config.max_triangles = o.max_triangles;
  ShapeScene scene = cli::quiet_stderr([&] {
    try {
      return load_shape_scene(o.shape, config);
    } catch (const FileError& e) {  // the user's flags, not the library's settings
      std::string message = cli::name_limit_flag(e.what(), "--max-mpx");
      const std::string hint = "(raise MeshReadConfig::max_triangles)";
      if (const auto at = message.find(hint); at != std::string::npos)
        message.replace(at, hint.size(), "(raise --max-triangles to allow it)");
      throw FileError(message);
    }
  });
  // where the proxy starts: clear of the shape's box, its ball too
  const glm::dvec3 above = scene.top + glm::dvec3{0.0, 0.0, 0.005 + o.radius_mm * 1e-3};
  ProxyConfig tool;
  tool.radius = o.radius_mm * 1e-3;
  if (scene.mesh) {
    ShapeProxyField<MeshShape> field(std::move(*scene.mesh), scene.shift, above, tool);
    return run_shape_with(o, scene, field);
  }
  ShapeProxyField<HeightFieldShape> field(std::move(*scene.height_field), scene.shift, above, tool);
  return run_shape_with(o, scene, field);
}

#else

int run_shape(const Arguments&) {
  throw Error("this build has no mesh readers (tinygltf and tinyobjloader): --shape is unavailable");
}

#endif

int run(const Arguments& o) {
  if (o.list_devices) return cli::print_device_list();
  if (!o.shape.empty()) return run_shape(o);
  SceneConfig first = o.scene;
  const bool still = is_still_picture(o.source);
  if (still) {
    if (o.kind_given && first.kind == FieldKind::video)
      usage("'" + o.source + "' is a still picture: --field video needs a video file");
    if (!o.video_only.empty()) usage(o.video_only.front() + " is for a video; '" + o.source + "' is a still picture");
  } else if (!o.kind_given) {
    first.kind = FieldKind::video;
  }
  if (first.kind == FieldKind::video && o.blur_given)
    usage("--denoise SIGMA blurs a picture; the video field takes --denoise none, temporal, spatial or both");
  std::optional<VideoPlayer> video;
  cv::Mat picture;
  if (still) {
    picture = cli::to_bgr8(cli::quiet_stderr([&] { return load_image(o.source, o.max_pixels); }));
  } else {
    quiet_video_logs(false);
    video.emplace(o.source, o.video);
    picture = video->frame();
  }
  if (o.screenshot.empty() && !std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY"))
    throw Error(
        "no display (DISPLAY is not set): run it on a desktop, or draw off-screen with --screenshot OUT.png "
        "--seconds S");
  const PlaneMapping mapping = PlaneMapping::fit(picture.cols, picture.rows, 80.0);  // the picture spans 80 mm
  Scene scene;
  if (first.kind == FieldKind::video) {
    scene.field = video->start(first, mapping);
    scene.underlay = picture;
    scene.label = scene_label(first);
  } else {
    scene = build_scene(picture, first, mapping);
  }
  LiveField<AnyField> live(std::move(scene.field));
  VideoPlayer* player = video ? &*video : nullptr;
  LiveRef live_ref{&live};
  SteadyClock clock;
  const auto now = [&clock] { return clock.now(); };

  if (o.device == "mouse") {
    MouseDevice<SteadyClock> mouse(mapping, clock);
    const glm::dvec2 start = o.start ? *o.start : glm::dvec2{picture.cols / 2.0, picture.rows / 2.0};
    mouse.set_pixel(start.x, start.y);
    return run_view(o, mouse, live_ref, live, picture, player, scene, first, mapping, clock, false,
                    [&mouse](glm::dvec2 p) { mouse.set_pixel(p.x, p.y); });
  }

  // An arm: a stiff wall holds the handle on the picture's plane z = 0 (Fc)
  // and the field adds its forces while the handle touches it.
  const PlaneConstraint wall(
      PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0.0, 0.0, 1.0}, 1500.0, 0.0});  // [m], [N/m]
  auto felt = contact(wall, live_ref);
  // A simulated arm's hand aims 8 mm behind the plane and raster-scans 90 % of the picture.
  const double width = picture.cols / mapping.px_per_mm() * 1e-3, height = picture.rows / mapping.px_per_mm() * 1e-3;
  DeviceOptions options;
  options.now = now;
  options.hand.path = HandPath::raster(glm::dvec3{0.0, 0.0, -0.008}, width * 0.9, height * 0.9, 8, 0.06);
  AnyDevice device = open_device(*o.arm, options);
  return run_view(o, device, felt, live, picture, player, scene, first, mapping, clock, !o.arm->simulated, {});
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // errors are reported once, by us
  return cli::main("hapticfield_view", usage_text, argc, argv, [](cli::Parser& p) { return run(parse(p)); });
}
