// tangible_video: feel a video (tangible video, "movie haptics").
//
//   tangible_video VIDEO [--mask prewitt|sobel|scharr|roberts|gauss|emboss] [--size M]
//                  [--border suspend|clamp|reflect|fade] [--denoise none|temporal|spatial|both]
//                  [--fade-ms MS] [--cuts OUT.csv] [--probes IN.csv --forces OUT.csv]
//                  [--seconds S] [--device sim|hid[:VID:PID]|...] [--clock wall|virtual]
//                  [--trace OUT.csv] [--plots DIR] [--max-mpx N] [--verbose]
//
// With --probes it renders offline, as fast as it can: t,x,y per line (t in
// seconds of video time, frame k at k / fps; x, y in pixels as
// tangible_image) to t,x,y,fx,fy (normalised, 1 = a black/white edge, fy
// down), blends and fades included (the first frame fades in from zero). Without --probes it plays the video to
// the simulated arm (a scripted hand raster-scans it) or a HID arm in the
// 1 kHz servo loop, with a live status line; --clock virtual runs the
// simulated arm on simulated time, in lockstep with the video's worker, so
// a run's trace is the same on any machine. Bad input: one line on stderr,
// exit status 1 (2 for usage errors).
#include <hapticfield/video.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/cli.hpp"
#include "common/csv.hpp"
#include "common/device_option.hpp"
#include "common/loop_thread.hpp"
#include "common/mask_options.hpp"
#include "common/plots.hpp"
#include "common/servo_options.hpp"
#include "common/simple_plot.hpp"
#include "common/stop_signal.hpp"

#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/devices/open_device.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"

namespace hf = hapticfield;

