// The options the example tools share (tools/common/cli.hpp,
// mask_options.hpp, servo_options.hpp and tools/view/view_options.hpp): the
// one positional input, --max-mpx, a whole --rate, --mask/--size/--border,
// --view/--distance, --realtime, --clock and its arm, the --seconds floor. Random
// command lines against a walk of the same tokens by the rules the usage
// texts state.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/cli.hpp"
#include "common/mask_options.hpp"
#include "common/servo_options.hpp"
#include "hapticfield/devices/open_device.hpp"
#include "run_seed.hpp"
#include "view/view_options.hpp"

namespace {

using namespace hapticfield;

/// argv for a Parser: "tool" then the tokens.
struct Argv {
  explicit Argv(std::vector<std::string> tokens) : words(std::move(tokens)) {
    words.insert(words.begin(), "tool");
    for (std::string& w : words)
      pointers.push_back(w.data());
  }
  [[nodiscard]] cli::Parser parser() { return {static_cast<int>(pointers.size()), pointers.data()}; }
  std::vector<std::string> words;
  std::vector<char*> pointers;
};

/// Runs f(parser) on the tokens; the UsageError's text, or "" when none.
template <class F>
std::string usage_error(const std::vector<std::string>& tokens, F&& f) {
  Argv argv(tokens);
  cli::Parser p = argv.parser();
  try {
    f(p);
  } catch (const cli::UsageError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("a tool's one input: the one value among its flags; none or two are one usage error naming it") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  // "--flag" takes no value, "--size" one; "-q" and "--bogus" are unknown;
  // "-" and "" are values (a lone '-' is stdin to some tools).
  const std::vector<std::string> pool = {"--flag", "--size", "-q", "--bogus", "a.png", "b.png", "-", "", "x y.png"};
  for (int trial = 0; trial < 5000; ++trial) {
    std::vector<std::string> tokens(std::uniform_int_distribution<std::size_t>(0, 6)(rng));
    for (std::string& t : tokens)
      t = pool[std::uniform_int_distribution<std::size_t>(0, pool.size() - 1)(rng)];
    CAPTURE(tokens);

    // the oracle: a walk by the usage's rules, to the first error
    std::string expected;
    std::vector<std::string> values;
    for (std::size_t i = 0; i < tokens.size() && expected.empty(); ++i) {
      const std::string& t = tokens[i];
      if (t == "--flag") continue;
      if (t == "--size") {
        if (i + 1 == tokens.size()) expected = "--size needs a value";
        ++i;
      } else if (t.size() >= 2 && t[0] == '-') {
        expected = "unknown option '" + t + "'";
      } else if (!values.empty()) {
        expected = "more than one IMAGE given ('" + values.front() + "', '" + t + "')";
      } else {
        values.push_back(t);
      }
    }
    if (expected.empty() && values.empty()) expected = "no IMAGE given";

    std::optional<std::string> got;
    const std::string error = usage_error(tokens, [&](cli::Parser& p) {
      cli::Input image("IMAGE");
      while (p.next()) {
        if (p.is("--flag"))
          continue;
        else if (p.is("--size"))
          (void)p.value();
        else
          p.input_or_unknown(image);
      }
      CHECK(image.given() == !values.empty());
      got = image.required();
    });
    CHECK(error == expected);
    if (expected.empty()) {
      REQUIRE(got.has_value());
      CHECK(*got == values.front());
    }
  }
}

TEST_CASE("an optional input: value() is empty and given() false when none is given") {
  const std::string error = usage_error({"--flag"}, [](cli::Parser& p) {
    cli::Input image("IMAGE");
    while (p.next())
      if (!p.is("--flag")) p.input_or_unknown(image);
    CHECK_FALSE(image.given());
    CHECK(image.value().empty());
    CHECK(image.name() == "IMAGE");
  });
  CHECK(error.empty());
}

TEST_CASE("whole(): a real number that is whole and in range, else one message naming the flag and the unit") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  const cli::Interval range = cli::closed(8000.0, 192000.0);
  for (int trial = 0; trial < 5000; ++trial) {
    double x = std::uniform_real_distribution<double>(0.0, 250000.0)(rng);
    if (trial % 2 == 0) x = std::round(x);  // half of them whole
    char text[64];
    std::snprintf(text, sizeof text, trial % 3 == 0 ? "%.17g" : "%.6e", x);
    const double written = std::strtod(text, nullptr);  // what the tool reads
    CAPTURE(text);
    double got = -1.0;
    const std::string error = usage_error({"--rate", text}, [&](cli::Parser& p) {
      REQUIRE(p.next());
      got = p.whole(range, "Hz");
    });
    if (!range.contains(written)) {
      CHECK(error == "--rate must be in [8000, 192000], got '" + std::string(text) + "'");
    } else if (written != std::floor(written)) {
      CHECK(error == "--rate must be a whole number of Hz, got '" + std::string(text) + "'");
    } else {
      CHECK(error.empty());
      CHECK(got == written);
    }
  }
}

TEST_CASE("megapixels(): --max-mpx in (0, 1e6] millions of pixels, as a pixel count") {
  const auto pixels = [](const std::string& text) {
    std::uint64_t n = 0;
    const std::string error = usage_error({"--max-mpx", text}, [&](cli::Parser& p) {
      REQUIRE(p.next());
      n = p.megapixels();
    });
    return error.empty() ? std::optional<std::uint64_t>(n) : std::nullopt;
  };
  CHECK(pixels("0.001") == 1000u);
  CHECK(pixels("100") == 100000000u);
  CHECK(pixels("1e6") == 1000000000000u);
  CHECK_FALSE(pixels("0"));
  CHECK_FALSE(pixels("-1"));
  CHECK_FALSE(pixels("1e6.5"));
  CHECK_FALSE(pixels("2e6"));
  CHECK(usage_error({"--max-mpx", "0"}, [](cli::Parser& p) {
          REQUIRE(p.next());
          (void)p.megapixels();
        }) == "--max-mpx must be in (0, 1e6], got '0'");
}

TEST_CASE(
    "--view and --distance: yaw in [-180, 180], pitch in [-89, 89] degrees, else one message; aim() turns "
    "the camera") {
  std::uniform_int_distribution<int> degrees(-200, 200);  // [degrees], beyond both ranges
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 3000; ++trial) {
    const int yaw = degrees(rng), pitch = degrees(rng);
    const std::string text = std::to_string(yaw) + "," + std::to_string(pitch);
    CAPTURE(text);
    view::ViewOptions options;
    const std::string error = usage_error({"--view", text}, [&](cli::Parser& p) {
      REQUIRE(p.next());
      const bool taken = options.take(p);  // throws for a bad value
      CHECK(taken);
    });
    if (std::abs(yaw) > 180 || std::abs(pitch) > 180) {
      CHECK(error == "--view values must be in [-180, 180], got '" + text + "'");
    } else if (std::abs(pitch) > 89) {
      CHECK(error == "--view pitch must be in [-89, 89] degrees, got " + std::to_string(pitch));
    } else {
      CHECK(error.empty());
      view::OrbitCamera camera;
      camera.distance = 0.123;
      options.aim(camera);
      CHECK(camera.yaw == Approx(yaw * std::numbers::pi / 180.0));
      CHECK(camera.pitch == Approx(pitch * std::numbers::pi / 180.0));
      CHECK(camera.distance == 0.123);  // no --distance: the tool's own
    }
  }
  view::ViewOptions options;
  CHECK(usage_error({"--distance", "250", "--other"}, [&](cli::Parser& p) {
          REQUIRE(p.next());
          CHECK(options.take(p));
          REQUIRE(p.next());
          CHECK_FALSE(options.take(p));  // not its flag: left to the tool
        }).empty());
  view::OrbitCamera camera;
  options.aim(camera);
  CHECK(camera.distance == Approx(0.25));
  CHECK(usage_error({"--distance", "0.5"}, [&](cli::Parser& p) {
          REQUIRE(p.next());
          (void)options.take(p);
        }) == "--distance must be in [1, 100000], got '0.5'");
}

