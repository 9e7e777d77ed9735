#pragma once
/// @file hd_api.hpp
/// The part of the OpenHaptics HDAPI (3D Systems Touch, Phantom) the
/// adapter calls, declared from the documented facts (types, values and C
/// signatures of hdDefines.h, hdDevice.h and hdScheduler.h; see
/// docs/arms-openhaptics.md) and loaded at run time from libHD.so. No vendor
/// header is used. The utility layer (HDU) is a static library and cannot
/// be loaded: nothing here needs it.

#include <climits>
#include <cstdint>
#include <cstdio>
#include <string>

#include "hapticfield/arms/dynamic_library.hpp"

namespace hapticfield::hd {

// Types (hdDefines.h). HDCALLBACK/HDAPIENTRY are the default C calling
// convention on Linux (stdcall only on Windows).
using Handle = unsigned int;               ///< HHD
using Enum = unsigned int;                 ///< HDenum
using ErrorCode = unsigned int;            ///< HDerror
using Boolean = unsigned char;             ///< HDboolean
using UShort = unsigned short;             ///< HDushort
using ULong = unsigned long;               ///< HDulong
using SchedulerHandle = unsigned long;     ///< HDSchedulerHandle
using CallbackCode = unsigned int;         ///< HDCallbackCode
using String = const char*;                ///< HDstring
using Callback = CallbackCode (*)(void*);  ///< HDSchedulerCallback

/// HDErrorInfo, returned by value from hdGetError(): 12 bytes.
struct ErrorInfo {
  ErrorCode error_code;     ///< errorCode
  int internal_error_code;  ///< internalErrorCode (vendor-specific)
  Handle device;            ///< hHD
};
static_assert(sizeof(ErrorInfo) == 12, "HDErrorInfo is three 4-byte fields");

inline constexpr String default_device = nullptr;  ///< HD_DEFAULT_DEVICE

// Callback, wait and priority codes (hdScheduler.h).
inline constexpr CallbackCode callback_done = 0;             ///< HD_CALLBACK_DONE
inline constexpr CallbackCode callback_continue = 1;         ///< HD_CALLBACK_CONTINUE
inline constexpr unsigned int wait_check_status = 0;         ///< HD_WAIT_CHECK_STATUS
inline constexpr unsigned int wait_infinite = 1;             ///< HD_WAIT_INFINITE
inline constexpr UShort min_scheduler_priority = 0;          ///< HD_MIN_SCHEDULER_PRIORITY
inline constexpr UShort max_scheduler_priority = USHRT_MAX;  ///< HD_MAX_SCHEDULER_PRIORITY
inline constexpr UShort default_scheduler_priority = (max_scheduler_priority + min_scheduler_priority) / 2;  ///< 32767
inline constexpr Handle invalid_handle = 0xFFFFFFFFu;  ///< HD_INVALID_HANDLE
inline constexpr ErrorCode success = 0;                ///< HD_SUCCESS

// Get/set parameters (hdDefines.h).
inline constexpr Enum current_buttons = 0x2000;         ///< HD_CURRENT_BUTTONS (int bit mask)
inline constexpr Enum current_safety_switch = 0x2001;   ///< HD_CURRENT_SAFETY_SWITCH
inline constexpr Enum current_inkwell_switch = 0x2002;  ///< HD_CURRENT_INKWELL_SWITCH
inline constexpr Enum current_position = 0x2050;        ///< HD_CURRENT_POSITION, 3 doubles [mm]
inline constexpr Enum current_velocity = 0x2051;        ///< HD_CURRENT_VELOCITY, 3 doubles [mm/s]
inline constexpr Enum current_transform = 0x2052;  ///< HD_CURRENT_TRANSFORM, 16 doubles column-major, translation [mm]
inline constexpr Enum current_angular_velocity = 0x2053;      ///< HD_CURRENT_ANGULAR_VELOCITY
inline constexpr Enum current_jacobian = 0x2054;              ///< HD_CURRENT_JACOBIAN
inline constexpr Enum current_joint_angles = 0x2100;          ///< HD_CURRENT_JOINT_ANGLES [rad]
inline constexpr Enum current_gimbal_angles = 0x2150;         ///< HD_CURRENT_GIMBAL_ANGLES [rad]
inline constexpr Enum last_offset = 0x200;                    ///< HD_LAST_x = HD_CURRENT_x + 0x200 in the state block
inline constexpr Enum device_model_type = 0x2501;             ///< HD_DEVICE_MODEL_TYPE (string)
inline constexpr Enum device_serial_number = 0x2504;          ///< HD_DEVICE_SERIAL_NUMBER (string)
inline constexpr Enum max_workspace_dimensions = 0x2550;      ///< HD_MAX_WORKSPACE_DIMENSIONS, 6 doubles [mm]
inline constexpr Enum usable_workspace_dimensions = 0x2551;   ///< HD_USABLE_WORKSPACE_DIMENSIONS, min xyz, max xyz [mm]
inline constexpr Enum update_rate = 0x2600;                   ///< HD_UPDATE_RATE [Hz]
inline constexpr Enum instantaneous_update_rate = 0x2601;     ///< HD_INSTANTANEOUS_UPDATE_RATE [Hz]
inline constexpr Enum nominal_max_stiffness = 0x2602;         ///< HD_NOMINAL_MAX_STIFFNESS [N/mm]
inline constexpr Enum nominal_max_force = 0x2603;             ///< HD_NOMINAL_MAX_FORCE [N]
inline constexpr Enum nominal_max_continuous_force = 0x2604;  ///< HD_NOMINAL_MAX_CONTINUOUS_FORCE [N]
inline constexpr Enum motor_temperature = 0x2605;             ///< HD_MOTOR_TEMPERATURE
inline constexpr Enum software_velocity_limit = 0x2606;       ///< HD_SOFTWARE_VELOCITY_LIMIT
inline constexpr Enum software_force_impulse_limit = 0x2607;  ///< HD_SOFTWARE_FORCE_IMPULSE_LIMIT
inline constexpr Enum force_ramping_rate = 0x2608;            ///< HD_FORCE_RAMPING_RATE
inline constexpr Enum nominal_max_damping = 0x2609;           ///< HD_NOMINAL_MAX_DAMPING
inline constexpr Enum current_force = 0x2700;                 ///< HD_CURRENT_FORCE, 3 doubles [N]
inline constexpr Enum current_torque = 0x2701;                ///< HD_CURRENT_TORQUE (deprecated) [mN m]
inline constexpr Enum current_joint_torque = 0x2703;          ///< HD_CURRENT_JOINT_TORQUE
inline constexpr Enum current_gimbal_torque = 0x2704;         ///< HD_CURRENT_GIMBAL_TORQUE
inline constexpr Enum last_force = current_force + 0x100;     ///< HD_LAST_FORCE (0x2800)

// Capabilities for hdEnable/hdDisable: enum values, not bit flags.
inline constexpr Enum force_output = 0x4000;          ///< HD_FORCE_OUTPUT
inline constexpr Enum max_force_clamping = 0x4001;    ///< HD_MAX_FORCE_CLAMPING
inline constexpr Enum force_ramping = 0x4002;         ///< HD_FORCE_RAMPING
inline constexpr Enum software_force_limit = 0x4003;  ///< HD_SOFTWARE_FORCE_LIMIT
inline constexpr Enum one_frame_limit = 0x4004;       ///< HD_ONE_FRAME_LIMIT

// hdCheckCalibration results.
inline constexpr Enum calibration_ok = 0x5000;                  ///< HD_CALIBRATION_OK
inline constexpr Enum calibration_needs_update = 0x5001;        ///< HD_CALIBRATION_NEEDS_UPDATE
inline constexpr Enum calibration_needs_manual_input = 0x5002;  ///< HD_CALIBRATION_NEEDS_MANUAL_INPUT

// Error codes.
inline constexpr ErrorCode invalid_enum = 0x100;                ///< HD_INVALID_ENUM
inline constexpr ErrorCode bad_handle = 0x104;                  ///< HD_BAD_HANDLE
inline constexpr ErrorCode warm_motors = 0x200;                 ///< HD_WARM_MOTORS
inline constexpr ErrorCode exceeded_max_force = 0x201;          ///< HD_EXCEEDED_MAX_FORCE
inline constexpr ErrorCode exceeded_max_force_impulse = 0x202;  ///< HD_EXCEEDED_MAX_FORCE_IMPULSE
inline constexpr ErrorCode exceeded_max_velocity = 0x203;       ///< HD_EXCEEDED_MAX_VELOCITY
inline constexpr ErrorCode force_error = 0x204;                 ///< HD_FORCE_ERROR
inline constexpr ErrorCode device_fault = 0x300;                ///< HD_DEVICE_FAULT
inline constexpr ErrorCode device_already_initiated = 0x301;    ///< HD_DEVICE_ALREADY_INITIATED
inline constexpr ErrorCode comm_error = 0x302;                  ///< HD_COMM_ERROR
inline constexpr ErrorCode timer_error = 0x304;                 ///< HD_TIMER_ERROR
inline constexpr ErrorCode illegal_begin = 0x400;               ///< HD_ILLEGAL_BEGIN
inline constexpr ErrorCode scheduler_full = 0x501;              ///< HD_SCHEDULER_FULL
inline constexpr ErrorCode invalid_license = 0x600;             ///< HD_INVALID_LICENSE

/// The names libHD is loaded by: the unversioned name, as the SDK installs
/// it (/usr/lib/libHD.so) and as CHAI3D and pyOpenHaptics load it.
inline const char* const library_name = "libHD.so";
/// Environment variable naming another libHD to load instead.
inline const char* const library_variable = "HAPTICFIELD_HD_LIBRARY";

/// The HDAPI functions the adapter calls, resolved from the library; every
/// one is required.
struct Api {
  DynamicLibrary library;
  Handle (*init_device)(String){};                                      ///< hdInitDevice
  void (*make_current_device)(Handle){};                                ///< hdMakeCurrentDevice
  Handle (*get_current_device)(){};                                     ///< hdGetCurrentDevice
  void (*disable_device)(Handle){};                                     ///< hdDisableDevice
  void (*begin_frame)(Handle){};                                        ///< hdBeginFrame
  void (*end_frame)(Handle){};                                          ///< hdEndFrame
  void (*get_integerv)(Enum, int*){};                                   ///< hdGetIntegerv
  void (*get_doublev)(Enum, double*){};                                 ///< hdGetDoublev
  String (*get_string)(Enum){};                                         ///< hdGetString
  void (*set_doublev)(Enum, const double*){};                           ///< hdSetDoublev
  void (*enable)(Enum){};                                               ///< hdEnable
  void (*disable)(Enum){};                                              ///< hdDisable
  ErrorInfo (*get_error)(){};                                           ///< hdGetError
  String (*get_error_string)(ErrorCode){};                              ///< hdGetErrorString
  Enum (*check_calibration)(){};                                        ///< hdCheckCalibration
  void (*start_scheduler)(){};                                          ///< hdStartScheduler
  void (*stop_scheduler)(){};                                           ///< hdStopScheduler
  void (*set_scheduler_rate)(ULong){};                                  ///< hdSetSchedulerRate
  SchedulerHandle (*schedule_asynchronous)(Callback, void*, UShort){};  ///< hdScheduleAsynchronous
  void (*unschedule)(SchedulerHandle){};                                ///< hdUnschedule

