// A stand-in for OpenHaptics' libHD.so, built only by the tests: the HDAPI
// functions the adapter calls, exported with C linkage under their
// documented names, with a simulated arm behind them and faults on demand.
// Its numbers are written here from the documented values, not taken from
// the adapter's header, so a wrong value on either side shows.
//
// HFSTANDIN_HD (comma-separated, read at hdInitDevice):
//   init_fails              hdInitDevice fails (HD_DEVICE_FAULT)
//   already_initiated       the first hdInitDevice reports HD_DEVICE_ALREADY_INITIATED
//   calibration             hdCheckCalibration says HD_CALIBRATION_NEEDS_MANUAL_INPUT
//   device_error_at=N       HD_COMM_ERROR in tick N's frame
//   exceeded_at=N           HD_EXCEEDED_MAX_FORCE in tick N's frame
//   nan_at=N                the position is NaN from tick N on
//   scheduler_stops_at=N    the scheduler stops calling callbacks after N ticks
//   lockstep                no scheduler thread: ticks run in hfstandin_hd_step()
// HFSTANDIN_REPORT=PATH     hdDisableDevice writes what the arm was last told.
// hfstandin_hd_inject("lose" | "impossible") raises a fault from now on.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#define HF_EXPORT extern "C" __attribute__((visibility("default")))

namespace {

struct ErrorInfo {
  unsigned int code;
  int internal;
  unsigned int device;
};
using Callback = unsigned int (*)(void*);

struct Scheduled {
  unsigned long handle;
  Callback fn;
  void* data;
  unsigned short priority;
};

struct Faults {
  bool init_fails{false};
  int already_initiated{0};
  bool calibration{false};
  long device_error_at{-1};
  long exceeded_at{-1};
  long nan_at{-1};
  long scheduler_stops_at{-1};
  bool lockstep{false};
};

std::mutex mutex;       // guards the callback list and the arm's state between threads
std::mutex tick_mutex;  // held while a tick's callbacks run: hdUnschedule waits for them
std::vector<Scheduled> callbacks;
std::thread scheduler;
std::atomic<bool> running{false};
std::atomic<bool> scheduler_stopped_once{false};
std::atomic<long> ticks{0};
Faults faults;
bool initiated = false;
bool enabled_force = false;
unsigned long next_handle = 1;
unsigned long rate = 1000;
double force[3] = {0, 0, 0};  // last force set in a frame [N]
double position[3] = {0, 0, 0};
double velocity[3] = {0, 0, 0};
bool order_ok = true;
bool injected_impossible = false;  // hfstandin_hd_inject("impossible"): NaN positions from now on
bool injected_lost = false;        // hfstandin_hd_inject("lose"): HD_COMM_ERROR in every frame from now on
long frames_outside_callback = 0;
thread_local bool in_callback = false;
thread_local bool in_frame = false;
thread_local ErrorInfo errors[16];
thread_local int error_count = 0;

void push_error(unsigned int code) {
  if (error_count < 16) errors[error_count++] = ErrorInfo{code, 0, 0};
}

long parse_at(const std::string& item, const char* key) {
  const std::string k = std::string(key) + "=";
  if (item.rfind(k, 0) != 0) return -2;
  return std::strtol(item.c_str() + k.size(), nullptr, 10);
}

void read_faults() {
  faults = Faults{};
  const char* env = std::getenv("HFSTANDIN_HD");
  std::string s = env != nullptr ? env : "";
  std::size_t start = 0;
  while (start <= s.size()) {
    const std::size_t end = s.find(',', start);
    const std::string item = s.substr(start, end == std::string::npos ? std::string::npos : end - start);
    long v = 0;
    if (item == "init_fails") faults.init_fails = true;
    if (item == "already_initiated") faults.already_initiated = 1;
    if (item == "calibration") faults.calibration = true;
    if (item == "lockstep") faults.lockstep = true;
    if ((v = parse_at(item, "device_error_at")) >= -1) faults.device_error_at = v;
    if ((v = parse_at(item, "exceeded_at")) >= -1) faults.exceeded_at = v;
    if ((v = parse_at(item, "nan_at")) >= -1) faults.nan_at = v;
    if ((v = parse_at(item, "scheduler_stops_at")) >= -1) faults.scheduler_stops_at = v;
    if (end == std::string::npos) break;
    start = end + 1;
  }
}

// The simulated arm: a hand draws a 20 mm circle at 0.5 Hz about
// (0, -20, 0) mm in HD's frame, and the stylus gives 1 mm per N of force.
void move_arm(long tick) {
  const double t = static_cast<double>(tick) / static_cast<double>(rate);
  const double w = 2.0 * 3.14159265358979323846 * 0.5;
  const double hand[3] = {20.0 * std::cos(w * t), -20.0 + 20.0 * std::sin(w * t), 0.0};
  const double hand_v[3] = {-20.0 * w * std::sin(w * t), 20.0 * w * std::cos(w * t), 0.0};
  for (int i = 0; i < 3; ++i) {
    position[i] = hand[i] + force[i];
    velocity[i] = hand_v[i];
  }
  if ((faults.nan_at >= 0 && tick >= faults.nan_at) || injected_impossible) position[0] = std::nan("");
}

void run_tick() {
  const long tick = ticks.load();
  if (faults.scheduler_stops_at >= 0 && tick >= faults.scheduler_stops_at) return;  // stopped calling
  std::lock_guard<std::mutex> running_callbacks(tick_mutex);
  thread_local std::vector<Scheduled> now;  // keeps its capacity: no allocation after the first ticks
  {
    std::lock_guard<std::mutex> lock(mutex);
    move_arm(tick);
    now.assign(callbacks.begin(), callbacks.end());
  }
  in_callback = true;
  for (const Scheduled& s : now) {
    if (s.fn(s.data) == 0) {  // HD_CALLBACK_DONE: removed
      std::lock_guard<std::mutex> lock(mutex);
      for (auto it = callbacks.begin(); it != callbacks.end(); ++it)
        if (it->handle == s.handle) {
          callbacks.erase(it);
          break;
        }
    }
  }
  in_callback = false;
  ticks.fetch_add(1);
}

void write_report() {
  const char* path = std::getenv("HFSTANDIN_REPORT");
  if (path == nullptr || *path == '\0') return;
  if (FILE* f = std::fopen(path, "w")) {
    std::fprintf(f, "ticks %ld\nlast_force %.9g %.9g %.9g\nshutdown_order %s\nframes_outside_callback %ld\n",
                 ticks.load(), force[0], force[1], force[2], order_ok ? "ok" : "bad", frames_outside_callback);
    std::fclose(f);
  }
}

}  // namespace

