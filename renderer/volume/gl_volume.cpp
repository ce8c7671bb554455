// GlVolumeRenderer: textures, per-frame ray setup on the CPU (double precision, shared with
// the CPU caster), one draw over the brick's footprint into an RGBA32F FBO, float readback.
#include "renderer/volume/gl_volume.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "common/clock.h"
#include "common/parallel.h"
#include "renderer/gl/gl_context.h"
#include "renderer/gl/gl_functions.h"
#include "renderer/volume/gl_volume_shader.h"
#include "renderer/volume/minmax.h"
#include "renderer/volume/ray_setup.h"
#include "renderer/volume/tf_table.h"

namespace tessera::renderer {

namespace {

constexpr float kQuantScale = 65535.0f;  // same quantization as the CPU fast path
constexpr int64_t kMaxSamples = int64_t{1} << 24;  // sample indices travel as exact floats


void texParams(GLenum target, GLint filter) {
  glTexParameteri(target, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(target, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
  glTexParameteri(target, GL_TEXTURE_BASE_LEVEL, 0);
  glTexParameteri(target, GL_TEXTURE_MAX_LEVEL, 0);
}

void checkGl(const char* what) {
  const GLenum err = glGetError();
  if (err != GL_NO_ERROR) throw std::runtime_error(std::string("OSMesa: GL error ") + std::to_string(err) + " " + what);
}

// Per-pixel spans in double precision (the CPU caster's own code) for the rows of the
// footprint: s0 = (u0, k_first), s1 = (du, k_end) per pixel, zero where a ray misses. The
// jitter lives in u0, so the shader samples the CPU caster's grid either way.
void raySpans(const RayGenerator& gen, const VolumeGeometry& geom, const Brick& brick, double step, bool jitter,
              const Rect& fp, unsigned threads, std::vector<float>& s0, std::vector<float>& s1) {
  s0.assign((size_t)fp.w * fp.h * 4, 0.0f);
  s1.assign((size_t)fp.w * fp.h * 4, 0.0f);
  std::atomic<bool> too_long{false};
  parallelRanges(fp.h, threads, [&](long long r0, long long r1) {
    for (long long r = r0; r < r1; ++r)
      for (int x = 0; x < fp.w; ++x) {
        RaySpan span;
        const int px = fp.x + x, py = fp.y + (int)r;
        if (!raySpan(geom, gen.pixelRay(px, py), brick, step, span, jitter ? pixelJitter(px, py) : 0.5)) continue;
        if (span.k_end >= kMaxSamples) {
          too_long = true;
          continue;
        }
        float* a = &s0[((size_t)r * fp.w + x) * 4];
        float* b = &s1[((size_t)r * fp.w + x) * 4];
        for (int c = 0; c < 3; ++c) a[c] = (float)span.u0[c], b[c] = (float)span.du[c];
        a[3] = (float)span.k_first;
        b[3] = (float)span.k_end;
      }
  });
  if (too_long)
    throw std::invalid_argument("GlVolumeRenderer::render: more than 2^24 samples on one ray (step too small)");
}

}  // namespace

struct GlVolumeRenderer::Impl {
  std::shared_ptr<const Volume> volume;
  TransferFunction tf;
  std::optional<gl::GlContext> context;
  unsigned program = 0, vao = 0, fbo = 0;
  unsigned tex_vol = 0, tex_table = 0, tex_dist = 0, tex_span0 = 0, tex_span1 = 0, tex_color = 0, tex_counts = 0;
  int fb_w = 0, fb_h = 0, span_w = 0, span_h = 0;
  double table_step = -1;
  int first_nz = 0, last_nz = -1;
  float table_scale = TfTable::kEntries - 1, table_offset = 0;
  std::array<int, 3> nb{1, 1, 1};
  mutable std::mutex mu;
  std::unique_ptr<Raycaster> reference;  // CPU double-precision path for quality: reference

  void makeCurrent() { context->makeCurrent(); }
  int uniform(const char* name) const { return gl::GetUniformLocation(program, name); }
  void uploadVolume();
  void uploadDistance();
  void ensureTable(double step);
  void ensureTargets(int w, int h);
  void uploadSpans(const std::vector<float>& s0, const std::vector<float>& s1, int w, int h);
  // Draws the footprint `fp` with the spans s0/s1; reads back colours (and sample counts).
  void castRays(const Quality& q, const Rect& fp, const std::vector<float>& s0, const std::vector<float>& s1,
                std::vector<float>& rgba, std::vector<float>* counts);
};

void GlVolumeRenderer::Impl::uploadVolume() {
  const Volume& v = *volume;
  GLint max3d = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3d);
  for (int a = 0; a < 3; ++a)
    if (v.dims[a] > max3d)
      throw std::invalid_argument("GlVolumeRenderer: volume dimension " + std::to_string(v.dims[a]) +
                                  " exceeds the 3D texture limit " + std::to_string(max3d));
  std::vector<uint16_t> q(v.voxelCount());
  for (size_t i = 0; i < q.size(); ++i)
    q[i] = (uint16_t)(std::clamp(v.values[i], 0.0f, 1.0f) * kQuantScale + 0.5f);  // finite values: no fmin/fmax calls
  glGenTextures(1, &tex_vol);
  glBindTexture(GL_TEXTURE_3D, tex_vol);
  texParams(GL_TEXTURE_3D, GL_LINEAR);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl::TexImage3D(GL_TEXTURE_3D, 0, GL_R16, v.dims[0], v.dims[1], v.dims[2], 0, GL_RED, GL_UNSIGNED_SHORT, q.data());
  checkGl("uploading the volume texture");
}

void GlVolumeRenderer::Impl::uploadDistance() {
  const MinMaxHierarchy h(*volume);
  const TransferFunction& f = tf;
  const auto e = h.classify([&f](float lo, float hi) { return TfTable::rangeIsEmpty(f, lo, hi); });
  nb = h.dims(0);
  const size_t per = (size_t)nb[0] * nb[1] * nb[2];
  std::vector<uint8_t> d(per * 8);
  for (int o = 0; o < 8; ++o) std::memcpy(&d[per * o], e.octant_distance[o].data(), per);
  glGenTextures(1, &tex_dist);
  glBindTexture(GL_TEXTURE_3D, tex_dist);
  texParams(GL_TEXTURE_3D, GL_NEAREST);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl::TexImage3D(GL_TEXTURE_3D, 0, GL_R8UI, nb[0], nb[1], nb[2] * 8, 0, GL_RED_INTEGER, GL_UNSIGNED_BYTE, d.data());
  checkGl("uploading the distance maps");
}

void GlVolumeRenderer::Impl::ensureTable(double step) {
  if (step == table_step) return;
  const TfTable t(tf, step);
  if (!tex_table) glGenTextures(1, &tex_table);
  glBindTexture(GL_TEXTURE_1D, tex_table);
  texParams(GL_TEXTURE_1D, GL_LINEAR);  // one filtered fetch: ~25% faster than two texelFetch
  glTexImage1D(GL_TEXTURE_1D, 0, GL_RGBA32F, TfTable::kEntries, 0, GL_RGBA, GL_FLOAT, t.rgba());
  checkGl("uploading the transfer-function table");
  first_nz = t.firstNonzero();
  last_nz = t.lastNonzero();
  table_scale = t.scale(), table_offset = t.offset();
  table_step = step;
}

void GlVolumeRenderer::Impl::ensureTargets(int w, int h) {
  if (w <= fb_w && h <= fb_h) return;
  w = std::max(w, fb_w);
  h = std::max(h, fb_h);
  for (unsigned* t : {&tex_color, &tex_counts}) {
    if (!*t) glGenTextures(1, t);
    glBindTexture(GL_TEXTURE_2D, *t);
    texParams(GL_TEXTURE_2D, GL_NEAREST);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
  }
  if (!fbo) gl::GenFramebuffers(1, &fbo);
  gl::BindFramebuffer(GL_FRAMEBUFFER, fbo);
  gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex_color, 0);
  gl::FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, tex_counts, 0);
  const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl::DrawBuffers(2, bufs);
  const GLenum st = gl::CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (st != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("OSMesa: RGBA32F framebuffer " + std::to_string(w) + "x" + std::to_string(h) +
                             " is incomplete (status " + std::to_string(st) + ")");
  fb_w = w;
  fb_h = h;
}

void GlVolumeRenderer::Impl::uploadSpans(const std::vector<float>& s0, const std::vector<float>& s1, int w, int h) {
  const bool realloc = w != span_w || h != span_h;
  int i = 0;
  for (unsigned* t : {&tex_span0, &tex_span1}) {
    const float* data = (i++ == 0 ? s0 : s1).data();
    if (!*t) glGenTextures(1, t);
    glBindTexture(GL_TEXTURE_2D, *t);
    if (realloc) {
      texParams(GL_TEXTURE_2D, GL_NEAREST);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, data);
    } else {
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, data);
    }
  }
  span_w = w;
  span_h = h;
}