namespace {

constexpr const char* usage =
    "usage: tangible_video VIDEO [options]\n"
    "Feels a video: each frame as a tangible image, blended between frames, faded across scene cuts.\n"
    "  VIDEO                 a video file (anything OpenCV opens), an image sequence (a printf\n"
    "                        pattern such as frames/%04d.png) or camera:N (camera index N, 0..99)\n"
    "  --mask KIND           prewitt (default), sobel, scharr, roberts, gauss or emboss\n"
    "  --size M              mask size [px]: prewitt/gauss/emboss odd 3..129 (default 17),\n"
    "                        sobel odd 3..31 (default 3), scharr 3, roberts 2\n"
    "  --border B            suspend (default), clamp, reflect or fade\n"
    "  --denoise D           none, temporal (default), spatial or both (compression noise)\n"
    "  --fade-ms MS          fade out and in across a scene cut [ms], in [0, 10000] (default 100);\n"
    "                        the video's first frame fades in from zero force the same way\n"
    "  --cuts OUT.csv        write frame,time [s] for each detected cut (frame = first of the new scene)\n"
    "  --probes IN.csv       t,x,y per line: t [s of video time, frame k at k / fps], x, y [px]\n"
    "                        (x right, y down, integer = pixel centre; a header line allowed); needs --forces\n"
    "  --forces OUT.csv      t,x,y,fx,fy per probe: the normalised force (1 = black/white edge), fy down\n"
    "  --seconds S           play time [s], in (0, 3600] (default: the video's length, at most 60)\n"
    "  --device D            sim (default: the simulated arm, a scripted hand), hid, hid:VID:PID, or any\n"
    "                        arm servo_demo opens (servo_demo --list-devices says which are present)\n"
    "  --clock C             wall (default: real time) or virtual (simulated arms only: simulated\n"
    "                        time, each tick waits for its frame, none dropped: the same trace on any\n"
    "                        machine)\n"
    "  --trace OUT.csv       write t, position [m], force [N] per tick (play mode)\n"
    "  --plots DIR           write force.png (play mode: the lateral force sent to the arm [N]) or\n"
    "                        forces.png (probe mode: the normalised force), with the cuts found,\n"
    "                        their data (force.csv / forces.csv, cuts.csv) into DIR\n"
    "  --max-mpx N           largest frame accepted [megapixels], in (0, 1e6] (default 100),\n"
    "                        checked before any frame is decoded\n"
    "  --verbose             let OpenCV's and FFmpeg's own log lines through\n"
    "  -h, --help            this text\n"
    "Ctrl-C or SIGTERM stops the loop through its stop (zero force, then disarm).\n"
    "Exit status: 0 done, 1 bad input (files, videos, devices), 2 usage error, 128 + N stopped\n"
    "by signal N.\n";

struct Arguments {
  std::string video;
  hf::TangibleConfig options;
  hf::DenoiseMode denoise = hf::DenoiseMode::temporal;
  double fade_s = hf::default_cut_fade;
  std::optional<std::string> cuts, probes, forces, trace, plots;
  std::optional<double> seconds;
  hf::DeviceSpec device{hf::parse_device_spec("sim")};
  std::optional<bool> virtual_clock;                  ///< --clock virtual (true) or wall; given or not
  std::uint64_t max_pixels = hf::default_max_pixels;  ///< largest frame decoded [px]
  bool verbose = false;
};

Arguments parse(hf::cli::Parser& p) {
  Arguments a;
  hf::cli::Input video("VIDEO");
  hf::cli::MaskOptions mask;
  while (p.next()) {
    if (mask.take(p)) continue;  // --mask, --size, --border
    if (p.is("--denoise")) {
      a.denoise = p.choice<hf::DenoiseMode>("denoise mode", {{"none", hf::DenoiseMode::none},
                                                             {"temporal", hf::DenoiseMode::temporal},
                                                             {"spatial", hf::DenoiseMode::spatial},
                                                             {"both", hf::DenoiseMode::both}});
    } else if (p.is("--fade-ms")) {
      a.fade_s = p.real(hf::cli::closed(0.0, 10000.0)) * 1e-3;
    } else if (p.is("--cuts")) {
      a.cuts = p.output_file();
    } else if (p.is("--probes")) {
      a.probes = p.value();
    } else if (p.is("--forces")) {
      a.forces = p.output_file();
    } else if (p.is("--seconds")) {
      a.seconds = p.real(hf::cli::open_closed(0.0, 3600.0));
    } else if (p.is("--device")) {
      a.device = hf::cli::device_option(p.value());
    } else if (p.is("--clock")) {
      a.virtual_clock = hf::cli::virtual_clock_option(p);
    } else if (p.is("--trace")) {
      a.trace = p.output_file();
    } else if (p.is("--plots")) {
      a.plots = p.output_dir();
    } else if (p.is("--max-mpx")) {
      a.max_pixels = p.megapixels();
    } else if (p.is("--verbose")) {
      a.verbose = true;
    } else {
      p.input_or_unknown(video);
    }
  }
  a.video = video.required();
  if (a.probes.has_value() != a.forces.has_value()) throw hf::cli::UsageError("--probes and --forces go together");
  if (a.probes && (a.trace || a.seconds || a.virtual_clock))
    throw hf::cli::UsageError("--trace, --seconds and --clock are for play mode, not --probes");
  hf::cli::check_clock_fits_arm(a.virtual_clock.value_or(false), a.device);
  a.options = mask.apply(a.options);
  if (a.video.rfind("camera:", 0) == 0) (void)hf::cli::parse_integer(a.video.substr(7), "camera:N", 0, 99);
  p.finish();
  return a;
}

std::unique_ptr<hf::VideoSource> open_source(const Arguments& a) {
  const hf::VideoSourceConfig config{.max_pixels = a.max_pixels};
  try {
    if (a.video.rfind("camera:", 0) == 0)
      return std::make_unique<hf::VideoSource>(static_cast<int>(std::stol(a.video.substr(7))), config);
    return std::make_unique<hf::VideoSource>(a.video, config);
  } catch (const hf::VideoError& e) {
    throw hf::VideoError(hf::cli::name_limit_flag(e.what(), "--max-mpx"));  // the user's flag, not the library's
  }
}

void warn_variable_rate(const std::string& name) {
  std::printf(
      "warning: '%s' has a variable frame rate: frame k is felt at k / fps, which strays from the file's own "
      "timestamps\n",
      name.c_str());
}

hf::PrepareConfig prepare_config(const Arguments& a) {
  hf::PrepareConfig c;
  c.tangible = a.options;
  c.denoise.mode = a.denoise;
  return c;
}

void write_cuts(const std::string& path, const std::vector<hf::SceneCut>& cuts) {
  std::FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw std::runtime_error("cannot write cuts file '" + path + "'");
  std::fprintf(out, "frame,time\n");
  for (const hf::SceneCut& c : cuts)
    std::fprintf(out, "%ld,%.9g\n", c.frame, c.time);
  if (std::fclose(out) != 0) throw std::runtime_error("cannot write cuts file '" + path + "'");
}

/// What a force plot shows: play mode, the lateral force commanded to the
/// arm [N]; probe mode, the normalised force at the probes.
enum class PlotMode { play, probes };

/// The simple force plot (OpenCV, when matplotlib is absent): fx, fy and
/// |F| against video time with numbered axes, units, a legend and the
/// scene cuts found drawn and numbered by frame.
cv::Mat simple_force_plot(const std::vector<std::array<double, 3>>& rows, const std::vector<hf::SceneCut>& cuts,
                          PlotMode mode) {
  namespace plot = hf::plots;
  const int w = 1000, h = 440;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  double t0 = rows.front()[0], t1 = rows.back()[0], peak = 1e-9;
  for (const auto& r : rows)
    peak = std::max(peak, std::hypot(r[1], r[2]));
  if (t1 <= t0) t1 = t0 + 1e-3;
  const plot::Axes axes(cv::Rect(80, 60, w - 110, h - 120), t0, t1, -1.05 * peak, 1.05 * peak);
  const bool play = mode == PlotMode::play;
  plot::text(img,
             play ? "Force sent to the arm while playing: fx, fy (device frame), lateral |F|"
                  : "Force at the probes (normalised, fy down)",
             {10, 20}, 0.5);
  plot::text(
      img,
      "scene cuts found: " + std::to_string(cuts.size()) + " (orange, numbered by the first frame of the new scene)",
      {10, 40}, 0.42);
  axes.draw(img, play ? "video time [s] (1x from the first tick)" : "video time [s]",
            play ? "lateral force commanded [N]" : "normalised force (1 = black/white edge)");
  const cv::Scalar cut_colour(0, 140, 255);
  for (const hf::SceneCut& c : cuts) {
    if (c.time < t0 || c.time > t1) continue;
    const cv::Point top = axes.at(c.time, 1.05 * peak), bottom = axes.at(c.time, -1.05 * peak);
    cv::line(img, top, bottom, cut_colour, 1);
    plot::text(img, "cut " + std::to_string(c.frame), {top.x + 3, top.y + 12}, 0.35, cut_colour);
  }
  std::vector<double> t, fx, fy, magnitude;
  for (const auto& r : rows) {
    t.push_back(r[0]);
    fx.push_back(r[1]);
    fy.push_back(r[2]);
    magnitude.push_back(std::hypot(r[1], r[2]));
  }
  const cv::Scalar blue(200, 0, 0), green(0, 150, 0), black(0, 0, 0);
  axes.line(img, t, fx, blue);
  axes.line(img, t, fy, green);
  axes.line(img, t, magnitude, black);
  plot::legend(img, {axes.box().x + axes.box().width - 170, axes.box().y + 6},
               {{blue, "fx"}, {green, "fy"}, {black, play ? "|F| lateral" : "|F|"}, {cut_colour, "scene cut"}});
  return img;
}

/// Writes DIR/NAME.png: t, fx, fy rows and the cuts go to DIR/NAME.csv and
/// DIR/cuts.csv for scripts/hapticfield_plots.py (matplotlib) when present,
/// else the simple plot is drawn. Returns who drew it.
std::string plot_forces(const std::string& dir, const std::string& name, const std::vector<std::array<double, 3>>& rows,
                        const std::vector<hf::SceneCut>& cuts, PlotMode mode) {
  std::filesystem::create_directories(dir);
  const std::string png = dir + "/" + name + ".png", data = dir + "/" + name + ".csv", cut_file = dir + "/cuts.csv";
  {
    std::ofstream out(data);
    out << "t_s,fx,fy\n";
    for (const auto& r : rows)
      out << r[0] << ',' << r[1] << ',' << r[2] << '\n';
    if (!out) throw hf::FileError("--plots: cannot write '" + data + "'");
  }
  write_cuts(cut_file, cuts);
  std::string why;
  if (hf::plots::matplotlib({"video", "--forces", data, "--cuts", cut_file, "--mode",
                             mode == PlotMode::play ? "play" : "probes", "--out", png},
                            why))
    return "drawn with matplotlib";
  if (!cv::imwrite(png, simple_force_plot(rows, cuts, mode)))
    throw hf::FileError("--plots: cannot write '" + png + "'");
  return "simple plots: " + why;
}

int run_probes(const Arguments& a) {
  auto source = open_source(a);
  const auto probes = hf::cli::read_csv<3>(*a.probes, {.columns = "t,x,y", .what = "probes", .finite_only = true});
  for (std::size_t i = 0; i < probes.size(); ++i)
    if (probes[i][0] < 0.0 || probes[i][0] > 1e6)
      throw hf::FileError(*a.probes + ": probe " + std::to_string(i + 1) + ": t must be in [0, 1e6] s");
  std::vector<std::size_t> order(probes.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t i, std::size_t j) { return probes[i][0] < probes[j][0]; });
  hf::VideoTimeline timeline(*source, prepare_config(a), a.fade_s);
  std::vector<std::array<double, 5>> rows(probes.size());
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i : order) {
    const auto& [t, x, y] = probes[i];
    const glm::dvec2 f = timeline.at(t, x, y);
    rows[i] = {t, x, y, f.x, f.y};
  }
  if (a.cuts) timeline.run_to_end();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::FILE* out = std::fopen(a.forces->c_str(), "w");
  if (!out) throw std::runtime_error("cannot write forces file '" + *a.forces + "'");
  std::fprintf(out, "t,x,y,fx,fy\n");
  for (const auto& r : rows)
    std::fprintf(out, "%.17g,%.17g,%.17g,%.17g,%.17g\n", r[0], r[1], r[2], r[3], r[4]);
  if (std::fclose(out) != 0) throw std::runtime_error("cannot write forces file '" + *a.forces + "'");
  std::printf("%s: %d x %d px at %.3f fps, %ld frames prepared in %.2f s, %zu cuts, %ld undecodable frames\n",
              a.video.c_str(), source->width(), source->height(), source->fps(), timeline.prepared(), seconds,
              timeline.cuts().size(), source->bad_frames());
  if (source->variable_rate()) warn_variable_rate(a.video);
  std::printf("forces at %zu probes written to %s\n", rows.size(), a.forces->c_str());
  if (a.cuts) {
    write_cuts(*a.cuts, timeline.cuts());
    std::printf("cuts: %s\n", a.cuts->c_str());
  }
  if (a.plots && !rows.empty()) {
    std::vector<std::array<double, 3>> sorted;
    for (std::size_t i : order)
      sorted.push_back({rows[i][0], rows[i][3], rows[i][4]});
    const std::string drawn_by = plot_forces(*a.plots, "forces", sorted, timeline.cuts(), PlotMode::probes);
    std::printf("plots: %s/forces.png (%s)\n", a.plots->c_str(), drawn_by.c_str());
  }
  return 0;
}

