#include "drivers/render/shaders.hpp"

namespace visvol::render::detail {

const char* const kTerrainVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_skirt;
uniform mat4 u_view_proj;
out vec3 v_position;
out vec3 v_normal;
out float v_skirt;
void main() {
  v_position = a_position;
  v_normal = a_normal;
  v_skirt = a_skirt;
  gl_Position = u_view_proj * vec4(a_position, 1.0);
}
)";

// u_mode 0: F_p at scene height u_height (grey where the ground is above it);
// 1: F_p u_height above the ground; 2: plain u_plain_colour. The skirt
// (the block's sides) is always u_skirt_colour.
const char* const kTerrainFragment = R"(#version 330 core
in vec3 v_position;
in vec3 v_normal;
in float v_skirt;
uniform sampler3D u_field;
uniform sampler2D u_colour_map;
uniform vec3 u_tex_scale;
uniform vec3 u_tex_offset;
uniform int u_mode;
uniform float u_height;
uniform vec3 u_light;
uniform vec3 u_plain_colour;
uniform vec3 u_skirt_colour;
out vec4 o_colour;
void main() {
  vec3 base = u_plain_colour;
  if (v_skirt > 0.5) {
    base = u_skirt_colour;
  } else if (u_mode != 2) {
    float z = u_mode == 0 ? u_height : v_position.z + u_height;
    if (z >= v_position.z) {
      float fp = texture(u_field, vec3(v_position.xy, z) * u_tex_scale + u_tex_offset).r;
      base = texture(u_colour_map, vec2(fp * (255.0 / 256.0) + 0.5 / 256.0, 0.5)).rgb;
    }
  }
  float shade = 0.45 + 0.55 * max(dot(normalize(v_normal), u_light), 0.0);
  o_colour = vec4(base * shade, 1.0);
}
)";

const char* const kTubeVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_fp;
uniform mat4 u_view_proj;
uniform float u_inflate;
out vec3 v_normal;
out float v_fp;
void main() {
  v_normal = a_normal;
  v_fp = a_fp;
  gl_Position = u_view_proj * vec4(a_position + a_normal * u_inflate, 1.0);
}
)";

const char* const kTubeFragment = R"(#version 330 core
in vec3 v_normal;
in float v_fp;
uniform sampler2D u_colour_map;
uniform vec3 u_light;
uniform int u_outline;
uniform vec3 u_outline_colour;
out vec4 o_colour;
void main() {
  if (u_outline == 1) {
    o_colour = vec4(u_outline_colour, 1.0);
    return;
  }
  vec3 base = texture(u_colour_map, vec2(clamp(v_fp, 0.0, 1.0) * (255.0 / 256.0) + 0.5 / 256.0, 0.5)).rgb;
  float shade = 0.6 + 0.4 * max(dot(normalize(v_normal), u_light), 0.0);
  o_colour = vec4(base * shade, 1.0);
}
)";

const char* const kOverlayVertex = R"(#version 330 core
layout(location = 0) in vec2 a_pixel;
layout(location = 1) in vec4 a_colour;
layout(location = 2) in float a_fp;
uniform vec2 u_size;
out vec4 v_colour;
out float v_fp;
void main() {
  v_colour = a_colour;
  v_fp = a_fp;
  // window rows run top to bottom (see scene.hpp), so no flip here
  gl_Position = vec4(a_pixel / u_size * 2.0 - 1.0, 0.0, 1.0);
}
)";

const char* const kOverlayFragment = R"(#version 330 core
in vec4 v_colour;
in float v_fp;
uniform sampler2D u_colour_map;
out vec4 o_colour;
void main() {
  if (v_fp >= 0.0) {
    o_colour = vec4(texture(u_colour_map, vec2(v_fp * (255.0 / 256.0) + 0.5 / 256.0, 0.5)).rgb, 1.0);
  } else {
    o_colour = v_colour;
  }
}
)";

const char* const kFullscreenVertex = R"(#version 330 core
void main() {
  vec2 corner = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
  gl_Position = vec4(corner, 0.0, 1.0);
}
)";