GlVolumeRenderer::GlVolumeRenderer(std::shared_ptr<const Volume> volume, TransferFunction tf)
    : impl_(std::make_unique<Impl>()) {
  if (!volume) throw std::invalid_argument("GlVolumeRenderer: null volume");
  const Volume& v = *volume;
  for (int a = 0; a < 3; ++a)
    if (v.dims[a] <= 0) throw std::invalid_argument("GlVolumeRenderer: volume dims must be positive");
  if (v.values.size() != v.voxelCount())
    throw std::invalid_argument("GlVolumeRenderer: volume value count != dims product");
  if (tf.points().empty()) throw std::invalid_argument("GlVolumeRenderer: transfer function has no points");
  for (size_t i = 0; i < v.values.size(); ++i)
    if (!std::isfinite(v.values[i]))
      throw std::invalid_argument("GlVolumeRenderer: non-finite volume value at linear index " + std::to_string(i));
  Impl& m = *impl_;
  m.volume = std::move(volume);
  m.tf = std::move(tf);
  m.context.emplace("GLSL volume backend");  // destroyed with impl_: frees what is left on failure
  m.program = gl::buildProgram(glv::volumeVertexShader(), glv::volumeFragmentShader());
  gl::GenVertexArrays(1, &m.vao);
  m.uploadVolume();
  m.uploadDistance();
}