TEST_CASE("--mask, --size and --border: the mask's own size without --size, a size that does not suit it refused") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 3000; ++trial) {
    const MaskKind mask = mask_kinds[std::uniform_int_distribution<std::size_t>(0, mask_kinds.size() - 1)(rng)];
    const Border border = border_kinds[std::uniform_int_distribution<std::size_t>(0, border_kinds.size() - 1)(rng)];
    const bool size_given = trial % 3 != 0;
    const int size = std::uniform_int_distribution<int>(1, 40)(rng);
    std::vector<std::string> tokens = {"--border", std::string(to_string(border)), "--other", "--mask",
                                       std::string(to_string(mask))};
    if (size_given) tokens.insert(tokens.begin(), {"--size", std::to_string(size)});
    CAPTURE(tokens);
    // the oracle: the mask's default size, and the library's own check
    const int expected_size = size_given ? size : default_mask_size(mask);
    std::string expected_error;
    try {
      validate_mask_size(mask, expected_size);
    } catch (const std::invalid_argument& e) {
      expected_error = std::string("--size: ") + e.what();
    }
    TangibleConfig config;
    config.sigma = 2.5;  // not a mask flag: kept
    int others = 0;
    const std::string error = usage_error(tokens, [&](cli::Parser& p) {
      cli::MaskOptions options;
      while (p.next())
        if (!options.take(p)) ++others;
      config = options.apply(config);
    });
    CHECK(others == 1);
    CHECK(error == expected_error);
    if (expected_error.empty()) {
      CHECK(config.mask == mask);
      CHECK(config.border == border);
      CHECK(config.size == expected_size);
      CHECK(config.sigma == 2.5);
    }
  }
  CHECK(usage_error({"--mask", "fancy"}, [](cli::Parser& p) {
          REQUIRE(p.next());
          cli::MaskOptions options;
          (void)options.take(p);
        }).rfind("--mask: unknown mask 'fancy' (one of prewitt, ", 0) == 0);
}

