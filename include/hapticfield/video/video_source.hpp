#pragma once
/// @file video_source.hpp
/// VideoSource: frames from a video file (anything cv::VideoCapture opens),
/// a camera (by index) or an image sequence (a printf pattern such as
/// "frames/%04d.png"), with their timestamps.
///
/// A file's frame k has timestamp k / fps. A damaged stream plays what it
/// can decode: a frame that fails to decode is skipped (counted), and the
/// stream ends after `max_bad_frames` failures in a row; failures at the very
/// end of a file are its end, not undecodable frames (a variable-rate file's
/// frame count is an estimate). Camera frames are stamped by the caller
/// (they are live).
///
/// An image sequence is read here, file by file (SequencePattern): its
/// frames are the files the pattern names in their folder, from the
/// smallest number to the largest; frame k (k = number - smallest) has
/// timestamp k / fps, fps = VideoSourceConfig::fallback_fps (25 by
/// default). A missing, truncated or undecodable file, or a picture of
/// another size than the first, is skipped and counted (bad_frames()), and
/// keeps its time slot.
///
/// No frame larger than VideoSourceConfig::max_pixels is decoded: a file's
/// size as its container reports it is checked when it opens, a sequence's
/// files by their headers (read_picture_size()) before decoding.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/image/load.hpp"
#include "hapticfield/image/picture_size.hpp"
#include "hapticfield/video/sequence_pattern.hpp"

namespace hapticfield {

/// A video that cannot be opened or decoded (a FileError naming it).
class VideoError : public FileError {
 public:
  using FileError::FileError;
};

struct VideoSourceConfig {
  double fallback_fps = 25.0;  ///< an image sequence's rate, and a file's when its container gives none [frames/s]
  int max_bad_frames = 25;     ///< decode failures in a row that end the stream
  bool verbose = false;        ///< let FFmpeg's own log lines through (see quiet_video_logs())
  std::uint64_t max_pixels = default_max_pixels;  ///< largest frame (width x height) decoded [px]
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
  /// @throws FileError for a missing or unreadable file; SequencePatternError
  ///         for a bad sequence pattern; VideoError when no backend can open
  ///         it, its frames are larger than config.max_pixels, or no frame
  ///         decodes among the first max_bad_frames.
  explicit VideoSource(const std::string& path, const VideoSourceConfig& config = {}) : config_(config), name_(path) {
    if (!(config.fallback_fps >= 1e-3 && config.fallback_fps <= 1000.0))
      throw std::invalid_argument("VideoSource: fallback_fps must be in [0.001, 1000] frames/s");
    if (config.max_bad_frames < 1) throw std::invalid_argument("VideoSource: max_bad_frames must be at least 1");
    if (path.find('%') != std::string::npos) {
      open_sequence();
      return;
    }
    (void)check_file(path, std::uintmax_t{1} << 40);
    // Named backends only: cv::CAP_ANY would also probe camera backends
    // (gphoto2 over libusb) for a file that FFmpeg refuses.
    bool opened = false;
    for (const int api : {cv::CAP_FFMPEG, cv::CAP_OPENCV_MJPEG}) {
      try {
        opened = capture_.open(path, api) && capture_.isOpened();
      } catch (const cv::Exception&) {
        opened = false;
      }
      if (opened) break;
    }
    if (!opened) throw VideoError("cannot decode '" + path + "': not a video that this build can open");
    init_capture();
  }

  /// A camera by index (live).
  /// @throws VideoError when the camera does not open or gives no frame.
  VideoSource(int camera, const VideoSourceConfig& config = {})
      : config_(config), name_("camera " + std::to_string(camera)), live_(true) {
    if (camera < 0 || !capture_.open(camera, cv::CAP_V4L2) || !capture_.isOpened())
      throw VideoError("cannot open " + name_);
    init_capture();
  }