GlVolumeRenderer::~GlVolumeRenderer() {
  Impl& m = *impl_;
  try {
    m.makeCurrent();
    for (unsigned t : {m.tex_vol, m.tex_table, m.tex_dist, m.tex_span0, m.tex_span1, m.tex_color, m.tex_counts})
      if (t) glDeleteTextures(1, &t);
    if (m.fbo) gl::DeleteFramebuffers(1, &m.fbo);
    gl::DeleteVertexArrays(1, &m.vao);
    gl::DeleteProgram(m.program);
  } catch (...) {  // destroying the context (with impl_) frees everything anyway
  }
}

void GlVolumeRenderer::Impl::castRays(const Quality& q, const Rect& fp, const std::vector<float>& s0,
                                      const std::vector<float>& s1, std::vector<float>& rgba,
                                      std::vector<float>* counts) {
  const Volume& v = *volume;
  makeCurrent();
  ensureTable(q.step);
  ensureTargets(fp.w, fp.h);
  uploadSpans(s0, s1, fp.w, fp.h);
  gl::BindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, fp.w, fp.h);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  gl::UseProgram(program);
  gl::Uniform3f(uniform("inv_n"), 1.0f / v.dims[0], 1.0f / v.dims[1], 1.0f / v.dims[2]);
  gl::Uniform3f(uniform("umax"), (float)(v.dims[0] - 1), (float)(v.dims[1] - 1), (float)(v.dims[2] - 1));
  gl::Uniform3i(uniform("imax"), std::max(0, v.dims[0] - 2), std::max(0, v.dims[1] - 2), std::max(0, v.dims[2] - 2));
  gl::Uniform3i(uniform("nb"), nb[0], nb[1], nb[2]);
  gl::Uniform1f(uniform("et"), (float)std::min(q.early_termination, 2.0));
  gl::Uniform1i(uniform("skip"), q.skip_empty ? 1 : 0);
  gl::Uniform1i(uniform("first_nz"), first_nz);
  gl::Uniform1i(uniform("last_nz"), last_nz);
  gl::Uniform1f(uniform("table_max"), (float)(TfTable::kEntries - 1));
  gl::Uniform1f(uniform("table_scale"), table_scale);
  gl::Uniform1f(uniform("table_offset"), table_offset);
  const std::pair<GLenum, unsigned> units[] = {{GL_TEXTURE_3D, tex_vol},   {GL_TEXTURE_1D, tex_table},
                                               {GL_TEXTURE_3D, tex_dist},  {GL_TEXTURE_2D, tex_span0},
                                               {GL_TEXTURE_2D, tex_span1}};
  for (int i = 0; i < 5; ++i) {
    gl::ActiveTexture(GL_TEXTURE0 + i);
    glBindTexture(units[i].first, units[i].second);
  }
  gl::ActiveTexture(GL_TEXTURE0);
  gl::BindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);

  rgba.assign((size_t)fp.w * fp.h * 4, 0.0f);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, fp.w, fp.h, GL_RGBA, GL_FLOAT, rgba.data());
  if (counts) {
    counts->resize(rgba.size());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, fp.w, fp.h, GL_RGBA, GL_FLOAT, counts->data());
  }
  checkGl("while ray casting");
}

