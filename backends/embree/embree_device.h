#pragma once
/// Embree devices, one per configuration string, and Embree's errors as rp::Error. Internal to
/// the Embree adapter (backends/embree/).

#include <embree3/rtcore.h>

#include <atomic>
#include <cstdint>
#include <string>

namespace rp::embree::detail {

/// One Embree device per configuration string, alive for the whole process. Embree reports
/// errors through a callback (it cannot throw through C); the message is kept per thread and
/// turned into rp::Error by check() after each API call that can fail.
struct Device {
  RTCDevice handle = nullptr;
  std::atomic<int64_t> bytes{0};  ///< live bytes allocated by this device (memory monitor)
};

/// Throws rp::Error starting with `what` when `device` has an error pending: the message its
/// error callback kept on this thread, or the error code's name.
void check(RTCDevice device, const char* what);

/// The device for the configuration string `config` ("" for Embree's defaults), created on
/// first use with the error and memory callbacks set; throws rp::Error when Embree cannot.
Device& device_for(const std::string& config);

}  // namespace rp::embree::detail