  /// Reads the next frame into `frame` and its index. False at the end of
  /// the stream. Skips frames that fail to decode (see bad_frames()).
  bool read(cv::Mat& frame, long& index) {
    if (pending_) {
      pending_ = false;
      frame = first_.clone();
      index = first_index_;
      next_index_ = first_index_ + 1;
      return true;
    }
    long trailing = 0;  // failures not yet known to be before a good frame
    for (int fails = 0; fails < config_.max_bad_frames; ++fails) {
      if (frame_count_ > 0 && next_index_ >= frame_count_ && !live_) break;
      const long i = next_index_++;
      if (sequence_ ? read_file(i, frame) : read_capture(frame)) {
        index = i;
        bad_frames_ += trailing;
        if (!sequence_ && !live_) check_time(i);
        return true;
      }
      if (sequence_)
        ++bad_frames_;  // the last file exists: a failure before it is a bad frame
      else
        ++trailing;
      if (!sequence_ && frame_count_ <= 0) break;  // no count: a failure is the end
    }
    return false;
  }

  /// Skips the next frame without decoding it fully (a dropped frame).
  bool skip() {
    if (pending_) {
      pending_ = false;
      next_index_ = first_index_ + 1;
      return true;
    }
    if (frame_count_ > 0 && next_index_ >= frame_count_ && !live_) return false;
    if (sequence_) return ++next_index_ <= frame_count_;
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
    if (!sequence_) capture_.set(cv::CAP_PROP_POS_FRAMES, static_cast<double>(index));
    next_index_ = index;
    timed_ = false;  // a seek may land near, not on, the frame asked for
  }

  [[nodiscard]] double fps() const noexcept { return fps_; }
  /// Timestamp of frame `index` [s].
  [[nodiscard]] double time_of(long index) const noexcept { return static_cast<double>(index) / fps_; }
  /// Frames in the file as the container says, or in the sequence (0 when unknown).
  [[nodiscard]] long frame_count() const noexcept { return frame_count_; }
  /// Length of the file [s] (infinity when unknown or live).
  [[nodiscard]] double duration() const noexcept {
    return frame_count_ > 0 && !live_ ? static_cast<double>(frame_count_) / fps_ : HUGE_VAL;
  }
  [[nodiscard]] int width() const noexcept { return first_.cols; }
  [[nodiscard]] int height() const noexcept { return first_.rows; }
  [[nodiscard]] bool live() const noexcept { return live_; }
  [[nodiscard]] bool sequence() const noexcept { return sequence_.has_value(); }
  [[nodiscard]] long bad_frames() const noexcept { return bad_frames_; }
  /// True once a decoded frame's timestamp in the file was off its slot k /
  /// fps by more than half a period: the file has a variable frame rate,
  /// and this source's frame times (k / fps) are only an approximation.
  [[nodiscard]] bool variable_rate() const noexcept { return variable_rate_; }
  [[nodiscard]] const std::string& name() const noexcept { return name_; }

 private:
  [[nodiscard]] std::string too_large(std::uint64_t w, std::uint64_t h) const {
    return "cannot decode '" + name_ + "': its frames are " + std::to_string(w) + " x " + std::to_string(h) + " px (" +
           std::to_string(w * h) + " px), larger than the limit of " + std::to_string(config_.max_pixels) +
           " px (raise max_pixels to allow it)";
  }

  /// Reads the first frame that decodes, counting the failures before it
  /// (their time slots kept): it is the reference size, held for read().
  void read_first() {
    bool ok = false;
    for (int i = 0; i < config_.max_bad_frames && !ok; ++i) {
      if (frame_count_ > 0 && next_index_ >= frame_count_ && !live_) break;
      const long index = next_index_++;
      ok = sequence_ ? read_file(index, first_) : read_capture(first_);
      if (ok)
        first_index_ = index;
      else
        ++bad_frames_;
    }
    if (!ok) throw VideoError("cannot decode '" + name_ + "': no frame decodes");
    if (std::uint64_t(first_.cols) * std::uint64_t(first_.rows) > config_.max_pixels)
      throw VideoError(too_large(std::uint64_t(first_.cols), std::uint64_t(first_.rows)));
    if (!sequence_ && !live_) check_time(first_index_);
    pending_ = true;
  }

