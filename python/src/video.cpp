// Tangible video from Python: forces at (video time, pixel) probes offline,
// the scene cuts, and a VideoField (a worker thread prepares the frames) that
// composes like any field and runs in the servo loop. Built only when the
// library's video target (OpenCV videoio) is; otherwise the calls raise.
#include "field.hpp"

#include <pybind11/stl.h>

#if HAPTICFIELD_PYTHON_VIDEO
#include <hapticfield/video.hpp>
#endif

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <utility>
#include <vector>

namespace hapticfield::python {

#if HAPTICFIELD_PYTHON_VIDEO

namespace {

/// The VideoField shared between the Python handle (controls, statistics)
/// and the fields it is composed into (forces): the worker stops when the
/// last of them goes.
struct SharedVideo {
  std::shared_ptr<VideoField> video;
  glm::dvec3 force(const Probe& probe) noexcept { return video->force(probe); }
  void reset() noexcept { video->reset(); }  // plays from the configured start again
};

/// A Field that is a video: the handle keeps the playback controls.
struct VideoHandle : Field {
  std::shared_ptr<VideoField> video;
};

DenoiseMode denoise_kind(const std::string& name) {
  return choose<DenoiseMode>("denoise", name,
                             {{"none", DenoiseMode::none},
                              {"temporal", DenoiseMode::temporal},
                              {"spatial", DenoiseMode::spatial},
                              {"both", DenoiseMode::both}});
}

PrepareConfig prepare_config(const std::string& mask, std::optional<int> size, const std::string& border,
                             const std::string& denoise) {
  PrepareConfig c;
  c.tangible = tangible_options(mask, size, border, 0.0);
  c.denoise.mode = denoise_kind(denoise);
  return c;
}

std::unique_ptr<VideoSource> open_video(const py::object& path) {
  const std::string p = py::str(py::module_::import("os").attr("fspath")(path));
  quiet_video_logs(false);
  return std::make_unique<VideoSource>(p);
}

py::list cut_list(const std::vector<SceneCut>& cuts) {
  py::list l;
  for (const SceneCut& c : cuts)
    l.append(py::make_tuple(c.frame, c.time));
  return l;
}

/// Forces at N (t, x, y) probes: sorted by time (stable) for the timeline,
/// returned in the input order, as `tangible_video --probes` does.
py::array_t<double> video_forces(const py::object& path, const Array& t, const Array& xy, const std::string& mask,
                                 std::optional<int> size, const std::string& border, const std::string& denoise,
                                 double fade) {
  const py::ssize_t n = rows_of(t, 0, "t");
  if (rows_of(xy, 2, "xy") != n) throw py::value_error("xy: must have as many rows as t has entries");
  const double* times = t.data();
  for (py::ssize_t i = 0; i < n; ++i)
    if (!(std::isfinite(times[i]) && times[i] >= 0.0 && times[i] <= 1e6))
      throw py::value_error("t: video times must be finite and within [0, 1e6] [s], got " + std::to_string(times[i]) +
                            " at " + std::to_string(i));
  const PrepareConfig config = prepare_config(mask, size, border, denoise);
  auto source = open_video(path);
  auto out = matrix(n, 2);
  const double* p = xy.data();
  double* f = out.mutable_data();
  {
    py::gil_scoped_release release;
    std::vector<py::ssize_t> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), py::ssize_t{0});
    std::stable_sort(order.begin(), order.end(), [&](py::ssize_t i, py::ssize_t j) { return times[i] < times[j]; });
    VideoTimeline timeline(*source, config, fade);
    for (const py::ssize_t i : order) {
      const glm::dvec2 r = timeline.at(times[i], p[2 * i], p[2 * i + 1]);
      f[2 * i] = r.x, f[2 * i + 1] = r.y;
    }
  }
  return out;
}

