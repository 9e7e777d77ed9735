// servo_demo: runs a field against the simulated arm (or a real HID arm) in
// the 1 kHz servo loop while a scripted hand raster-scans the picture; shows
// the loop's rate and jitter live, writes a CSV trace and PNG plots.
//
//   servo_demo [IMAGE] [--field tangible|wall|spring|none] [--seconds S] [--rate HZ]
//              [--realtime off|best_effort|enforce] [--clock wall|virtual] [--trace OUT.csv] [--plots DIR]
//              [--device sim|hid[:VID:PID]|serial:PATH|woody:p1|p2|p4[:PRESET][:sim|:PATH]|inverse3:PATH|sim]
//              [--list-devices]
//              [--shape FILE [--height-mm H] [--snapshot OUT.png] [--view YAW,PITCH] [--distance MM]]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.hpp"
#include "common/device_option.hpp"
#include "common/loop_thread.hpp"
#include "common/plots.hpp"
#include "common/servo_options.hpp"
#include "common/share.hpp"
#include "common/stop_signal.hpp"

#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/devices/open_device.hpp"
#include "hapticfield/kernels.hpp"
#include "hapticfield/servo.hpp"
#if HAPTICFIELD_EXAMPLE_SHAPES
#include "view/scene3d.hpp"
#include "view/shape_scene.hpp"
#include "view/view_options.hpp"
#endif

using namespace hapticfield;

