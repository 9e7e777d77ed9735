// libFuzzer target for the report decoders and ForceArm::read: every report
// type is decoded from the raw input, then the input is cut into reports
// (first byte of each chunk = its length) and streamed through ForceArm.
// Built with clang -fsanitize=fuzzer (HAPTICFIELD_FUZZ=ON); the seed corpus
// also runs as a plain ctest test through corpus_runner.cpp.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>

#include "hapticfield/arms.hpp"
#include "hapticfield/transport.hpp"

namespace {

using namespace hapticfield;

/// Serves the fuzz input as a queue of input reports; reports are copied to
/// a heap buffer of exactly their size so ASan sees any over-read.
class ChunkTransport final : public Transport {
 public:
  ChunkTransport(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int) noexcept override {
    if (at_ >= size_) return Status::no_data;
    std::size_t n = data_[at_++];
    if (n > size_ - at_) n = size_ - at_;
    if (n > buffer.size()) n = buffer.size();
    std::memcpy(buffer.data(), data_ + at_, n);
    at_ += n;
    size = n;
    return Status::ok;
  }
  Status write(std::span<const std::uint8_t>) noexcept override { return Status::ok; }
  Status get_feature(std::span<std::uint8_t>, std::size_t&) noexcept override { return Status::unsupported; }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::unsupported; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_{0};
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Exactly-sized copy: a decoder reading past the end trips ASan.
  auto* copy = static_cast<std::uint8_t*>(std::malloc(size ? size : 1));
  if (size) std::memcpy(copy, data, size);
  const std::span<const std::uint8_t> in(copy, size);
  protocol::StateReport s;
  protocol::CommandReport c;
  protocol::DeviceInfoReport i;
  protocol::ConfigurationReport g;
  protocol::ControlOp op;
  if (protocol::decode(in, s) == Status::ok) {
    std::array<std::uint8_t, 64> out{};
    protocol::encode(s, out);
    if (std::memcmp(out.data(), copy, protocol::state_size) != 0) std::abort();  // round trip must be exact
  }
  (void)protocol::decode(in, c);
  (void)protocol::decode(in, i);
  (void)protocol::decode(in, g);
  (void)protocol::decode(in, op);
  (void)protocol::crc16(in);
  std::free(copy);

  ChunkTransport transport(data, size);
  ForceArmConfig options;
  options.query_device = false;
  ForceArm arm(transport, options);
  DeviceState state;
  for (int k = 0; k < 4; ++k) {
    if (arm.read(state) == Status::ok) {
      if (!std::isfinite(state.position.x) || !std::isfinite(state.velocity.x)) std::abort();
    }
    (void)arm.write({0.0, 1.0, 0.0});
  }
  return 0;
}