py::list video_cuts(const py::object& path) {
  PrepareConfig config;
  config.tangible.mask = MaskKind::roberts;  // the cheapest mask: cuts are found on the gray levels
  config.tangible.size = 2;
  config.denoise.mode = DenoiseMode::none;
  auto source = open_video(path);
  std::vector<SceneCut> cuts;
  {
    py::gil_scoped_release release;
    VideoTimeline timeline(*source, config);
    timeline.run_to_end();
    cuts = timeline.cuts();
  }
  return cut_list(cuts);
}

VideoHandle video_field(const py::object& path, const std::string& mask, std::optional<int> size,
                        const std::string& border, const std::string& denoise, double fade, double gain, double rate,
                        double start, bool loop, std::optional<double> px_per_mm, std::optional<double> workspace_mm) {
  VideoFieldConfig config;
  config.prepare = prepare_config(mask, size, border, denoise);
  config.fade = fade;
  config.gain = gain;
  config.playback.rate = rate;
  config.playback.start = start;
  config.playback.loop = loop;
  config.playback.validate();
  if (!(std::isfinite(fade) && fade >= 0.0 && fade <= 10.0)) throw py::value_error("fade: must be within [0, 10] [s]");
  if (px_per_mm && !(std::isfinite(*px_per_mm) && *px_per_mm > 0.0))
    throw py::value_error("px_per_mm: must be finite and > 0 [px/mm]");
  if (workspace_mm && !(std::isfinite(*workspace_mm) && *workspace_mm > 0.0))
    throw py::value_error("workspace_mm: must be finite and > 0 [mm]");
  auto source = open_video(path);
  const std::string name = source->name();
  const PlaneMapping mapping = mapping_for(source->width(), source->height(), px_per_mm, workspace_mm);
  VideoHandle h;
  h.video = std::make_shared<VideoField>(std::move(source), mapping, std::move(config));
  h.impl = std::make_shared<AnyField>(SharedVideo{h.video});
  h.guards = guards_of();
  h.guards.front()->lockstep = [video = std::weak_ptr<VideoField>(h.video)](bool on) {
    if (const auto v = video.lock()) v->set_lockstep(on);
  };
  h.description =
      "video " + name + " " + std::to_string(h.video->width()) + " x " + std::to_string(h.video->height()) + " px";
  return h;
}

py::dict statistics_dict(const VideoStatistics& s) {
  py::dict d;
  d["prepared"] = s.prepared;
  d["dropped"] = s.dropped;
  d["bad"] = s.bad;
  d["published"] = s.published;
  d["cuts"] = s.cuts;
  d["stale_ticks"] = s.stale;
  d["ended"] = s.ended;
  d["video_time_s"] = s.video_time;
  return d;
}

}  // namespace