  /// Loads libHD (or $HAPTICFIELD_HD_LIBRARY, or library_path when not
  /// empty) and resolves every function above.
  /// @throws LibraryError naming the library or the missing symbol.
  [[nodiscard]] static Api load(const std::string& library_path = {}) {
    Api a;
    a.library = library_path.empty() ? DynamicLibrary::open_first("OpenHaptics HD", {library_name}, library_variable)
                                     : DynamicLibrary::open_first("OpenHaptics HD", {library_path});
    const DynamicLibrary& l = a.library;
    a.init_device = l.get<decltype(a.init_device)>("hdInitDevice");
    a.make_current_device = l.get<decltype(a.make_current_device)>("hdMakeCurrentDevice");
    a.get_current_device = l.get<decltype(a.get_current_device)>("hdGetCurrentDevice");
    a.disable_device = l.get<decltype(a.disable_device)>("hdDisableDevice");
    a.begin_frame = l.get<decltype(a.begin_frame)>("hdBeginFrame");
    a.end_frame = l.get<decltype(a.end_frame)>("hdEndFrame");
    a.get_integerv = l.get<decltype(a.get_integerv)>("hdGetIntegerv");
    a.get_doublev = l.get<decltype(a.get_doublev)>("hdGetDoublev");
    a.get_string = l.get<decltype(a.get_string)>("hdGetString");
    a.set_doublev = l.get<decltype(a.set_doublev)>("hdSetDoublev");
    a.enable = l.get<decltype(a.enable)>("hdEnable");
    a.disable = l.get<decltype(a.disable)>("hdDisable");
    a.get_error = l.get<decltype(a.get_error)>("hdGetError");
    a.get_error_string = l.get<decltype(a.get_error_string)>("hdGetErrorString");
    a.check_calibration = l.get<decltype(a.check_calibration)>("hdCheckCalibration");
    a.start_scheduler = l.get<decltype(a.start_scheduler)>("hdStartScheduler");
    a.stop_scheduler = l.get<decltype(a.stop_scheduler)>("hdStopScheduler");
    a.set_scheduler_rate = l.get<decltype(a.set_scheduler_rate)>("hdSetSchedulerRate");
    a.schedule_asynchronous = l.get<decltype(a.schedule_asynchronous)>("hdScheduleAsynchronous");
    a.unschedule = l.get<decltype(a.unschedule)>("hdUnschedule");
    return a;
  }

