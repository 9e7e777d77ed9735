#pragma once
/// @file dhd_api.hpp
/// The part of the Force Dimension DHD SDK (omega, delta, sigma, lambda,
/// and the Falcon through it) the adapter calls, declared from the
/// documented facts (values and C signatures of dhdc.h; see
/// docs/arms-dhd.md) and loaded at run time from libdhd.so.3, else
/// libdhd.so. No vendor header is used. The trailing `char ID` of every
/// call is a C++ default argument in the SDK's header, so it is always
/// passed here.

#include <string>

#include "hapticfield/arms/dynamic_library.hpp"

namespace hapticfield::dhd {

// Return codes: calls return 0 on success and -1 on error (the code is
// dhdErrorGetLast(), per thread); positive values are warnings.
inline constexpr int ok = 0;               ///< DHD_NO_ERROR as a return value
inline constexpr int failed = -1;          ///< a call that failed
inline constexpr int timeguard = 1;        ///< DHD_TIMEGUARD: data still fresh, no USB transfer
inline constexpr int motor_saturated = 2;  ///< DHD_MOTOR_SATURATED: the force asked exceeds a motor

// Error codes (dhdErrorGetLast), counted from DHD_NO_ERROR.
inline constexpr int no_error = 0;                    ///< DHD_NO_ERROR
inline constexpr int error = 1;                       ///< DHD_ERROR
inline constexpr int error_com = 2;                   ///< DHD_ERROR_COM
inline constexpr int error_no_device_found = 5;       ///< DHD_ERROR_NO_DEVICE_FOUND
inline constexpr int error_timeout = 7;               ///< DHD_ERROR_TIMEOUT
inline constexpr int error_expert_mode_disabled = 9;  ///< DHD_ERROR_EXPERT_MODE_DISABLED
inline constexpr int error_device_not_ready = 12;     ///< DHD_ERROR_DEVICE_NOT_READY
inline constexpr int error_device_in_use = 20;        ///< DHD_ERROR_DEVICE_IN_USE
inline constexpr int error_no_regulation = 22;        ///< DHD_ERROR_NO_REGULATION

// System types (dhdGetSystemType).
inline constexpr int device_omega3 = 33;          ///< DHD_DEVICE_OMEGA3
inline constexpr int device_falcon = 60;          ///< DHD_DEVICE_FALCON
inline constexpr int device_delta3 = 63;          ///< DHD_DEVICE_DELTA3
inline constexpr int device_sigma7_right = 104;   ///< DHD_DEVICE_SIGMA7_RIGHT
inline constexpr int device_lambda7_right = 108;  ///< DHD_DEVICE_LAMBDA7_RIGHT

inline constexpr unsigned char on = 1;   ///< DHD_ON
inline constexpr unsigned char off = 0;  ///< DHD_OFF

/// The names libdhd is loaded by, in order: the soname the SDK's shared
/// library carries, then the unversioned development name.
inline const char* const library_names[] = {"libdhd.so.3", "libdhd.so"};
/// Environment variable naming another libdhd to load instead.
inline const char* const library_variable = "HAPTICFIELD_DHD_LIBRARY";

/// The DHD functions the adapter calls, resolved from the library.
/// Required ones throw when missing; optional ones (older SDKs) are
/// nullptr then, and the adapter does without them (CHAI3D's Windows
/// driver degrades the same way).
struct Api {
  DynamicLibrary library;
  // required
  int (*get_device_count)(){};                             ///< dhdGetDeviceCount
  int (*open_id)(char){};                                  ///< dhdOpenID
  int (*close)(char){};                                    ///< dhdClose
  int (*get_position)(double*, double*, double*, char){};  ///< dhdGetPosition [m]
  int (*set_force)(double, double, double, char){};        ///< dhdSetForce [N]
  int (*enable_force)(unsigned char, char){};              ///< dhdEnableForce
  int (*error_get_last)(){};                               ///< dhdErrorGetLast
  const char* (*error_get_last_str)(){};                   ///< dhdErrorGetLastStr
  // optional
  int (*get_linear_velocity)(double*, double*, double*, char){};  ///< dhdGetLinearVelocity [m/s]
  const char* (*get_system_name)(char){};                         ///< dhdGetSystemName
  int (*get_system_type)(char){};                                 ///< dhdGetSystemType
  unsigned int (*get_button_mask)(char){};                        ///< dhdGetButtonMask
  int (*stop)(char){};                                            ///< dhdStop (forces and brakes off)

  /// Loads libdhd.so.3, else libdhd.so (or $HAPTICFIELD_DHD_LIBRARY, or
  /// library_path when not empty) and resolves the functions above.
  /// @throws LibraryError naming the library or the missing symbol.
  [[nodiscard]] static Api load(const std::string& library_path = {}) {
    Api a;
    a.library =
        library_path.empty()
            ? DynamicLibrary::open_first("Force Dimension DHD", {library_names[0], library_names[1]}, library_variable)
            : DynamicLibrary::open_first("Force Dimension DHD", {library_path});
    const DynamicLibrary& l = a.library;
    a.get_device_count = l.get<decltype(a.get_device_count)>("dhdGetDeviceCount");
    a.open_id = l.get<decltype(a.open_id)>("dhdOpenID");
    a.close = l.get<decltype(a.close)>("dhdClose");
    a.get_position = l.get<decltype(a.get_position)>("dhdGetPosition");
    a.set_force = l.get<decltype(a.set_force)>("dhdSetForce");
    a.enable_force = l.get<decltype(a.enable_force)>("dhdEnableForce");
    a.error_get_last = l.get<decltype(a.error_get_last)>("dhdErrorGetLast");
    a.error_get_last_str = l.get<decltype(a.error_get_last_str)>("dhdErrorGetLastStr");
    a.get_linear_velocity = l.find<decltype(a.get_linear_velocity)>("dhdGetLinearVelocity");
    a.get_system_name = l.find<decltype(a.get_system_name)>("dhdGetSystemName");
    a.get_system_type = l.find<decltype(a.get_system_type)>("dhdGetSystemType");
    a.get_button_mask = l.find<decltype(a.get_button_mask)>("dhdGetButtonMask");
    a.stop = l.find<decltype(a.stop)>("dhdStop");
    return a;
  }

  /// "<the SDK's text> (error N)" for the calling thread's last error.
  [[nodiscard]] std::string last_error() const {
    const int code = error_get_last != nullptr ? error_get_last() : -1;
    const char* text = error_get_last_str != nullptr ? error_get_last_str() : nullptr;
    return std::string(text != nullptr && *text ? text : "DHD error") + " (error " + std::to_string(code) + ")";
  }
};

}  // namespace hapticfield::dhd
