// What parseScene refuses a scene with, for the scene tests: the message, which must start
// with the file's name.
#pragma once
#include <gtest/gtest.h>

#include <string>

#include "common/scene.h"

namespace tessera::test {

inline std::string sceneErrorOf(const std::string& yaml, const std::string& base = ".") {
  try {
    parseScene(yaml, base, "s.yaml");
  } catch (const SceneError& e) {
    std::string m = e.what();
    EXPECT_EQ(m.rfind("s.yaml: ", 0), 0u) << "message must start with the file: " << m;
    return m;
  }
  return "<no error>";
}

}  // namespace tessera::test

#define EXPECT_ERROR(yaml, text)                                                                      \
  EXPECT_NE(tessera::test::sceneErrorOf(yaml).find(text), std::string::npos) << "want '" << text << "' in: " \
                                                                            << tessera::test::sceneErrorOf(yaml)