void bind_video(py::module_& m) {
  m.attr("has_video") = true;
  m.def("video_forces", &video_forces, py::arg("path"), py::arg("t"), py::arg("xy"), py::arg("mask") = "prewitt",
        py::arg("size") = py::none(), py::arg("border") = "suspend", py::arg("denoise") = "temporal",
        py::arg("fade") = default_cut_fade,
        "Tangible-video forces offline (the same numbers as `tangible_video --probes`, bit for bit): N video "
        "times t [s] (frame k at k / fps; any order: they are evaluated sorted, stable, and returned in the input "
        "order) and N x 2 pixel positions xy [px] (x right, y down, integer = pixel centre) -> N x 2 normalised "
        "forces (1 = a black/white edge), fy down, blended between frames and faded across scene cuts. path: a "
        "video file or an image sequence pattern such as 'frames/%04d.png' (25 frames/s). mask, size [px], "
        "border as tangible_forces(); denoise none|temporal|spatial|both; fade [s] across a cut, [0, 10]. "
        "The frames are decoded and prepared on the calling thread, the GIL released.");
  m.def("video_cuts", &video_cuts, py::arg("path"),
        "The scene cuts of a video: a list of (frame, time [s]), frame the first of the new scene, as "
        "`tangible_video --cuts` writes them.");
  py::class_<VideoHandle, Field>(m, "VideoField",
                                 "A video felt as a field: a worker thread decodes and prepares the frames; the "
                                 "servo thread maps its loop time [s] to video time and blends the two frames "
                                 "that bracket it (never waiting, locking or allocating). Use it like any Field "
                                 "(forces, composition, run_servo); the probes' time is the loop time [s].")
      .def(
          "pause", [](VideoHandle& h) { h.video->playback().pause(); }, "Holds the video time where it is.")
      .def(
          "resume", [](VideoHandle& h) { h.video->playback().resume(); }, "Lets the video time advance again.")
      .def(
          "seek",
          [](VideoHandle& h, double t) {
            if (!std::isfinite(t)) throw py::value_error("seek: time must be finite [s]");
            h.video->playback().seek(t);
          },
          py::arg("t"), "Jumps to video time t [s] (clamped to the video) at the next tick.")
      .def(
          "set_rate", [](VideoHandle& h, double rate) { h.video->playback().set_rate(rate); }, py::arg("rate"),
          "Video seconds per loop second, in (0, 16].")
      .def(
          "statistics", [](const VideoHandle& h) { return statistics_dict(h.video->statistics()); },
          "Counters: prepared, dropped (preparation lagged), bad (undecodable), published (windows), cuts, "
          "stale_ticks (ticks whose window was past its 0.5 s hold: the worker late; the force fades out), ended, "
          "video_time_s (the servo thread's latest video time [s]).")
      .def(
          "cuts", [](const VideoHandle& h) { return cut_list(h.video->cuts()); },
          "The scene cuts found so far: a list of (frame, time [s]).")
      .def(
          "error", [](const VideoHandle& h) { return h.video->error(); },
          "The worker's error message if it stopped on one, else ''.")
      .def(
          "stop",
          [](VideoHandle& h) {
            py::gil_scoped_release release;
            h.video->stop();
          },
          "Stops the worker thread (the field keeps its last window).")
      .def_property_readonly(
          "lockstep", [](const VideoHandle& h) { return h.video->lockstep(); },
          "True while run_servo(clock='virtual') holds the video: each tick waits for the frame that covers its "
          "video time, and the worker drops no frame.")
      .def_property_readonly(
          "fps", [](const VideoHandle& h) { return h.video->fps(); }, "Frames per second [1/s].")
      .def_property_readonly(
          "width", [](const VideoHandle& h) { return h.video->width(); }, "Frame width [px].")
      .def_property_readonly(
          "height", [](const VideoHandle& h) { return h.video->height(); }, "Frame height [px].")
      .def_property_readonly(
          "duration", [](VideoHandle& h) { return h.video->playback().config().duration; },
          "Length of the video [s] (frames / fps; inf when the container does not say).");
  m.def("video_field", &video_field, py::arg("path"), py::arg("mask") = "prewitt", py::arg("size") = py::none(),
        py::arg("border") = "suspend", py::arg("denoise") = "temporal", py::arg("fade") = default_cut_fade,
        py::arg("gain") = 1.0, py::arg("rate") = 1.0, py::arg("start") = 0.0, py::arg("loop") = false,
        py::arg("px_per_mm") = py::none(), py::arg("workspace_mm") = py::none(),
        "A VideoField in the device's x-y plane: the video centred on the origin at px_per_mm [px/mm] (default "
        "6.4) or fitted so its longer side spans workspace_mm [mm]; gain [N] at a black/white edge; playback rate "
        "(video s per loop s, (0, 16]), start [s of video time], loop. mask, size, border, denoise, fade as "
        "video_forces(). Device frame x right, y up.");
}

#else  // no videoio in this build

void bind_video(py::module_& m) {
  m.attr("has_video") = false;
  const auto absent = [](const py::args&, const py::kwargs&) -> py::object {
    throw hapticfield::Error("tangible video: this build of the module has no OpenCV videoio");
  };
  for (const char* name : {"video_forces", "video_cuts", "video_field"})
    m.def(name, absent, "Unavailable: this build of the module has no OpenCV videoio (raises hapticfield.Error).");
}

#endif

}  // namespace hapticfield::python