TEST_CASE("--realtime and --clock: their names, and nothing else") {
  const auto realtime = [](const std::string& text, RealTime& out) {
    return usage_error({"--realtime", text}, [&](cli::Parser& p) {
      REQUIRE(p.next());
      out = cli::realtime_option(p);
    });
  };
  RealTime mode = RealTime::off;
  CHECK(realtime("enforce", mode).empty());
  CHECK(mode == RealTime::enforce);
  CHECK(realtime("best_effort", mode).empty());
  CHECK(mode == RealTime::best_effort);
  CHECK(realtime("off", mode).empty());
  CHECK(mode == RealTime::off);
  CHECK(realtime("sometimes", mode) ==
        "--realtime: unknown real-time mode 'sometimes' (one of off, best_effort, enforce)");

  bool virtual_clock = false;
  const auto clock = [&](const std::string& text) {
    return usage_error({"--clock", text}, [&](cli::Parser& p) {
      REQUIRE(p.next());
      virtual_clock = cli::virtual_clock_option(p);
    });
  };
  CHECK(clock("virtual").empty());
  CHECK(virtual_clock);
  CHECK(clock("wall").empty());
  CHECK_FALSE(virtual_clock);
  CHECK(clock("sundial") == "--clock: unknown clock 'sundial' (one of wall, virtual)");
}

TEST_CASE("--clock virtual goes with a simulated arm only, and the message names the arm's flag") {
  const auto check = [](bool virtual_clock, const std::string& device, const char* flag) {
    try {
      cli::check_clock_fits_arm(virtual_clock, parse_device_spec(device), flag);
    } catch (const cli::UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  for (const char* simulated : {"sim", "woody:p4:sim", "inverse3:sim"}) {
    CHECK(check(true, simulated, "--device").empty());
    CHECK(check(false, simulated, "--device").empty());
  }
  CHECK(check(false, "hid", "--device").empty());
  CHECK(check(true, "hid", "--device") ==
        "--clock virtual needs a simulated arm (--device sim, woody:GEN[:PRESET]:sim or inverse3:sim); --device 'hid' "
        "is a real arm, which runs on the wall clock");
  CHECK(check(true, "serial:/dev/null", "--student").find("--student 'serial:/dev/null' is a real arm") !=
        std::string::npos);
}

TEST_CASE("--seconds must hold at least one tick at the loop's rate") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 5000; ++trial) {
    const double rate = std::uniform_real_distribution<double>(1.0, 10000.0)(rng);
    const double seconds = std::exp(std::uniform_real_distribution<double>(std::log(1e-6), std::log(10.0))(rng));
    CAPTURE(rate, seconds);
    std::string error;
    try {
      cli::check_at_least_one_tick(seconds, rate);
    } catch (const cli::UsageError& e) {
      error = e.what();
    }
    // one tick or more: seconds x rate rounds to 1 or more (0.5 rounds up)
    if (seconds * rate >= 0.5) {
      CHECK(error.empty());
    } else {
      CHECK(error.find("is less than one tick at") != std::string::npos);
      CHECK(error.find("the minimum is") != std::string::npos);
    }
  }
  try {
    cli::check_at_least_one_tick(0.0001, 1000.0);
    FAIL("no error");
  } catch (const cli::UsageError& e) {
    CHECK(std::string(e.what()) == "--seconds 0.0001 is less than one tick at 1000 Hz; the minimum is 0.0005 s");
  }
}
