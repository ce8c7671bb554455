// GLSL sources of the volume backend's ray-casting program (gl_volume_shader.cpp). The
// context and entry points come from renderer/gl (GlContext, gl_functions.h).
#pragma once

namespace tessera::renderer::glv {

const char* volumeVertexShader();
const char* volumeFragmentShader();

}  // namespace tessera::renderer::glv
