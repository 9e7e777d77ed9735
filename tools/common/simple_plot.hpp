#pragma once
/// @file simple_plot.hpp
/// The examples' own plots when matplotlib is absent (see plots.hpp): axes
/// with numbered ticks and units, colour bars and legends drawn with OpenCV,
/// so that a fallback picture still says what it shows and at what scale.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace hapticfield::plots {

/// Ink of the axes, ticks and labels (BGR).
inline const cv::Scalar ink{40, 40, 40};

/// Round tick values covering [lo, hi]: steps of 1, 2 or 5 x 10^k, about
/// `count` of them.
[[nodiscard]] inline std::vector<double> nice_ticks(double lo, double hi, int count = 5) {
  std::vector<double> ticks;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi) || count < 1) return ticks;
  const double raw = (hi - lo) / count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * magnitude >= raw) {
      step = m * magnitude;
      break;
    }
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step)
    ticks.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
  return ticks;
}

/// A tick's label: %g with 3 significant digits.
[[nodiscard]] inline std::string tick_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

inline void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.4, const cv::Scalar& colour = ink) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

[[nodiscard]] inline int text_width(const std::string& s, double scale = 0.4) {
  int baseline = 0;
  return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).width;
}

/// A plot area `box` [px of img] showing x in [x0, x1] and y in [y0, y1]:
/// maps data to pixels and draws the frame, numbered ticks and axis labels
/// (units in brackets) outside the box.
class Axes {
 public:
  /// y_down: y grows downward, as in a picture (y0 at the top).
  Axes(cv::Rect box, double x0, double x1, double y0, double y1, bool y_down = false)
      : box_(box), x0_(x0), x1_(x1 > x0 ? x1 : x0 + 1.0), y0_(y0), y1_(y1 > y0 ? y1 : y0 + 1.0), y_down_(y_down) {}

  [[nodiscard]] cv::Point at(double x, double y) const {
    const double u = (x - x0_) / (x1_ - x0_), v = (y - y0_) / (y1_ - y0_);
    const int rows = static_cast<int>(std::lround(v * (box_.height - 1)));
    return {box_.x + static_cast<int>(std::lround(u * (box_.width - 1))),
            y_down_ ? box_.y + rows : box_.y + box_.height - 1 - rows};
  }
  [[nodiscard]] const cv::Rect& box() const { return box_; }

  /// Frame, ticks with numbers, a faint grid and the axis labels.
  void draw(cv::Mat& img, const std::string& xlabel, const std::string& ylabel, bool grid = true) const {
    for (double x : nice_ticks(x0_, x1_, std::max(2, box_.width / 90))) {
      const cv::Point p(at(x, y0_).x, box_.y + box_.height - 1);  // along the bottom edge
      if (grid) cv::line(img, {p.x, box_.y}, {p.x, box_.y + box_.height - 1}, cv::Scalar(225, 225, 225));
      cv::line(img, p, {p.x, p.y + 4}, ink);
      const std::string s = tick_text(x);
      text(img, s, {p.x - text_width(s) / 2, p.y + 16});
    }
    for (double y : nice_ticks(y0_, y1_, std::max(3, box_.height / 35))) {
      const cv::Point p = at(x0_, y);
      if (grid) cv::line(img, {box_.x, p.y}, {box_.x + box_.width - 1, p.y}, cv::Scalar(225, 225, 225));
      cv::line(img, {p.x - 4, p.y}, p, ink);
      const std::string s = tick_text(y);
      text(img, s, {p.x - 7 - text_width(s), p.y + 4});
    }
    cv::rectangle(img, box_, ink, 1);
    text(img, xlabel, {box_.x + (box_.width - text_width(xlabel)) / 2, box_.y + box_.height + 32});
    // the y label above the axis (OpenCV draws no rotated text)
    text(img, ylabel, {std::max(2, box_.x - 40), box_.y - 8});
  }

  /// A polyline of (x, y) samples, clipped to the box.
  void line(cv::Mat& img, const std::vector<double>& xs, const std::vector<double>& ys, const cv::Scalar& colour,
            int thickness = 1) const {
    std::vector<cv::Point> points;
    for (std::size_t i = 0; i < xs.size() && i < ys.size(); ++i)
      points.push_back(at(xs[i], std::clamp(ys[i], y0_, y1_)));
    cv::Mat area = img(box_);
    for (cv::Point& p : points)
      p -= box_.tl();
    cv::polylines(area, points, false, colour, thickness, cv::LINE_AA);
  }

 private:
  cv::Rect box_;
  double x0_, x1_, y0_, y1_;
  bool y_down_;
};

/// A vertical colour bar in `box`: value lo at the bottom, hi at the top,
/// each row coloured by colour_of(value); numbered ticks on its right and
/// `label` (with units) above it.
inline void colour_bar(cv::Mat& img, cv::Rect box, double lo, double hi,
                       const std::function<cv::Vec3b(double)>& colour_of, const std::string& label) {
  for (int r = 0; r < box.height; ++r) {
    const double v = hi - (hi - lo) * r / std::max(1, box.height - 1);
    img(cv::Rect(box.x, box.y + r, box.width, 1)).setTo(cv::Scalar(colour_of(v)));
  }
  cv::rectangle(img, box, ink, 1);
  for (double v : nice_ticks(lo, hi, std::max(2, box.height / 40))) {
    const int y = box.y + static_cast<int>(std::lround((hi - v) / (hi - lo) * (box.height - 1)));
    cv::line(img, {box.x + box.width, y}, {box.x + box.width + 4, y}, ink);
    text(img, tick_text(v), {box.x + box.width + 7, y + 4});
  }
  text(img, label, {box.x, box.y - 8});
}

/// A legend: one coloured sample line and its text per entry, from `at`
/// (top left) downward.
inline void legend(cv::Mat& img, cv::Point at, const std::vector<std::pair<cv::Scalar, std::string>>& entries) {
  int width = 0;
  for (const auto& [colour, label] : entries)
    width = std::max(width, text_width(label));
  const cv::Rect frame(at.x, at.y, width + 40, 18 * static_cast<int>(entries.size()) + 6);
  cv::rectangle(img, frame, cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(img, frame, cv::Scalar(190, 190, 190), 1);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const int y = at.y + 13 + 18 * static_cast<int>(i);
    cv::line(img, {at.x + 6, y - 4}, {at.x + 28, y - 4}, entries[i].first, 2, cv::LINE_AA);
    text(img, entries[i].second, {at.x + 34, y});
  }
}

}  // namespace hapticfield::plots