  void init_capture() {
    const double fps = capture_.get(cv::CAP_PROP_FPS);
    fps_ = std::isfinite(fps) && fps >= 1.0 && fps <= 1000.0 ? fps : config_.fallback_fps;
    const double count = capture_.get(cv::CAP_PROP_FRAME_COUNT);
    frame_count_ = std::isfinite(count) && count > 0 && count < 1e9 ? static_cast<long>(count) : 0;
    // The size the container reports, before any frame is decoded.
    const double w = capture_.get(cv::CAP_PROP_FRAME_WIDTH), h = capture_.get(cv::CAP_PROP_FRAME_HEIGHT);
    if (std::isfinite(w) && std::isfinite(h) && w > 0.0 && h > 0.0 && w < 1e9 && h < 1e9) {
      const auto uw = static_cast<std::uint64_t>(w), uh = static_cast<std::uint64_t>(h);
      if (uw * uh > config_.max_pixels) throw VideoError(too_large(uw, uh));
    }
    next_index_ = 0;
    read_first();
  }

  bool read_capture(cv::Mat& frame) {
    try {
      return capture_.read(frame) && !frame.empty();
    } catch (const cv::Exception&) {
      return false;
    }
  }

  /// Compares the container's timestamp of the frame just read with its slot.
  void check_time(long index) {
    if (!timed_ || variable_rate_) return;
    double ms = 0.0;
    try {
      ms = capture_.get(cv::CAP_PROP_POS_MSEC);
    } catch (const cv::Exception&) {
      return;
    }
    if (std::isfinite(ms) && ms > 0.0 && std::abs(ms * 1e-3 - time_of(index)) > 0.5 / fps_) variable_rate_ = true;
  }

  void open_sequence() {
    sequence_.emplace(name_);
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path folder(sequence_->folder());
    if (!fs::is_directory(folder, ec))
      throw FileError("cannot open image sequence '" + name_ + "': no folder '" + sequence_->folder() + "'");
    long smallest = -1, largest = -1;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
      const std::optional<long> n = sequence_->number_of(it->path().filename().string());
      if (!n) continue;
      if (smallest < 0 || *n < smallest) smallest = *n;
      largest = std::max(largest, *n);
    }
    if (ec) throw FileError("cannot open image sequence '" + name_ + "': cannot list '" + sequence_->folder() + "'");
    if (smallest < 0) throw FileError("cannot open image sequence '" + name_ + "': no file matches the pattern");
    first_number_ = smallest;
    frame_count_ = largest - smallest + 1;
    fps_ = config_.fallback_fps;
    next_index_ = 0;
    read_first();
  }

  /// Reads sequence frame `index` into `frame`; false (a bad frame) for a
  /// missing or undecodable file or one of another size than the first.
  /// @throws VideoError for a first frame whose header is larger than max_pixels.
  bool read_file(long index, cv::Mat& frame) {
    const std::string path = sequence_->path(first_number_ + index);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return false;
    const bool have_size = !first_.empty();
    std::optional<PictureSize> declared;
    try {
      declared = read_picture_size(path);
    } catch (const FileError&) {
      return false;
    }
    if (declared) {
      if (declared->width == 0 || declared->height == 0) return false;
      if (have_size &&
          (declared->width != std::uint64_t(first_.cols) || declared->height != std::uint64_t(first_.rows)))
        return false;  // another size: not decoded
      if (!have_size && declared->pixels() > config_.max_pixels)
        throw VideoError(too_large(declared->width, declared->height) + " (the header of '" + path + "')");
    }
    try {
      frame = cv::imread(path, cv::IMREAD_COLOR);
    } catch (const cv::Exception&) {
      frame.release();
    }
    if (frame.empty()) return false;
    if (have_size && frame.size() != first_.size()) return false;
    return true;
  }

  VideoSourceConfig config_;
  std::string name_;
  bool live_ = false;
  cv::VideoCapture capture_;
  std::optional<SequencePattern> sequence_;
  long first_number_ = 0;  ///< a sequence's smallest file number (frame 0)
  cv::Mat first_;          ///< the first frame that decoded (the reference size)
  long first_index_ = 0;
  bool pending_ = false;
  double fps_ = 25.0;
  long frame_count_ = 0;
  long next_index_ = 0;
  long bad_frames_ = 0;
  bool variable_rate_ = false;
  bool timed_ = true;  ///< no seek yet: the timestamps are compared with their slots
};

}  // namespace hapticfield
