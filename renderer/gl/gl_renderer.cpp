// OSMesa core-profile triangle renderer (see gl_renderer.h). Why a scissor and not a tile-sized
// framebuffer with an offset viewport: llvmpipe evaluates attribute planes and edge functions in
// float relative to the framebuffer origin, so moving the origin can change the last bit of an
// interpolated colour; with the same framebuffer and viewport every fragment is computed alike.
#include "renderer/gl/gl_renderer.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "common/clock.h"
#include "renderer/gl/gl_functions.h"

namespace tessera::renderer {

namespace {

const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 color;
uniform mat4 mvp;
uniform mat4 view;
out vec3 v_normal;
out vec3 v_color;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  v_normal = mat3(view) * normal;
  v_color = color;
})";

// Two-sided Lambert (abs) so that a camera inside a closed mesh still sees lit surfaces.
const char* kFragmentShader = R"(#version 450 core
in vec3 v_normal;
in vec3 v_color;
uniform vec3 light;  // view space, towards the light, unit length
uniform float ambient;
out vec4 frag;
void main() {
  float n2 = dot(v_normal, v_normal);
  float lambert = n2 > 1e-30 ? min(abs(dot(v_normal, light)) * inversesqrt(n2), 1.0) : 1.0;
  frag = vec4(clamp(v_color, 0.0, 1.0) * (ambient + (1.0 - ambient) * lambert), 1.0);
})";


std::array<float, 16> toFloat(const std::array<double, 16>& m) {
  std::array<float, 16> f;
  for (int i = 0; i < 16; ++i) f[i] = (float)m[i];
  return f;
}

}  // namespace

GlRenderer::GlRenderer() : context_("triangle renderer") {
  {
    makeCurrent();
    program_ = gl::buildProgram(kVertexShader, kFragmentShader);
    loc_mvp_ = gl::GetUniformLocation(program_, "mvp");
    loc_view_ = gl::GetUniformLocation(program_, "view");
    loc_light_ = gl::GetUniformLocation(program_, "light");
    loc_ambient_ = gl::GetUniformLocation(program_, "ambient");
    gl::GenVertexArrays(1, &vao_);
    gl::GenBuffers(1, &vbo_);
    gl::GenBuffers(1, &ibo_);
    gl::ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);  // reversed float depth, see projection.h
  }
}

GlRenderer::~GlRenderer() {
  makeCurrent();
  releaseTargets();
  gl::DeleteBuffers(1, &vbo_);
  gl::DeleteBuffers(1, &ibo_);
  gl::DeleteVertexArrays(1, &vao_);
  gl::DeleteProgram(program_);
}

void GlRenderer::makeCurrent() { context_.makeCurrent(); }

void GlRenderer::setMesh(const Mesh& mesh) {
  validateMesh(mesh, "GlRenderer::setMesh");
  makeCurrent();
  // Interleaved position, normal, colour: 9 floats per vertex.
  std::vector<float> v(mesh.vertexCount() * 9);
  for (size_t i = 0; i < mesh.vertexCount(); ++i)
    for (int c = 0; c < 3; ++c) {
      v[9 * i + c] = mesh.positions[3 * i + c];
      v[9 * i + 3 + c] = mesh.normals[3 * i + c];
      v[9 * i + 6 + c] = mesh.colors[3 * i + c];
    }
  gl::BindVertexArray(vao_);
  gl::BindBuffer(GL_ARRAY_BUFFER, vbo_);
  gl::BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
  gl::BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  gl::BufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(mesh.indices.size() * 4), mesh.indices.data(), GL_STATIC_DRAW);
  for (int a = 0; a < 3; ++a) {
    gl::EnableVertexAttribArray(a);
    gl::VertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 9 * sizeof(float), (const void*)(size_t)(a * 3 * sizeof(float)));
  }
  bounds_ = bounds(mesh);
  triangles_ = mesh.triangleCount();
}

void GlRenderer::releaseTargets() {
  gl::DeleteFramebuffers(1, &fbo_draw_);
  gl::DeleteFramebuffers(1, &fbo_resolve_);
  gl::DeleteRenderbuffers(1, &rb_color_);
  gl::DeleteRenderbuffers(1, &rb_depth_);
  gl::DeleteRenderbuffers(1, &rb_resolve_);
  fbo_draw_ = fbo_resolve_ = rb_color_ = rb_depth_ = rb_resolve_ = 0;
  fb_w_ = fb_h_ = fb_samples_ = 0;
}