// Front-to-back compositing, premultiplied output (blend ONE,
// ONE_MINUS_SRC_ALPHA). The ray stops at the opaque scene's depth (terrain
// and path) and when nearly opaque. A per-pixel offset of the first sample
// hides the step pattern; it is a hash of the pixel, so images repeat exactly.
const char* const kVolumeFragment = R"(#version 330 core
uniform mat4 u_inverse;
uniform vec4 u_viewport;
uniform vec3 u_depth_map;  // frame pixel of the depth = gl_FragCoord.xy * z + xy
uniform vec3 u_box_min;
uniform vec3 u_box_max;
uniform sampler2D u_depth;
uniform sampler3D u_field;
uniform sampler2D u_colour_map;
uniform vec3 u_tex_scale;
uniform vec3 u_tex_offset;
uniform float u_step;
uniform int u_max_steps;
out vec4 o_colour;
vec3 unproject(vec2 ndc, float z) {
  vec4 p = u_inverse * vec4(ndc, z, 1.0);
  return p.xyz / p.w;
}
void main() {
  vec2 ndc = (gl_FragCoord.xy - u_viewport.xy) / u_viewport.zw * 2.0 - 1.0;
  vec3 origin = unproject(ndc, -1.0);
  vec3 dir = normalize(unproject(ndc, 1.0) - origin);
  float depth = texelFetch(u_depth, ivec2(gl_FragCoord.xy * u_depth_map.z + u_depth_map.xy), 0).r;
  float t_scene = dot(unproject(ndc, depth * 2.0 - 1.0) - origin, dir);
  vec3 safe = vec3(abs(dir.x) < 1e-8 ? 1e-8 : dir.x, abs(dir.y) < 1e-8 ? 1e-8 : dir.y,
                   abs(dir.z) < 1e-8 ? 1e-8 : dir.z);
  vec3 t0 = (u_box_min - origin) / safe;
  vec3 t1 = (u_box_max - origin) / safe;
  vec3 lo = min(t0, t1);
  vec3 hi = max(t0, t1);
  float t_in = max(max(lo.x, lo.y), max(lo.z, 0.0));
  float t_out = min(min(hi.x, hi.y), min(hi.z, t_scene));
  if (t_in >= t_out) discard;
  float jitter = fract(sin(dot(gl_FragCoord.xy, vec2(12.9898, 78.233))) * 43758.5453);
  vec4 sum = vec4(0.0);
  float t = t_in + jitter * u_step;
  for (int i = 0; i < u_max_steps && t < t_out; ++i) {
    float fp = texture(u_field, (origin + dir * t) * u_tex_scale + u_tex_offset).r;
    vec4 c = texture(u_colour_map, vec2(fp * (255.0 / 256.0) + 0.5 / 256.0, 0.5));
    sum += (1.0 - sum.a) * vec4(c.rgb * c.a, c.a);
    if (sum.a > 0.97) break;
    t += u_step;
  }
  o_colour = sum;
}
)";

// The volume drawn at half resolution, blended over the frame (premultiplied).
const char* const kCompositeFragment = R"(#version 330 core
uniform vec4 u_viewport;
uniform vec2 u_texture_size;
uniform sampler2D u_half;
out vec4 o_colour;
void main() {
  vec2 half_px = (gl_FragCoord.xy - u_viewport.xy) * 0.5;
  o_colour = texture(u_half, half_px / u_texture_size);
}
)";

// u_profile: one texel per viewport column: scene x, y and ground z along the path.
const char* const kSliceFragment = R"(#version 330 core
uniform vec4 u_viewport;
uniform sampler2D u_profile;
uniform sampler3D u_field;
uniform sampler2D u_colour_map;
uniform vec3 u_tex_scale;
uniform vec3 u_tex_offset;
uniform float u_z_top;
uniform float u_z_bottom;
uniform vec3 u_ground_colour;
out vec4 o_colour;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy) - ivec2(u_viewport.xy);
  vec4 p = texelFetch(u_profile, ivec2(px.x, 0), 0);
  float z_per_px = (u_z_top - u_z_bottom) / u_viewport.w;
  float z = u_z_top - (float(px.y) + 0.5) * z_per_px;
  if (z < p.z) {
    float edge = p.z - z < 1.5 * z_per_px ? 0.45 : 1.0;
    o_colour = vec4(u_ground_colour * edge, 1.0);
    return;
  }
  float fp = texture(u_field, vec3(p.xy, z) * u_tex_scale + u_tex_offset).r;
  o_colour = vec4(texture(u_colour_map, vec2(fp * (255.0 / 256.0) + 0.5 / 256.0, 0.5)).rgb, 1.0);
}
)";

}  // namespace visvol::render::detail
