#include "render/build_info.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenImageIO/imageio.h>
#include <embree3/rtcore.h>
#include <oneapi/tbb/version.h>

#include <cstdio>

#include "knit/surface.h"

namespace knit::render {

namespace {

// OpenImageIO's run-time version, 10000 major + 100 minor + patch.
std::string oiio_version() {
  const int v = OIIO::openimageio_version();
  char buf[32];
  std::snprintf(buf, sizeof buf, "%d.%d.%d", v / 10000, (v / 100) % 100, v % 100);
  return buf;
}

// Embree's run-time version, from a device (the header's when none can be made).
std::string embree_version() {
  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) return RTC_VERSION_STRING;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%d.%d.%d", int(rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION_MAJOR)),
                int(rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION_MINOR)),
                int(rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION_PATCH)));
  rtcReleaseDevice(device);
  return buf;
}

std::string compiler() {
#if defined(__clang__)
  return std::string("Clang ") + __clang_version__;
#elif defined(__GNUC__)
  return std::string("GCC ") + __VERSION__;
#else
  return "unknown";
#endif
}

}  // namespace

std::vector<std::pair<std::string, std::string>> build_info() {
  const KnitSurface::BatchIsa isa = KnitSurface::batch_best_isa();
  std::string batch = KnitSurface::batch_isa_name(isa);
  batch += isa == KnitSurface::BatchIsa::Avx512 ? " (32 points at a time, 16 in calls of fewer than 128)"
           : isa == KnitSurface::BatchIsa::Avx2 ? " (16 points at a time, 8 in calls of fewer than 32)"
                                                 : " (no AVX2 with FMA on this CPU: one point at a time)";
  return {
      {"compiler", compiler()},
      {"batched query", batch},
      {"Embree", embree_version()},
      {"OpenImageIO", oiio_version()},
      {"OpenColorIO", OCIO_NAMESPACE::GetVersion()},
      {"oneTBB", TBB_runtime_version()},
  };
}

}  // namespace knit::render
