/* Knitshade kernel: every shared kernel header, in dependency order.
 * A host includes its adaptation header (host_c.h, or osl/knit_osl_host.h)
 * first, then this file. */
#ifndef KNIT_KERNEL_H
#define KNIT_KERNEL_H

#include "kmath.h"
#include "cubic.h"
#include "stitch.h"
#include "query.h"
#include "capm.h"
#include "multiscale.h"
#include "bsdf_common.h"
#include "bsdf_microfacet.h"
#include "bsdf_lommel_seeliger.h"
#include "bsdf_lambert_transmission.h"
#include "bsdf_attenuation.h"
#include "bsdf_delta.h"
#include "yarn_bsdf.h"
#include "bsdf_cycles.h"
#include "ply_profile.h"
#include "yarn_frame.h"
#include "multiscale_frame.h"

#endif /* KNIT_KERNEL_H */
