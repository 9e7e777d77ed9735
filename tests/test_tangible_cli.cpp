// End-to-end tests of the tangible_image command: probes in, forces out, and
// one clear stderr line with a non-zero exit for every bad input.
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "hapticfield/kernels.hpp"

using namespace hapticfield;

namespace {

const std::filesystem::path tmp = std::filesystem::path(HAPTICFIELD_TEST_TMP) / "cli";

std::string path_of(const std::string& name) {
  std::filesystem::create_directories(tmp);
  return (tmp / name).string();
}

struct Run {
  int status;
  std::string err;
};

/// Runs tangible_image with args; returns the exit status and stderr.
Run run(const std::string& args) {
  const std::string err_file = path_of("stderr.txt");
  const std::string cmd =
      std::string(HAPTICFIELD_TANGIBLE_IMAGE) + " " + args + " > " + path_of("stdout.txt") + " 2> " + err_file;
  const int raw = std::system(cmd.c_str());
  std::ifstream in(err_file);
  std::stringstream ss;
  ss << in.rdbuf();
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, ss.str()};
}

std::vector<std::vector<double>> read_csv(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ','))
      row.push_back(std::strtod(cell.c_str(), nullptr));
    rows.push_back(row);
  }
  return rows;
}

std::string write_step_picture() {
  cv::Mat step(40, 60, CV_8UC3, cv::Scalar::all(255));
  step(cv::Rect(30, 0, 30, 40)).setTo(cv::Scalar::all(0));  // black from column 30
  const std::string p = path_of("step.png");
  REQUIRE(cv::imwrite(p, step));
  return p;
}

}  // namespace

TEST_CASE("--probes / --forces: normalised forces at pixel positions") {
  const std::string picture = write_step_picture();
  const std::string probes = path_of("probes.csv");
  {
    std::ofstream out(probes);
    out << "x,y\n30,20\n29.5,20\n10,20\n30,20.25\nnan,3\n-5,20\n200,20\n";
  }
  const std::string forces = path_of("forces.csv");
  for (const char* mask : {"prewitt", "sobel", "scharr", "roberts", "gauss", "emboss"}) {
    CAPTURE(mask);
    const Run r = run(picture + " --mask " + mask + " --size " + (std::string(mask) == "roberts" ? "2" : "3") +
                      " --probes " + probes + " --forces " + forces);
    REQUIRE(r.status == 0);
    const auto rows = read_csv(forces);
    REQUIRE(rows.size() == 7);
    CHECK(rows[0][2] == Approx(1.0));  // on the edge: magnitude 1 toward black (+x)
    CHECK(rows[0][3] == Approx(0.0).margin(1e-12));
    CHECK(rows[2][2] == 0.0);          // flat white
    CHECK(rows[3][2] == Approx(1.0));  // along the edge: the same
    CHECK(rows[4][2] == 0.0);          // NaN probe: zero
    CHECK(rows[5][2] == 0.0);          // outside the picture: zero
    CHECK(rows[6][2] == 0.0);
  }
}

TEST_CASE("--probes output equals the library on a real photograph") {
  const std::string photo = std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png";
  const std::string probes = path_of("photo_probes.csv");
  {
    std::ofstream out(probes);
    for (int i = 0; i < 50; ++i)
      out << 20 + i * 11.3 << "," << 15 + i * 7.1 << "\n";
  }
  const std::string forces = path_of("photo_forces.csv");
  REQUIRE(run(photo + " --mask gauss --size 9 --sigma 2 --border reflect --gray bt601 --probes " + probes +
              " --forces " + forces)
              .status == 0);
  const TangibleImage image(load_gray(photo, GrayWeights::bt601), {MaskKind::gaussian, 9, 2.0, Border::reflect});
  for (const auto& row : read_csv(forces)) {
    const glm::dvec2 f = image.at(row[0], row[1]);
    REQUIRE(row[2] == Approx(f.x).margin(1e-15));
    REQUIRE(row[3] == Approx(f.y).margin(1e-15));
  }
}

TEST_CASE("--maps writes the pictures") {
  const std::string picture = write_step_picture();
  const std::string dir = path_of("maps");
  REQUIRE(run(picture + " --size 5 --maps " + dir).status == 0);
  for (const char* name : {"fx.png", "fy.png", "magnitude.png", "arrows.png", "fx.tiff", "fy.tiff"})
    CHECK(std::filesystem::exists(std::filesystem::path(dir) / name));
  const cv::Mat fx = cv::imread((std::filesystem::path(dir) / "fx.tiff").string(), cv::IMREAD_UNCHANGED);
  REQUIRE(fx.type() == CV_32FC1);
  CHECK(fx.at<float>(20, 30) == Approx(1.0f));
}

TEST_CASE("bad input: one clear line on stderr and a non-zero exit") {
  const std::string picture = write_step_picture();
  const std::string corrupt = path_of("corrupt.jpg");
  {
    std::ofstream out(corrupt, std::ios::binary);
    out << "\xff\xd8\xff garbage";
  }
  const std::string tiny = path_of("tiny.png");
  REQUIRE(cv::imwrite(tiny, cv::Mat(1, 1, CV_8UC1, cv::Scalar(0))));
  const std::string bad_probes = path_of("bad_probes.csv");
  {
    std::ofstream out(bad_probes);
    out << "x,y\n1,2\nthree,4\n";
  }
  const std::string huge = path_of("huge.png");  // a 45-byte PNG header declaring 20000 x 20000 px
  {
    std::ofstream out(huge, std::ios::binary);
    out.write("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x4e\x20\0\0\x4e\x20\x08\0\0\0\0\0\0\0\0", 33);
  }
  struct Case {
    std::string args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {path_of("missing.png"), "no such file"},
      {corrupt, "cannot decode"},
      {tiny, "smaller than the 17 x 17 mask"},
      {picture + " --size 4", "size 4 px is not allowed"},
      {picture + " --size 131", "size 131 px is not allowed"},
      {picture + " --size 41", "smaller than the 41 x 41 mask"},
      {picture + " --mask sobel --size 33", "not allowed"},
      {picture + " --mask fancy", "unknown mask"},
      {picture + " --border wrap", "unknown border"},
      {picture + " --gray hdr", "unknown gray"},
      {picture + " --sigma -1 --mask gauss --size 5", "--sigma"},
      {picture + " --mask gauss --sigma 0.01 --size 5", "sigma must be finite and at least 0.05 px"},
      {huge, "20000 x 20000 px (400000000 px) is larger than the limit of 100000000 px"},
      {picture + " --max-mpx 0.001", "is larger than the limit of 1000 px"},
      {picture + " --max-mpx -1", "--max-mpx"},
      {picture + " --size five", "expects an integer"},
      {picture + " --probes " + bad_probes, "go together"},
      {picture + " --size 3 --probes " + bad_probes + " --forces " + path_of("f.csv"), ":3: expected 'x,y'"},
      {picture + " --size 3 --probes " + path_of("nope.csv") + " --forces " + path_of("f.csv"), "cannot open probes"},
      {"", "no IMAGE"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.args);
    const Run r = run(c.args);
    CHECK(r.status != 0);
    CHECK_THAT(r.err, Catch::Contains(c.says));
    CHECK_THAT(r.err, Catch::StartsWith("tangible_image: "));
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
}
