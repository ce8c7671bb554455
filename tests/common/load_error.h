// What loading a scene's volume says when it fails ("<no error>" when it loads): the message
// tests compare with what a user must be told.
#pragma once
#include <exception>
#include <string>

#include "common/scene.h"

namespace tessera::test {

inline std::string loadError(const std::string& yaml, const std::string& dir) {
  try {
    loadVolume(parseScene(yaml, dir, "s.yaml"));
  } catch (const std::exception& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace tessera::test
