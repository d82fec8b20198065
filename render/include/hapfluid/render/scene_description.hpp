// From a scene file (config library) to what the renderer draws: body meshes, particle radius,
// the fluid's look (eq. 15 parameters) and a default view of the domain.
#pragma once

#include "hapfluid/config/scene.hpp"
#include "hapfluid/render/frame_source.hpp"

namespace hapfluid::render {

// Loads every body mesh; throws config::ConfigError if a mesh cannot be read.
SceneDescription describe_scene(const config::Scene& scene);

}  // namespace hapfluid::render
