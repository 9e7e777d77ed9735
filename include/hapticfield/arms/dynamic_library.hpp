#pragma once
/// @file dynamic_library.hpp
/// DynamicLibrary: a shared library loaded at run time (dlopen), closed when
/// the handle goes, with typed symbol lookup and errors that name the
/// library, the names tried and what the loader said. The seam of the
/// vendor SDK arms (arms/openhaptics/, arms/dhd/): hapticfield builds and
/// tests without the vendor's library, and a machine that has it uses it
/// without a rebuild. Never on the servo path: load and look up once.

#include <dlfcn.h>

#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "hapticfield/device/device_error.hpp"

namespace hapticfield {

/// A library that cannot be loaded, or a symbol it lacks; what() names the
/// library (or every name tried) and the loader's message.
class LibraryError : public DeviceError {
 public:
  using DeviceError::DeviceError;
};

class DynamicLibrary {
 public:
  DynamicLibrary() = default;

  /// Loads the first of names that loads (each as dlopen takes it: a bare
  /// name searches LD_LIBRARY_PATH, the ld.so cache and the system
  /// directories; a name with a slash is a path). When override_variable
  /// names a set, non-empty environment variable, its value is the only
  /// name tried (a lab's own copy, or a stand-in in tests).
  /// @param what  what the library is, for messages ("OpenHaptics HD")
  /// @throws LibraryError naming every name tried and the loader's message for each.
  [[nodiscard]] static DynamicLibrary open_first(const std::string& what, const std::vector<std::string>& names,
                                                 const char* override_variable = nullptr) {
    std::vector<std::string> tried = names;
    std::string origin;
    if (override_variable != nullptr) {
      const char* v = std::getenv(override_variable);
      if (v != nullptr && *v != '\0') {
        tried = {v};
        origin = std::string(" (from ") + override_variable + ")";
      }
    }
    std::string reasons;
    for (const std::string& name : tried) {
      dlerror();
      if (void* h = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL)) return DynamicLibrary(h, name);
      const char* e = dlerror();
      reasons += std::string(reasons.empty() ? "" : "; ") + (e != nullptr ? e : name + ": unknown loader error");
    }
    std::string list;
    for (const std::string& name : tried)
      list += (list.empty() ? "" : ", ") + name;
    throw LibraryError(
        what + ": cannot load " + list + origin + ": " + reasons +
        (origin.empty() ? "; is the vendor's SDK installed (and its directory in LD_LIBRARY_PATH)?" : ""));
  }

  DynamicLibrary(DynamicLibrary&& o) noexcept : handle_(std::exchange(o.handle_, nullptr)), name_(std::move(o.name_)) {}
  DynamicLibrary& operator=(DynamicLibrary&& o) noexcept {
    if (this != &o) {
      close();
      handle_ = std::exchange(o.handle_, nullptr);
      name_ = std::move(o.name_);
    }
    return *this;
  }
  DynamicLibrary(const DynamicLibrary&) = delete;
  DynamicLibrary& operator=(const DynamicLibrary&) = delete;
  ~DynamicLibrary() { close(); }

  [[nodiscard]] bool loaded() const noexcept { return handle_ != nullptr; }
  /// The name it was loaded by.
  [[nodiscard]] const std::string& name() const noexcept { return name_; }

  /// The symbol as a pointer of type Fn (a function pointer type), or
  /// nullptr when the library does not export it (an optional symbol).
  template <class Fn>
  [[nodiscard]] Fn find(const char* symbol) const noexcept {
    if (handle_ == nullptr) return nullptr;
    void* p = dlsym(handle_, symbol);
    return reinterpret_cast<Fn>(p);  // POSIX: function pointers and void* convert
  }

  /// The symbol as a pointer of type Fn.
  /// @throws LibraryError naming the symbol and the library when it is missing.
  template <class Fn>
  [[nodiscard]] Fn get(const char* symbol) const {
    Fn f = find<Fn>(symbol);
    if (f == nullptr)
      throw LibraryError(name_ + " has no symbol " + symbol +
                         " (not the expected library, or a version too old for this adapter)");
    return f;
  }

 private:
  DynamicLibrary(void* handle, std::string name) noexcept : handle_(handle), name_(std::move(name)) {}
  void close() noexcept {
    if (handle_ != nullptr) dlclose(handle_);
    handle_ = nullptr;
  }

  void* handle_{nullptr};
  std::string name_;
};

}  // namespace hapticfield
