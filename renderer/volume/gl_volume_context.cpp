// Context creation, extra entry points and program building for the GLSL volume backend.
#include "renderer/volume/gl_volume_context.h"

#include <stdexcept>
#include <string>

#include "renderer/gl/gl_functions.h"

namespace tessera::renderer::glv {

#define TESSERA_GLV_DEFINE(type, name) type name = nullptr;
TESSERA_GLV_FUNCTIONS(TESSERA_GLV_DEFINE)
#undef TESSERA_GLV_DEFINE

OSMesaContext createCoreContext(int major, int minor) {
  const int attrs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_STENCIL_BITS, 0,
                       OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, major,
                       OSMESA_CONTEXT_MINOR_VERSION, minor, 0};
  OSMesaContext ctx = OSMesaCreateContextAttribs(attrs, nullptr);
  if (!ctx)
    throw std::runtime_error("OSMesa: cannot create an OpenGL " + std::to_string(major) + "." + std::to_string(minor) +
                             " core profile context (volume backend needs 4.5)");
  return ctx;
}

void loadVolumeGlFunctions() {
  gl::loadGlFunctions();
  static bool loaded = false;
  if (loaded) return;
#define TESSERA_GLV_LOAD(type, name)                                                            \
  name = reinterpret_cast<type>(OSMesaGetProcAddress("gl" #name));                              \
  if (!name) throw std::runtime_error("OSMesa: OpenGL entry point gl" #name " is not available");
  TESSERA_GLV_FUNCTIONS(TESSERA_GLV_LOAD)
#undef TESSERA_GLV_LOAD
  loaded = true;
}


}  // namespace tessera::renderer::glv
