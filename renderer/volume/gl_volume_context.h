// OSMesa plumbing for the GLSL volume backend: core-profile context creation with a clear
// error, the GL entry points it needs beyond gl_functions.h, and shader program building.
// Not thread-safe: call with the context current on the calling thread.
#pragma once
#include <GL/osmesa.h>

namespace tessera::renderer::glv {

#define TESSERA_GLV_FUNCTIONS(X)                                 \
  X(PFNGLTEXIMAGE3DPROC, TexImage3D)                             \
  X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                       \
  X(PFNGLUNIFORM1IPROC, Uniform1i)                               \
  X(PFNGLUNIFORM3IPROC, Uniform3i)                               \
  X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                           \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)

#define TESSERA_GLV_DECLARE(type, name) extern type name;
TESSERA_GLV_FUNCTIONS(TESSERA_GLV_DECLARE)
#undef TESSERA_GLV_DECLARE

// Creates an OSMesa core-profile context of the given version. Throws std::runtime_error
// with one line naming what was asked for if OSMesa refuses (e.g. 4.6 on Mesa 22).
OSMesaContext createCoreContext(int major, int minor);

// Loads gl_functions.h's entry points and the ones above (idempotent).
void loadVolumeGlFunctions();

// GLSL sources of the ray-casting program (gl_volume_shader.cpp).
const char* volumeVertexShader();
const char* volumeFragmentShader();

}  // namespace tessera::renderer::glv
