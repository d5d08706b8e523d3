// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet mesh: the projection hook, the one interface between the quality stage
// (refine/refine_mesh.h), which calls it on the points it puts on the surface, and the CAD layer
// (cad/cad_projection.h), which provides one backed by the CAD model.
#pragma once

#include <cstdint>
#include <functional>

#include "bsptet/numerics/vec3.h"

namespace bsptet {

/// Moves a surface point onto the true surface: (point on the facet, face tag of its input
/// triangle, second tag or -1) -> point. `other_tag` is not -1 only for a point on an input edge
/// between triangles of two different tags (a CAD edge: the point belongs on both faces).
/// Tags are the surface's `tag` entries, or -1 when the surface has none.
using ProjectionHook = std::function<Vec3(const Vec3& point, std::int32_t tag, std::int32_t other_tag)>;

}  // namespace bsptet
