// Ray-differential transfer through scattering events (Igehy 1999):
// the offset rays of the continuation ray after a pass-through, a specular
// reflection or a specular refraction. Other events drop the differentials.
#pragma once

#include "render/interaction.h"
#include "render/material.h"
#include "render/ray.h"

namespace knit::render {

// `in`: the ray that hit `si` (with differentials and a valid footprint);
// `out`: the continuation ray, whose o and d are already set.
void differentials_pass_through(const RayDifferential& in, const SurfaceInteraction& si, RayDifferential& out);
void differentials_specular(const RayDifferential& in, const SurfaceInteraction& si, const BsdfSample& bs,
                            RayDifferential& out);

}  // namespace knit::render
