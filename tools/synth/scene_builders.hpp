// The preset scenes (room, corridor_loop, street, marker_wall) and the nominal camera path of each.
#pragma once

#include "tools/synth/preset.hpp"
#include "tools/synth/scene.hpp"
#include "tools/synth/trajectory.hpp"

namespace heslam::synth {

struct BuiltScene {
  Scene scene;
  PathSpec path;
};

// Builds the scene of preset.scene with its textures (photographs from preset.photo_dir plus
// procedural ones). The layout is fixed per scene kind; only the trajectory depends on the seed.
BuiltScene build_scene(const Preset& preset);

}  // namespace heslam::synth
