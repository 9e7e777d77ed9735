// Every command-line tool against a table of bad input: missing, empty,
// folder, truncated and mislabelled files; NaN, Inf, huge, zero, negative
// and non-numeric values for every numeric flag; unknown flags and flags
// without a value. Each case must end, within a hard time limit, in exit
// status 2 (usage) or 1 (bad input) and exactly one stderr line starting
// with the tool's name; the cases that must succeed check their result.
#include <catch2/catch.hpp>

#include "child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#ifdef HAPTICFIELD_TOOL_TANGIBLE_VIDEO
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#endif

extern char** environ;

namespace {

namespace fs = std::filesystem;

const std::map<std::string, std::string> tools = {
    {"tangible_image", HAPTICFIELD_TOOL_TANGIBLE_IMAGE},
    {"tangible_experiment", HAPTICFIELD_TOOL_TANGIBLE_EXPERIMENT},
    {"servo_demo", HAPTICFIELD_TOOL_SERVO_DEMO},
    {"servo_callback", HAPTICFIELD_TOOL_SERVO_CALLBACK},
    {"picture_normals", HAPTICFIELD_TOOL_PICTURE_NORMALS},
    {"box_demo", HAPTICFIELD_TOOL_BOX_DEMO},
    {"texture_gallery", HAPTICFIELD_TOOL_TEXTURE_GALLERY},
    {"false_texture", HAPTICFIELD_TOOL_FALSE_TEXTURE},
    {"two_arms", HAPTICFIELD_TOOL_TWO_ARMS},
#ifdef HAPTICFIELD_TOOL_HAPTICFIELD_VIEW
    {"hapticfield_view", HAPTICFIELD_TOOL_HAPTICFIELD_VIEW},
#endif
#ifdef HAPTICFIELD_TOOL_TANGIBLE_VIDEO
    {"tangible_video", HAPTICFIELD_TOOL_TANGIBLE_VIDEO},
#endif
#ifdef HAPTICFIELD_TOOL_HJIF_RENDER
    {"hjif_render", HAPTICFIELD_TOOL_HJIF_RENDER},
#endif
#ifdef HAPTICFIELD_TOOL_FEEL_MUJOCO
    {"feel_mujoco", HAPTICFIELD_TOOL_FEEL_MUJOCO},
#endif
};

constexpr int ok = 0;
constexpr int bad_input = 1;
constexpr int usage = 2;
constexpr auto time_limit = std::chrono::seconds(60);  // a hung tool is killed and fails (--plots took 11 s under load)

// one folder per process: ctest runs parts of this program side by side
const fs::path tmp = fs::path(HAPTICFIELD_TEST_TMP) / ("cli_bad_input_" + std::to_string(::getpid()));

std::string in_tmp(const std::string& name) {
  return (tmp / name).string();
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

struct Result {
  int status{-1};  // exit status, -1 when killed or signalled
  bool timed_out{false};
  std::string out;
  std::string err;
};

/// Runs a tool with posix_spawn, stdout and stderr to files, killed after
/// the time limit.
Result run(const std::string& tool, const std::vector<std::string>& args) {
  const std::string out_file = in_tmp("stdout.txt");
  const std::string err_file = in_tmp("stderr.txt");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const pid_t pid = hapticfield::testing::spawn_tool(tools.at(tool), args, actions);

  Result r;
  int raw = 0;
  const auto deadline = std::chrono::steady_clock::now() + time_limit;
  while (waitpid(pid, &raw, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &raw, 0);
      r.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (!r.timed_out && WIFEXITED(raw)) r.status = WEXITSTATUS(raw);
  r.out = slurp(out_file);
  r.err = slurp(err_file);
  return r;
}

struct Case {
  std::string tool;
  std::vector<std::string> args;
  int expect;
  std::string says{};  // a piece of the stderr line, when it matters
};

/// Checks one error case: status, one stderr line naming the tool.
void check_error(const Case& c) {
  std::string shown = c.tool;
  for (const auto& a : c.args)
    shown += " '" + a + "'";
  CAPTURE(shown);
  const Result r = run(c.tool, c.args);
  CAPTURE(r.err);
  REQUIRE_FALSE(r.timed_out);
  CHECK(r.status == c.expect);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.size() > c.tool.size() + 3);
  CHECK(r.err.rfind(c.tool + ": ", 0) == 0);
  CHECK(r.err.back() == '\n');
  CHECK(r.err.find("terminate called") == std::string::npos);
  CHECK(r.err.find("Aborted") == std::string::npos);
  if (!c.says.empty()) CHECK(r.err.find(c.says) != std::string::npos);
}

/// The bad files every file flag is tried with.
struct BadFiles {
  std::string missing, empty, folder, truncated_png, text_png, truncated_csv, garbage_csv, plain_file;
};

BadFiles make_bad_files() {
  fs::create_directories(tmp / "folder");
  BadFiles b;
  b.missing = in_tmp("missing.png");
  b.empty = in_tmp("empty.png");
  write(b.empty, "");
  b.folder = in_tmp("folder");
  b.truncated_png = in_tmp("truncated.png");
  const std::string photo = slurp(fs::path(HAPTICFIELD_SOURCE_DIR) / "examples/data/coffee.png");
  REQUIRE(photo.size() > 400);
  write(b.truncated_png, photo.substr(0, 300));
  b.text_png = in_tmp("text.png");
  write(b.text_png, "this is text, not a picture\n");
  b.truncated_csv = in_tmp("truncated.csv");
  write(b.truncated_csv, "x,y,vx,vy\n10,10,100,0\n12,1");
  b.garbage_csv = in_tmp("garbage.csv");
  write(b.garbage_csv, std::string("x,y,vx,vy\n10,10,100,0\n\x01\x02garbage,\xff,,\n", 38));
  b.plain_file = in_tmp("plain.txt");
  write(b.plain_file, "a file, not a folder\n");
  return b;
}

/// A 60 x 40 px picture, white with black from column 30.
std::string make_step_picture() {
  cv::Mat step(40, 60, CV_8UC3, cv::Scalar::all(255));
  step(cv::Rect(30, 0, 30, 40)).setTo(cv::Scalar::all(0));
  const std::string p = in_tmp("step.png");
  REQUIRE(cv::imwrite(p, step));
  return p;
}

const std::vector<std::string> bad_numbers = {"nan", "inf", "-inf", "1e400", "0", "-1", "abc", "3x", "", " 3"};

/// Adds a case per bad value of a numeric flag (values the flag accepts
/// are left out).
void add_numeric(std::vector<Case>& cases, const std::string& tool, std::vector<std::string> before,
                 const std::string& flag, const std::vector<std::string>& accepted = {}, const std::string& prefix = "",
                 const std::string& suffix = "", std::vector<std::string> after = {}) {
  for (const std::string& v : bad_numbers) {
    if (std::find(accepted.begin(), accepted.end(), v) != accepted.end()) continue;
    std::vector<std::string> args = before;
    args.push_back(flag);
    args.push_back(prefix + v + suffix);
    args.insert(args.end(), after.begin(), after.end());
    cases.push_back({tool, args, usage, flag});
  }
}

const std::string face = "10,10 50,10 50,30 10,30";

#ifdef HAPTICFIELD_TOOL_TANGIBLE_VIDEO
/// A 4-frame MJPG clip of 16 x 12 px at 10 fps: smaller than the default 17 x 17 mask.
std::string make_tiny_clip() {
  const std::string path = in_tmp("tiny.avi");
  cv::VideoWriter w(path, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(16, 12));
  REQUIRE(w.isOpened());
  for (int k = 0; k < 4; ++k)
    w.write(cv::Mat(12, 16, CV_8UC3, cv::Scalar::all(40 * k)));
  w.release();
  return path;
}
#endif

}  // namespace

TEST_CASE("--help: usage on stdout, nothing on stderr, exit 0") {
  fs::create_directories(tmp);
  for (const auto& [tool, path] : tools) {
    for (const char* flag : {"--help", "-h"}) {
      CAPTURE(tool, flag);
      const Result r = run(tool, {flag});
      REQUIRE_FALSE(r.timed_out);
      CHECK(r.status == ok);
      CHECK(r.err.empty());
      CHECK(r.out.rfind("usage: " + tool, 0) == 0);
      CHECK(r.out.find("--help") != std::string::npos);
      if (tool == "servo_demo")  // the help every other tool points to for --device names every family
        for (const char* family : {"sim:", "hid[", "serial:", "woody:", "inverse3:", "openhaptics[", "dhd[", "falcon["})
          CHECK(r.out.find(family) != std::string::npos);
    }
  }
}

TEST_CASE("unknown flags, flags without a value, stray arguments: exit 2") {
  fs::create_directories(tmp);
  const std::string picture = make_step_picture();
  const std::vector<Case> cases = {
      {"tangible_image", {picture, "--bogus"}, usage, "unknown option '--bogus'"},
      {"tangible_image", {picture, "--size"}, usage, "--size needs a value"},
      {"tangible_image", {}, usage, "no IMAGE"},
      {"tangible_image", {picture, picture}, usage, "more than one IMAGE"},
      {"tangible_image", {picture, "--mask", "fancy"}, usage, "unknown mask"},
      {"tangible_image", {picture, "--probes", "x.csv"}, usage, "go together"},
      {"tangible_experiment", {"--bogus"}, usage, "unknown option"},
      {"tangible_experiment", {"--size"}, usage, "needs a value"},
      {"tangible_experiment", {"stray"}, usage, "unexpected argument"},
      {"servo_demo", {"--bogus"}, usage, "unknown option"},
      {"servo_demo", {"--seconds"}, usage, "needs a value"},
      {"servo_demo", {"--field", "lava"}, usage, "unknown field"},
      {"servo_demo", {"--realtime", "sometimes"}, usage, "unknown real-time mode"},
      {"servo_demo", {"--device", "usb"}, usage, "--device"},
      {"servo_demo", {"--device", "hid:12345:1"}, usage, "--device"},
      {"servo_demo", {"--device", "serial:"}, usage, "--device"},
      {"servo_demo", {"--device", "inverse3:"}, usage, "--device"},
      {"servo_demo", {"--device", "woody:p9:sim"}, usage, "--device"},
      {"servo_demo", {"--device", "woody:p4:polhem_v3:sim"}, usage, "--device"},
      {"servo_demo", {"--device", "woody:p1:/dev/ttyACM0"}, usage, "--device"},
      {"servo_demo", {"--device", "woody:p4"}, usage, "needs the arm's tty"},
      {"two_arms", {"--bogus"}, usage, "unknown option"},
      {"two_arms", {"--policy", "panic"}, usage, "fault policy"},
      {"two_arms", {"--seconds"}, usage, "needs a value"},
      {"two_arms", {"--clock", "virtual", "--student", "hid"}, usage, "--student 'hid' is a real arm"},
      {"servo_demo", {picture, picture}, usage, "more than one IMAGE given"},
      {"servo_callback", {"--bogus"}, usage, "unknown option"},
      {"servo_callback", {"stray"}, usage, "unexpected argument"},
      {"picture_normals", {picture}, usage, "no --face"},
      {"picture_normals", {picture, "--face"}, usage, "needs a value"},
      {"picture_normals", {picture, "--face", face, "--bogus"}, usage, "unknown option"},
      {"picture_normals", {picture, "--face", "1,2 3,4"}, usage, "4 corners"},
      {"picture_normals", {picture, "--face", face, "--center", "1,2"}, usage, "--center needs --focal"},
      {"picture_normals", {picture, "--face", face, "--forces", "f.csv"}, usage, "go together"},
      {"picture_normals", {picture, picture, "--face", face}, usage, "more than one IMAGE given"},
      {"box_demo", {"--bogus"}, usage, "unknown option"},
      {"box_demo", {"--trials"}, usage, "needs a value"},
      {"box_demo", {"--check", "x.txt"}, usage, "--check needs --rotation"},
      {"texture_gallery", {"--bogus"}, usage, "unknown option"},
      {"texture_gallery", {"--out"}, usage, "needs a value"},
      {"false_texture", {}, usage, "no IMAGE"},
      {"false_texture", {picture, "--levels"}, usage, "needs a value"},
      {"false_texture", {picture, "--bogus"}, usage, "unknown option"},
      {"false_texture", {picture, picture}, usage, "more than one IMAGE given"},
  };
  for (const Case& c : cases)
    check_error(c);
}

TEST_CASE("every numeric flag: NaN, Inf, huge, zero, negative, garbage: exit 2 naming the flag") {
  fs::create_directories(tmp);
  const std::string picture = make_step_picture();
  std::vector<Case> cases;
  add_numeric(cases, "tangible_image", {picture}, "--size");
  add_numeric(cases, "tangible_image", {picture, "--mask", "gauss", "--size", "5"}, "--sigma");
  add_numeric(cases, "tangible_image", {picture}, "--max-mpx");
  add_numeric(cases, "tangible_experiment", {}, "--size");
  add_numeric(cases, "servo_demo", {"--field", "none"}, "--seconds");
  add_numeric(cases, "servo_demo", {"--field", "none"}, "--rate");
  add_numeric(cases, "picture_normals", {picture, "--face", face}, "--focal");
  add_numeric(cases, "picture_normals", {picture, "--face", face}, "--shading");
  // pairs allow spaces around the comma ("x, y"), so " 3" is fine there
  add_numeric(cases, "picture_normals", {picture, "--face", face}, "--size", {" 3"}, "", ",100");
  add_numeric(cases, "picture_normals", {picture, "--face", face}, "--size", {" 3"}, "100,");
  add_numeric(cases, "picture_normals", {picture, "--face", face, "--focal", "500"}, "--center", {"0", "-1", " 3"}, "",
              ",20");
  add_numeric(cases, "picture_normals", {picture}, "--face", {"0", "-1", " 3"}, "", ",10 50,10 50,30 10,30");
  add_numeric(cases, "box_demo", {}, "--rotation");
  add_numeric(cases, "box_demo", {}, "--noise", {"0"});
  add_numeric(cases, "box_demo", {}, "--trials");
  add_numeric(cases, "box_demo", {}, "--seed", {"0"});
  add_numeric(cases, "false_texture", {picture}, "--levels");
  add_numeric(cases, "false_texture", {picture}, "--max-mpx");
  add_numeric(cases, "picture_normals", {picture, "--face", face}, "--max-mpx");
  add_numeric(cases, "two_arms", {}, "--seconds");
  add_numeric(cases, "two_arms", {}, "--stiffness");
  // values just outside the documented ranges
  cases.push_back({"tangible_image", {picture, "--size", "99999999999"}, usage, "--size"});
  cases.push_back({"tangible_image", {picture, "--size", "4"}, usage, "not allowed"});
  cases.push_back({"tangible_experiment", {"--size", "255"}, usage, "256..8192"});
  cases.push_back({"servo_demo", {"--seconds", "0.0001"}, usage, "the minimum is 0.0005 s"});
  cases.push_back({"servo_demo", {"--seconds", "0.004", "--rate", "100"}, usage, "the minimum is 0.005 s"});
  cases.push_back({"servo_demo", {"--seconds", "3601"}, usage, "(0, 3600]"});
  cases.push_back({"servo_demo", {"--rate", "10001"}, usage, "[1, 10000]"});
  cases.push_back({"picture_normals", {picture, "--face", face, "--focal", "1e-300"}, usage, "[1, 1e6]"});
  cases.push_back({"picture_normals", {picture, "--face", face, "--focal", "1e7"}, usage, "[1, 1e6]"});
  cases.push_back({"box_demo", {"--rotation", "90"}, usage, "(0, 90)"});
  cases.push_back({"box_demo", {"--trials", "2e9"}, usage, "--trials"});
  cases.push_back({"box_demo", {"--trials", "100001"}, usage, "1..100000"});
  cases.push_back({"box_demo", {"--seed", "4294967296"}, usage, "--seed"});
  cases.push_back({"box_demo", {"--noise", "100.5"}, usage, "[0, 100]"});
  cases.push_back({"false_texture", {picture, "--levels", "9"}, usage, "2..8"});
  cases.push_back({"false_texture", {picture, "--levels", "99999999999"}, usage, "2..8"});
  for (const Case& c : cases)
    check_error(c);
}

TEST_CASE("bad files: missing, empty, folder, truncated, mislabelled: exit 1") {
  const BadFiles b = make_bad_files();
  const std::string picture = make_step_picture();
  std::vector<Case> cases;
  for (const std::string& file : {b.missing, b.empty, b.folder, b.truncated_png, b.text_png}) {
    cases.push_back({"tangible_image", {file}, bad_input, file});
    cases.push_back({"servo_demo", {file, "--seconds", "0.001"}, bad_input, file});
    cases.push_back({"picture_normals", {file, "--face", face}, bad_input, file});
    cases.push_back({"false_texture", {file, "--out", in_tmp("false_texture")}, bad_input, file});
  }
  // a picture above --max-mpx: the message names the flag that raises the limit
  cases.push_back({"tangible_image",
                   {picture, "--max-mpx", "0.001"},
                   bad_input,
                   "60 x 40 px (2400 px) is larger than the limit of 1000 px (raise --max-mpx to allow it)"});
  cases.push_back({"picture_normals",
                   {picture, "--face", face, "--max-mpx", "0.001"},
                   bad_input,
                   "60 x 40 px (2400 px) is larger than the limit of 1000 px (raise --max-mpx to allow it)"});
  cases.push_back({"false_texture",
                   {picture, "--out", in_tmp("false_texture"), "--max-mpx", "0.001"},
                   bad_input,
                   "60 x 40 px (2400 px) is larger than the limit of 1000 px (raise --max-mpx to allow it)"});
  for (const std::string& file : {b.missing, b.empty, b.folder, b.truncated_csv, b.garbage_csv, b.text_png}) {
    cases.push_back(
        {"tangible_image", {picture, "--size", "3", "--probes", file, "--forces", in_tmp("f.csv")}, bad_input, file});
    cases.push_back(
        {"picture_normals", {picture, "--face", face, "--probes", file, "--forces", in_tmp("f.csv")}, bad_input, file});
    cases.push_back({"box_demo", {"--rotation", "45", "--check", file}, bad_input, "--check"});
    cases.push_back({"picture_normals", {picture, "--face", face, "--intrinsics", file}, bad_input, file});
  }
  // the truncated CSV names its line; NaN in picture_normals' probes is bad input
  cases.push_back({"tangible_image",
                   {picture, "--size", "3", "--probes", b.truncated_csv, "--forces", in_tmp("f.csv")},
                   bad_input,
                   "truncated.csv:2: expected 'x,y'"});
  write(in_tmp("nan4.csv"), "1,2,nan,4\n");
  cases.push_back({"picture_normals",
                   {picture, "--face", face, "--probes", in_tmp("nan4.csv"), "--forces", in_tmp("f.csv")},
                   bad_input,
                   "nan4.csv:1: values must be finite"});
  // devices that are not there, or are not serial ports: one line, exit 1
  cases.push_back(
      {"servo_demo", {"--seconds", "0.001", "--device", "serial:" + b.missing}, bad_input, "no serial port"});
  cases.push_back(
      {"servo_demo", {"--seconds", "0.001", "--device", "serial:" + b.plain_file}, bad_input, "not a serial port"});
  cases.push_back({"servo_demo", {"--seconds", "0.001", "--device", "woody:p4:" + b.folder}, bad_input, "cannot open"});
  cases.push_back(
      {"servo_demo", {"--seconds", "0.001", "--device", "inverse3:" + b.missing}, bad_input, "no serial port"});
  // output paths, checked before any work
  const std::string no_dir = in_tmp("no/such/dir/out.csv");
  const std::string under_file = b.plain_file + "/sub";
  cases.push_back(
      {"tangible_image", {picture, "--probes", b.truncated_csv, "--forces", no_dir}, bad_input, "--forces"});
  cases.push_back(
      {"tangible_image", {picture, "--probes", b.truncated_csv, "--forces", b.folder}, bad_input, "--forces"});
  cases.push_back({"tangible_image", {picture, "--maps", b.plain_file}, bad_input, "--maps"});
  cases.push_back({"tangible_image", {picture, "--maps", under_file}, bad_input, "--maps"});
  cases.push_back({"servo_demo", {"--seconds", "0.001", "--trace", no_dir}, bad_input, "--trace"});
  cases.push_back({"servo_demo", {"--seconds", "0.001", "--plots", under_file}, bad_input, "--plots"});
  cases.push_back({"picture_normals", {picture, "--face", face, "--overlay", no_dir}, bad_input, "--overlay"});
  cases.push_back({"picture_normals", {picture, "--face", face, "--force-map", b.folder}, bad_input, "--force-map"});
  cases.push_back({"box_demo", {"--rotation", "45", "--out", under_file}, bad_input, "--out"});
  cases.push_back({"texture_gallery", {"--out", under_file}, bad_input, "--out"});
  cases.push_back({"texture_gallery", {"--out", in_tmp("gallery"), "--hatt", b.missing}, bad_input, "--hatt"});
  cases.push_back({"texture_gallery", {"--out", in_tmp("gallery"), "--hatt", b.plain_file}, bad_input, "--hatt"});
  cases.push_back({"false_texture", {picture, "--out", b.plain_file}, bad_input, "--out"});
  for (const Case& c : cases)
    check_error(c);
  CHECK_FALSE(fs::exists(in_tmp("no")));  // nothing was created on the way
}

TEST_CASE("good input at the edges of the ranges gives the right result") {
  fs::create_directories(tmp);
  const std::string picture = make_step_picture();

  SECTION("servo_demo: the shortest run is one tick, traced") {
    for (const auto& [seconds, rate, ticks] : std::vector<std::tuple<std::string, std::string, int>>{
             {"0.0005", "1000", 1}, {"0.001", "1000", 1}, {"0.003", "1000", 3}, {"0.05", "100", 5}}) {
      CAPTURE(seconds, rate);
      const std::string trace = in_tmp("trace.csv");
      fs::remove(trace);
      const Result r = run("servo_demo", {"--field", "none", "--realtime", "off", "--seconds", seconds, "--rate", rate,
                                          "--trace", trace, "--plots", in_tmp("plots/new")});
      REQUIRE_FALSE(r.timed_out);
      CAPTURE(r.err);
      REQUIRE(r.status == ok);
      CHECK(r.out.find(std::to_string(ticks) + " ticks at") != std::string::npos);
      const std::string text = slurp(trace);
      CHECK(std::count(text.begin(), text.end(), '\n') == ticks + 1);  // header + one row per tick
      CHECK(fs::exists(in_tmp("plots/new/force.png")));
    }
  }
  SECTION("tangible_image: probes with a header, CRLF, comments and blank lines") {
    const std::string probes = in_tmp("probes_crlf.csv");
    write(probes, "x,y\r\n# a comment\r\n30,20\r\n\r\n 10 , 20 \r\n");
    const std::string forces = in_tmp("forces_crlf.csv");
    const Result r = run("tangible_image", {picture, "--size", "3", "--probes", probes, "--forces", forces});
    CAPTURE(r.err);
    REQUIRE(r.status == ok);
    std::string text = slurp(forces);
    REQUIRE(text.rfind("x,y,fx,fy\n", 0) == 0);
    text = text.substr(10);
    std::replace(text.begin(), text.end(), ',', ' ');
    std::istringstream numbers(text);
    const std::vector<double> v{std::istream_iterator<double>(numbers), std::istream_iterator<double>()};
    REQUIRE(v.size() == 8);  // two probes: x, y, fx, fy
    CHECK(v[0] == 30.0);
    CHECK(v[2] == Approx(1.0));  // on the edge: magnitude 1 toward black (+x)
    CHECK(v[3] == Approx(0.0).margin(1e-12));
    CHECK(v[4] == 10.0);
    CHECK(v[6] == 0.0);  // flat white
  }
  SECTION("box_demo: one view, one trial, a fresh output folder") {
    const Result r = run(
        "box_demo", {"--rotation", "45", "--trials", "1", "--noise", "0", "--seed", "0", "--out", in_tmp("box/new")});
    CAPTURE(r.err);
    REQUIRE(r.status == ok);
    CHECK(fs::exists(in_tmp("box/new/box_45.png")));
    CHECK(r.out.find("worst:") != std::string::npos);
  }
  SECTION("tangible_experiment: the smallest picture") {
    const Result r = run("tangible_experiment", {"--size", "256"});
    REQUIRE(r.status == ok);
    CHECK(r.out.find("| 17 |") != std::string::npos);
  }
  SECTION("false_texture: the most and fewest levels") {
    for (const char* levels : {"2", "8"}) {
      const Result r = run("false_texture", {picture, "--levels", levels, "--out", in_tmp("ft")});
      CAPTURE(r.err);
      REQUIRE(r.status == ok);
      CHECK(fs::file_size(in_tmp("ft/strokes.csv")) > 100);
    }
  }
}

#ifdef HAPTICFIELD_TOOL_HAPTICFIELD_VIEW
TEST_CASE("hapticfield_view: bad command lines exit 2, bad pictures and paths exit 1, before any window") {
  const BadFiles b = make_bad_files();
  const std::string picture = make_step_picture();
  const std::string shot = in_tmp("view.png");
  // every case fails before a window could open; were one accepted, it
  // would draw off-screen and exit 0 (and fail here) instead of opening one
  const std::vector<std::string> offscreen = {"--seconds", "0.01", "--screenshot", shot};
  std::vector<Case> cases = {
      {"hapticfield_view", {}, usage, "missing SOURCE"},
      {"hapticfield_view", {picture, "--bogus"}, usage, "unknown option"},
      {"hapticfield_view", {picture, "--seconds"}, usage, "needs a value"},
      {"hapticfield_view", {picture, "--field", "lava"}, usage, "unknown field"},
      {"hapticfield_view", {picture, "--mask", "fancy"}, usage, "unknown mask"},
      {"hapticfield_view", {picture, "--border", "wrap"}, usage, "unknown border"},
      {"hapticfield_view", {picture, "--realtime", "sometimes"}, usage, "unknown real-time mode"},
      {"hapticfield_view", {picture, "--device", "usb"}, usage, "--device"},
      {"hapticfield_view", {picture, "--device", "hid:12345:1"}, usage, "--device"},
      {"hapticfield_view", {picture, picture}, usage, "more than one SOURCE given"},
      {"hapticfield_view", {picture, "--screenshot", shot}, usage, "--screenshot needs --seconds"},
      {"hapticfield_view", {picture, "--field", "normals"}, usage, "needs at least one --face"},
      {"hapticfield_view", {picture, "--face", "1,2 3,4"}, usage, "4 corners"},
      {"hapticfield_view", {picture, "--size", "4"}, usage, "does not suit mask prewitt"},
      {"hapticfield_view", {picture, "--mask", "sobel", "--size", "33"}, usage, "odd 3..31"},
      {"hapticfield_view", {picture, "--mask", "roberts", "--size", "3"}, usage, "(2)"},
      {"hapticfield_view", {picture, "--seconds", "0.0001"}, usage, "the minimum is 0.0005 s"},
      {"hapticfield_view", {picture, "--seconds", "3601"}, usage, "(0, 3600]"},
      {"hapticfield_view", {picture, "--rate", "10001"}, usage, "[1, 10000]"},
  };
  const auto with_offscreen = [&](std::vector<std::string> args) {
    args.insert(args.begin(), picture);
    return args;
  };
  add_numeric(cases, "hapticfield_view", {picture, "--screenshot", shot}, "--seconds");
  add_numeric(cases, "hapticfield_view", with_offscreen({}), "--rate", {}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({}), "--size", {}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({}), "--denoise", {"0"}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({}), "--gain", {"0"}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({"--field", "texture"}), "--grain", {}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({"--field", "texture"}), "--texture-gain", {"0"}, "", "",
              offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({"--field", "normals", "--face", face}), "--focal", {}, "", "",
              offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({}), "--start", {"0", "-1", " 3"}, "", ",20", offscreen);
  add_numeric(cases, "hapticfield_view", with_offscreen({"--field", "normals"}), "--face", {"0", "-1", " 3"}, "",
              ",10 50,10 50,30 10,30", offscreen);
  // bad pictures, output paths, and faces no camera can see: exit 1
  for (const std::string& file : {b.missing, b.empty, b.folder, b.truncated_png, b.text_png}) {
    std::vector<std::string> args = {file};
    args.insert(args.end(), offscreen.begin(), offscreen.end());
    cases.push_back({"hapticfield_view", args, bad_input, file});
  }
  cases.push_back({"hapticfield_view",
                   {picture, "--seconds", "0.01", "--screenshot", in_tmp("no/such/dir/v.png")},
                   bad_input,
                   "--screenshot"});
  cases.push_back(
      {"hapticfield_view", {picture, "--seconds", "0.01", "--screenshot", b.folder}, bad_input, "--screenshot"});
  cases.push_back({"hapticfield_view", {picture, "--shots", b.plain_file + "/sub"}, bad_input, "--shots"});
  cases.push_back(
      {"hapticfield_view",
       {picture, "--field", "normals", "--face", "10,10 20,20 30,30 40,40", "--seconds", "0.01", "--screenshot", shot},
       bad_input,
       "face 1"});
  for (const Case& c : cases)
    check_error(c);
  CHECK_FALSE(fs::exists(shot));  // no case drew anything
}

TEST_CASE("hapticfield_view --field video: video options on a picture, bad videos, bad video options") {
  const BadFiles b = make_bad_files();
  const std::string picture = make_step_picture();
  const std::string shot = in_tmp("view_video.png");
  fs::remove(shot);
  // a 10-frame MJPG clip, 64 x 48 px at 10 fps (1 s)
  const std::string clip = in_tmp("view_clip.avi");
  {
    cv::VideoWriter w(clip, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(64, 48));
    REQUIRE(w.isOpened());
    for (int k = 0; k < 10; ++k)
      w.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(20 * k)));
  }
  const std::string text_avi = in_tmp("text.avi");
  write(text_avi, "this is not a video\n");
  const std::string empty_avi = in_tmp("empty.avi");
  write(empty_avi, "");
  const std::vector<std::string> offscreen = {"--seconds", "0.01", "--screenshot", shot};
  const auto with = [&](std::string source, std::vector<std::string> args) {
    args.insert(args.begin(), source);
    args.insert(args.end(), offscreen.begin(), offscreen.end());
    return args;
  };
  std::vector<Case> cases = {
      {"hapticfield_view", with(picture, {"--field", "video"}), usage,
       "is a still picture: --field video needs a video"},
      {"hapticfield_view", with(picture, {"--speed", "2"}), usage, "--speed is for a video"},
      {"hapticfield_view", with(picture, {"--from", "1"}), usage, "--from is for a video"},
      {"hapticfield_view", with(picture, {"--loop"}), usage, "--loop is for a video"},
      {"hapticfield_view", with(picture, {"--fade-ms", "50"}), usage, "--fade-ms is for a video"},
      {"hapticfield_view", with(picture, {"--denoise", "temporal"}), usage, "--denoise temporal is for a video"},
      {"hapticfield_view", with(picture, {"--denoise", "fancy"}), usage, "--denoise expects a blur sigma"},
      {"hapticfield_view", with(clip, {"--denoise", "2"}), usage, "--denoise SIGMA blurs a picture"},
      {"hapticfield_view", with(clip, {"--field", "video", "--denoise", "0.5"}), usage, "--denoise SIGMA"},
      {"hapticfield_view", with(clip, {"--from", "1.5"}), bad_input, "past the end"},
      {"hapticfield_view", with(text_avi, {}), bad_input, "text.avi"},
      {"hapticfield_view", with(in_tmp("no_such_clip.avi"), {"--field", "video"}), bad_input, "no_such_clip.avi"},
      {"hapticfield_view", with(empty_avi, {"--field", "video"}), bad_input, empty_avi},
      {"hapticfield_view", with(b.folder, {"--field", "video"}), bad_input, b.folder},
  };
  add_numeric(cases, "hapticfield_view", {clip}, "--speed", {}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", {clip}, "--from", {"0"}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", {clip}, "--fade-ms", {"0"}, "", "", offscreen);
  cases.push_back({"hapticfield_view", with(clip, {"--speed", "17"}), usage, "(0, 16]"});
  add_numeric(cases, "hapticfield_view", {clip}, "--max-mpx", {}, "", "", offscreen);
  cases.push_back({"hapticfield_view", with(clip, {"--max-mpx", "0.001"}), bad_input,
                   "64 x 48 px (3072 px), larger than the limit of 1000 px"});
  cases.push_back({"hapticfield_view", with(picture, {"--max-mpx", "0.001"}), bad_input, "larger than the limit"});
  cases.push_back(
      {"hapticfield_view", with(make_tiny_clip(), {}), bad_input, "(16 x 12 px) are smaller than the 17 x 17 mask"});
  cases.push_back({"hapticfield_view", with(in_tmp("%999999999d.png"), {}), bad_input, "at most 9"});
  for (const Case& c : cases)
    check_error(c);
  CHECK_FALSE(fs::exists(shot));  // no case drew anything
  // and the clip itself plays
  const Result r = run("hapticfield_view", with(clip, {"--from", "0.5", "--loop"}));
  CAPTURE(r.out, r.err);
  CHECK(r.status == ok);
  CHECK(r.out.find("frame 5 shown") != std::string::npos);
  CHECK(fs::exists(shot));
}

