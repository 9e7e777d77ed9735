#pragma once
/// @file video_source.hpp
/// VideoSource: frames from a video file (anything cv::VideoCapture opens),
/// a camera (by index) or an image sequence (a printf pattern such as
/// "frames/%04d.png"), with their timestamps.
///
/// A file's frame k has timestamp k / fps. A damaged stream plays what it
/// can decode: a frame that fails to decode is skipped (counted), and the
/// stream ends after `max_bad_frames` failures in a row. Camera frames are
/// stamped by the caller (they are live).

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "hapticfield/core/error.hpp"

namespace hapticfield {

/// A video that cannot be opened or decoded (a FileError naming it).
class VideoError : public FileError {
 public:
  using FileError::FileError;
};

struct VideoSourceConfig {
  double fallback_fps = 25.0;  ///< when the container gives no usable rate [frames/s]
  int max_bad_frames = 25;     ///< decode failures in a row that end the stream
  bool verbose = false;        ///< let FFmpeg's own log lines through (see quiet_video_logs())
};

/// Mutes OpenCV's and FFmpeg's own log lines (call before opening a video);
/// errors still come back as exceptions and counters.
inline void quiet_video_logs(bool verbose) {
  if (!verbose) {
    ::setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0);  // AV_LOG_QUIET
    ::setenv("OPENCV_LOG_LEVEL", "SILENT", 0);
  } else {
    ::setenv("OPENCV_FFMPEG_LOGLEVEL", "32", 0);  // AV_LOG_INFO
  }
}

class VideoSource {
 public:
  /// A file or an image sequence (a name containing '%').
  /// @throws FileError for a missing or unreadable file; VideoError when no
  ///         backend can open it or its first frame does not decode.
  explicit VideoSource(const std::string& path, const VideoSourceConfig& config = {}) : config_(config), name_(path) {
    const bool sequence = path.find('%') != std::string::npos;
    if (!sequence) (void)check_file(path, std::uintmax_t{1} << 40);
    // Named backends only: cv::CAP_ANY would also probe camera backends
    // (gphoto2 over libusb) for a file that FFmpeg refuses.
    bool opened = false;
    const std::vector<int> apis = sequence ? std::vector<int>{cv::CAP_FFMPEG, cv::CAP_IMAGES}
                                           : std::vector<int>{cv::CAP_FFMPEG, cv::CAP_OPENCV_MJPEG};
    for (const int api : apis) {
      try {
        opened = capture_.open(path, api) && capture_.isOpened();
      } catch (const cv::Exception&) {
        opened = false;
      }
      if (opened) break;
    }
    if (!opened) throw VideoError("cannot decode '" + path + "': not a video that this build can open");
    init();
  }

  /// A camera by index (live).
  /// @throws VideoError when the camera does not open or gives no frame.
  VideoSource(int camera, const VideoSourceConfig& config = {})
      : config_(config), name_("camera " + std::to_string(camera)), live_(true) {
    if (camera < 0 || !capture_.open(camera, cv::CAP_V4L2) || !capture_.isOpened())
      throw VideoError("cannot open " + name_);
    init();
  }

  /// Reads the next frame into `frame` and its index. False at the end of
  /// the stream. Skips frames that fail to decode (see bad_frames()).
  bool read(cv::Mat& frame, long& index) {
    if (pending_) {
      pending_ = false;
      frame = first_.clone();
      index = next_index_++;
      return true;
    }
    for (int fails = 0; fails < config_.max_bad_frames; ++fails) {
      if (frame_count_ > 0 && next_index_ >= frame_count_ && !live_) return false;
      bool ok = false;
      try {
        ok = capture_.read(frame) && !frame.empty();
      } catch (const cv::Exception&) {
        ok = false;
      }
      const long i = next_index_++;
      if (ok) {
        index = i;
        return true;
      }
      ++bad_frames_;
      if (frame_count_ <= 0) return false;  // no count: a failure is the end
    }
    return false;
  }

  /// Skips the next frame without decoding it fully (a dropped frame).
  bool skip() {
    if (pending_) {
      pending_ = false;
      ++next_index_;
      return true;
    }
    if (frame_count_ > 0 && next_index_ >= frame_count_ && !live_) return false;
    bool ok = false;
    try {
      ok = capture_.grab();
    } catch (const cv::Exception&) {
      ok = false;
    }
    ++next_index_;
    return ok || (frame_count_ > 0 && next_index_ < frame_count_);
  }

  /// Goes to frame `index` (files only): the next read() returns it.
  void seek(long index) {
    if (live_) return;
    index = std::max(0L, index);
    pending_ = false;
    capture_.set(cv::CAP_PROP_POS_FRAMES, static_cast<double>(index));
    next_index_ = index;
  }

  [[nodiscard]] double fps() const noexcept { return fps_; }
  /// Timestamp of frame `index` [s].
  [[nodiscard]] double time_of(long index) const noexcept { return static_cast<double>(index) / fps_; }
  /// Frames in the file as the container says (0 when unknown).
  [[nodiscard]] long frame_count() const noexcept { return frame_count_; }
  /// Length of the file [s] (infinity when unknown or live).
  [[nodiscard]] double duration() const noexcept {
    return frame_count_ > 0 && !live_ ? static_cast<double>(frame_count_) / fps_ : HUGE_VAL;
  }
  [[nodiscard]] int width() const noexcept { return first_.cols; }
  [[nodiscard]] int height() const noexcept { return first_.rows; }
  [[nodiscard]] bool live() const noexcept { return live_; }
  [[nodiscard]] long bad_frames() const noexcept { return bad_frames_; }
  [[nodiscard]] const std::string& name() const noexcept { return name_; }

 private:
  void init() {
    const double fps = capture_.get(cv::CAP_PROP_FPS);
    fps_ = std::isfinite(fps) && fps >= 1.0 && fps <= 1000.0 ? fps : config_.fallback_fps;
    const double count = capture_.get(cv::CAP_PROP_FRAME_COUNT);
    frame_count_ = std::isfinite(count) && count > 0 && count < 1e9 ? static_cast<long>(count) : 0;
    long index = 0;
    bool ok = false;
    try {
      for (int i = 0; i < config_.max_bad_frames && !ok; ++i)
        ok = capture_.read(first_) && !first_.empty();
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok) throw VideoError("cannot decode '" + name_ + "': no frame decodes");
    (void)index;
    pending_ = true;
    next_index_ = 0;
  }

  VideoSourceConfig config_;
  std::string name_;
  bool live_ = false;
  cv::VideoCapture capture_;
  cv::Mat first_;
  bool pending_ = false;
  double fps_ = 25.0;
  long frame_count_ = 0;
  long next_index_ = 0;
  long bad_frames_ = 0;
};

}  // namespace hapticfield
