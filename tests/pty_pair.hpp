#pragma once
// A pseudo-terminal pair for the serial tests: the test plays the device on
// the master side, the transport under test opens the slave by its path.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <pty.h>
#include <unistd.h>

#include <cstdint>
#include <span>
#include <string>

namespace hapticfield::testing {

/// A pseudo-terminal pair; the master is non-blocking.
struct Pty {
  int master{-1};
  int slave{-1};
  std::string path;  ///< the slave's device path, e.g. /dev/pts/3

  Pty() {
    char name[128]{};
    REQUIRE(::openpty(&master, &slave, name, nullptr, nullptr) == 0);
    path = name;
    ::fcntl(master, F_SETFL, ::fcntl(master, F_GETFL) | O_NONBLOCK);
    // Not inherited by a tool started as a child: only this process plays the
    // device, so closing the master hangs the line up for the child.
    ::fcntl(master, F_SETFD, FD_CLOEXEC);
    ::fcntl(slave, F_SETFD, FD_CLOEXEC);
  }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  ~Pty() {
    if (master >= 0) ::close(master);
    if (slave >= 0) ::close(slave);
  }
  /// The device side hangs up.
  void close_master() {
    ::close(master);
    master = -1;
  }
  void write_master(std::span<const std::uint8_t> bytes) const {
    REQUIRE(::write(master, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size()));
  }
  void write_master(const std::string& text) const {
    write_master(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
  }
};

}  // namespace hapticfield::testing