void GlRenderer::ensureTargets(int w, int h, int samples) {
  if (w == fb_w_ && h == fb_h_ && samples == fb_samples_) return;
  releaseTargets();
  auto storage = [&](unsigned rb, GLenum format, int s) {
    gl::BindRenderbuffer(GL_RENDERBUFFER, rb);
    if (s > 1) gl::RenderbufferStorageMultisample(GL_RENDERBUFFER, s, format, w, h);
    else gl::RenderbufferStorage(GL_RENDERBUFFER, format, w, h);
  };
  auto check = [&](const char* what) {
    const GLenum st = gl::CheckFramebufferStatus(GL_FRAMEBUFFER);
    if (st != GL_FRAMEBUFFER_COMPLETE) {
      char msg[160];
      std::snprintf(msg, sizeof msg, "OSMesa: %s framebuffer %dx%d with %d samples is incomplete (status 0x%x)",
                    what, w, h, samples, (unsigned)st);
      releaseTargets();
      throw std::runtime_error(msg);
    }
  };
  gl::GenRenderbuffers(1, &rb_color_);
  gl::GenRenderbuffers(1, &rb_depth_);
  storage(rb_color_, GL_RGBA8, samples);
  storage(rb_depth_, GL_DEPTH_COMPONENT32F, samples);
  gl::GenFramebuffers(1, &fbo_draw_);
  gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_draw_);
  gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_color_);
  gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_depth_);
  check("draw");
  if (samples > 1) {
    gl::GenRenderbuffers(1, &rb_resolve_);
    storage(rb_resolve_, GL_RGBA8, 1);
    gl::GenFramebuffers(1, &fbo_resolve_);
    gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_resolve_);
    gl::FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_resolve_);
    check("resolve");
  }
  fb_w_ = w;
  fb_h_ = h;
  fb_samples_ = samples;
}

uint64_t GlRenderer::drawChunks(std::span<const Chunk> draw) {
  uint64_t tris = 0;
  for (size_t i = 0; i < draw.size();) {
    // Consecutive chunks go in one call: fewer draws, same fragments in the same order.
    size_t j = i + 1;
    uint32_t count = draw[i].triangle_count;
    while (j < draw.size() && draw[j].first_triangle == draw[i].first_triangle + count)
      count += draw[j++].triangle_count;
    if (draw[i].first_triangle + (uint64_t)count > triangles_)
      throw std::invalid_argument("GlRenderer: chunk beyond the uploaded mesh");
    if (count > 0)
      glDrawElements(GL_TRIANGLES, (GLsizei)(3 * count), GL_UNSIGNED_INT,
                     (const void*)((size_t)draw[i].first_triangle * 12));
    tris += count;
    i = j;
  }
  return tris;
}

namespace {

// The k x k box average of GL's bottom-up rows of sw x sh pixels, as a w x h image top to
// bottom (k = 1: a flip only).
Image8 boxDownsample(const std::vector<uint8_t>& raw, int sw, int sh, int w, int h, int k) {
  Image8 out(w, h);
  const int kk = k * k;
  for (int y = 0; y < h; ++y) {
    uint8_t* dst = out.at(0, y);
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c) {
        int sum = 0;
        for (int dy = 0; dy < k; ++dy) {
          const int gl_row = sh - 1 - (y * k + dy);  // flip to rows top to bottom
          const uint8_t* src = &raw[((size_t)gl_row * sw + (size_t)x * k) * 4];
          for (int dx = 0; dx < k; ++dx) sum += src[dx * 4 + c];
        }
        dst[4 * x + c] = (uint8_t)((sum + kk / 2) / kk);
      }
  }
  return out;
}

}  // namespace

Image8 GlRenderer::render(const Camera& cam, int width, int height, const Rect& tile, const GlRenderOptions& opt,
                          GlRenderStats* stats) {
  const Chunk all{0, (uint32_t)triangles_, bounds_};
  return render(cam, width, height, tile, std::span<const Chunk>(&all, 1), opt, stats);
}

