#pragma once
/// @file view_frame.hpp
/// Draws one frame of the viewer: the picture (or the field's own underlay)
/// with the probe as a cursor and the force as an arrow, a status panel
/// (the loop's rate, jitter, late ticks, missed deadlines, safety events)
/// and the rolling force scope. Viewer thread only.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/servo/safety.hpp"
#include "hapticfield/servo/statistics.hpp"
#include "view/scope.hpp"

namespace hapticfield::view {

/// The cursor's fill colour (BGR): pure magenta, drawn without smoothing so
/// the probe's pixel has exactly this colour.
inline const cv::Scalar cursor_colour(255, 0, 255);
/// The force arrow's colour (BGR).
inline const cv::Scalar arrow_colour(0, 200, 255);

/// Where things go on the canvas.
struct ViewLayout {
  static constexpr int margin = 10;                                        ///< [px]
  static constexpr int panel_width = 330;                                  ///< status panel [px]
  static constexpr int scope_height = 230;                                 ///< [px]
  static constexpr int max_picture_width = 800, max_picture_height = 600;  ///< [px]

  cv::Rect picture;  ///< the picture, scaled by `scale`
  cv::Rect panel;
  cv::Rect scope;
  cv::Size canvas;
  double scale{1.0};  ///< canvas px per picture px

  /// Layout for a picture of w x h px: shown at its own size when it fits in
  /// 800 x 600, otherwise scaled down to fit.
  static ViewLayout for_picture(int w, int h) {
    ViewLayout l;
    l.scale = std::min({1.0, static_cast<double>(max_picture_width) / w, static_cast<double>(max_picture_height) / h});
    const int pw = std::max(1, static_cast<int>(std::lround(w * l.scale)));
    const int ph = std::max(1, static_cast<int>(std::lround(h * l.scale)));
    const int body_h = std::max(ph, 400);  // room for the status lines
    l.picture = {margin, margin, pw, ph};
    l.panel = {margin * 2 + pw, margin, panel_width, body_h};
    l.canvas = {margin * 3 + pw + panel_width, margin * 3 + body_h + scope_height};
    l.scope = {margin, margin * 2 + body_h, l.canvas.width - 2 * margin, scope_height};
    return l;
  }

