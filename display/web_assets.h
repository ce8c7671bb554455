// The web view's page and script (display/web/), compiled into tessera-display so that it
// serves them wherever it runs, with no files to install and nothing fetched elsewhere.
#pragma once
#include <cstddef>
#include <vector>

namespace tessera::display {

struct WebAsset {
  const char* path;  // "/index.html", "/viewer.js"
  const char* mime;
  const unsigned char* data;
  size_t size;
};

const std::vector<WebAsset>& webAssets();

}  // namespace tessera::display
