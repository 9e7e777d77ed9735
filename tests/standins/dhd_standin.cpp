// A stand-in for Force Dimension's libdhd.so.3, built only by the tests:
// the DHD functions the adapter calls, exported with C linkage under their
// documented names (the trailing char ID passed explicitly), with a
// simulated arm behind them and faults on demand. Its numbers are written
// here from the documented values, not taken from the adapter's header.
//
// HFSTANDIN_DHD (comma-separated, read at dhdGetDeviceCount):
//   no_device            dhdGetDeviceCount is 0
//   open_fails           dhdOpenID fails (DHD_ERROR_DEVICE_IN_USE)
//   com_error_at=N       the Nth dhdGetPosition fails (DHD_ERROR_COM)
//   saturate_above=F     dhdSetForce returns DHD_MOTOR_SATURATED above F [N]
//   nan_at=N             dhdGetPosition gives NaN from the Nth call on
//   falcon               dhdGetSystemType is DHD_DEVICE_FALCON (60), else OMEGA3 (33)
//   no_velocity          dhdGetLinearVelocity fails: the adapter differentiates positions
// HFSTANDIN_REPORT=PATH  dhdClose writes what the arm was last told.
// hfstandin_dhd_inject("lose" | "impossible") raises a fault from now on.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#define HF_EXPORT extern "C" __attribute__((visibility("default")))

namespace {

struct Faults {
  bool no_device{false};
  bool open_fails{false};
  long com_error_at{-1};
  double saturate_above{-1.0};
  long nan_at{-1};
  bool falcon{false};
  bool no_velocity{false};
};

Faults faults;
thread_local int last_error = 0;
bool open = false;
bool force_enabled = false;
long position_calls = 0;
double force[3] = {0, 0, 0};       // last force the motors were told [N], DHD frame
long expert_calls = 0;             // dhdSetVelocityThreshold / dhdSetWatchdog / dhdEnableExpertMode
bool injected_lost = false;        // hfstandin_dhd_inject("lose"): every call fails (DHD_ERROR_COM)
bool injected_impossible = false;  // hfstandin_dhd_inject("impossible"): NaN positions

void read_faults() {
  faults = Faults{};
  const char* env = std::getenv("HFSTANDIN_DHD");
  const std::string s = env != nullptr ? env : "";
  std::size_t start = 0;
  while (start <= s.size()) {
    const std::size_t end = s.find(',', start);
    const std::string item = s.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (item == "no_device") faults.no_device = true;
    if (item == "open_fails") faults.open_fails = true;
    if (item == "falcon") faults.falcon = true;
    if (item == "no_velocity") faults.no_velocity = true;
    if (item.rfind("com_error_at=", 0) == 0) faults.com_error_at = std::strtol(item.c_str() + 13, nullptr, 10);
    if (item.rfind("nan_at=", 0) == 0) faults.nan_at = std::strtol(item.c_str() + 7, nullptr, 10);
    if (item.rfind("saturate_above=", 0) == 0) faults.saturate_above = std::strtod(item.c_str() + 15, nullptr);
    if (end == std::string::npos) break;
    start = end + 1;
  }
}

// The simulated arm, in DHD's frame (x toward the operator, y right, z
// up) [m]: a hand draws a 20 mm circle in the y-z plane at 0.5 Hz, one
// step per 1 ms read; the handle gives 1 mm per N.
void hand(long call, double* p, double* v) {
  const double t = static_cast<double>(call) * 1e-3;
  const double w = 2.0 * 3.14159265358979323846 * 0.5;
  p[0] = 0.01 + 0.001 * force[0];
  p[1] = 0.02 * std::cos(w * t) + 0.001 * force[1];
  p[2] = 0.02 * std::sin(w * t) + 0.001 * force[2];
  v[0] = 0.0;
  v[1] = -0.02 * w * std::sin(w * t);
  v[2] = 0.02 * w * std::cos(w * t);
}

int fail(int code) {
  last_error = code;
  return -1;
}

void write_report() {
  const char* path = std::getenv("HFSTANDIN_REPORT");
  if (path == nullptr || *path == '\0') return;
  if (FILE* f = std::fopen(path, "w")) {
    std::fprintf(f, "reads %ld\nlast_force %.9g %.9g %.9g\nforce_enabled %d\nexpert_calls %ld\n", position_calls,
                 force[0], force[1], force[2], force_enabled ? 1 : 0, expert_calls);
    std::fclose(f);
  }
}

}  // namespace

