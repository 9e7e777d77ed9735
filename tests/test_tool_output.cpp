// What the tools write for a reader: pictures that say what they show (axes,
// units, colour bars, legends, a stated scale), drawn by matplotlib when it is
// present and by the tools themselves otherwise; progress lines that redraw
// themselves with '\r' only on a terminal; file lists without repeats.
// The tools run as child processes.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "child_process.hpp"
#include "pty_pair.hpp"

namespace {

namespace fs = std::filesystem;
using hapticfield::testing::Child;
using hapticfield::testing::slurp;

const fs::path tmp = fs::path(HAPTICFIELD_TEST_TMP) / "tool_output";

/// Runs a tool to its end (bounded) with stdout and stderr to files.
struct Finished {
  int status{-1};
  std::string out, err;
};
Finished finish(const std::string& tool, const std::vector<std::string>& args, const std::string& name) {
  Child child(tool, args, tmp, name, false);
  REQUIRE(child.wait(std::chrono::seconds(240)));
  return {child.status(), child.out(), child.err()};
}

/// The plot script is made unreachable for the scope: the tools draw their
/// own plots (the fallback).
struct NoPlotScript {
  NoPlotScript() { ::setenv("HAPTICFIELD_PLOT_SCRIPT", (tmp / "no_such_script.py").c_str(), 1); }
  ~NoPlotScript() { ::unsetenv("HAPTICFIELD_PLOT_SCRIPT"); }
  NoPlotScript(const NoPlotScript&) = delete;
  NoPlotScript& operator=(const NoPlotScript&) = delete;
};

/// True when a python3 the tools would use imports matplotlib.
bool matplotlib_present() {
  static const bool present = [] {
    for (const char* python : {"python3", "/usr/bin/python3"}) {
      const std::string command =
          std::string(python) + " " + HAPTICFIELD_SOURCE_DIR "/scripts/hapticfield_plots.py --check >/dev/null 2>&1";
      if (std::system(command.c_str()) == 0) return true;
    }
    return false;
  }();
  return present;
}

std::string step_picture() {
  fs::create_directories(tmp);
  cv::Mat step(40, 60, CV_8UC3, cv::Scalar::all(255));
  step(cv::Rect(30, 0, 30, 40)).setTo(cv::Scalar::all(0));  // black from column 30: |F| = 1 at the edge
  const std::string p = (tmp / "step.png").string();
  REQUIRE(cv::imwrite(p, step));
  return p;
}

/// A colour bar: in some column, a run of at least `length` rows from the
/// `top` colour to the `bottom` colour (each within 40 per channel) whose
/// neighbouring rows differ by less than 24 per channel (a smooth ramp, not
/// text or a border).
bool has_colour_bar(const cv::Mat& img, cv::Vec3b top, cv::Vec3b bottom, int length) {
  const auto near = [](cv::Vec3b a, cv::Vec3b b, int tolerance) {
    return std::abs(a[0] - b[0]) < tolerance && std::abs(a[1] - b[1]) < tolerance && std::abs(a[2] - b[2]) < tolerance;
  };
  for (int x = 0; x < img.cols; ++x)
    for (int y = 0; y + length < img.rows; ++y) {
      if (!near(img.at<cv::Vec3b>(y, x), top, 40)) continue;
      for (int end = y + 1; end < img.rows && near(img.at<cv::Vec3b>(end, x), img.at<cv::Vec3b>(end - 1, x), 24); ++end)
        if (end - y >= length && near(img.at<cv::Vec3b>(end, x), bottom, 40)) return true;
    }
  return false;
}

/// The largest red value in a BGR picture.
int max_red(const cv::Mat& img) {
  std::vector<cv::Mat> channels;
  cv::split(img, channels);
  double lo = 0, hi = 0;
  cv::minMaxLoc(channels[2], &lo, &hi);
  return static_cast<int>(hi);
}

}  // namespace

