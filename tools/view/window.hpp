#pragma once
/// @file window.hpp
/// The viewer's window and its mouse wheel. OpenCV's Qt backend zooms its
/// default view on every wheel notch (1.1 times a notch, up to 100 times)
/// besides passing the event to the mouse callback, and no window flag stops
/// it; its OpenGL view leaves the wheel to the program. So under Qt the
/// viewer asks for an OpenGL view when OpenCV has one, and the wheel only
/// moves the probe (wheel_notches). GTK and the other backends do not zoom.
/// Pure functions (window_flags, wheel_notches) and the window's opening
/// and drawing with a fallback to the plain view (ViewWindow).

#include <cstdio>
#include <sstream>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>
#include <opencv2/highgui.hpp>

namespace hapticfield::view {

/// Whether OpenCV's build information (cv::getBuildInformation()) says its
/// GUI is Qt with OpenGL: the line "QT OpenGL support:" reads YES.
[[nodiscard]] inline bool qt_with_opengl(std::string_view build_information) {
  std::istringstream lines{std::string(build_information)};
  for (std::string line; std::getline(lines, line);) {
    const std::size_t at = line.find("QT OpenGL support:");
    if (at == std::string::npos) continue;
    const std::size_t value = line.find_first_not_of(' ', at + 18);
    return value != std::string::npos && line.compare(value, 3, "YES") == 0;
  }
  return false;
}

/// The flags of the viewer's window: its size fixed by the canvas, no
/// toolbar, and under Qt with OpenGL an OpenGL view (whose wheel does not
/// zoom).
[[nodiscard]] inline int window_flags(std::string_view build_information) {
  const int flags = cv::WINDOW_AUTOSIZE | cv::WINDOW_GUI_NORMAL;
  return qt_with_opengl(build_information) ? flags | cv::WINDOW_OPENGL : flags;
}

/// The wheel notches of one mouse event, positive away from the user (the
/// wheel rolled forward): the vertical wheel's delta over 120, so a
/// fine-grained wheel or a touchpad gives fractions of a notch. 0 for any
/// other event, the horizontal wheel included. `flags` as OpenCV passes them
/// to a mouse callback (the delta in their upper 16 bits, as
/// cv::getMouseWheelDelta reads it).
[[nodiscard]] inline double wheel_notches(int event, int flags) noexcept {
  if (event != cv::EVENT_MOUSEWHEEL) return 0.0;
  const auto delta = static_cast<short>((static_cast<unsigned>(flags) >> 16) & 0xffffu);
  return delta / 120.0;
}

/// The viewer's window: opened with window_flags(); if OpenCV cannot make
/// or draw its OpenGL view (no OpenGL at run time), it is opened again as a
/// plain view (whose wheel Qt also zooms) and says so on stderr once.
class ViewWindow {
 public:
  ViewWindow(const char* title, cv::MouseCallback on_mouse, void* user)
      : title_(title), on_mouse_(on_mouse), user_(user), flags_(window_flags(cv::getBuildInformation())) {
    open();
  }
  ViewWindow(const ViewWindow&) = delete;
  ViewWindow& operator=(const ViewWindow&) = delete;

  /// Draws `canvas` in the window.
  void show(const cv::Mat& canvas) {
    try {
      cv::imshow(title_, canvas);
    } catch (const cv::Exception& e) {
      if (!(flags_ & cv::WINDOW_OPENGL)) throw;
      plain(e);
      cv::imshow(title_, canvas);
    }
  }
  /// Whether the window is an OpenGL view.
  [[nodiscard]] bool opengl() const noexcept { return (flags_ & cv::WINDOW_OPENGL) != 0; }

 private:
  void open() {
    try {
      cv::namedWindow(title_, flags_);
    } catch (const cv::Exception& e) {
      if (!(flags_ & cv::WINDOW_OPENGL)) throw;
      plain(e);
      return;
    }
    cv::setMouseCallback(title_, on_mouse_, user_);
  }
  void plain(const cv::Exception& e) {
    std::fprintf(stderr, "hapticfield_view: no OpenGL view (%s); the plain window's wheel also zooms it\n",
                 e.err.c_str());
    try {
      cv::destroyWindow(title_);
    } catch (const cv::Exception&) {  // it was never made
    }
    flags_ &= ~cv::WINDOW_OPENGL;
    cv::namedWindow(title_, flags_);
    cv::setMouseCallback(title_, on_mouse_, user_);
  }

  const char* title_;
  cv::MouseCallback on_mouse_;
  void* user_;
  int flags_;
};

}  // namespace hapticfield::view
