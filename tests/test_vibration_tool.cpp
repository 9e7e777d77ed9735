// The vibration example (examples/14_vibration.cpp) run as a user runs it:
// a scripted HaTT stroke to a WAV file read back with libsndfile (rate,
// length, silence before the touch, sound while sliding, the same file on
// every run: the time is simulated), to ALSA's null PCM (no device needed),
// its spectrum against the model's, and its bad inputs (one line, exit 1
// or 2). Nothing here depends on the machine's speed.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "hapticfield/vibration/wav_sink.hpp"

using hapticfield::testing::Child;
using hapticfield::testing::slurp;
namespace fs = std::filesystem;
namespace vib = hapticfield::vibration;

namespace {

const fs::path tmp = fs::path(HAPTICFIELD_TEST_TMP) / "vibration_tool";
const std::string tool = HAPTICFIELD_TOOL_VIBRATION;
/// A 10 kHz AR model set shaped like the toolkit's (in the repository).
const std::string model_file =
    (fs::path(HAPTICFIELD_SOURCE_DIR) / "tests" / "data" / "hatt" / "Models_Toolkit 10kHz AR.xml").string();
/// The toolkit's own files live beside the project, never in it.
const fs::path real_hatt_dir = fs::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data" / "hatt" / "10000Hz";

struct Run {
  int status{-1};
  std::string out, err;
};

Run run(const std::vector<std::string>& args, const std::string& name,
        std::chrono::seconds patience = std::chrono::seconds(60)) {
  Child child(tool, args, tmp, name, /*press_enter=*/false);  // the tool reads no stdin
  REQUIRE(child.wait(patience));
  REQUIRE(child.exited_normally());
  return {child.status(), child.out(), child.err()};
}

double rms(const std::vector<float>& v, std::size_t from, std::size_t to) {
  double s = 0.0;
  for (std::size_t i = from; i < to; ++i)
    s += static_cast<double>(v[i]) * static_cast<double>(v[i]);
  return std::sqrt(s / static_cast<double>(to - from));
}

/// Median |audio_dB - model_dB| up to 4 kHz, and the highest frequency, of a --spectrum CSV.
std::pair<double, double> spectrum_error(const fs::path& csv) {
  std::istringstream in(slurp(csv));
  std::string line;
  std::getline(in, line);
  REQUIRE(line == "frequency_Hz,audio_dB,model_dB");
  std::vector<double> errors;
  double top = 0.0;
  while (std::getline(in, line)) {
    double f = 0.0, a = 0.0, m = 0.0;
    REQUIRE(std::sscanf(line.c_str(), "%lf,%lf,%lf", &f, &a, &m) == 3);
    REQUIRE(std::isfinite(a));
    REQUIRE(std::isfinite(m));
    top = f;
    if (f <= 4000.0) errors.push_back(std::fabs(a - m));
  }
  REQUIRE(errors.size() > 100);
  std::sort(errors.begin(), errors.end());
  return {errors[errors.size() / 2], top};
}

}  // namespace

TEST_CASE(
    "vibration tool: a stroke to a WAV file has the rate, the length, silence before the touch and sound while "
    "sliding") {
  const fs::path wav = tmp / "stroke.wav";
  const fs::path csv = tmp / "stroke.csv";
  fs::create_directories(tmp);
  const Run r = run({"--hatt", model_file, "--wav", wav.string(), "--spectrum", csv.string(), "--rate", "16000",
                     "--block", "128", "--seconds", "3"},
                    "stroke");
  CAPTURE(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.empty());

  const vib::WavData d = vib::read_wav(wav);
  CHECK(d.sample_rate == 16000.0);
  CHECK(d.channels == 1);
  CHECK(d.frames() == 48000);  // 3 s in whole blocks of 128 frames: 375 blocks
  for (float v : d.samples)
    REQUIRE((std::isfinite(v) && std::fabs(v) <= 1.0f));

  // 0.1 s above the surface, plus the playout delay (128 / 16000 + 2 ms): silence
  for (std::size_t i = 0; i < 1600; ++i)
    REQUIRE(d.samples[i] == 0.0f);
  // sliding from 0.2 s to 2.9 s: sound
  const double sliding = rms(d.samples, 3200, 46400);
  CHECK(sliding > 1e-3);
  // lifted at 2.9 s: held 20 ms, then the filter rings down
  CHECK(rms(d.samples, 47200, 48000) < 0.1 * sliding);

  // the sliding part's spectrum is the model's (the bound: 1.5 dB up to 4 kHz)
  const auto [median_error, top] = spectrum_error(csv);
  CHECK(median_error <= 1.5);
  CHECK(top < 5000.0);  // up to the model's Nyquist frequency

  SECTION("simulated time: a second run writes the same file") {
    const fs::path again = tmp / "again.wav";
    REQUIRE(run({"--hatt", model_file, "--wav", again.string(), "--rate", "16000", "--block", "128", "--seconds", "3"},
                "again")
                .status == 0);
    CHECK(slurp(again) == slurp(wav));
  }
}

TEST_CASE("vibration tool: the real toolkit models at 48 kHz (skipped without ../shared/data/hatt)") {
  const fs::path book = real_hatt_dir / "Models_Book.xml";
  if (!fs::exists(book)) {
    WARN("SKIPPED: no real HaTT models at " << real_hatt_dir);
    return;
  }
  const fs::path csv = tmp / "book.csv";
  fs::create_directories(tmp);
  const Run r = run({"--hatt", book.string(), "--spectrum", csv.string(), "--seconds", "6"}, "book");
  CAPTURE(r.err);
  REQUIRE(r.status == 0);
  const auto [median_error, top] = spectrum_error(csv);
  CHECK(median_error <= 1.5);
  CHECK(top < 5000.0);
}