namespace {

struct Arguments {
  std::string image;  ///< empty: the installed example picture (share/hapticfield/data/coffee.png)
  std::string field{"tangible"};
  double seconds{5.0};
  double rate{1000.0};
  RealTime realtime{RealTime::best_effort};
  std::string trace;
  std::string plots;
  DeviceSpec device{parse_device_spec("sim")};
  bool list_devices{false};   ///< --list-devices: say which arms are present, then exit
  bool virtual_clock{false};  ///< --clock virtual: simulated time, as fast as the CPU allows
  bool field_given{false};
  // a shape felt through a proxy (--shape)
  std::string shape;
  double height_mm{4.0};
  std::string snapshot;
  view::ViewOptions view;  ///< the snapshot's camera; no distance: the shape fills about 70 % of the view
};

/// The usage up to the device's options.
constexpr const char* usage_head =
    "usage: servo_demo [IMAGE] [options]\n"
    "Runs a field in the servo loop on the simulated arm (or a real HID arm) while a\n"
    "scripted hand raster-scans the picture; shows the loop's rate and jitter live.\n"
    "  IMAGE                 picture felt by --field tangible (default: the example picture coffee.png,\n"
    "                        installed in share/hapticfield/data/)\n"
    "  --field F             tangible (default), wall, spring or none\n"
    "  --seconds S           run time [s], in (0, 3600] and at least one tick (default 5)\n"
    "  --rate HZ             servo rate [Hz], in [1, 10000] (default 1000)\n"
    "  --realtime R          off, best_effort (default: ask for SCHED_FIFO, warn if refused)\n"
    "                        or enforce (refuse to start without real-time scheduling)\n"
    "  --clock C             wall (default) or virtual: simulated time for a simulated arm (sim, or a\n"
    "                        family's :sim twin), as fast as the CPU allows, the same\n"
    "                        ticks, safety chain and trace whatever the machine's load\n"
    "  --trace OUT.csv       write t, position [m], force [N], period [s] and the device's\n"
    "                        homed,armed (0/1) per tick\n"
    "  --plots DIR           write force.png and periods.png into DIR (created if needed), drawn with\n"
    "                        matplotlib when python3 has it, else simpler plots\n";
/// The options after the device's (cli::device_help() in between).
constexpr const char* usage_tail =
    "  --shape FILE          feel a mesh (.stl, .obj, .gltf, .glb) or a height map picture (white\n"
    "                        high) through a proxy (k = 1500 N/m) instead of --field: scaled so its\n"
    "                        footprint spans 80 mm, its top 1 mm below the start; the hand scans 70 %\n"
    "                        of the footprint 8 mm below its top\n"
    "  --height-mm H         a height map's height of white over black [mm], in (0, 100] (default 4)\n"
    "  --snapshot OUT.png    with --shape: write the 3D view of the shape, the proxy, the HIP and the\n"
    "                        force at the end of the run (800 x 600 px, no display needed)\n"
    "  --view YAW,PITCH      the snapshot's camera orbit [degrees] (default 25,30; see hapticfield_view)\n"
    "  --distance MM         the snapshot camera's distance from the shape's centre [mm], in [1, 1e5]\n"
    "  -h, --help            this text\n"
    "Ctrl-C or SIGTERM stops the loop through its stop (zero force, then disarm).\n"
    "Exit status: 0 done, 1 bad input or failure, 2 usage error, 128 + N stopped by signal N\n"
    "(130 for Ctrl-C).\n";

/// A usage error found while setting up (an unknown field or device).
[[noreturn]] void usage(const std::string& error) {
  throw cli::UsageError(error);
}

Arguments parse(cli::Parser& p) {
  Arguments o;
  cli::Input image("IMAGE");
  while (p.next()) {
    if (o.view.take(p)) continue;  // --view, --distance
    if (p.is("--field")) {
      o.field = p.choice<const char*>(
          "field", {{"tangible", "tangible"}, {"wall", "wall"}, {"spring", "spring"}, {"none", "none"}});
      o.field_given = true;
    } else if (p.is("--shape")) {
      o.shape = p.value();
    } else if (p.is("--height-mm")) {
      o.height_mm = p.real(cli::open_closed(0.0, 100.0));
    } else if (p.is("--snapshot")) {
      o.snapshot = p.output_file();
    } else if (p.is("--seconds")) {
      o.seconds = p.real(cli::open_closed(0.0, 3600.0));
    } else if (p.is("--rate")) {
      o.rate = p.real(cli::closed(min_servo_rate, max_servo_rate));
    } else if (p.is("--realtime")) {
      o.realtime = cli::realtime_option(p);
    } else if (p.is("--clock")) {
      o.virtual_clock = cli::virtual_clock_option(p);
    } else if (p.is("--trace")) {
      o.trace = p.output_file();
    } else if (p.is("--plots")) {
      o.plots = p.output_dir();
    } else if (p.is("--device")) {
      o.device = cli::device_option(p.value());
    } else if (p.is("--list-devices")) {
      o.list_devices = true;
    } else {
      p.input_or_unknown(image);
    }
  }
  o.image = image.value();
  if (o.list_devices) {
    p.finish();
    return o;
  }
  if (!o.shape.empty() && (o.field_given || image.given()))
    usage("--shape is felt through its proxy: give no IMAGE or --field with it");
  if (!o.snapshot.empty() && o.shape.empty()) usage("--snapshot draws the 3D view of --shape FILE: give --shape");
  cli::check_clock_fits_arm(o.virtual_clock, o.device);
  cli::check_at_least_one_tick(o.seconds, o.rate);
  p.finish();  // the trace and plot paths, before the run
  if (o.shape.empty() && o.image.empty()) {
    o.image = share::example_picture();
    if (o.image.empty())
      throw FileError("the example picture coffee.png is not installed (share/hapticfield/data/ beside " +
                      share::executable_dir().string() + "); give IMAGE");
  }
  // the picture, before the run (decoders' own complaints muted: one line)
  if (o.shape.empty()) (void)cli::quiet_stderr([&] { return load_image(o.image); });
  return o;
}

// ---- simple fields defined here (the device and servo layers know none) ----

/// A spring to the workspace centre with a little damping.
struct CentreSpring {
  double stiffness{40.0};  // [N/m]
  double damping{0.5};     // [N s/m]
  glm::dvec3 force(const Probe& p) const noexcept { return -stiffness * p.position - damping * p.velocity; }
};

/// The one place fields are chosen by name.
AnyField make_field(const std::string& name, const cv::Mat& image, const PlaneMapping& mapping) {
  // A stiff virtual wall: the picture's plane z = 0, solid behind it (z < 0).
  const PlaneConstraint wall(
      PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0.0, 0.0, 1.0}, 1500.0, 0.0});  // [m], [N/m]
  if (name == "tangible") {
    // The wall holds the hand on the plane (Fc); while it touches the plane
    // the hand feels the picture's forces (Prewitt 17 x 17, 1 N at a
    // black/white edge) on top: F = Fc + picture.
    TangibleConfig options;
    options.border = Border::fade;
    return AnyField(contact(wall, TangibleImageField(TangibleImage(to_gray(image), options), mapping, 1.0)));
  }
  if (name == "wall") return AnyField(wall);
  if (name == "spring") return AnyField(CentreSpring{});
  if (name == "none") return AnyField(ZeroField{});
  usage("unknown field '" + name + "' (choose tangible, wall, spring or none)");
}