TEST_CASE("hapticfield_view opens an image sequence (a pattern ending in .png is not a still picture)") {
  const fs::path dir = tmp / "view_sequence";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (int k = 0; k < 10; ++k)
    REQUIRE(cv::imwrite((dir / (std::to_string(100 + k).substr(1) + ".png")).string(),
                        cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(20 * k))));
  const std::string shot = in_tmp("view_sequence.png");
  fs::remove(shot);
  // 10 frames at 25 fps; from 0.2 s: frame 5
  const Result r = run("hapticfield_view",
                       {(dir / "%02d.png").string(), "--from", "0.2", "--seconds", "0.01", "--screenshot", shot});
  CAPTURE(r.out, r.err);
  CHECK(r.status == ok);
  CHECK(r.err.empty());
  CHECK(r.out.find("frame 5 shown") != std::string::npos);
  CHECK(fs::exists(shot));
}
#endif

#ifdef HAPTICFIELD_TOOL_TANGIBLE_VIDEO
namespace {
/// A 20-frame MJPG clip, 64 x 48 px at 20 fps: white, black from column 32
/// (frames 0..9), then black, white from column 32 (a cut at frame 10).
std::string make_clip() {
  const std::string path = in_tmp("clip.avi");
  cv::VideoWriter w(path, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 20.0, cv::Size(64, 48));
  REQUIRE(w.isOpened());
  w.set(cv::VIDEOWRITER_PROP_QUALITY, 100);
  for (int k = 0; k < 20; ++k) {
    cv::Mat f(48, 64, CV_8UC3, cv::Scalar::all(k < 10 ? 255 : 0));
    f(cv::Rect(32, 0, 32, 48)).setTo(cv::Scalar::all(k < 10 ? 0 : 255));
    w.write(f);
  }
  w.release();
  return path;
}
}  // namespace

