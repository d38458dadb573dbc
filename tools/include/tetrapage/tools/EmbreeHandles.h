#pragma once
/// @file EmbreeHandles.h
/// Owning handles for Embree 3 objects (device, scene, geometry): each releases its object
/// when it goes out of scope, and a device turns Embree's error codes into tetrapage errors.
/// Embree lives only in tools/, tests/ and bench/ (the independent reference), never in the
/// runtime.

#include <embree3/rtcore.h>

#include <memory>
#include <string>

namespace tetrapage {

struct EmbreeRelease {
  void operator()(RTCDevice device) const { rtcReleaseDevice(device); }
  void operator()(RTCScene scene) const { rtcReleaseScene(scene); }
  void operator()(RTCGeometry geometry) const { rtcReleaseGeometry(geometry); }
};

using EmbreeScene = std::unique_ptr<RTCSceneTy, EmbreeRelease>;
using EmbreeGeometry = std::unique_ptr<RTCGeometryTy, EmbreeRelease>;

/// An Embree device; every scene and geometry made from it must be released before it.
class EmbreeDevice {
 public:
  /// `threads` = 0 lets Embree use every hardware thread; otherwise its pool has that many.
  /// @throw Error if Embree cannot create a device (the message carries Embree's reason).
  explicit EmbreeDevice(unsigned threads = 0);

  RTCDevice get() const { return device_.get(); }

  /// A new scene of this device with the given flags and build quality.
  /// @throw Error on failure.
  EmbreeScene new_scene(RTCSceneFlags flags, RTCBuildQuality quality) const;
  /// A new geometry of this device.
  /// @throw Error on failure.
  EmbreeGeometry new_geometry(RTCGeometryType type) const;

  /// Throws when Embree recorded an error since the last call; `what` names the operation.
  /// @throw Error naming `what`, Embree's error code and its message.
  void check(const std::string& what) const;

 private:
  struct ErrorLog;
  std::shared_ptr<ErrorLog> errors_;  // a stable address for Embree's error callback
  std::unique_ptr<RTCDeviceTy, EmbreeRelease> device_;
};

}  // namespace tetrapage