ImageF GlVolumeRenderer::render(const Camera& cam, int width, int height, const Brick& brick, const RenderOptions& opt,
                                RenderStats* stats, Rect* active, ImageF recycled) const {
  const auto start = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  const Volume& v = *m.volume;
  checkRenderArguments("GlVolumeRenderer::render", v, width, height, brick, opt.quality);
  const Quality q = samplingQuality(opt.quality, v);
  std::lock_guard lock(m.mu);
  if (q.reference) {
    // The reference is defined in double precision; GLSL floats cannot give it.
    if (!m.reference) m.reference = std::make_unique<Raycaster>(m.volume, m.tf);
    return m.reference->render(cam, width, height, brick, opt, stats, active, std::move(recycled));
  }

  const RayGenerator gen(cam, width, height);  // validates the camera
  const VolumeGeometry geom(v);
  ImageF img = takeRecycled(width, height, std::move(recycled));
  const Rect fp = brickFootprint(gen, geom, brick, width, height);
  if (active) *active = Rect{};
  if (stats) *stats = RenderStats{};
  if (fp.empty()) return img;

  std::vector<float> s0, s1;
  raySpans(gen, geom, brick, q.step, q.jitter, fp, threadCount(opt.threads, fp.h), s0, s1);
  std::vector<float> rgba, counts;
  m.castRays(q, fp, s0, s1, rgba, stats ? &counts : nullptr);

  // FBO row r holds footprint row r (the spans were laid out that way): no flip needed.
  int ax0 = width, ay0 = height, ax1 = -1, ay1 = -1;
  for (int r = 0; r < fp.h; ++r) {
    const float* src = &rgba[(size_t)r * fp.w * 4];
    std::memcpy(img.at(fp.x, fp.y + r), src, (size_t)fp.w * 4 * sizeof(float));
    for (int x = 0; x < fp.w; ++x)
      if (src[4 * x + 3] > 0) {
        ax0 = std::min(ax0, fp.x + x), ax1 = std::max(ax1, fp.x + x);
        ay0 = std::min(ay0, fp.y + r), ay1 = std::max(ay1, fp.y + r);
      }
  }
  if (active && ax1 >= 0) *active = Rect{ax0, ay0, ax1 - ax0 + 1, ay1 - ay0 + 1};
  if (stats) {
    for (size_t i = 0; i < counts.size(); i += 4) {
      stats->samples += (uint64_t)counts[i];
      stats->samples_skipped += (uint64_t)counts[i + 1];
      stats->samples_terminated += (uint64_t)counts[i + 2];
    }
    stats->ms = msSince(start);
  }
  return img;
}

}  // namespace tessera::renderer