struct Row {
  double t{0.0};
  glm::dvec3 position{0.0};
  glm::dvec3 force{0.0};
};

/// Play mode on the loop clock `Clock`: SteadyClock (real time) or
/// VirtualClock (simulated time, the video in lockstep).
template <class Clock>
int run_play(const Arguments& a) {
  auto source = open_source(a);
  const double duration = source->duration();
  const double seconds = a.seconds.value_or(std::min(std::isfinite(duration) ? duration : 10.0, 60.0));
  const int width = source->width(), height = source->height();
  const std::string name = source->name();
  const double fps = source->fps();
  const hf::PlaneMapping mapping = hf::PlaneMapping::fit(width, height, 80.0);  // the video spans 80 mm
  hf::VideoFieldConfig config;
  config.prepare = prepare_config(a);
  config.fade = a.fade_s;
  config.gain = 1.0;  // [N] at a black/white edge
  hf::VideoField video(std::move(source), mapping, config);
  hf::VideoField* video_ptr = &video;
  // The picture's plane holds the hand (Fc); the video's forces on top.
  const hf::PlaneConstraint wall(hf::PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0.0, 0.0, 1.0}, 1500.0, 0.0});
  auto field = hf::contact(wall, std::move(video));
  video_ptr = &field.part<0>();

  Clock clock;
  const auto now = [&clock] { return clock.now(); };
  constexpr bool simulated_time = std::is_same_v<Clock, hf::VirtualClock>;
  if (simulated_time) video_ptr->set_lockstep(true);  // each tick waits for its frame
  const double w_m = width / mapping.px_per_mm() * 1e-3, h_m = height / mapping.px_per_mm() * 1e-3;
  hf::DeviceOptions device_options;
  device_options.now = now;
  device_options.hand.path = hf::HandPath::raster(glm::dvec3{0.0, 0.0, -0.008}, w_m * 0.9, h_m * 0.9, 8, 0.06);
  hf::AnyDevice device = hf::open_device(a.device, device_options);
  const bool hardware = !a.device.simulated;
  hf::LoopConfig loop_config;
  loop_config.recover_after = 0.5;
  hf::ServoLoop<hf::AnyDevice, Clock> loop(device, clock, loop_config);
  hf::cli::StopOnSignal stop(loop);  // Ctrl-C: zero force and disarm through the loop's stop
  if (hardware) hf::cli::wait_for_operator();
  if (stop.caught()) {
    std::printf("stopped by signal %d before the loop started; no force was commanded\n", stop.caught());
    return stop.exit_status();
  }
  std::printf("%s: %d x %d px at %.3f fps, mask %s %d, denoise %s, fade %.0f ms; playing %.2f s%s (Ctrl-C stops)\n",
              name.c_str(), width, height, fps, hf::to_string(a.options.mask), a.options.size, hf::to_string(a.denoise),
              a.fade_s * 1e3, seconds, simulated_time ? " of simulated time (lockstep)" : "");

  const auto ticks = static_cast<std::uint64_t>(std::max(1L, std::lround(seconds * loop_config.rate)));
  std::vector<Row> rows;
  rows.reserve(ticks + 8);  // the tick path only fills reserved rows
  auto callback = [&](const hf::TickInput& in) noexcept {
    if (rows.size() < rows.capacity()) {
      if (!rows.empty()) rows.back().force = loop.last_command();
      rows.push_back({in.probe.time, in.probe.position, glm::dvec3{0.0}});
    }
    return field.force(in.probe);
  };
  hf::cli::LoopThread servo(loop, callback, {.max_ticks = ticks});
  // On a terminal one live line, redrawn in place with '\r' every 200 ms;
  // into a file or a pipe a plain line every 10 s and the last one, no '\r'.
  const bool terminal = hf::cli::stdout_is_terminal();
  const auto status = [&] {
    const hf::LoopSnapshot s = loop.statistics();
    const hf::VideoStatistics v = video_ptr->statistics();
    std::printf(
        "%s video %7.2f s | frames %5ld dropped %4ld bad %3ld | cuts %3ld | rate %8.2f Hz | p99 %6.3f ms | "
        "peak %5.2f N%s%s",
        terminal ? "\r" : "", v.video_time, v.prepared, v.dropped, v.bad, v.cuts, s.rate, s.period_p99 * 1e3,
        s.peak_force, loop.safety().latched() ? " | ZERO FORCE" : "", terminal ? "   " : "\n");
    std::fflush(stdout);
  };
  for (int polls = 1; !servo.done(); ++polls) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    if (terminal || polls % 50 == 0) status();
  }
  servo.join();
  status();
  if (terminal) std::printf("\n");
  const bool disconnected = servo.outcome() == hf::StopReason::disconnected;  // rethrows what the loop threw
  if (disconnected) std::printf("the device disconnected; zero force was commanded\n");
  if (stop.caught()) std::printf("stopped by signal %d: zero force commanded, then the arm disarmed\n", stop.caught());
  const hf::VideoStatistics v = video_ptr->statistics();
  const std::vector<hf::SceneCut> cuts = video_ptr->cuts();
  video_ptr->stop();
  std::printf("%ld frames prepared, %ld dropped (preparation lagged), %ld undecodable, %zu cuts:", v.prepared,
              v.dropped, v.bad, cuts.size());
  for (const hf::SceneCut& c : cuts)
    std::printf(" %ld (%.3f s)", c.frame, c.time);
  std::printf("\n");
  if (v.variable_rate) warn_variable_rate(name);
  const std::string stopped = video_ptr->error();
  if (a.cuts) {
    write_cuts(*a.cuts, cuts);
    std::printf("cuts: %s\n", a.cuts->c_str());
  }
  if (a.trace) {
    std::ofstream f(*a.trace);
    if (!f) throw std::runtime_error("cannot write " + *a.trace);
    f << "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N\n";
    for (const Row& r : rows)
      f << r.t << ',' << r.position.x << ',' << r.position.y << ',' << r.position.z << ',' << r.force.x << ','
        << r.force.y << ',' << r.force.z << '\n';
    std::printf("trace: %s (%zu rows)\n", a.trace->c_str(), rows.size());
  }
  if (a.plots && !rows.empty()) {
    // video time = loop time since the first tick (playback at 1x from 0)
    std::vector<std::array<double, 3>> plot;
    const double t_start = rows.front().t;
    for (const Row& r : rows)
      plot.push_back({r.t - t_start, r.force.x, r.force.y});
    const std::string drawn_by = plot_forces(*a.plots, "force", plot, cuts, PlotMode::play);
    std::printf("plots: %s/force.png (%s)\n", a.plots->c_str(), drawn_by.c_str());
  }
  // The worker failed on a frame (bad input): one line on stderr, exit 1.
  if (!stopped.empty())
    throw hf::VideoError(hf::cli::name_limit_flag("the video stopped early: " + stopped, "--max-mpx"));
  if (disconnected) throw hf::DeviceError("the device disconnected during the run; zero force was commanded");
  return stop.caught() ? stop.exit_status() : 0;
}

int play(const Arguments& a) {
  return a.virtual_clock.value_or(false) ? run_play<hf::VirtualClock>(a) : run_play<hf::SteadyClock>(a);
}

int run(const Arguments& a) {
  hf::quiet_video_logs(a.verbose);
  if (a.verbose) return a.probes ? run_probes(a) : play(a);
  // FFmpeg writes its own complaints about damaged streams to stderr: muted.
  return hf::cli::quiet_stderr([&] { return a.probes ? run_probes(a) : play(a); });
}

}  // namespace

int main(int argc, char** argv) {
  bool verbose = false;
  for (int i = 1; i < argc; ++i)
    verbose = verbose || std::string(argv[i]) == "--verbose";
  hf::quiet_video_logs(verbose);
  if (!verbose) cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return hf::cli::main("tangible_video", usage, argc, argv, [](hf::cli::Parser& p) { return run(parse(p)); });
}