TEST_CASE("tangible_image --maps: maps.png with colour bars, maps.txt with the scale, --full-scale fixes it") {
  const std::string picture = step_picture();
  SECTION("own scale: the map's largest magnitude, stated") {
    const NoPlotScript fallback;
    const std::string dir = (tmp / "maps_own").string();
    const Finished r = finish(HAPTICFIELD_TOOL_TANGIBLE_IMAGE, {picture, "--size", "3", "--maps", dir}, "maps_own");
    CAPTURE(r.out, r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("colour scale: full colour = 1 (this map's largest magnitude") != std::string::npos);
    CHECK(r.out.find("maps.png (simple plots: the plot script") != std::string::npos);
    const std::string caption = slurp(fs::path(dir) / "maps.txt");
    CHECK(caption.find("full scale: 1 (this map's largest magnitude; --full-scale fixes it)") != std::string::npos);
    CHECK(caption.find("maps.png: fx, fy and |F| with axes [px] and colour bars (simple plots") != std::string::npos);
    const cv::Mat figure = cv::imread(dir + "/maps.png", cv::IMREAD_COLOR);
    REQUIRE(!figure.empty());
    // fx and fy: full red (+scale) at the top to full blue (-scale) at the bottom; |F|: white to black
    CHECK(has_colour_bar(figure, {0, 0, 255}, {255, 0, 0}, 150));
    CHECK(has_colour_bar(figure, {255, 255, 255}, {0, 0, 0}, 150));
    // the edge's force, 1, is full colour in fx.png
    CHECK(max_red(cv::imread(dir + "/fx.png", cv::IMREAD_COLOR)) == 255);
  }
  SECTION("--full-scale 2: the edge's force 1 is half colour, and the scale is stated as fixed") {
    const NoPlotScript fallback;
    const std::string dir = (tmp / "maps_fixed").string();
    const Finished r = finish(HAPTICFIELD_TOOL_TANGIBLE_IMAGE,
                              {picture, "--size", "3", "--maps", dir, "--full-scale", "2"}, "maps_fixed");
    CAPTURE(r.out, r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("colour scale: full colour = 2 (fixed by --full-scale)") != std::string::npos);
    CHECK(slurp(fs::path(dir) / "maps.txt").find("full scale: 2 (fixed by --full-scale)") != std::string::npos);
    CHECK(max_red(cv::imread(dir + "/fx.png", cv::IMREAD_COLOR)) == 128);  // 1 / 2 of 255, rounded
    CHECK(max_red(cv::imread(dir + "/magnitude.png", cv::IMREAD_COLOR)) == 128);
  }
  SECTION("--full-scale without --maps is a usage error") {
    const Finished r = finish(HAPTICFIELD_TOOL_TANGIBLE_IMAGE, {picture, "--full-scale", "2"}, "maps_usage");
    CHECK(r.status == 2);
    CHECK(r.err == "tangible_image: --full-scale needs --maps (--help shows the usage)\n");
  }
  SECTION("with matplotlib: maps.png drawn by it, and said so") {
    if (!matplotlib_present()) {
      WARN("no python3 with matplotlib: the matplotlib path is not checked");
      return;
    }
    const std::string dir = (tmp / "maps_matplotlib").string();
    const Finished r = finish(HAPTICFIELD_TOOL_TANGIBLE_IMAGE, {picture, "--size", "3", "--maps", dir}, "maps_mpl");
    CAPTURE(r.out, r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("maps.png (drawn with matplotlib)") != std::string::npos);
    const cv::Mat figure = cv::imread(dir + "/maps.png", cv::IMREAD_COLOR);
    REQUIRE(!figure.empty());
    CHECK(figure.cols > 1000);
  }
}

