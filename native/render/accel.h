// The ray-tracing acceleration structure: one Embree device and one RTCScene
// holding every Shape, each with its material or light. Embree's own memory
// (BVH and internal buffers; vertex data is shared with our meshes and not
// counted) is tracked with a device memory monitor for the render report.
#pragma once

#include <embree3/rtcore.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "render/interaction.h"
#include "render/ray.h"
#include "render/shape.h"

namespace knit::render {

struct GeometryRecord {
  std::unique_ptr<Shape> shape;
  int material = -1;  // index into Scene::materials (-1 for pure emitters)
  int light = -1;     // index into Scene::lights when the shape emits
  bool pass_through = false;  // Accel::set_pass_through
};

class Accel {
 public:
  Accel();
  ~Accel();
  Accel(const Accel&) = delete;
  Accel& operator=(const Accel&) = delete;

  // Adds a shape; returns its geometry id. Call commit() once after the last add.
  unsigned add(std::unique_ptr<Shape> shape, int material, int light);
  void commit();  // builds the BVH; throws std::runtime_error on Embree errors

  // Closest hit in (ray.tmin, ray.tmax); fills si (including footprint when
  // the ray carries differentials) and returns true on a hit.
  bool intersect(const RayDifferential& ray, SurfaceInteraction& si) const;
  // Any hit in (tmin, tmax).
  bool occluded(const Ray& ray) const;
  // Marks geometry `id` as one that shadow rays may pass through (a material
  // with pass-through events, Material::can_pass_through). Call before
  // commit(). Unmarked geometry blocks them.
  void set_pass_through(unsigned id);
  // Any hit in (tmin, tmax) on geometry that blocks shadow rays outright:
  // when there is one, the ray's transmittance is 0 whatever it crosses.
  bool occluded_by_blockers(const Ray& ray) const;
  // Whether any geometry blocks shadow rays outright (and ray masks work):
  // without, occluded_by_blockers is always false and need not be asked.
  bool has_blockers() const;

  const GeometryRecord& record(unsigned geom_id) const { return records_[geom_id]; }
  size_t num_geometries() const { return records_.size(); }
  size_t num_primitives() const;
  void bounds(Vec3& lo, Vec3& hi) const;

  // Bytes Embree holds now / held at most (from the memory monitor).
  int64_t embree_bytes() const { return bytes_.load(); }
  int64_t embree_peak_bytes() const { return peak_.load(); }

 private:
  static bool memory_monitor(void* self, ssize_t bytes, bool post);
  static void error_callback(void* self, RTCError code, const char* message);

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  bool ray_masks_ = false;  // RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED
  std::vector<GeometryRecord> records_;
  std::atomic<int64_t> bytes_{0}, peak_{0};
  std::mutex error_mutex_;
  std::string first_error_;
};

}  // namespace knit::render