TEST_CASE("tangible_video: bad values, bad files and bad outputs end in one line; good input plays") {
  const BadFiles b = make_bad_files();
  const std::string clip = make_clip();
  const std::string forces = in_tmp("vf.csv");
  const std::string probes = in_tmp("vp.csv");
  write(probes, "t,x,y\n0.2,31.5,20\n0.25,31.5,20\n0.5,31.5,20\n0.56,31.5,20\n0.0,10,20\n");
  std::vector<Case> cases = {
      {"tangible_video", {}, usage, "no VIDEO"},
      {"tangible_video", {clip, "--bogus"}, usage, "unknown option '--bogus'"},
      {"tangible_video", {clip, clip}, usage, "more than one VIDEO"},
      {"tangible_video", {clip, "--denoise", "lots"}, usage, "unknown denoise mode"},
      {"tangible_video", {clip, "--mask", "fancy"}, usage, "unknown mask"},
      {"tangible_video", {clip, "--border", "wrap"}, usage, "unknown border"},
      {"tangible_video", {clip, "--size", "4"}, usage, "not allowed"},
      {"tangible_video", {clip, "--probes", probes}, usage, "go together"},
      {"tangible_video", {clip, "--device", "usb"}, usage, "--device"},
      {"tangible_video", {"camera:abc"}, usage, "camera:N"},
      {"tangible_video", {"camera:100"}, usage, "camera:N"},
      {"tangible_video", {clip, "--fade-ms", "10001"}, usage, "[0, 10000]"},
      {"tangible_video", {clip, "--seconds", "3601"}, usage, "(0, 3600]"},
      {"tangible_video", {clip, "--clock", "moon"}, usage, "unknown clock 'moon'"},
      {"tangible_video",
       {clip, "--clock", "virtual", "--device", "hid"},
       usage,
       "--clock virtual needs a simulated arm (--device sim, woody:GEN[:PRESET]:sim or inverse3:sim); --device 'hid' "
       "is a real arm"},
      {"tangible_video", {clip, "--clock", "wall", "--probes", probes, "--forces", forces}, usage, "play mode"},
  };
  add_numeric(cases, "tangible_video", {clip}, "--size");
  add_numeric(cases, "tangible_video", {clip}, "--fade-ms", {"0"});
  add_numeric(cases, "tangible_video", {clip}, "--seconds");
  add_numeric(cases, "tangible_video", {clip}, "--max-mpx");
  // frames above --max-mpx, refused before decoding; a clip smaller than the mask, in both modes; a
  // sequence pattern wider than %09d, refused at once
  const std::string tiny = make_tiny_clip();
  for (const std::vector<std::string>& mode : {std::vector<std::string>{}, {"--probes", probes, "--forces", forces}}) {
    std::vector<std::string> args = {clip, "--max-mpx", "0.001"};
    args.insert(args.end(), mode.begin(), mode.end());
    cases.push_back({"tangible_video", args, bad_input,
                     "64 x 48 px (3072 px), larger than the limit of 1000 px (raise --max-mpx to allow it)"});
    args = {tiny};
    args.insert(args.end(), mode.begin(), mode.end());
    cases.push_back({"tangible_video", args, bad_input, "(16 x 12 px) are smaller than the 17 x 17 mask"});
    args = {in_tmp("%999999999d.png")};
    args.insert(args.end(), mode.begin(), mode.end());
    cases.push_back({"tangible_video", args, bad_input, "at most 9"});
  }
  // videos: missing, empty, a folder, text named .avi, a truncated clip
  const std::string text_avi = in_tmp("text.avi");
  write(text_avi, "this is text, not a video\n");
  const std::string truncated_avi = in_tmp("truncated.avi");
  write(truncated_avi, slurp(clip).substr(0, 300));
  for (const std::string& file : {b.missing, b.empty, b.folder, text_avi, truncated_avi, b.text_png})
    cases.push_back({"tangible_video", {file, "--probes", probes, "--forces", forces}, bad_input, file});
  // probes: missing, empty, folder, truncated, garbage, NaN, negative time
  write(in_tmp("vnan.csv"), "0.1,nan,3\n");
  write(in_tmp("vneg.csv"), "-0.5,3,3\n");
  for (const std::string& file :
       {b.missing, b.empty, b.folder, b.truncated_csv, b.garbage_csv, in_tmp("vnan.csv"), in_tmp("vneg.csv")})
    cases.push_back({"tangible_video", {clip, "--probes", file, "--forces", forces}, bad_input, file});
  // outputs, checked before any work
  const std::string no_dir = in_tmp("no/such/dir/out.csv");
  cases.push_back({"tangible_video", {clip, "--probes", probes, "--forces", no_dir}, bad_input, "--forces"});
  cases.push_back({"tangible_video", {clip, "--probes", probes, "--forces", b.folder}, bad_input, "--forces"});
  cases.push_back({"tangible_video", {clip, "--cuts", no_dir}, bad_input, "--cuts"});
  cases.push_back({"tangible_video", {clip, "--trace", no_dir}, bad_input, "--trace"});
  cases.push_back({"tangible_video", {clip, "--plots", b.plain_file + "/sub"}, bad_input, "--plots"});
  for (const Case& c : cases)
    check_error(c);

  SECTION("offline forces: the edge, the held frame before the cut, the fade, the new scene") {
    const std::string cuts = in_tmp("vcuts.csv");
    const Result r = run("tangible_video", {clip, "--size", "3", "--border", "clamp", "--denoise", "none", "--probes",
                                            probes, "--forces", forces, "--cuts", cuts});
    CAPTURE(r.err);
    REQUIRE(r.status == ok);
    CHECK(r.err.empty());
    CHECK(slurp(cuts) == "frame,time\n10,0.5\n");
    std::string text = slurp(forces);
    REQUIRE(text.rfind("t,x,y,fx,fy\n", 0) == 0);
    text = text.substr(12);
    std::replace(text.begin(), text.end(), ',', ' ');
    std::istringstream numbers(text);
    const std::vector<double> v{std::istream_iterator<double>(numbers), std::istream_iterator<double>()};
    REQUIRE(v.size() == 25);  // five probes, in the order given
    // x = 31.5 is midway between pixel 31 (white) and 32 (black): an edge
    // pixel's force through a 3 x 3 mask is 1, toward black (+x).
    CHECK(v[3] == Approx(1.0).margin(0.03));    // t = 0.2: scene 1
    CHECK(v[8] == Approx(1.0).margin(0.03));    // t = 0.25
    CHECK(v[13] == Approx(1.0).margin(0.03));   // t = 0.5: the cut, the old scene held at full force
    CHECK(v[18] == Approx(-0.2).margin(0.03));  // t = 0.56: fading in at 0.2 the new scene (toward -x)
    CHECK(v[23] == Approx(0.0).margin(0.03));   // t = 0: white, and fading in from 0
  }
  SECTION("a damaged stream plays what decodes, without decoder chatter") {
    std::string bytes = slurp(clip);
    for (std::size_t i = bytes.size() / 3; i < bytes.size() / 2; i += 7)
      bytes[i] = static_cast<char>(i * 31);
    const std::string damaged = in_tmp("damaged.avi");
    write(damaged, bytes);
    const Result r = run("tangible_video", {damaged, "--probes", probes, "--forces", forces});
    CAPTURE(r.err, r.out);
    REQUIRE_FALSE(r.timed_out);
    CHECK(r.status == ok);
    CHECK(r.err.empty());
  }
  SECTION("play mode on the simulated arm, traced") {
    const std::string trace = in_tmp("vtrace.csv");
    const Result r = run("tangible_video", {clip, "--seconds", "0.3", "--trace", trace, "--cuts", in_tmp("pc.csv")});
    CAPTURE(r.err);
    REQUIRE(r.status == ok);
    CHECK(r.err.empty());
    const std::string t = slurp(trace);
    CHECK(std::count(t.begin(), t.end(), '\n') == 301);
  }
  SECTION("play mode on simulated time: the same trace every run, no frame dropped") {
    const std::string trace1 = in_tmp("vtrace_v1.csv"), trace2 = in_tmp("vtrace_v2.csv");
    for (const std::string& trace : {trace1, trace2}) {
      const Result r = run("tangible_video", {clip, "--seconds", "0.8", "--clock", "virtual", "--trace", trace});
      CAPTURE(r.err, r.out);
      REQUIRE(r.status == ok);
      CHECK(r.err.empty());
      CHECK(r.out.find("0 dropped") != std::string::npos);
    }
    const std::string t = slurp(trace1);
    CHECK(std::count(t.begin(), t.end(), '\n') == 801);
    CHECK(t == slurp(trace2));
  }
}
#endif

