// One OSMesa core-profile context (llvmpipe) with the entry points of gl_functions.h loaded:
// what both OSMesa users (the triangle renderer and the GLSL volume backend) start from. OSMesa
// needs a default framebuffer to make a context current; both draw into FBOs, so it is 1x1.
// Owns the context. Not thread-safe: callers serialize use and call makeCurrent() first.
#pragma once
#include <GL/osmesa.h>

namespace tessera::renderer::gl {

class GlContext {
 public:
  // Throws std::runtime_error with one line naming the version asked for (e.g. 4.6 on Mesa 22)
  // and `who` if OSMesa refuses, or the first missing entry point.
  explicit GlContext(const char* who, int major = 4, int minor = 5);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;
  void makeCurrent();

 private:
  OSMesaContext ctx_ = nullptr;
  unsigned char dummy_[4] = {};
};

}  // namespace tessera::renderer::gl