// ---- trace and plots -------------------------------------------------------

void write_trace(const std::string& path, const std::vector<TraceRow>& rows) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,period_s,homed,armed\n";
  for (const TraceRow& r : rows)
    f << r.t << ',' << r.position.x << ',' << r.position.y << ',' << r.position.z << ',' << r.force.x << ','
      << r.force.y << ',' << r.force.z << ',' << r.period << ',' << int{r.homed} << ',' << int{r.armed} << '\n';
}

void plot_force(const std::string& path, const std::vector<TraceRow>& rows, double limit) {
  const int w = 1000, h = 420, m = 50;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  const double t_end = rows.empty() ? 1.0 : std::max(rows.back().t, 1e-3);
  const auto px = [&](double t, double f) {
    return cv::Point(m + static_cast<int>((w - 2 * m) * t / t_end), h / 2 - static_cast<int>((h / 2 - m) * f / limit));
  };
  cv::line(img, px(0, 0), px(t_end, 0), cv::Scalar(180, 180, 180));
  cv::line(img, px(0, limit), px(t_end, limit), cv::Scalar(200, 200, 255));
  cv::line(img, px(0, -limit), px(t_end, -limit), cv::Scalar(200, 200, 255));
  const cv::Scalar colours[4] = {{200, 0, 0}, {0, 150, 0}, {0, 0, 220}, {0, 0, 0}};
  const std::size_t step = std::max<std::size_t>(1, rows.size() / 4000);
  for (std::size_t i = step; i < rows.size(); i += step)
    for (int c = 0; c < 4; ++c) {
      const double a = c < 3 ? rows[i - step].force[c] : glm::length(rows[i - step].force);
      const double b = c < 3 ? rows[i].force[c] : glm::length(rows[i].force);
      cv::line(img, px(rows[i - step].t, a), px(rows[i].t, b), colours[c], 1, cv::LINE_AA);
    }
  cv::putText(img, "force [N] over time [s]: Fx blue, Fy green, Fz red, |F| black; limit +-" + std::to_string(limit),
              {m, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
  cv::putText(img, "0 s", {m, h - 15}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0});
  cv::putText(img, std::to_string(t_end).substr(0, 5) + " s", {w - m - 40, h - 15}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
              {0, 0, 0});
  cv::imwrite(path, img);
}

void plot_periods(const std::string& path, const DurationHistogram& periods, double nominal) {
  const int w = 1000, h = 420, m = 50;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  // Window: nominal +-20 %, 1 us bins (the loop's own histogram); overflow at the edges.
  const auto lo = static_cast<std::int64_t>(nominal * 0.8e9) / DurationHistogram::bin_ns;
  const auto hi = static_cast<std::int64_t>(nominal * 1.2e9) / DurationHistogram::bin_ns;
  std::vector<double> counts(static_cast<std::size_t>(hi - lo + 1), 0.0);
  double peak = 1.0;
  std::uint64_t below = 0, above = 0;
  for (std::int64_t i = 0; i < static_cast<std::int64_t>(DurationHistogram::bins); ++i) {
    const std::uint64_t c = periods.bin(static_cast<std::size_t>(i));
    if (i < lo)
      below += c;
    else if (i > hi)
      above += c;
    else
      peak = std::max(peak, counts[static_cast<std::size_t>(i - lo)] = static_cast<double>(c));
  }
  const double bar = static_cast<double>(w - 2 * m) / static_cast<double>(counts.size());
  for (std::size_t i = 0; i < counts.size(); ++i) {
    const int top = h - m - static_cast<int>((h - 2 * m) * std::log1p(counts[i]) / std::log1p(peak));
    cv::rectangle(img, cv::Point(m + static_cast<int>(i * bar), top),
                  cv::Point(m + static_cast<int>((i + 1) * bar), h - m), cv::Scalar(160, 90, 20), cv::FILLED);
  }
  const int centre = m + (w - 2 * m) / 2;
  cv::line(img, {centre, m}, {centre, h - m}, cv::Scalar(0, 0, 220));
  cv::putText(img,
              "tick period histogram (log count), nominal " + std::to_string(nominal * 1e3).substr(0, 5) +
                  " ms at the red line, window +-20 %; below " + std::to_string(below) + ", above " +
                  std::to_string(above),
              {m, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
  cv::imwrite(path, img);
}

/// The tick-period histogram (nominal +-20 %, the loop's 1 us bins) as CSV
/// for the plot script: period_ms,count.
void write_period_histogram(const std::string& path, const DurationHistogram& periods, double nominal) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "period_ms,count\n";
  const auto lo = static_cast<std::int64_t>(nominal * 0.8e9) / DurationHistogram::bin_ns;
  const auto hi = static_cast<std::int64_t>(nominal * 1.2e9) / DurationHistogram::bin_ns;
  for (std::int64_t i = lo; i <= hi && i < static_cast<std::int64_t>(DurationHistogram::bins); ++i)
    f << static_cast<double>(i * DurationHistogram::bin_ns) * 1e-6 << ',' << periods.bin(static_cast<std::size_t>(i))
      << '\n';
}

/// One status line: on a terminal rewritten in place with '\r', into a file
/// or a pipe a whole line; a latch is shown with its reason for as long as
/// it holds.
void print_status(const LoopSnapshot& s, std::uint32_t latched, double t, bool terminal) {
  std::printf(
      "%s t %6.2f s | rate %8.2f Hz | period p50 %6.3f p99 %6.3f max %6.3f ms | late %3llu | peak %5.2f N | "
      "latches %llu%s%s%s",
      terminal ? "\r" : "", t, s.rate, s.period_p50 * 1e3, s.period_p99 * 1e3, s.period_max * 1e3,
      static_cast<unsigned long long>(s.overruns), s.peak_force, static_cast<unsigned long long>(s.latches),
      latched ? " | ZERO FORCE: " : "", latched ? safety_events::names(latched).c_str() : "", terminal ? "   " : "\n");
  std::fflush(stdout);
}

/// The clocks a run may use: the wall clock, or simulated time (--clock virtual).
struct Clocks {
  SteadyClock wall;
  VirtualClock simulated;
  bool use_simulated{false};
  [[nodiscard]] std::int64_t now() const noexcept { return use_simulated ? simulated.now() : wall.now(); }
};

/// What the loop runs, and what happens after it.
struct Felt {
  AnyField field;
  /// A shape's proxy starts only once the arm is armed (its pose before is
  /// not to be felt); until then the field is reset and the force is zero.
  bool wait_for_arm{false};
  /// Called after the run with the last HIP [m] and commanded force [N]
  /// (the --snapshot of a shape); may be empty.
  std::function<void(const glm::dvec3&, const glm::dvec3&)> at_end;
};

template <Device D, ServoClock C>
int run_demo(const Arguments& o, D& device, Felt& felt, C& clock, bool hardware);

/// run_demo on the clock --clock chose.
template <Device D>
int run_on_clock(const Arguments& o, D& device, Felt& felt, Clocks& clocks, bool hardware) {
  if (clocks.use_simulated) return run_demo(o, device, felt, clocks.simulated, hardware);
  return run_demo(o, device, felt, clocks.wall, hardware);
}

#if HAPTICFIELD_EXAMPLE_SHAPES
/// A field that forwards to one that stays put (the shape's proxy, read
/// again after the run).
template <class F>
struct FieldRef {
  F* field;
  glm::dvec3 force(const Probe& p) noexcept { return field->force(p); }
  void reset() noexcept { field->reset(); }
  void anticipate(const Probe& next) const noexcept { anticipate_if_able(*field, next); }
  [[nodiscard]] bool looks_ahead() const noexcept { return field_looks_ahead(*field); }
};

/// --shape: the scene, its proxy field, and the snapshot after the run.
struct ShapeRun {
  view::ShapeScene scene;
  std::unique_ptr<view::ShapeProxyField<MeshShape>> mesh;
  std::unique_ptr<view::ShapeProxyField<HeightFieldShape>> height_field;

  [[nodiscard]] glm::dvec3 proxy() const { return mesh ? mesh->proxy() : height_field->proxy(); }
  [[nodiscard]] bool touching() const {
    return mesh ? mesh->last_contact().touching : height_field->last_contact().touching;
  }
};

/// Loads --shape and sets `felt` up to feel it; the snapshot writes --snapshot.
std::unique_ptr<ShapeRun> load_shape(const Arguments& o, Felt& felt) {
  auto run = std::make_unique<ShapeRun>();
  view::ShapeSceneConfig config;
  config.height_mm = o.height_mm;
  run->scene = cli::quiet_stderr([&] { return view::load_shape_scene(o.shape, config); });
  const glm::dvec3 above = run->scene.top + glm::dvec3{0.0, 0.0, 0.005};  // where the proxy starts
  if (run->scene.mesh) {
    run->mesh =
        std::make_unique<view::ShapeProxyField<MeshShape>>(std::move(*run->scene.mesh), run->scene.shift, above);
    felt.field = AnyField(FieldRef<view::ShapeProxyField<MeshShape>>{run->mesh.get()});
  } else {
    run->height_field = std::make_unique<view::ShapeProxyField<HeightFieldShape>>(std::move(*run->scene.height_field),
                                                                                  run->scene.shift, above);
    felt.field = AnyField(FieldRef<view::ShapeProxyField<HeightFieldShape>>{run->height_field.get()});
  }
  felt.wait_for_arm = true;
  std::printf("shape: %s\n", run->scene.label.c_str());
  if (!o.snapshot.empty()) {
    felt.at_end = [&o, shape = run.get()](const glm::dvec3& hip, const glm::dvec3& force) {
      view::OrbitCamera camera;
      camera.frame(shape->scene.centre, shape->scene.radius);
      o.view.aim(camera);
      view::Sample3d now;
      now.hip = hip;
      now.proxy = shape->proxy();
      now.force = force;
      now.touching = shape->touching();
      view::RenderTarget target;
      const auto t0 = std::chrono::steady_clock::now();
      const view::Scene3dMarks marks = view::draw_scene3d(target, shape->scene.display, camera, now);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (!cv::imwrite(o.snapshot, target.image)) throw FileError("--snapshot: cannot write '" + o.snapshot + "'");
      std::printf("snapshot: %s, proxy at %d,%d and HIP at %d,%d px, %s; %zu triangles drawn in %.1f ms\n",
                  o.snapshot.c_str(), marks.proxy.x, marks.proxy.y, marks.hip.x, marks.hip.y,
                  now.touching ? "touching" : "not touching", marks.stats.drawn, ms);
    };
  }
  return run;
}
#endif

int run(const Arguments& o) {
  if (o.list_devices) return cli::print_device_list();
  Felt felt;
  double width = 0.0, height = 0.0;  // the area scanned [m]
  glm::dvec3 surface{0.0};           // the scan's centre on the surface (its top) [m]
#if HAPTICFIELD_EXAMPLE_SHAPES
  std::unique_ptr<ShapeRun> shape;
#endif
  if (o.shape.empty()) {
    const cv::Mat image = cv::imread(o.image, cv::IMREAD_COLOR);
    if (image.empty()) throw std::runtime_error("cannot read image " + o.image);
    const double workspace_mm = 80.0;  // the picture spans 80 mm of the device plane
    const PlaneMapping mapping = PlaneMapping::fit(image.cols, image.rows, workspace_mm);
    felt.field = make_field(o.field, image, mapping);
    width = image.cols / mapping.px_per_mm() * 1e-3;
    height = image.rows / mapping.px_per_mm() * 1e-3;
  } else {
#if HAPTICFIELD_EXAMPLE_SHAPES
    shape = load_shape(o, felt);
    width = shape->scene.display.hi.x - shape->scene.display.lo.x;
    height = shape->scene.display.hi.y - shape->scene.display.lo.y;
    surface = shape->scene.top;
#else
    throw std::runtime_error("this build has no mesh readers (tinygltf and tinyobjloader): --shape is unavailable");
#endif
  }

  Clocks clocks;
  clocks.use_simulated = o.virtual_clock;
  const auto now = [&clocks] { return clocks.now(); };
  // The hand aims 8 mm behind the picture plane or the shape's top (its
  // spring then presses with up to 300 N/m * 8 mm = 2.4 N) and raster-scans
  // 90 % of the picture or 70 % of the shape's footprint.
  // A shape's scan keeps to 70 %: the handle overshoots the scan's first
  // corner as the hand catches it, and a hand that leaves a height map's
  // edge below its top is under the sheet (surfaces are one-sided).
  const double cover = o.shape.empty() ? 0.9 : 0.7;
  const auto scan = [&](glm::dvec3 centre) {
    return HandPath::raster(centre + surface + glm::dvec3{0.0, 0.0, -0.008}, width * cover, height * cover, 8, 0.06);
  };

  // The hand pulls a simulated arm's handle from its rest pose onto the picture.
  DeviceOptions options;
  options.now = now;
  options.hand.path = scan(glm::dvec3{0.0});
  AnyDevice device = open_device(o.device, options);  // throws naming the device when it is not there
  return run_on_clock(o, device, felt, clocks, !o.device.simulated);
}

template <Device D, ServoClock C>
int run_demo(const Arguments& o, D& device, Felt& felt, C& clock, bool hardware) {
  constexpr bool simulated_time = std::is_same_v<C, VirtualClock>;
  LoopConfig config;
  config.rate = o.rate;
  config.realtime = simulated_time ? RealTime::off : o.realtime;  // simulated time never sleeps: no SCHED_FIFO
  // A stall of the machine (a late wake, a stale state) latches zero force;
  // the demo re-arms through the soft start once states are fresh for 0.5 s.
  config.recover_after = 0.5;
  const auto ticks = static_cast<std::uint64_t>(std::llround(o.seconds * o.rate));
  std::vector<TraceRow> rows;
  rows.reserve(ticks + 8);  // the tick path only fills reserved rows
  TracedDevice<D> traced(device, rows);
  ServoLoop<TracedDevice<D>, C> loop(traced, clock, config);
  cli::StopOnSignal stop(loop);  // Ctrl-C: zero force and disarm through the loop's stop

  if (hardware) cli::wait_for_operator();
  if (stop.caught()) {
    std::printf("stopped by signal %d before the loop started; no force was commanded\n", stop.caught());
    return stop.exit_status();
  }

  double previous_time = 0.0;
  auto callback = [&](const TickInput& in) noexcept {
    traced.open(in, in.probe.time - previous_time);
    previous_time = in.probe.time;
    if (felt.wait_for_arm && !(in.trusted && in.state.armed())) {
      felt.field.reset();
      return glm::dvec3{0.0};
    }
    return felt.field.force(in.probe);
  };

  auto ahead = with_anticipation(callback, felt.field);  // a shape's proxy looks ahead before each deadline
  cli::LoopThread servo(loop, ahead, {.max_ticks = ticks});
  const auto t0 = std::chrono::steady_clock::now();
  const std::int64_t loop_start = clock.now();
  std::uint64_t latches_shown = 0;
  const auto wall_elapsed = [&t0] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  // Status lines show the loop's own time: simulated seconds on the virtual clock.
  const auto elapsed = [&] {
    return simulated_time ? static_cast<double>(clock.now() - loop_start) * 1e-9 : wall_elapsed();
  };
  // On a terminal one live line every 200 ms; into a file or a pipe a
  // whole line every 10 s and the last one.
  const bool terminal = cli::stdout_is_terminal();
  double printed_at = wall_elapsed();
  while (!servo.done()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const LoopSnapshot s = loop.statistics();
    if (s.latches > latches_shown) {  // every latch gets a line of its own
      latches_shown = s.latches;
      std::printf(
          "%s t %6.2f s: the safety chain latched (%s): zero force, disarmed; re-arming once states are "
          "fresh for %.1f s\n",
          terminal ? "\n" : "", elapsed(), safety_events::names(s.last_latch).c_str(), config.recover_after);
    }
    if (terminal || wall_elapsed() - printed_at >= 10.0) {
      print_status(s, loop.safety().latched(), elapsed(), terminal);
      printed_at = wall_elapsed();
    }
  }
  servo.join();
  print_status(loop.statistics(), loop.safety().latched(), elapsed(), terminal);
  if (terminal) std::printf("\n");
  const bool disconnected = servo.outcome() == StopReason::disconnected;
  if (disconnected) std::printf("the device disconnected; zero force was commanded\n");
  if (stop.caught()) std::printf("stopped by signal %d: zero force commanded, then the arm disarmed\n", stop.caught());
  if (simulated_time) {
    const double simulated = static_cast<double>(loop.statistics().ticks) * loop.period();
    std::printf("simulated time: %.3f s in %.3f s of wall time (%.0f x real time)\n", simulated, servo.wall_seconds(),
                simulated / std::max(servo.wall_seconds(), 1e-9));
  }

  const LoopSnapshot s = loop.statistics();
  std::printf(
      "%llu ticks at %.3f Hz (nominal %.0f), period p50 %.4f / p99 %.4f / p99.9 %.4f / max %.4f ms, "
      "late ticks %llu (%llu periods skipped), wake latency p99 %.1f us, compute p99 %.1f us, peak force "
      "%.2f N\n",
      static_cast<unsigned long long>(s.ticks), s.rate, o.rate, s.period_p50 * 1e3, s.period_p99 * 1e3,
      s.period_p999 * 1e3, s.period_max * 1e3, static_cast<unsigned long long>(s.overruns),
      static_cast<unsigned long long>(s.missed_deadlines), s.wake_p99 * 1e6, s.compute_p99 * 1e6, s.peak_force);
  if (s.latches == 0) {
    std::printf("safety: no latch\n");
  } else {
    std::printf("safety: %llu latch(es), the last for %s; %llu recovered through the soft start%s\n",
                static_cast<unsigned long long>(s.latches), safety_events::names(s.last_latch).c_str(),
                static_cast<unsigned long long>(s.recoveries),
                loop.safety().latched() ? "; still latched at the end" : "");
  }
  cli::print_link(device);
  if (felt.at_end) felt.at_end(rows.empty() ? glm::dvec3{0.0} : rows.back().position, loop.last_command());
  if (!o.trace.empty()) {
    write_trace(o.trace, rows);
    std::printf("trace: %s (%zu rows)\n", o.trace.c_str(), rows.size());
  }
  if (!o.plots.empty()) {
    std::filesystem::create_directories(o.plots);
    // matplotlib (axes, ticks, units, legends) when present; else drawn here.
    const std::string trace = o.trace.empty() ? o.plots + "/trace.csv" : o.trace;
    if (o.trace.empty()) write_trace(trace, rows);
    write_period_histogram(o.plots + "/periods.csv", loop.detailed_statistics().periods(), loop.period());
    std::string why;
    if (!plots::matplotlib(
            {"servo", "--trace", trace, "--periods", o.plots + "/periods.csv", "--nominal-ms",
             std::to_string(loop.period() * 1e3), "--limit", std::to_string(device.info().max_force), "--out", o.plots},
            why)) {
      plot_force(o.plots + "/force.png", rows, device.info().max_force);
      plot_periods(o.plots + "/periods.png", loop.detailed_statistics().periods(), loop.period());
      std::printf("plots: %s/force.png, %s/periods.png (simple plots: %s)\n", o.plots.c_str(), o.plots.c_str(),
                  why.c_str());
    }
  }
  // A run cut short by the device is a failure (exit 1), after the report above.
  if (disconnected) throw DeviceError("the device disconnected during the run; zero force was commanded");
  return stop.caught() ? stop.exit_status() : 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);  // errors are reported once, by us
  static const std::string usage_text = usage_head + cli::device_help() + usage_tail;
  return cli::main("servo_demo", usage_text.c_str(), argc, argv, [](cli::Parser& p) { return run(parse(p)); });
}
