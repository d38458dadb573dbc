#include "tetrapage/tools/EmbreeHandles.h"

#include <cstdlib>
#include <mutex>

#include "tetrapage/formats/base/Error.h"

namespace tetrapage {
namespace {

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognised error code";
}

}  // namespace

// Embree reports the message through a callback, possibly from its worker threads, and the
// code through rtcGetDeviceError; check() joins the two.
struct EmbreeDevice::ErrorLog {
  std::mutex mutex;
  std::string message;

  static void record(void* self, RTCError code, const char* message) {
    auto* log = static_cast<ErrorLog*>(self);
    const std::lock_guard lock(log->mutex);
    if (log->message.empty()) log->message = std::string(error_name(code)) + ": " + (message ? message : "");
  }
};

EmbreeDevice::EmbreeDevice(unsigned threads) : errors_(std::make_shared<ErrorLog>()) {
  std::string config = threads > 0 ? "threads=" + std::to_string(threads) : "";
  // TETRAPAGE_EMBREE_CONFIG (e.g. "isa=avx2") reproduces another machine's Embree kernels.
  if (const char* extra = std::getenv("TETRAPAGE_EMBREE_CONFIG"); extra && *extra)
  {
    if (!config.empty()) config += ',';
    config += extra;
  }
  device_.reset(rtcNewDevice(config.c_str()));
  if (!device_)
    throw Error("Embree: cannot create a device (" + std::string(error_name(rtcGetDeviceError(nullptr))) +
                ", config '" + config + "')");
  rtcSetDeviceErrorFunction(device_.get(), &ErrorLog::record, errors_.get());
}

EmbreeScene EmbreeDevice::new_scene(RTCSceneFlags flags, RTCBuildQuality quality) const {
  EmbreeScene scene(rtcNewScene(device_.get()));
  check("rtcNewScene");
  rtcSetSceneFlags(scene.get(), flags);
  rtcSetSceneBuildQuality(scene.get(), quality);
  check("rtcSetSceneFlags/BuildQuality");
  return scene;
}

EmbreeGeometry EmbreeDevice::new_geometry(RTCGeometryType type) const {
  EmbreeGeometry geometry(rtcNewGeometry(device_.get(), type));
  check("rtcNewGeometry");
  return geometry;
}

void EmbreeDevice::check(const std::string& what) const {
  const RTCError code = rtcGetDeviceError(device_.get());
  std::string message;
  {
    const std::lock_guard lock(errors_->mutex);
    message.swap(errors_->message);
  }
  if (code == RTC_ERROR_NONE && message.empty()) return;
  throw Error("Embree: " + what + " failed: " + (message.empty() ? error_name(code) : message));
}

}  // namespace tetrapage
