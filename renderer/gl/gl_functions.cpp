// Resolves the GL entry points listed in gl_functions.h through OSMesaGetProcAddress.
#include "renderer/gl/gl_functions.h"

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

static unsigned compile(GLenum kind, const char* src) {
  const unsigned s = gl::CreateShader(kind);
  gl::ShaderSource(s, 1, &src, nullptr);
  gl::CompileShader(s);
  GLint ok = 0;
  gl::GetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    gl::GetShaderInfoLog(s, sizeof log, nullptr, log);
    gl::DeleteShader(s);
    throw std::runtime_error(std::string("OSMesa: shader compilation failed: ") + log);
  }
  return s;
}
unsigned buildProgram(const char* vertex_src, const char* fragment_src) {
  const unsigned vs = compile(GL_VERTEX_SHADER, vertex_src);
  unsigned fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, fragment_src);
  } catch (...) {
    gl::DeleteShader(vs);
    throw;
  }
  const unsigned p = gl::CreateProgram();
  gl::AttachShader(p, vs);
  gl::AttachShader(p, fs);
  gl::LinkProgram(p);
  gl::DeleteShader(vs);
  gl::DeleteShader(fs);
  GLint ok = 0;
  gl::GetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    gl::GetProgramInfoLog(p, sizeof log, nullptr, log);
    gl::DeleteProgram(p);
    throw std::runtime_error(std::string("OSMesa: shader program failed to link: ") + log);
  }
  return p;
}

}  // namespace tessera::renderer::gl