  /// "HD_COMM_ERROR (0x302): <the library's text>" for an error code.
  [[nodiscard]] std::string describe(ErrorCode e) const {
    const char* name = error_name(e);
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%x", e);
    const String text = get_error_string != nullptr ? get_error_string(e) : nullptr;
    return std::string(name) + " (" + hex + ")" + (text != nullptr && *text ? std::string(": ") + text : "");
  }

  /// The documented name of an error code ("HD error" for others).
  [[nodiscard]] static const char* error_name(ErrorCode e) noexcept {
    switch (e) {
      case success:
        return "HD_SUCCESS";
      case invalid_enum:
        return "HD_INVALID_ENUM";
      case bad_handle:
        return "HD_BAD_HANDLE";
      case warm_motors:
        return "HD_WARM_MOTORS";
      case exceeded_max_force:
        return "HD_EXCEEDED_MAX_FORCE";
      case exceeded_max_force_impulse:
        return "HD_EXCEEDED_MAX_FORCE_IMPULSE";
      case exceeded_max_velocity:
        return "HD_EXCEEDED_MAX_VELOCITY";
      case force_error:
        return "HD_FORCE_ERROR";
      case device_fault:
        return "HD_DEVICE_FAULT";
      case device_already_initiated:
        return "HD_DEVICE_ALREADY_INITIATED";
      case comm_error:
        return "HD_COMM_ERROR";
      case timer_error:
        return "HD_TIMER_ERROR";
      case illegal_begin:
        return "HD_ILLEGAL_BEGIN";
      case scheduler_full:
        return "HD_SCHEDULER_FULL";
      case invalid_license:
        return "HD_INVALID_LICENSE";
      default:
        return "HD error";
    }
  }
};

}  // namespace hapticfield::hd
