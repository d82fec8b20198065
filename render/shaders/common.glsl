// Per-frame values every pass sees (set 0, binding 0). Mirrors FrameUniforms in
// src/frame_uniforms.hpp; std140, so every member is a vec4 or a mat4.
// View space: camera at the origin looking down -z; "depth" everywhere is the positive linear
// distance along the view axis, in metres (-view.z).
layout(set = 0, binding = 0, std140) uniform FrameUniforms {
  mat4 view;              // world -> view
  mat4 proj;              // view -> Vulkan clip space (y down, z in [0, 1])
  vec4 light_dir_view;    // xyz: unit vector towards the light, in view space
  vec4 viewport;          // full resolution: width, height, 1/width, 1/height (pixels)
  vec4 half_viewport;     // fluid buffers (half resolution, §5.1): width, height, 1/width, 1/height
  vec4 splat;             // x: splat radius m (1.2 x particle radius, §5.1), y: filter range sigma m,
                          // z: depth written where there is no fluid, w: depths above this are "no fluid"
  vec4 fluid_colour;      // F_c of eq. 15 (rgb)
  vec4 extinction;        // F_e of eq. 15, per metre of thickness (rgb)
  vec4 specular;          // rgb: k_s of eq. 15, w: specular exponent alpha
  vec4 refraction;        // x: beta of eq. 15 (uv offset per metre of thickness), y: P00, z: P11
  vec4 floor_params;      // x: checker square size m
} frame;

// View-space position of the pixel centre `pixel` of a buffer of `inv_size` (1/width, 1/height)
// seen at linear depth `depth`. Inverts the symmetric perspective projection.
vec3 view_position(vec2 pixel, vec2 inv_size, float depth) {
  vec2 ndc = (pixel + 0.5) * inv_size * 2.0 - 1.0;
  return vec3(ndc.x * depth / frame.refraction.y, ndc.y * depth / frame.refraction.z, -depth);
}