TEST_CASE("texture_gallery lists each file it wrote once, with and without matplotlib") {
  for (const bool fallback : {true, false}) {
    if (!fallback && !matplotlib_present()) {
      WARN("no python3 with matplotlib: the matplotlib path is not checked");
      continue;
    }
    CAPTURE(fallback);
    const std::string dir = (tmp / (fallback ? "gallery_simple" : "gallery_matplotlib")).string();
    fs::remove_all(dir);
    Finished r;
    if (fallback) {
      const NoPlotScript no_script;
      r = finish(HAPTICFIELD_TOOL_TEXTURE_GALLERY, {"--out", dir}, "gallery_simple");
    } else {
      r = finish(HAPTICFIELD_TOOL_TEXTURE_GALLERY, {"--out", dir}, "gallery_matplotlib");
    }
    CAPTURE(r.out, r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find(fallback ? "(simple plots: " : "(drawn with matplotlib)") != std::string::npos);
    std::istringstream lines(r.out);
    std::string line;
    std::multiset<std::string> listed;
    while (std::getline(lines, line)) {
      const auto png = line.find(".png");
      if (line.rfind("  ", 0) == 0 && png != std::string::npos) listed.insert(line.substr(2, png + 2));
    }
    std::set<std::string> written;
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.path().extension() == ".png") written.insert(entry.path().filename().string());
    CHECK(written.size() > 10);
    CHECK(std::set<std::string>(listed.begin(), listed.end()) == written);
    CHECK(listed.size() == written.size());  // none twice
  }
}

TEST_CASE("false_texture: the legend as regions.csv, the strokes drawn with axes when matplotlib is present") {
  const std::string picture = step_picture();
  const std::string dir = (tmp / "false_texture").string();
  fs::remove_all(dir);
  const NoPlotScript fallback;
  const Finished r = finish(HAPTICFIELD_TOOL_FALSE_TEXTURE, {picture, "--levels", "3", "--out", dir}, "ft_simple");
  CAPTURE(r.out, r.err);
  REQUIRE(r.status == 0);
  CHECK(slurp(fs::path(dir) / "regions.csv") ==
        "region,gray_lo,gray_hi,name,colour\n0,0,84,Gaussian lattice 2.00 mm,#dc2828\n"
        "1,85,169,square grating 1.25 mm,#28b428\n2,170,255,smooth,#1e78dc\n");
  CHECK(r.out.find("no strokes.png (the plot script") != std::string::npos);
  CHECK_FALSE(fs::exists(fs::path(dir) / "strokes.png"));
  const cv::Mat figure = cv::imread(dir + "/false_texture.png", cv::IMREAD_COLOR);
  REQUIRE(!figure.empty());
  CHECK(figure.rows > 40 + 250);  // picture, legend and the plot with its axes
}

TEST_CASE("false_texture with matplotlib: strokes.png") {
  if (!matplotlib_present()) {
    WARN("no python3 with matplotlib: the matplotlib path is not checked");
    return;
  }
  const std::string picture = step_picture();
  const std::string dir = (tmp / "false_texture_mpl").string();
  fs::remove_all(dir);
  const Finished r = finish(HAPTICFIELD_TOOL_FALSE_TEXTURE, {picture, "--out", dir}, "ft_mpl");
  CAPTURE(r.out, r.err);
  REQUIRE(r.status == 0);
  CHECK(r.out.find("strokes.png (drawn with matplotlib)") != std::string::npos);
  CHECK(fs::file_size(fs::path(dir) / "strokes.png") > 10000);
}

#ifdef HAPTICFIELD_TOOL_TANGIBLE_VIDEO
namespace {

/// A 16-frame image sequence at 25 frames/s with one scene cut at frame 8:
/// a dark bar moving right on a light ground, then a light disc on black.
std::string cut_clip() {
  const fs::path dir = tmp / "cut_clip";
  fs::create_directories(dir);
  for (int k = 0; k < 16; ++k) {
    cv::Mat frame(64, 96, CV_8UC1, cv::Scalar(k < 8 ? 230 : 20));
    if (k < 8)
      frame(cv::Rect(20 + 2 * k, 10, 12, 44)).setTo(30);
    else
      cv::circle(frame, {48, 32}, 18, cv::Scalar(220), cv::FILLED);
    char name[16];
    std::snprintf(name, sizeof name, "%04d.png", k);
    REQUIRE(cv::imwrite((dir / name).string(), frame));
  }
  return (dir / "%04d.png").string();
}

/// Runs a tool with stdout and stderr on a terminal (the slave of a pty,
/// output processing off so that '\n' stays '\n'); returns what it wrote.
std::string run_on_terminal(const std::vector<std::string>& args) {
  hapticfield::testing::Pty pty;
  termios mode{};
  REQUIRE(::tcgetattr(pty.slave, &mode) == 0);
  mode.c_oflag &= ~static_cast<tcflag_t>(OPOST);  // no '\n' -> "\r\n"
  REQUIRE(::tcsetattr(pty.slave, TCSANOW, &mode) == 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, pty.slave, STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, pty.slave, STDERR_FILENO);
  const pid_t pid = hapticfield::testing::spawn_tool(HAPTICFIELD_TOOL_TANGIBLE_VIDEO, args, actions);
  std::string out;
  const auto read_available = [&] {
    char buf[4096];
    for (ssize_t n; (n = ::read(pty.master, buf, sizeof buf)) > 0;)
      out.append(buf, static_cast<std::size_t>(n));
  };
  int raw = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(240);
  while (::waitpid(pid, &raw, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > give_up) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &raw, 0);
      FAIL("tangible_video on a terminal did not end");
    }
    pollfd p{pty.master, POLLIN, 0};
    if (::poll(&p, 1, 20) > 0) read_available();
  }
  read_available();
  CHECK((WIFEXITED(raw) && WEXITSTATUS(raw) == 0));
  return out;
}

}  // namespace