Image8 GlRenderer::render(const Camera& cam, int width, int height, const Rect& tile, std::span<const Chunk> draw,
                          const GlRenderOptions& opt, GlRenderStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  if (opt.samples != 1 && opt.samples != 2 && opt.samples != 4)
    throw std::invalid_argument("GlRenderer: samples must be 1, 2 or 4, got " + std::to_string(opt.samples));
  if (opt.supersample < 1 || opt.supersample > 8)
    throw std::invalid_argument("GlRenderer: supersample must be 1..8, got " + std::to_string(opt.supersample));
  if (width <= 0 || height <= 0 || tile.empty() || tile.x < 0 || tile.y < 0 || tile.x + tile.w > width ||
      tile.y + tile.h > height)
    throw std::invalid_argument("GlRenderer: tile " + std::to_string(tile.w) + "x" + std::to_string(tile.h) + "+" +
                                std::to_string(tile.x) + "+" + std::to_string(tile.y) + " is not inside the " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
  const int k = opt.supersample, fw = width * k, fh = height * k;
  makeCurrent();
  GLint max_rb = 0;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  if (fw > max_rb || fh > max_rb)
    throw std::invalid_argument("GlRenderer: " + std::to_string(fw) + "x" + std::to_string(fh) +
                                " exceeds the maximum framebuffer size " + std::to_string(max_rb));
  ensureTargets(fw, fh, opt.samples);
  // The projection depends on the image's aspect only, never on the tile or on k.
  const ViewProjection vp = makeViewProjection(cam, width, height, bounds_);

  gl::BindFramebuffer(GL_FRAMEBUFFER, fbo_draw_);
  glViewport(0, 0, fw, fh);
  const int sx = tile.x * k, sw = tile.w * k, sh = tile.h * k, sy = fh - (tile.y * k + sh);  // GL rows bottom-up
  glEnable(GL_SCISSOR_TEST);
  glScissor(sx, sy, sw, sh);
  glClearColor(0, 0, 0, 0);
  glClearDepth(0.0);  // reversed depth: far is 0
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDisable(GL_CULL_FACE);
  gl::UseProgram(program_);
  const auto mvp = toFloat(vp.mvp), view = toFloat(vp.view);
  gl::UniformMatrix4fv(loc_mvp_, 1, GL_FALSE, mvp.data());
  gl::UniformMatrix4fv(loc_view_, 1, GL_FALSE, view.data());
  Vec3 l{0, 0, 1};  // headlight: towards the eye in view space
  if (length(opt.light) > 0) {
    const Vec3 w = normalize(opt.light);
    l = {vp.view[0] * w.x + vp.view[4] * w.y + vp.view[8] * w.z, vp.view[1] * w.x + vp.view[5] * w.y + vp.view[9] * w.z,
         vp.view[2] * w.x + vp.view[6] * w.y + vp.view[10] * w.z};
  }
  gl::Uniform3f(loc_light_, (float)l.x, (float)l.y, (float)l.z);
  gl::Uniform1f(loc_ambient_, opt.ambient);
  gl::BindVertexArray(vao_);
  const uint64_t tris = drawChunks(draw);
  if (opt.samples > 1) {
    gl::BindFramebuffer(GL_READ_FRAMEBUFFER, fbo_draw_);
    gl::BindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo_resolve_);
    gl::BlitFramebuffer(sx, sy, sx + sw, sy + sh, sx, sy, sx + sw, sy + sh, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    gl::BindFramebuffer(GL_READ_FRAMEBUFFER, fbo_resolve_);
  } else {
    gl::BindFramebuffer(GL_READ_FRAMEBUFFER, fbo_draw_);
  }
  std::vector<uint8_t> raw((size_t)sw * sh * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(sx, sy, sw, sh, GL_RGBA, GL_UNSIGNED_BYTE, raw.data());
  glDisable(GL_SCISSOR_TEST);
  const GLenum err = glGetError();
  if (err != GL_NO_ERROR) throw std::runtime_error("OSMesa: GL error " + std::to_string(err) + " while rendering");

  Image8 out = boxDownsample(raw, sw, sh, tile.w, tile.h, k);
  if (stats) {
    stats->ms = msSince(t0);
    stats->triangles = tris;
    stats->chunks = (int)draw.size();
  }
  return out;
}

std::vector<Rect> gridTiles(int width, int height, int cols, int rows) {
  if (cols <= 0 || rows <= 0) throw std::invalid_argument("gridTiles: cols and rows must be positive");
  std::vector<Rect> tiles;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const int x0 = (int)((long long)c * width / cols), x1 = (int)((long long)(c + 1) * width / cols);
      const int y0 = (int)((long long)r * height / rows), y1 = (int)((long long)(r + 1) * height / rows);
      if (x1 > x0 && y1 > y0) tiles.push_back({x0, y0, x1 - x0, y1 - y0});
    }
  return tiles;
}

Image8 renderTiles(GlRenderer& r, const Camera& cam, int width, int height, const std::vector<Rect>& tiles,
                   const std::vector<Chunk>& chunks, const GlRenderOptions& opt, GlRenderStats* stats) {
  const ViewProjection vp = r.viewProjection(cam, width, height);
  Image8 out(width, height);
  GlRenderStats sum;
  for (const Rect& t : tiles) {
    std::vector<Chunk> draw;
    for (int i : chunksInTile(chunks, vp, t)) draw.push_back(chunks[i]);
    GlRenderStats s;
    const Image8 part = r.render(cam, width, height, t, draw, opt, &s);
    for (int y = 0; y < t.h; ++y) std::memcpy(out.at(t.x, t.y + y), part.at(0, y), (size_t)t.w * 4);
    sum.ms += s.ms;
    sum.triangles += s.triangles;
    sum.chunks += s.chunks;
  }
  if (stats) *stats = sum;
  return out;
}

}  // namespace tessera::renderer
