#include "backends/embree/embree_device.h"

#include <map>
#include <memory>
#include <mutex>

#include "backends/embree/embree_backend.h"
#include "base/error.h"

namespace rp::embree::detail {

namespace {

thread_local std::string t_last_error;

/// Embree's name of an error code.
const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE:
      return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN:
      return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION:
      return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED:
      return "RTC_ERROR_CANCELLED";
  }
  return "an unknown error code";
}

void on_error(void*, RTCError code, const char* message) {
  t_last_error = cat(message ? message : "(no message)", " (", error_name(code), ")");
}

bool on_memory(void* user, ssize_t bytes, bool) {
  static_cast<Device*>(user)->bytes.fetch_add(bytes, std::memory_order_relaxed);
  return true;
}

}  // namespace

void check(RTCDevice device, const char* what) {
  const RTCError code = rtcGetDeviceError(device);
  if (code != RTC_ERROR_NONE) {
    std::string msg = t_last_error.empty() ? std::string(error_name(code)) : t_last_error;
    t_last_error.clear();
    throw Error(cat(what, ": ", msg));
  }
}

Device& device_for(const std::string& config) {
  static std::mutex mutex;
  // Never destroyed: a backend held in a static (a benchmark fixture, say) may release its
  // scene during exit, after function-local statics built later than it are gone.
  static auto* devices = new std::map<std::string, std::unique_ptr<Device>>;
  std::lock_guard lock(mutex);
  std::unique_ptr<Device>& d = (*devices)[config];
  if (!d) {
    auto created = std::make_unique<Device>();
    created->handle = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!created->handle) {
      RTCError code = rtcGetDeviceError(nullptr);
      throw Error(cat("embree: cannot create a device with config '", config, "' (", error_name(code), ")"));
    }
    rtcSetDeviceErrorFunction(created->handle, on_error, nullptr);
    rtcSetDeviceMemoryMonitorFunction(created->handle, on_memory, created.get());
    d = std::move(created);
  }
  return *d;
}

}  // namespace rp::embree::detail

namespace rp::embree {

DeviceFacts device_facts() {
  const RTCDevice dev = detail::device_for("").handle;
  DeviceFacts f;
  f.version = cat(rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_MAJOR), ".",
                  rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_MINOR), ".",
                  rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_PATCH));
  f.native_ray4 = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED) != 0;
  f.native_ray8 = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0;
  f.native_ray16 = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
  f.stream = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED) != 0;
  // Embree 3 does not report the ISA it dispatches to; it takes the widest one it was built
  // for that the CPU has, and only its AVX-512 kernels trace 16-wide packets natively.
  __builtin_cpu_init();
  f.isa = f.native_ray16  ? "avx512"
          : f.native_ray8 ? (__builtin_cpu_supports("avx2") ? "avx2" : "avx")
                          : (__builtin_cpu_supports("sse4.2") ? "sse4.2" : "sse2");
  return f;
}

}  // namespace rp::embree
