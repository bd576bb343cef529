#include "render/accel.h"

#include <limits>
#include <stdexcept>

namespace knit::render {

bool Accel::memory_monitor(void* self, ssize_t bytes, bool) {
  auto* a = static_cast<Accel*>(self);
  const int64_t now = a->bytes_.fetch_add(bytes) + bytes;
  int64_t peak = a->peak_.load();
  while (now > peak && !a->peak_.compare_exchange_weak(peak, now)) {
  }
  return true;  // never refuse an allocation
}

void Accel::error_callback(void* self, RTCError code, const char* message) {
  auto* a = static_cast<Accel*>(self);
  std::lock_guard<std::mutex> lock(a->error_mutex_);
  if (a->first_error_.empty())
    a->first_error_ = "Embree error " + std::to_string(static_cast<int>(code)) + ": " +
                      (message ? message : "(no message)");
}

Accel::Accel() {
  device_ = rtcNewDevice("verbose=0");
  if (!device_) throw std::runtime_error("cannot create the Embree device");
  rtcSetDeviceErrorFunction(device_, &Accel::error_callback, this);
  rtcSetDeviceMemoryMonitorFunction(device_, &Accel::memory_monitor, this);
  ray_masks_ = rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
  scene_ = rtcNewScene(device_);
  // Robust mode: no shortcuts that trade intersection accuracy for speed.
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
}

Accel::~Accel() {
  records_.clear();
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

unsigned Accel::add(std::unique_ptr<Shape> shape, int material, int light) {
  const unsigned id = shape->attach(device_, scene_);
  if (id >= records_.size()) records_.resize(id + 1);
  records_[id].shape = std::move(shape);
  records_[id].material = material;
  records_[id].light = light;
  return id;
}

void Accel::commit() {
  rtcCommitScene(scene_);
  std::lock_guard<std::mutex> lock(error_mutex_);
  if (!first_error_.empty()) throw std::runtime_error(first_error_);
}

size_t Accel::num_primitives() const {
  size_t n = 0;
  for (const auto& r : records_)
    if (r.shape) n += r.shape->num_primitives();
  return n;
}

void Accel::bounds(Vec3& lo, Vec3& hi) const {
  const float inf = std::numeric_limits<float>::infinity();
  lo = {inf, inf, inf};
  hi = {-inf, -inf, -inf};
  for (const auto& r : records_) {
    if (!r.shape) continue;
    Vec3 a, b;
    r.shape->bounds(a, b);
    lo = vmin(lo, a);
    hi = vmax(hi, b);
  }
}

static void to_rtc(const Ray& ray, RTCRay& r) {
  r.org_x = ray.o.x;
  r.org_y = ray.o.y;
  r.org_z = ray.o.z;
  r.dir_x = ray.d.x;
  r.dir_y = ray.d.y;
  r.dir_z = ray.d.z;
  r.tnear = ray.tmin;
  r.tfar = ray.tmax;
  r.time = 0;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
}

bool Accel::intersect(const RayDifferential& ray, SurfaceInteraction& si) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  to_rtc(ray, rh.ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  // Shapes attached as an instance (CurveShape) are recorded under the instance's id.
  const unsigned id = rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? rh.hit.instID[0] : rh.hit.geomID;
  const GeometryRecord& rec = records_[id];
  si.geom_id = id;
  si.material = rec.material;
  si.light = rec.light;
  rec.shape->interaction(ray, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v, si);
  return true;
}

// Embree's ray masks: geometry that blocks shadow rays keeps the default
// mask (all bits), pass-through geometry has kPassThroughMask only, and a
// blocker-only ray carries kBlockerRayMask, which only the former has. Other
// rays carry all bits and see everything.
namespace {
constexpr unsigned kPassThroughMask = 0x2u;
constexpr unsigned kBlockerRayMask = 0x1u;

// Any hit in (tmin, tmax) on geometry whose mask shares a bit with `mask`.
bool occluded_with_mask(RTCScene scene, const Ray& ray, unsigned mask) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  to_rtc(ray, r);
  r.mask = mask;
  rtcOccluded1(scene, &ctx, &r);
  return r.tfar < 0;  // Embree sets tfar to -inf on a hit
}
}  // namespace

void Accel::set_pass_through(unsigned id) {
  records_[id].pass_through = true;
  if (!ray_masks_) return;
  RTCGeometry g = rtcGetGeometry(scene_, id);
  rtcSetGeometryMask(g, kPassThroughMask);
  rtcCommitGeometry(g);
}

bool Accel::has_blockers() const {
  if (!ray_masks_) return false;
  for (const GeometryRecord& r : records_)
    if (r.shape && !r.pass_through) return true;
  return false;
}

bool Accel::occluded_by_blockers(const Ray& ray) const {
  if (!ray_masks_) return false;  // an Embree built without ray masks: no shortcut, never a wrong answer
  return occluded_with_mask(scene_, ray, kBlockerRayMask);
}

bool Accel::occluded(const Ray& ray) const { return occluded_with_mask(scene_, ray, 0xffffffffu); }

}  // namespace knit::render