#ifdef HAPTICFIELD_TEST_ALSA
TEST_CASE("vibration tool: ALSA's null PCM takes the stroke (no sound card needed)") {
  const Run r = run({"--hatt", model_file, "--alsa", "null", "--seconds", "0.5", "--block", "64"}, "alsa_null");
  CAPTURE(r.err);
  CHECK(r.status == 0);
  CHECK(r.out.find("ALSA 'null'") != std::string::npos);
  CHECK(r.out.find("24000 frames at 48000 Hz") != std::string::npos);  // 375 blocks of 64
}
#endif

TEST_CASE("vibration tool: --help, bad usage (exit 2) and bad input (exit 1), each one line") {
  fs::create_directories(tmp);
  const Run help = run({"--help"}, "help");
  CHECK(help.status == 0);
  CHECK(help.out.find("usage: vibration") == 0);
  CHECK(help.out.find("at most 16 MB, <SampleRate> in 100..100000 Hz") != std::string::npos);  // its limits
  CHECK(help.err.empty());

  const fs::path not_xml = tmp / "not_a_model.xml";
  std::ofstream(not_xml) << "this is not a HaTT model set\n";
  const std::string out = (tmp / "bad.wav").string();
  struct Case {
    std::vector<std::string> args;
    int status;
    std::string says;
  };
  const std::vector<Case> cases{
      {{"--wav", out}, 2, "--hatt FILE is required"},
      {{"--hatt", model_file}, 2, "choose an output"},
      {{"--hatt", model_file, "--wav", out, "--alsa", "null"}, 2, "exclude each other"},
      {{"--hatt", model_file, "--wav", out, "--rate", "44k"}, 2, "--rate expects a number"},
      {{"--hatt", model_file, "--wav", out, "--rate", "4000"}, 2, "--rate must be in [8000, 192000]"},
      // the WAV header holds a whole rate: 8000.5 is refused, not written as 8001 and reported as 8000
      {{"--hatt", model_file, "--wav", out, "--rate", "8000.5"},
       2,
       "--rate must be a whole number of Hz, got '8000.5'"},
      {{"--hatt", model_file, "--wav", out, "--block", "0"}, 2, "--block must be in 16..8192"},
      {{"--hatt", model_file, "--wav", out, "--seconds", "nan"}, 2, "--seconds must be a finite number"},
      {{"--hatt", model_file, "--wav", out, "--gain", "0"}, 2, "--gain must be in (0, 10]"},
      {{"--hatt", model_file, "--wav", out, "--model", "9999"}, 2, "--model must be in 0.."},
      {{"--hatt", model_file, "--wav", out, "--spectrum", (tmp / "s.csv").string(), "--seconds", "0.5", "--rate",
        "8000"},
       2,
       "--spectrum needs a longer stroke"},
      {{"--hatt", model_file, "--wav", out, "--frobnicate"}, 2, "unknown option '--frobnicate'"},
      {{"--hatt", (tmp / "missing.xml").string(), "--wav", out}, 1, "missing.xml"},
      {{"--hatt", not_xml.string(), "--wav", out}, 1, "not_a_model.xml"},
      {{"--hatt", model_file, "--wav", (tmp / "no such folder" / "x.wav").string()}, 1, "does not exist"},
#ifdef HAPTICFIELD_TEST_ALSA
      {{"--hatt", model_file, "--alsa", "no_such_pcm_device"}, 1, "no_such_pcm_device"},
#endif
  };
  int i = 0;
  for (const Case& c : cases) {
    const Run r = run(c.args, "bad" + std::to_string(i++));
    CAPTURE(c.args, r.err);
    CHECK(r.status == c.status);
    CHECK(r.err.find(c.says) != std::string::npos);
    CHECK(r.err.rfind("vibration: ", 0) == 0);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.out.empty());
  }
}

TEST_CASE("vibration tool: a model file declaring a huge <SampleRate> is refused at once, in one line") {
  // such a file used to run one model step per 1/SampleRate of the stroke: 1e9 Hz never finished
  fs::create_directories(tmp);
  const std::string text = slurp(model_file);
  const std::string rate_tag = "<SampleRate>10000</SampleRate>";
  REQUIRE(text.find(rate_tag) != std::string::npos);
  for (const std::string rate : {"1e7", "1e9", "1e12", "1e300"}) {
    CAPTURE(rate);
    std::string fast = text;
    fast.replace(fast.find(rate_tag), rate_tag.size(), "<SampleRate>" + rate + "</SampleRate>");
    const fs::path file = tmp / ("rate_" + rate + ".xml");
    std::ofstream(file, std::ios::binary) << fast;
    const auto start = std::chrono::steady_clock::now();
    const Run r = run({"--hatt", file.string(), "--wav", (tmp / "fast.wav").string(), "--seconds", "1"}, "rate_" + rate,
                      std::chrono::seconds(20));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    CAPTURE(r.err, seconds);
    CHECK(r.status == 1);
    CHECK(r.err.rfind("vibration: ", 0) == 0);
    CHECK(r.err.find(file.string()) != std::string::npos);
    CHECK(r.err.find("<SampleRate> " + rate + " Hz is outside 100..100000 Hz") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.out.empty());
    CHECK(seconds < 10.0);  // a refusal, not a stroke (generous for a loaded machine)
  }
}
