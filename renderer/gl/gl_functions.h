// Pointers to the OpenGL entry points past 1.1 that the OSMesa backend uses, resolved with
// OSMesaGetProcAddress (libOSMesa does not export every core function, e.g. glCreateVertexArrays).
// loadGlFunctions() needs a current context; it is idempotent and not thread-safe.
#pragma once
#include <GL/osmesa.h>

namespace tessera::renderer::gl {

#define TESSERA_GL_FUNCTIONS(X)                                      \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                       \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                 \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                       \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)       \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)         \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)                     \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)               \
  X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)                     \
  X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)               \
  X(PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC, RenderbufferStorageMultisample) \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer)                       \
  X(PFNGLGENBUFFERSPROC, GenBuffers)                                 \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                           \
  X(PFNGLBINDBUFFERPROC, BindBuffer)                                 \
  X(PFNGLBUFFERDATAPROC, BufferData)                                 \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                       \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                 \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                       \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)       \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)               \
  X(PFNGLCREATESHADERPROC, CreateShader)                             \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                             \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                           \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                               \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                     \
  X(PFNGLDELETESHADERPROC, DeleteShader)                             \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                           \
  X(PFNGLATTACHSHADERPROC, AttachShader)                             \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                               \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                             \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                   \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                           \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                                 \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                 \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)                     \
  X(PFNGLUNIFORM3FPROC, Uniform3f)                                   \
  X(PFNGLUNIFORM1FPROC, Uniform1f)                                   \
  X(PFNGLCLIPCONTROLPROC, ClipControl)                               \
  X(PFNGLDRAWELEMENTSBASEVERTEXPROC, DrawElementsBaseVertex)        \
  X(PFNGLTEXIMAGE3DPROC, TexImage3D)                                 \
  X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                           \
  X(PFNGLUNIFORM1IPROC, Uniform1i)                                   \
  X(PFNGLUNIFORM3IPROC, Uniform3i)                                   \
  X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                               \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)

#define TESSERA_GL_DECLARE(type, name) extern type name;
TESSERA_GL_FUNCTIONS(TESSERA_GL_DECLARE)
#undef TESSERA_GL_DECLARE

// Throws std::runtime_error naming the first entry point the context does not provide.
void loadGlFunctions();
// Compiles and links a vertex + fragment program; throws std::runtime_error with the log.
unsigned buildProgram(const char* vertex_src, const char* fragment_src);

}  // namespace tessera::renderer::gl
