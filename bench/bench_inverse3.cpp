// bench_inverse3: the per-tick cost of the Inverse3 adapter (read + write:
// decode a 25-byte reply, frame mapping, plausibility, clamp, encode a
// 13-byte request) over a loopback transport, against ForceArm read + write
// over a loopback transport (our own HID/serial protocol) measured in the
// same run as the baseline. Prints a Markdown table.
//
//   bench_inverse3 [--ticks N]   (default 1000000, 1000..100000000)
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "hapticfield/arms.hpp"
#include "hapticfield/servo/clock.hpp"
#include "hapticfield/transport.hpp"
#include "tick_cost.hpp"

using namespace hapticfield;
using hapticfield::bench::Cost;
using hapticfield::bench::ForceArmLoopback;
using hapticfield::bench::measure;

namespace {

/// Answers every 0x2A request with one pre-encoded state reply (a moving
/// position), the wake-up with an identity: Inverse3's own cost, no simulation.
class Inverse3Loopback final : public Transport {
 public:
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int) noexcept override {
    if (owed_ == 0) return Status::no_data;
    --owed_;
    if (frame_ == inverse3::wake_reply_size) {
      size = inverse3::encode_wake_reply(inverse3::Identity{}, buffer);
      return Status::ok;
    }
    reply_.first[0] = static_cast<float>(static_cast<double>(++k_ % 200) * 1e-4);  // [m]
    size = inverse3::encode_state_reply(reply_, buffer);
    return Status::ok;
  }
  Status write(std::span<const std::uint8_t> r) noexcept override {
    ++owed_;
    last_ = r[1];
    return Status::ok;
  }
  Status get_feature(std::span<std::uint8_t>, std::size_t&) noexcept override { return Status::unsupported; }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::unsupported; }
  Status set_frame_size(std::size_t n) noexcept override {
    frame_ = n;
    return Status::ok;
  }

 private:
  inverse3::StateReply reply_{0x2B, {0.0f, 0.1f, 0.05f}, {0.01f, 0.0f, 0.0f}};
  std::size_t frame_{0};
  std::uint64_t k_{0};
  int owed_{0};
  volatile std::uint8_t last_{0};
};

}  // namespace

int main(int argc, char** argv) {
  long n = 1'000'000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf(
          "usage: bench_inverse3 [--ticks N]\n"
          "  --ticks N   ticks timed per path, 1000..100000000 (default 1000000)\n");
      return 0;
    }
    if (a == "--ticks" && i + 1 < argc) {
      char* end = nullptr;
      const long v = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || v < 1000 || v > 100'000'000) {
        std::fprintf(stderr, "bench_inverse3: --ticks expects an integer in 1000..100000000, got '%s'\n", argv[i]);
        return 2;
      }
      n = v;
      continue;
    }
    std::fprintf(stderr, "bench_inverse3: unknown argument '%s' (--help shows the usage)\n", a.c_str());
    return 2;
  }

  ForceArmLoopback force_link;
  ForceArmConfig fo;
  fo.query_device = false;
  ForceArm force_arm(force_link, fo);
  Inverse3Loopback inv_link;
  Inverse3Config ic;
  ic.frame = Inverse3Frame::axes({1, 3, -2}, glm::dvec3{0.0, 0.1, 0.05});
  Inverse3 inv(inv_link, ic);
  inv.set_armed(true);
  DeviceState state;
  const glm::dvec3 f{0.1, 0.2, 0.3};  // [N]

  // Interleaved rounds so that drifts of a shared machine hit both paths alike.
  Cost base{}, adapter{};
  const int rounds = 5;
  for (int r = 0; r < rounds; ++r) {
    const Cost b = measure(n / rounds, [&] {
      force_arm.read(state);
      force_arm.write(f);
    });
    const Cost a = measure(n / rounds, [&] {
      inv.read(state);
      inv.write(f);
    });
    base.mean_ns += b.mean_ns / rounds;
    adapter.mean_ns += a.mean_ns / rounds;
    base.p99_ns = std::max(base.p99_ns, b.p99_ns);
    adapter.p99_ns = std::max(adapter.p99_ns, a.p99_ns);
    base.worst_ns = std::max(base.worst_ns, b.worst_ns);
    adapter.worst_ns = std::max(adapter.worst_ns, a.worst_ns);
  }
  if (inv.counters().implausible != 0 || inv.counters().replies < static_cast<std::uint64_t>(n)) {
    std::fprintf(stderr, "bench_inverse3: the loopback lost replies\n");
    return 1;
  }

  std::printf("## Inverse3 read + write per tick (%ld ticks per path, %d interleaved rounds)\n\n", n, rounds);
  std::printf(
      "| path | mean [ns] | p99 [ns] | worst [ns] | mean / baseline | p99 / baseline | mean / 1 ms |\n"
      "|---|---:|---:|---:|---:|---:|---:|\n");
  const auto row = [&](const char* name, const Cost& c) {
    std::printf("| %s | %.0f | %.0f | %.0f | %.2fx | %.2fx | %.4f %% |\n", name, c.mean_ns, c.p99_ns, c.worst_ns,
                c.mean_ns / base.mean_ns, c.p99_ns / base.p99_ns, c.mean_ns / 1e6 * 100.0);
  };
  row("ForceArm read + write, loopback (baseline)", base);
  row("Inverse3 read + write, loopback", adapter);
  std::printf(
      "\np99 and worst are the largest over the rounds and include the clock reads around each\n"
      "tick and any preemption by other processes.\n");
  return 0;
}
