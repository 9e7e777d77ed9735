// The tools that drive a simulated arm, on simulated time (--clock virtual):
// the same ticks and trace whatever the machine's load, far faster than real
// time, and refused for a real arm.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"

using hapticfield::testing::Child;
using hapticfield::testing::slurp;
namespace fs = std::filesystem;

namespace {

const fs::path tmp = fs::path(HAPTICFIELD_TEST_TMP) / "tools_virtual_clock";

/// Runs a tool to its end (bounded) and returns its stdout; fails on a non-zero exit.
std::string run_tool(const std::string& tool, const std::vector<std::string>& args, const std::string& name) {
  Child child(tool, args, tmp, name);
  CAPTURE(name, child.err());
  REQUIRE(child.wait());
  REQUIRE(child.exited_normally());
  CHECK(child.status() == 0);
  return child.out();
}

/// The lines of a servo_demo trace, header first.
std::vector<std::string> trace_rows(const fs::path& csv) {
  std::istringstream in(slurp(csv));
  std::vector<std::string> rows;
  for (std::string line; std::getline(in, line);)
    rows.push_back(line);
  return rows;
}

}  // namespace

TEST_CASE("servo_demo --clock virtual: 60 s of the simulated arm, the same trace on every run") {
  const std::vector<std::string> common = {"--seconds", "60", "--clock", "virtual", "--realtime", "best_effort"};
  std::vector<std::string> a = common, b = common;
  a.insert(a.end(), {"--trace", (tmp / "a.csv").string()});
  b.insert(b.end(), {"--trace", (tmp / "b.csv").string()});
  const std::string out = run_tool(HAPTICFIELD_TOOL_SERVO_DEMO, a, "demo_a");
  (void)run_tool(HAPTICFIELD_TOOL_SERVO_DEMO, b, "demo_b");
  CAPTURE(out);
  // Every tick at its deadline: 60000 ticks at exactly 1000 Hz, none late, no latch.
  CHECK(out.find("60000 ticks at 1000.000 Hz") != std::string::npos);
  CHECK(out.find("late ticks 0 (0 periods skipped)") != std::string::npos);
  CHECK(out.find("safety: no latch") != std::string::npos);
  CHECK(out.find("simulated time: 60.000 s") != std::string::npos);
  // Into a pipe the status comes as whole lines, never redrawn with '\r'.
  CHECK(out.find('\r') == std::string::npos);
  CHECK(out.find(" | rate ") != std::string::npos);
  const std::vector<std::string> rows_a = trace_rows(tmp / "a.csv"), rows_b = trace_rows(tmp / "b.csv");
  REQUIRE(rows_a.size() == 60001);  // a header and a row per tick
  CHECK(rows_a == rows_b);          // bit for bit, whatever the load was during either run
  // The hand pressed on the picture: the trace carries real forces, not zeros.
  bool pushed = false;
  for (std::size_t i = 1; i < rows_a.size() && !pushed; ++i) {
    std::istringstream row(rows_a[i]);
    std::vector<double> v;
    for (std::string cell; std::getline(row, cell, ',');)
      v.push_back(std::stod(cell));
    REQUIRE(v.size() == 10);  // t, x, y, z, fx, fy, fz, period, homed, armed
    pushed = v[6] > 1.0;      // fz [N]: the wall holds the hand
  }
  CHECK(pushed);
}

TEST_CASE("--clock virtual is refused for a real arm, and a bad clock name is a usage error") {
  struct Case {
    std::vector<std::string> args;
    int status;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"--clock", "virtual", "--device", "serial:/dev/null"}, 2, "--clock virtual needs a simulated arm"},
      {{"--clock", "virtual", "--device", "hid"}, 2, "--clock virtual needs a simulated arm"},
      {{"--clock", "virtual", "--device", "inverse3:/dev/null"}, 2, "--clock virtual needs a simulated arm"},
      {{"--clock", "virtual", "--device", "woody:p4:/dev/null"}, 2, "--clock virtual needs a simulated arm"},
      {{"--clock", "sundial"}, 2, "--clock"},
  };
  for (const Case& c : cases) {
    Child child(HAPTICFIELD_TOOL_SERVO_DEMO, c.args, tmp, "refused");
    REQUIRE(child.wait());
    const std::string err = child.err();
    CAPTURE(c.args, err);
    CHECK(child.status() == c.status);
    CHECK(err.find(c.says) != std::string::npos);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
  }
}

TEST_CASE("two_arms --clock virtual: a fault, its recovery and the tracking figures are the same on every run") {
  const std::vector<std::string> args = {"--seconds", "20", "--clock", "virtual", "--fault"};
  const std::string a = run_tool(HAPTICFIELD_TOOL_TWO_ARMS, args, "arms_a");
  const std::string b = run_tool(HAPTICFIELD_TOOL_TWO_ARMS, args, "arms_b");
  CAPTURE(a);
  CHECK(a == b);  // every figure printed, to the last digit
  CHECK(a.find("20000 ticks at 1000.00 Hz") != std::string::npos);
  CHECK(a.find("late ticks 0") != std::string::npos);
  // The stall at 1 s latches the student (stale state), and it recovers for real.
  CHECK(a.find("latched at 1.0") != std::string::npos);
  CHECK(a.find("recovered: latch and device fault cleared") != std::string::npos);
}