  /// Canvas position of picture position p [px].
  [[nodiscard]] cv::Point to_canvas(glm::dvec2 p) const {
    return {picture.x + static_cast<int>(std::lround(p.x * scale)),
            picture.y + static_cast<int>(std::lround(p.y * scale))};
  }
  /// Picture position [px] of a canvas point.
  [[nodiscard]] glm::dvec2 to_picture(int x, int y) const { return {(x - picture.x) / scale, (y - picture.y) / scale}; }
};

/// Everything the status panel shows.
struct ViewStatus {
  std::string source;  ///< picture file
  std::string device;  ///< device name
  std::string field;   ///< Scene::label
  LoopSnapshot loop{};
  bool latched{false};  ///< the safety chain holds zero force now
  std::uint32_t latch_bits{0};
  std::uint64_t dropped{0};  ///< samples the viewer missed
  bool paused{false};
  // a video source
  bool video{false};           ///< show the video lines below
  double video_time{0.0};      ///< [s]
  double video_duration{0.0};  ///< [s], infinity when unknown
  long video_frame{-1};        ///< index of the frame shown
  long frames_dropped{0};      ///< frames the video's worker skipped
  long scene_cuts{0};          ///< scene cuts detected
  std::string note;            ///< a transient message (a saved screenshot, a refused key)
  std::string probe_line;      ///< replaces the "probe x, y px" line when set (the 3D view)
  std::vector<std::string> keys{"keys: f field  m mask  +/- size  b border", "d denoise  space pause  [ ] seek",
                                "s screenshot  q / Esc quit"};  ///< the key help at the panel's foot
};

/// Settings of the drawing.
struct ViewDrawConfig {
  double arrow_px_per_newton{150.0};  ///< [px/N]
  double arrow_max_px{120.0};         ///< longest arrow [px]
  bool probe_marks{true};             ///< draw the cursor and arrow (false: the underlay has its own, the 3D view)
};

/// Draws the whole view into `canvas` (allocated here, BGR).
inline void draw_view(cv::Mat& canvas, const ViewLayout& layout, const cv::Mat& underlay, const Scope& scope,
                      const ViewSample& now, const ViewStatus& status, const ViewDrawConfig& config = {}) {
  canvas.create(layout.canvas, CV_8UC3);
  canvas.setTo(cv::Scalar(236, 236, 236));
  // picture
  if (layout.scale == 1.0) {
    underlay.copyTo(canvas(layout.picture));
  } else {
    cv::Mat scaled;
    cv::resize(underlay, scaled, layout.picture.size(), 0.0, 0.0, cv::INTER_AREA);
    scaled.copyTo(canvas(layout.picture));
  }
  // force arrow (image axes: device y up is picture y down), then the cursor
  cv::Mat pic = canvas(layout.picture);
  const cv::Point probe = layout.to_canvas(now.pixel) - layout.picture.tl();
  glm::dvec2 arrow{now.force.x, -now.force.y};
  arrow *= config.arrow_px_per_newton;
  if (const double len = glm::length(arrow); len > config.arrow_max_px) arrow *= config.arrow_max_px / len;
  if (config.probe_marks && glm::length(arrow) >= 3.0) {
    const cv::Point tip =
        probe + cv::Point(static_cast<int>(std::lround(arrow.x)), static_cast<int>(std::lround(arrow.y)));
    cv::arrowedLine(pic, probe, tip, cv::Scalar(0, 0, 0), 4, cv::LINE_AA, 0, 0.25);
    cv::arrowedLine(pic, probe, tip, arrow_colour, 2, cv::LINE_AA, 0, 0.25);
  }
  if (config.probe_marks) {
    cv::circle(pic, probe, 9, cv::Scalar(255, 255, 255), 3, cv::LINE_8);
    cv::circle(pic, probe, 9, cv::Scalar(0, 0, 0), 1, cv::LINE_8);
    cv::circle(pic, probe, 4, cursor_colour, cv::FILLED, cv::LINE_8);
  }
  // status panel
  cv::rectangle(canvas, layout.panel, cv::Scalar(250, 250, 250), cv::FILLED);
  int y = layout.panel.y + 20;
  const auto line = [&](const std::string& text, cv::Scalar colour = {30, 30, 30}, double scale = 0.42) {
    cv::putText(canvas, text, {layout.panel.x + 8, y}, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
    y += 18;
  };
  char text[200];
  const LoopSnapshot& s = status.loop;
  line("hapticfield_view", {120, 60, 0}, 0.55);
  line(status.source);
  line("device: " + status.device);
  // the field label can be long: two lines
  const std::string& f = status.field;
  const std::size_t cut = f.size() > 44 ? f.rfind(' ', 44) : std::string::npos;
  line(cut == std::string::npos ? f : f.substr(0, cut));
  if (cut != std::string::npos) line("  " + f.substr(cut + 1));
  y += 6;
  std::snprintf(text, sizeof text, "t %.2f s   ticks %llu", now.t, static_cast<unsigned long long>(s.ticks));
  line(text);
  std::snprintf(text, sizeof text, "rate %.1f Hz", s.rate);
  line(text);
  std::snprintf(text, sizeof text, "period p50 %.3f  p99 %.3f  max %.3f ms", s.period_p50 * 1e3, s.period_p99 * 1e3,
                s.period_max * 1e3);
  line(text);
  std::snprintf(text, sizeof text, "jitter p99-p50 %.0f us  wake p99 %.0f us", (s.period_p99 - s.period_p50) * 1e6,
                s.wake_p99 * 1e6);
  line(text);
  std::snprintf(text, sizeof text, "late ticks %llu   missed deadlines %llu",
                static_cast<unsigned long long>(s.overruns), static_cast<unsigned long long>(s.missed_deadlines));
  line(text);
  std::snprintf(text, sizeof text, "safety events %llu   latches %llu",
                static_cast<unsigned long long>(s.safety_events), static_cast<unsigned long long>(s.latches));
  line(text);
  // what the count counts (ServoLoop: a tick with any event but "not armed")
  line("  = ticks on which the safety chain clamped,", {110, 110, 110}, 0.36);
  line("    slowed, damped or zeroed the force", {110, 110, 110}, 0.36);
  if (status.latched)
    line("ZERO FORCE: " + safety_events::names(status.latch_bits), {0, 0, 220});
  else if (s.latches > 0)
    line("last latch: " + safety_events::names(s.last_latch), {0, 90, 200});
  y += 6;
  if (status.probe_line.empty()) {
    std::snprintf(text, sizeof text, "probe %.1f, %.1f px", now.pixel.x, now.pixel.y);
    line(text);
  } else {
    line(status.probe_line);
  }
  std::snprintf(text, sizeof text, "force %+.3f %+.3f %+.3f N", now.force.x, now.force.y, now.force.z);
  line(text);
  if (status.dropped > 0) {
    std::snprintf(text, sizeof text, "viewer missed %llu samples", static_cast<unsigned long long>(status.dropped));
    line(text);
  }
  if (status.video) {
    if (std::isfinite(status.video_duration))
      std::snprintf(text, sizeof text, "video %.2f / %.2f s   frame %ld", status.video_time, status.video_duration,
                    status.video_frame);
    else
      std::snprintf(text, sizeof text, "video %.2f s   frame %ld", status.video_time, status.video_frame);
    line(text);
    std::snprintf(text, sizeof text, "frames dropped %ld   scene cuts %ld", status.frames_dropped, status.scene_cuts);
    line(text);
  }
  if (status.paused) line("PAUSED", {0, 0, 220});
  if (!status.note.empty()) line(status.note, {0, 110, 0});
  y = std::max(y + 4, layout.panel.y + layout.panel.height - 4 * 16 - 4);
  for (const std::string& help : status.keys) {
    cv::putText(canvas, help, {layout.panel.x + 8, y}, cv::FONT_HERSHEY_SIMPLEX, 0.38, cv::Scalar(90, 90, 90), 1,
                cv::LINE_AA);
    y += 16;
  }
  scope.draw(canvas, layout.scope);
}

}  // namespace hapticfield::view
