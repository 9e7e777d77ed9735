#pragma once
/// @file version.hpp

#define HAPTICFIELD_VERSION_MAJOR 0
#define HAPTICFIELD_VERSION_MINOR 1
#define HAPTICFIELD_VERSION_PATCH 0

namespace hapticfield {
inline constexpr int version_major = HAPTICFIELD_VERSION_MAJOR;
inline constexpr int version_minor = HAPTICFIELD_VERSION_MINOR;
inline constexpr int version_patch = HAPTICFIELD_VERSION_PATCH;
}  // namespace hapticfield
