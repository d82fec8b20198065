#version 450
// On-screen statistics (windowed mode): text quads from stb_easy_font and force bars, in pixels.
layout(location = 0) in vec2 in_pixel;
layout(location = 1) in vec4 in_colour;
layout(push_constant) uniform Push { vec2 inv_size; } push;
layout(location = 0) out vec4 v_colour;
void main() {
  v_colour = in_colour;
  gl_Position = vec4(in_pixel * push.inv_size * 2.0 - 1.0, 0.0, 1.0);
}
