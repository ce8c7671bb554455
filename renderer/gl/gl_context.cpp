// OSMesa context creation and binding (see gl_context.h).
#include "renderer/gl/gl_context.h"

#include <stdexcept>
#include <string>

#include "renderer/gl/gl_functions.h"

namespace tessera::renderer::gl {

GlContext::GlContext(const char* who, int major, int minor) {
  const int attrs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_STENCIL_BITS, 0,
                       OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, major,
                       OSMESA_CONTEXT_MINOR_VERSION, minor, 0};
  ctx_ = OSMesaCreateContextAttribs(attrs, nullptr);
  if (!ctx_)
    throw std::runtime_error("OSMesa: cannot create an OpenGL " + std::to_string(major) + "." + std::to_string(minor) +
                             " core profile context for the " + who + " (it needs 4.5)");
  try {
    makeCurrent();
    loadGlFunctions();
  } catch (...) {
    OSMesaDestroyContext(ctx_);
    throw;
  }
}

GlContext::~GlContext() {
  if (OSMesaGetCurrentContext() == ctx_) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
  OSMesaDestroyContext(ctx_);
}

void GlContext::makeCurrent() {
  if (OSMesaGetCurrentContext() == ctx_) return;
  if (!OSMesaMakeCurrent(ctx_, dummy_, GL_UNSIGNED_BYTE, 1, 1))
    throw std::runtime_error("OSMesa: cannot make the context current");
}

}  // namespace tessera::renderer::gl
