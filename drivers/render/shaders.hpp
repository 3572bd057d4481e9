// GLSL 3.30 core sources of the renderer's passes.
//
// Conventions shared with renderer.cpp: scene coordinates (scene.hpp); the
// F_p texture is reached through u_tex_scale * scene + u_tex_offset; the
// colour map is a 256 x 1 texture, F_p = 0 at texel 0's centre and 1 at
// texel 255's (rgb: colour; a: the volume's opacity per ray step).
#pragma once

namespace visvol::render::detail {

// terrain: lit mesh, coloured by F_p at a height, or plain
extern const char* const kTerrainVertex;
extern const char* const kTerrainFragment;
// path tube (and its outline: the tube inflated, drawn dark first)
extern const char* const kTubeVertex;
extern const char* const kTubeFragment;
// flat overlay in pixel coordinates
extern const char* const kOverlayVertex;
extern const char* const kOverlayFragment;
// a triangle covering the viewport (volume and slice passes)
extern const char* const kFullscreenVertex;
// ray marching F_p through the transfer function, up to the scene's depth
extern const char* const kVolumeFragment;
// the half-resolution volume blended over a large frame
extern const char* const kCompositeFragment;
// F_p on the vertical surface along the path
extern const char* const kSliceFragment;

}  // namespace visvol::render::detail
