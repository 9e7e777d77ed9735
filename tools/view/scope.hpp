#pragma once
/// @file scope.hpp
/// The viewer's rolling scope: the last few seconds of Fx, Fy, Fz and |F|
/// with labelled axes, ticks and a legend, drawn with OpenCV. Viewer thread
/// only (allocates, draws); never on the servo path.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <opencv2/imgproc.hpp>

#include "view/view_sample.hpp"

namespace hapticfield::view {

/// Evenly spaced "nice" tick values (1, 2 or 5 times a power of ten) that
/// cover [lo, hi] with about `target` intervals. Empty for an empty or
/// non-finite range.
[[nodiscard]] inline std::vector<double> nice_ticks(double lo, double hi, int target = 5) {
  std::vector<double> ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo) || target < 1) return ticks;
  const double raw = (hi - lo) / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10.0 * magnitude;
  for (const double m : {1.0, 2.0, 5.0})
    if (m * magnitude >= raw * 0.999) {
      step = m * magnitude;
      break;
    }
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step)
    ticks.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
  return ticks;
}

/// Tick label: as few decimals as the step needs ("0.5", "-1", "0.25").
[[nodiscard]] inline std::string tick_label(double v, double step) {
  const int decimals = step >= 1.0 ? 0 : std::min(6, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

/// Settings of Scope.
struct ScopeConfig {
  double window{5.0};     ///< time shown [s]
  double min_range{0.1};  ///< smallest half-height of the force axis [N]
};

/// The scope's traces, in drawing order (|F| last, on top): their names
/// and colours (BGR).
inline constexpr int scope_traces = 4;
inline constexpr const char* scope_names[scope_traces] = {"Fx", "Fy", "Fz", "|F|"};
inline const cv::Scalar scope_colours[scope_traces] = {{200, 90, 0}, {0, 150, 0}, {0, 0, 210}, {20, 20, 20}};

/// Trace `c` of the scope (0 Fx, 1 Fy, 2 Fz, 3 |F|) of a force [N].
[[nodiscard]] inline double scope_value(const glm::dvec3& f, int c) noexcept {
  return c < 3 ? f[c] : glm::length(f);
}

/// History of samples for the scope, and its drawing.
class Scope {
 public:
  explicit Scope(ScopeConfig config = {}) : config_(config) {}

  /// Adds a sample; drops those older than the window.
  void add(const ViewSample& s) {
    samples_.push_back(s);
    while (!samples_.empty() && samples_.front().t < s.t - config_.window)
      samples_.pop_front();
  }
  void clear() { samples_.clear(); }
  [[nodiscard]] const std::deque<ViewSample>& samples() const noexcept { return samples_; }

  /// Half-height of the force axis [N]: a nice value above the largest
  /// force shown.
  [[nodiscard]] double range() const {
    double peak = 0.0;
    for (const ViewSample& s : samples_)
      peak = std::max(peak, glm::length(s.force));
    peak = std::max(peak * 1.1, config_.min_range);
    const double magnitude = std::pow(10.0, std::floor(std::log10(peak)));
    for (const double m : {1.0, 2.0, 2.5, 5.0, 10.0})
      if (m * magnitude >= peak) return m * magnitude;
    return 10.0 * magnitude;
  }

  /// Draws the scope into `area` of `canvas` (BGR): axes, ticks, units,
  /// legend and the four traces.
  void draw(cv::Mat& canvas, cv::Rect area) const {
    const cv::Scalar ink(30, 30, 30), grid(225, 225, 225);
    cv::rectangle(canvas, area, cv::Scalar(255, 255, 255), cv::FILLED);
    const int left = area.x + 62, right = area.x + area.width - 12;
    const int top = area.y + 26, bottom = area.y + area.height - 40;
    if (right - left < 20 || bottom - top < 20) return;
    const double r = range();
    const double t_end = samples_.empty() ? config_.window : samples_.back().t;
    const double t_start = t_end - config_.window;
    const auto x_of = [&](double t) {
      return left + static_cast<int>(std::lround((t - t_start) / config_.window * (right - left)));
    };
    const auto y_of = [&](double f) {
      return top + static_cast<int>(std::lround((r - f) / (2.0 * r) * (bottom - top)));
    };
    const auto text = [&](const std::string& s, cv::Point at, double scale = 0.42, cv::Scalar c = {30, 30, 30}) {
      cv::putText(canvas, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1, cv::LINE_AA);
    };
    // force axis: ticks and grid
    const std::vector<double> fticks = nice_ticks(-r, r, 4);
    const double fstep = fticks.size() > 1 ? fticks[1] - fticks[0] : r;
    for (const double f : fticks) {
      const int y = y_of(f);
      cv::line(canvas, {left, y}, {right, y}, f == 0.0 ? cv::Scalar(170, 170, 170) : grid);
      cv::line(canvas, {left - 5, y}, {left, y}, ink);
      const std::string label = tick_label(f, fstep);
      int base = 0;
      const cv::Size size = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.42, 1, &base);
      text(label, {left - 8 - size.width, y + size.height / 2});
    }
    // time axis: seconds before now
    const std::vector<double> tticks = nice_ticks(-config_.window, 0.0, 5);
    const double tstep = tticks.size() > 1 ? tticks[1] - tticks[0] : 1.0;
    for (const double dt : tticks) {
      const int x = x_of(t_end + dt);
      cv::line(canvas, {x, top}, {x, bottom}, grid);
      cv::line(canvas, {x, bottom}, {x, bottom + 5}, ink);
      const std::string label = tick_label(dt, tstep);
      int base = 0;
      const cv::Size size = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.42, 1, &base);
      text(label, {x - size.width / 2, bottom + 20});
    }
    cv::rectangle(canvas, cv::Point(left, top), cv::Point(right, bottom), ink);
    text("time before now [s]", {(left + right) / 2 - 60, area.y + area.height - 6});
    text("force [N]", {area.x + 4, area.y + 16});
    // traces: Fx blue, Fy green, Fz red (the push along the depth the wheel moves in 3D), |F| black
    std::vector<cv::Point> line;
    for (int c = 0; c < scope_traces; ++c) {
      line.clear();
      const std::size_t step = std::max<std::size_t>(1, samples_.size() / static_cast<std::size_t>(2 * (right - left)));
      for (std::size_t i = 0; i < samples_.size(); i += step) {
        const ViewSample& s = samples_[i];
        line.emplace_back(x_of(s.t), y_of(std::clamp(scope_value(s.force, c), -r, r)));
      }
      if (line.size() > 1) cv::polylines(canvas, line, false, scope_colours[c], 1, cv::LINE_AA);
      const int lx = right - 228 + 58 * c;
      cv::line(canvas, {lx, area.y + 12}, {lx + 18, area.y + 12}, scope_colours[c], 2);
      text(scope_names[c], {lx + 22, area.y + 16});
    }
  }

 private:
  ScopeConfig config_;
  std::deque<ViewSample> samples_;
};

}  // namespace hapticfield::view
