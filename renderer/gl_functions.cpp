// Resolves the GL entry points listed in gl_functions.h through OSMesaGetProcAddress.
#include "renderer/gl_functions.h"

#include <stdexcept>
#include <string>

namespace tessera::renderer::gl {

#define TESSERA_GL_DEFINE(type, name) type name = nullptr;
TESSERA_GL_FUNCTIONS(TESSERA_GL_DEFINE)
#undef TESSERA_GL_DEFINE

void loadGlFunctions() {
  static bool loaded = false;
  if (loaded) return;
#define TESSERA_GL_LOAD(type, name)                                                             \
  name = reinterpret_cast<type>(OSMesaGetProcAddress("gl" #name));                              \
  if (!name) throw std::runtime_error("OSMesa: OpenGL entry point gl" #name " is not available");
  TESSERA_GL_FUNCTIONS(TESSERA_GL_LOAD)
#undef TESSERA_GL_LOAD
  loaded = true;
}

}  // namespace tessera::renderer::gl