HF_EXPORT unsigned int hdInitDevice(const char* name) {
  static bool retrying = false;  // after HD_DEVICE_ALREADY_INITIATED the faults stay as they were
  if (!retrying) read_faults();
  retrying = false;
  (void)name;
  if (faults.init_fails) {
    push_error(0x300);  // HD_DEVICE_FAULT
    return 0xFFFFFFFFu;
  }
  if (faults.already_initiated > 0 && !initiated) {
    --faults.already_initiated;
    initiated = true;   // as left by a crashed run: disable it first
    push_error(0x301);  // HD_DEVICE_ALREADY_INITIATED
    retrying = true;
    return 0xFFFFFFFFu;
  }
  if (initiated) {
    retrying = true;
    push_error(0x301);
    return 0xFFFFFFFFu;
  }
  initiated = true;
  order_ok = true;
  injected_impossible = injected_lost = false;
  ticks = 0;
  force[0] = force[1] = force[2] = 0.0;
  return 1;
}
HF_EXPORT void hdMakeCurrentDevice(unsigned int) {}
HF_EXPORT unsigned int hdGetCurrentDevice() {
  return 1;
}
HF_EXPORT void hdDisableDevice(unsigned int) {
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (running.load() || !callbacks.empty()) order_ok = false;  // documented: stop, unschedule, then disable
  }
  write_report();
  initiated = false;
  enabled_force = false;
}
HF_EXPORT void hdBeginFrame(unsigned int) {
  if (!in_callback || in_frame) {
    ++frames_outside_callback;
    push_error(0x400);  // HD_ILLEGAL_BEGIN
    return;
  }
  in_frame = true;
}
HF_EXPORT void hdEndFrame(unsigned int) {
  if (!in_frame) return;
  in_frame = false;
  const long tick = ticks.load();
  if ((faults.device_error_at >= 0 && tick == faults.device_error_at) || injected_lost)
    push_error(0x302);                                                           // HD_COMM_ERROR
  if (faults.exceeded_at >= 0 && tick == faults.exceeded_at) push_error(0x201);  // HD_EXCEEDED_MAX_FORCE
}
HF_EXPORT void hdGetIntegerv(unsigned int what, int* v) {
  if (what == 0x2000) {  // HD_CURRENT_BUTTONS
    *v = 0;
    return;
  }
  push_error(0x100);  // HD_INVALID_ENUM
}
HF_EXPORT void hdGetDoublev(unsigned int what, double* v) {
  std::lock_guard<std::mutex> lock(mutex);
  switch (what) {
    case 0x2050:  // HD_CURRENT_POSITION [mm]
      if (!in_frame) push_error(0x400);
      std::memcpy(v, position, sizeof position);
      return;
    case 0x2051:  // HD_CURRENT_VELOCITY [mm/s]
      if (!in_frame) push_error(0x400);
      std::memcpy(v, velocity, sizeof velocity);
      return;
    case 0x2603:  // HD_NOMINAL_MAX_FORCE [N]
      *v = 3.3;
      return;
    case 0x2604:  // HD_NOMINAL_MAX_CONTINUOUS_FORCE [N]
      *v = 0.88;
      return;
    case 0x2551: {  // HD_USABLE_WORKSPACE_DIMENSIONS [mm]
      const double box[6] = {-80, -60, -35, 80, 60, 35};
      std::memcpy(v, box, sizeof box);
      return;
    }
    default:
      push_error(0x100);
  }
}
HF_EXPORT const char* hdGetString(unsigned int what) {
  if (what == 0x2501) return "Stand-in Touch";  // HD_DEVICE_MODEL_TYPE
  push_error(0x100);
  return nullptr;
}
HF_EXPORT void hdSetDoublev(unsigned int what, const double* v) {
  if (what != 0x2700) {  // HD_CURRENT_FORCE
    push_error(0x100);
    return;
  }
  if (!in_frame) {
    ++frames_outside_callback;
    push_error(0x400);
    return;
  }
  std::lock_guard<std::mutex> lock(mutex);
  for (int i = 0; i < 3; ++i)
    force[i] = enabled_force ? v[i] : 0.0;
}
HF_EXPORT void hdEnable(unsigned int cap) {
  if (cap == 0x4000)
    enabled_force = true;  // HD_FORCE_OUTPUT
  else if (cap != 0x4001 && cap != 0x4003)
    push_error(0x100);  // HD_MAX_FORCE_CLAMPING, HD_SOFTWARE_FORCE_LIMIT
}
HF_EXPORT void hdDisable(unsigned int cap) {
  if (cap == 0x4000) enabled_force = false;
}
HF_EXPORT ErrorInfo hdGetError() {
  if (error_count == 0) return ErrorInfo{0, 0, 0};
  return errors[--error_count];  // most recent first
}
HF_EXPORT const char* hdGetErrorString(unsigned int code) {
  switch (code) {
    case 0x300:
      return "stand-in device fault";
    case 0x301:
      return "stand-in device already initiated";
    case 0x302:
      return "stand-in communication error";
    default:
      return "stand-in error";
  }
}
HF_EXPORT unsigned int hdCheckCalibration() {
  return faults.calibration ? 0x5002u : 0x5000u;
}
HF_EXPORT void hdSetSchedulerRate(unsigned long hz) {
  rate = hz;
}
HF_EXPORT void hdStartScheduler() {
  if (running.exchange(true)) return;
  if (faults.lockstep) return;
  scheduler = std::thread([] {
    auto next = std::chrono::steady_clock::now();
    while (running.load()) {
      run_tick();
      next += std::chrono::nanoseconds(1'000'000'000 / rate);
      std::this_thread::sleep_until(next);
    }
  });
}
HF_EXPORT void hdStopScheduler() {
  if (!running.exchange(false)) return;
  if (scheduler.joinable()) scheduler.join();
  scheduler_stopped_once = true;
}
HF_EXPORT unsigned long hdScheduleAsynchronous(Callback fn, void* data, unsigned short priority) {
  std::lock_guard<std::mutex> lock(mutex);
  Scheduled s{next_handle++, fn, data, priority};
  auto it = callbacks.begin();
  while (it != callbacks.end() && it->priority >= priority)  // a higher priority runs first
    ++it;
  callbacks.insert(it, s);
  return s.handle;
}
HF_EXPORT void hdUnschedule(unsigned long handle) {
  std::unique_lock<std::mutex> wait_for_tick(tick_mutex, std::defer_lock);
  if (!in_callback) wait_for_tick.lock();  // a callback running now finishes first
  std::lock_guard<std::mutex> lock(mutex);
  for (auto it = callbacks.begin(); it != callbacks.end(); ++it)
    if (it->handle == handle) {
      callbacks.erase(it);
      return;
    }
}

// Controls for the tests.
HF_EXPORT void hfstandin_hd_step(int n) {  // lockstep: runs n ticks on the caller's thread
  for (int i = 0; i < n && running.load(); ++i)
    run_tick();
}
HF_EXPORT long hfstandin_hd_ticks() {
  return ticks.load();
}
HF_EXPORT void hfstandin_hd_last_force(double* f) {
  std::lock_guard<std::mutex> lock(mutex);
  std::memcpy(f, force, sizeof force);
}
HF_EXPORT void hfstandin_hd_position(double* p) {
  std::lock_guard<std::mutex> lock(mutex);
  std::memcpy(p, position, sizeof position);
}
HF_EXPORT int hfstandin_hd_shutdown_order_ok() {
  return order_ok ? 1 : 0;
}
HF_EXPORT long hfstandin_hd_frames_outside_callback() {
  return frames_outside_callback;
}
HF_EXPORT int hfstandin_hd_initiated() {
  return initiated ? 1 : 0;
}
HF_EXPORT void hfstandin_hd_inject(const char* fault) {  // "lose" or "impossible", until the next hdInitDevice
  std::lock_guard<std::mutex> lock(mutex);
  if (std::strcmp(fault, "lose") == 0) injected_lost = true;
  if (std::strcmp(fault, "impossible") == 0) injected_impossible = true;
}
