// GLSL ray casting (see gl_volume.h). One fragment per pixel of the brick's footprint; the
// CPU precomputes each pixel's span on the global sample grid in double precision
// (ray_setup.h), so both backends take exactly the same samples k. Sample k sits at the
// voxel coordinate fma(k, du, u0) in float, like the CPU fast kernel; the volume is a
// GL_LINEAR R16 texture of the same quantized values, the classification the same 4096-entry
// table with the same linear interpolation. Empty-space leaps follow the CPU Leaper (directional
// chessboard distance maps over the 8^3 min-max blocks): a sample is leapt over only when
// it lies kMargin inside an empty cube, and a sample taken in an empty block classifies to
// exactly zero alpha, so leaping changes no bit of the image.
#include "renderer/volume/gl_volume_shader.h"

namespace tessera::renderer::glv {

const char* volumeVertexShader() {
  return R"(#version 450 core
void main() {
  const vec2 p[3] = vec2[3](vec2(-1.0, -1.0), vec2(3.0, -1.0), vec2(-1.0, 3.0));
  gl_Position = vec4(p[gl_VertexID], 0.0, 1.0);
})";
}

// Over 80 lines on purpose: it returns one GLSL program as text, and the program reads
// best as the one ray loop it is.
const char* volumeFragmentShader() {
  return R"(#version 450 core
layout(binding = 0) uniform sampler3D vol;     // R16, GL_LINEAR, CLAMP_TO_EDGE
layout(binding = 1) uniform sampler1D table;   // RGBA32F premultiplied, opacity-corrected
layout(binding = 2) uniform usampler3D dist;   // R8UI, octant o at z + o * nb.z
layout(binding = 3) uniform sampler2D span0;   // u0.xyz, k_first
layout(binding = 4) uniform sampler2D span1;   // du.xyz, k_end
uniform vec3 inv_n;        // 1 / dims
uniform vec3 umax;         // dims - 1
uniform ivec3 imax;        // max(0, dims - 2)
uniform ivec3 nb;          // blocks per axis
uniform float et;          // early termination threshold (> 1: never)
uniform int skip;          // empty-space leaps on/off
uniform int first_nz;      // table entries that can give alpha > 0
uniform int last_nz;
uniform float table_max;   // entries - 1
uniform float table_scale, table_offset;  // scalar s at table position s * scale + offset (TfTable)
layout(location = 0) out vec4 color;
layout(location = 1) out vec4 counts;  // taken, leapt over, terminated

const float kBlock = 8.0;
const float kMargin = 1.0 / 64.0;
const float kInf = 1e30;
const int kMinRun = 16;

vec3 u0, du;

// Sample index at which the ray leaves the cube of r^3 blocks that starts at block b and
// extends along the ray's octant, shrunk by margin; inside: u is in that shrunk cube.
float cubeExit(vec3 u, ivec3 b, int r, float margin, out bool inside) {
  float e = kInf;
  inside = true;
  for (int a = 0; a < 3; ++a) {
    bool neg = du[a] < 0.0;
    int first = neg ? b[a] - r + 1 : b[a];
    int last = neg ? b[a] + 1 : b[a] + r;
    float lo = first <= 0 ? -kInf : float(first) * kBlock + margin;
    float hi = last >= nb[a] ? kInf : float(last) * kBlock - margin;
    inside = inside && u[a] >= lo && u[a] <= hi;
    if (du[a] != 0.0) e = min(e, ((du[a] > 0.0 ? hi : lo) - u0[a]) / du[a]);
  }
  return e;
}

void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 s0 = texelFetch(span0, p, 0), s1 = texelFetch(span1, p, 0);
  u0 = s0.xyz;
  du = s1.xyz;
  int k = int(s0.w), k_end = int(s1.w);
  int octant = (du.x < 0.0 ? 1 : 0) | (du.y < 0.0 ? 2 : 0) | (du.z < 0.0 ? 4 : 0);
  vec4 acc = vec4(0.0);
  float taken = 0.0, leapt = 0.0, terminated = 0.0;
  int check = k;  // next sample at which to consult the distance map
  while (k < k_end) {
    if (skip != 0 && k >= check) {
      vec3 u = fma(vec3(float(k)), du, u0);
      ivec3 b = min(ivec3(clamp(u, vec3(0.0), umax)), imax) / 8;
      int d = int(texelFetch(dist, ivec3(b.x, b.y, b.z + octant * nb.z), 0).r);
      bool inside;
      if (d > 0) {
        float e = min(cubeExit(u, b, d, kMargin, inside), float(k_end));
        int next = min(k_end, int(e) + 1);
        if (inside && next > k) {
          leapt += float(next - k);
          k = next;
          continue;
        }
      }
      float e = min(cubeExit(u, b, 1, 0.0, inside), float(k_end));
      check = max(int(e) + 1, k + kMinRun);
    }
    vec3 u = fma(vec3(float(k)), du, u0);
    float s = textureLod(vol, (u + 0.5) * inv_n, 0.0).r;
    float ft = clamp(s * table_scale + table_offset, 0.0, table_max);
    int ti = min(int(ft), int(table_max) - 1);
    taken += 1.0;
    ++k;
    if (ti < first_nz || ti > last_nz) continue;  // exactly zero alpha: a no-op
    // GL_LINEAR between entries ti and ti+1 at weight fract(ft): the CPU's lerp, done by
    // the texture unit in float.
    vec4 pc = textureLod(table, (ft + 0.5) / (table_max + 1.0), 0.0);
    acc = fma(vec4(1.0 - acc.a), pc, acc);
    if (acc.a >= et) {
      terminated = float(k_end - k);
      break;
    }
  }
  color = acc;
  counts = vec4(taken, leapt, terminated, 0.0);
})";
}

}  // namespace tessera::renderer::glv