#if HAPTICFIELD_TEST_SHAPES
TEST_CASE("--shape: bad shapes exit 1, bad shape options exit 2, before any window or run") {
  const BadFiles b = make_bad_files();
  const std::string picture = make_step_picture();
  const std::string mesh = in_tmp("triangle.obj");
  write(mesh, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string no_triangles = in_tmp("points.obj");
  write(no_triangles, "v 0 0 0\nv 1 0 0\n");
  const std::string degenerate = in_tmp("degenerate.obj");  // two triangles, neither with an area
  write(degenerate, "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 4\n");
  const std::string unknown = in_tmp("shape.xyz");
  write(unknown, "0 0 0\n");
  const std::string shot = in_tmp("shape_view.png");
  fs::remove(shot);
  const std::vector<std::string> offscreen = {"--seconds", "0.01", "--screenshot", shot};
  std::vector<Case> cases = {
      {"servo_demo", {"--snapshot", shot}, usage, "give --shape"},
      {"servo_demo", {"--shape", mesh, "--field", "wall"}, usage, "--shape"},
      {"servo_demo", {picture, "--shape", mesh}, usage, "--shape"},
      {"servo_demo", {"--shape", mesh, "--view", "10,90"}, usage, "[-89, 89]"},
      {"servo_demo", {"--shape", b.missing}, bad_input, b.missing},
      {"servo_demo", {"--shape", unknown}, bad_input, "unknown mesh format"},
      {"servo_demo", {"--shape", no_triangles}, bad_input, no_triangles},
      {"servo_demo",
       {"--shape", degenerate},
       bad_input,
       "cannot use '" + degenerate + "': all 2 triangles have zero area"},
      {"servo_demo", {"--shape", b.truncated_png}, bad_input, b.truncated_png},
  };
#ifdef HAPTICFIELD_TOOL_HAPTICFIELD_VIEW
  const auto view = [&](std::vector<std::string> args) {
    args.insert(args.end(), offscreen.begin(), offscreen.end());
    return args;
  };
  cases.push_back({"hapticfield_view", view({picture, "--shape", mesh}), usage, "not both"});
  cases.push_back({"hapticfield_view", view({"--shape", mesh, "--field", "texture"}), usage, "--field"});
  cases.push_back({"hapticfield_view", view({"--shape", mesh, "--start", "1,2"}), usage, "--start"});
  cases.push_back({"hapticfield_view", view({"--shape", mesh, "--loop"}), usage, "--loop"});
  cases.push_back({"hapticfield_view", view({"--shape", mesh, "--view", "10,90"}), usage, "[-89, 89]"});
  add_numeric(cases, "hapticfield_view", {"--shape", mesh}, "--height-mm", {}, "", "", offscreen);
  add_numeric(cases, "hapticfield_view", {"--shape", mesh}, "--max-triangles", {}, "", "", offscreen);
  cases.push_back(
      {"hapticfield_view", view({picture, "--max-triangles", "5"}), usage, "--max-triangles is for --shape"});
  {  // two quads make four triangles: above a limit of 3, counted before the file is read, named by the tool's flag
    const std::string quads = in_tmp("quads.obj");
    write(quads, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nf 1 2 3 4\nf 2 5 6 3\n");
    cases.push_back({"hapticfield_view", view({"--shape", quads, "--max-triangles", "3"}), bad_input,
                     "more than 3 triangles by line 8 (raise --max-triangles to allow it)"});
  }
  add_numeric(cases, "hapticfield_view", {"--shape", mesh}, "--distance", {}, "", "", offscreen);
  // the tool's radius [mm]: in [0, 50], for --shape
  add_numeric(cases, "hapticfield_view", {"--shape", mesh}, "--radius", {"0"}, "", "", offscreen);
  cases.push_back({"hapticfield_view", view({"--shape", mesh, "--radius", "50.5"}), usage, "[0, 50]"});
  cases.push_back({"hapticfield_view", view({picture, "--radius", "2"}), usage, "--radius is for --shape"});
  add_numeric(cases, "hapticfield_view", {"--shape", mesh}, "--view", {"0", "-1", " 3"}, "", ",10", offscreen);
  for (const std::string& file : {b.missing, b.empty, b.folder, b.truncated_png, unknown, no_triangles})
    cases.push_back({"hapticfield_view", view({"--shape", file}), bad_input, file});
#endif
  add_numeric(cases, "servo_demo", {"--shape", mesh}, "--height-mm");
  add_numeric(cases, "servo_demo", {"--shape", mesh}, "--distance");
  for (const Case& c : cases)
    check_error(c);
  CHECK_FALSE(fs::exists(shot));  // no case drew anything
}
#endif

#ifdef HAPTICFIELD_TOOL_HJIF_RENDER
TEST_CASE("hjif_render: bad command lines and numbers exit 2, bad files exit 1") {
  const BadFiles b = make_bad_files();
  const std::string wav = in_tmp("hjif_render.wav");
  std::vector<Case> cases = {
      {"hjif_render", {}, usage, "no FILE.hjif given"},
      {"hjif_render", {"x.hjif"}, usage, "--wav OUT.wav or --info is required"},
      {"hjif_render", {"x.hjif", "--info", "--bogus"}, usage, "unknown option '--bogus'"},
      {"hjif_render", {"x.hjif", "--wav"}, usage, "--wav needs a value"},
      {"hjif_render", {"x.hjif", "--info", "--rate"}, usage, "--rate needs a value"},
      {"hjif_render", {"x.hjif", "y.hjif", "--info"}, usage, "more than one FILE.hjif given ('x.hjif', 'y.hjif')"},
      {"hjif_render", {"x.hjif", "--info", "--rate", "8000.5"}, usage, "whole number"},
      {"hjif_render", {"x.hjif", "--info", "--rate", "99"}, usage, "--rate"},
      {"hjif_render", {"x.hjif", "--info", "--rate", "384001"}, usage, "--rate"},
  };
  add_numeric(cases, "hjif_render", {"x.hjif", "--info"}, "--rate");
  // the file's faults come after the command line's: one line naming the file
  for (const std::string& file : {b.missing, b.empty, b.folder, b.text_png}) {
    cases.push_back({"hjif_render", {file, "--info"}, bad_input, file});
    cases.push_back({"hjif_render", {file, "--wav", wav}, bad_input, file});
  }
  for (const Case& c : cases)
    check_error(c);
  CHECK_FALSE(fs::exists(wav));  // nothing written from a bad file
}
#endif

#ifdef HAPTICFIELD_TOOL_FEEL_MUJOCO
TEST_CASE("feel_mujoco: bad command lines and numbers exit 2, bad scenes exit 1") {
  const BadFiles b = make_bad_files();
  const std::string scene = (fs::path(HAPTICFIELD_SOURCE_DIR) / "examples/data/mujoco_ball.xml").string();
  // the command line is read before the scene: a bad number is named even with no scene there
  std::vector<Case> cases = {
      {"feel_mujoco", {}, usage, "no scene (MJCF .xml) given"},
      {"feel_mujoco", {scene, "--bogus"}, usage, "unknown option '--bogus'"},
      {"feel_mujoco", {scene, "--seconds"}, usage, "--seconds needs a value"},
      {"feel_mujoco", {scene, "--trace"}, usage, "--trace needs a value"},
      {"feel_mujoco", {scene, scene}, usage, "more than one scene (MJCF .xml) given"},
      {"feel_mujoco", {scene, "--mode", "glue"}, usage, "glue"},
      {"feel_mujoco", {scene, "--view", "0,90"}, usage, "pitch"},
  };
  add_numeric(cases, "feel_mujoco", {"no_scene.xml"}, "--seconds");
  add_numeric(cases, "feel_mujoco", {"no_scene.xml"}, "--rate");
  add_numeric(cases, "feel_mujoco", {"no_scene.xml"}, "--stiffness");
  add_numeric(cases, "feel_mujoco", {"no_scene.xml"}, "--speed");
  add_numeric(cases, "feel_mujoco", {"no_scene.xml"}, "--distance");
  for (const std::string& file : {b.missing, b.empty, b.folder, b.text_png})
    cases.push_back({"feel_mujoco", {file, "--seconds", "0.01"}, bad_input, file});
  for (const Case& c : cases)
    check_error(c);
}
#endif