HF_EXPORT int dhdGetDeviceCount() {
  read_faults();
  return faults.no_device ? 0 : 1;
}
HF_EXPORT int dhdOpenID(char id) {
  if (faults.open_fails) return fail(20);  // DHD_ERROR_DEVICE_IN_USE
  if (id != 0) return fail(5);             // DHD_ERROR_NO_DEVICE_FOUND
  open = true;
  injected_lost = injected_impossible = false;
  position_calls = 0;
  force[0] = force[1] = force[2] = 0.0;
  return 0;
}
HF_EXPORT int dhdClose(char) {
  write_report();
  open = false;
  force_enabled = false;
  return 0;
}
HF_EXPORT int dhdGetSystemType(char) {
  return faults.falcon ? 60 : 33;
}
HF_EXPORT const char* dhdGetSystemName(char) {
  return faults.falcon ? "stand-in falcon" : "stand-in omega.3";
}
HF_EXPORT int dhdEnableForce(unsigned char on, char) {
  if (!open) return fail(2);
  force_enabled = on != 0;
  if (!force_enabled) force[0] = force[1] = force[2] = 0.0;
  return 0;
}
HF_EXPORT int dhdGetPosition(double* x, double* y, double* z, char) {
  if (!open) return fail(2);
  const long call = position_calls++;
  if ((faults.com_error_at >= 0 && call >= faults.com_error_at) || injected_lost) return fail(2);  // DHD_ERROR_COM
  double p[3], v[3];
  hand(call, p, v);
  if ((faults.nan_at >= 0 && call >= faults.nan_at) || injected_impossible) p[0] = std::nan("");
  *x = p[0];
  *y = p[1];
  *z = p[2];
  return 0;
}
HF_EXPORT int dhdGetLinearVelocity(double* x, double* y, double* z, char) {
  if (!open) return fail(2);
  if (faults.no_velocity) return fail(1);
  double p[3], v[3];
  hand(position_calls, p, v);
  *x = v[0];
  *y = v[1];
  *z = v[2];
  return 0;
}
HF_EXPORT unsigned int dhdGetButtonMask(char) {
  return 0;
}
HF_EXPORT int dhdSetForce(double fx, double fy, double fz, char) {
  if (!open || injected_lost) return fail(2);
  const double f[3] = {fx, fy, fz};
  const double m = std::sqrt(fx * fx + fy * fy + fz * fz);
  const bool saturated = faults.saturate_above >= 0.0 && m > faults.saturate_above;
  for (int i = 0; i < 3; ++i)
    force[i] = !force_enabled ? 0.0 : saturated ? f[i] * faults.saturate_above / m : f[i];
  return saturated ? 2 : 0;  // DHD_MOTOR_SATURATED
}
HF_EXPORT int dhdStop(char) {
  force_enabled = false;
  force[0] = force[1] = force[2] = 0.0;
  return 0;
}
HF_EXPORT int dhdErrorGetLast() {
  return last_error;
}
HF_EXPORT const char* dhdErrorGetLastStr() {
  switch (last_error) {
    case 2:
      return "stand-in communication error";
    case 5:
      return "stand-in: no device found";
    case 20:
      return "stand-in: device in use";
    default:
      return "stand-in error";
  }
}
// Expert-mode calls the adapter must never make (CHAI3D turns the
// velocity threshold and the watchdog off through them).
HF_EXPORT int dhdEnableExpertMode() {
  ++expert_calls;
  return 0;
}
HF_EXPORT int dhdSetVelocityThreshold(unsigned int, char) {
  ++expert_calls;
  return 0;
}
HF_EXPORT int dhdSetWatchdog(unsigned char, char) {
  ++expert_calls;
  return 0;
}

// Controls for the tests.
HF_EXPORT void hfstandin_dhd_inject(const char* fault) {  // "lose" or "impossible", until the next dhdOpenID
  if (std::strcmp(fault, "lose") == 0) injected_lost = true;
  if (std::strcmp(fault, "impossible") == 0) injected_impossible = true;
}
HF_EXPORT void hfstandin_dhd_last_force(double* f) {
  std::memcpy(f, force, sizeof force);
}
HF_EXPORT long hfstandin_dhd_expert_calls() {
  return expert_calls;
}
HF_EXPORT int hfstandin_dhd_force_enabled() {
  return force_enabled ? 1 : 0;
}
HF_EXPORT void hfstandin_dhd_position(double* p) {
  double v[3];
  hand(position_calls, p, v);
}