TEST_CASE("tangible_video's status line: redrawn with '\\r' on a terminal, whole lines into a pipe or file") {
  const std::string clip = cut_clip();
  const std::vector<std::string> args = {clip, "--clock", "virtual", "--seconds", "0.5"};
  const Finished piped = finish(HAPTICFIELD_TOOL_TANGIBLE_VIDEO, args, "video_file");
  CAPTURE(piped.out, piped.err);
  REQUIRE(piped.status == 0);
  CHECK(piped.out.find('\r') == std::string::npos);
  CHECK(piped.out.find("\n video ") != std::string::npos);  // the last status, a line of its own
  const std::string terminal = run_on_terminal(args);
  CAPTURE(terminal);
  CHECK(terminal.find("\r video ") != std::string::npos);
}

TEST_CASE("tangible_video --plots: says what it plots and draws the cuts it found") {
  const std::string clip = cut_clip();
  SECTION("play mode, the simple plot") {
    const NoPlotScript fallback;
    const std::string dir = (tmp / "video_play").string();
    fs::remove_all(dir);
    const Finished r = finish(HAPTICFIELD_TOOL_TANGIBLE_VIDEO,
                              {clip, "--clock", "virtual", "--seconds", "0.6", "--plots", dir}, "video_play");
    CAPTURE(r.out, r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("1 cuts: 8 (0.320 s)") != std::string::npos);
    CHECK(r.out.find("force.png (simple plots: the plot script") != std::string::npos);
    CHECK(slurp(fs::path(dir) / "cuts.csv") == "frame,time\n8,0.32\n");
    CHECK(slurp(fs::path(dir) / "force.csv").rfind("t_s,fx,fy\n", 0) == 0);
    const cv::Mat plot = cv::imread(dir + "/force.png", cv::IMREAD_COLOR);
    REQUIRE(!plot.empty());
    // the cut: a vertical orange line across the plot area
    cv::Mat orange;
    cv::inRange(plot, cv::Scalar(0, 140, 255), cv::Scalar(0, 140, 255), orange);
    int tallest = 0;
    for (int x = 0; x < orange.cols; ++x)
      tallest = std::max(tallest, cv::countNonZero(orange.col(x)));
    CHECK(tallest > 250);
  }
  SECTION("play mode with matplotlib") {
    if (!matplotlib_present()) {
      WARN("no python3 with matplotlib: the matplotlib path is not checked");
      return;
    }
    const std::string dir = (tmp / "video_play_mpl").string();
    fs::remove_all(dir);
    const Finished r = finish(HAPTICFIELD_TOOL_TANGIBLE_VIDEO,
                              {clip, "--clock", "virtual", "--seconds", "0.6", "--plots", dir}, "video_play_mpl");
    CAPTURE(r.out, r.err);
    REQUIRE(r.status == 0);
    CHECK(r.out.find("force.png (drawn with matplotlib)") != std::string::npos);
    CHECK(fs::file_size(fs::path(dir) / "force.png") > 10000);
  }
}
#endif
