// PNG folder sink: one file per frame, <dir>/frame_<id, 6 digits>.png, via writePng.
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "common/io/image_io.h"
#include "display/sink.h"

namespace tessera::display {
namespace {

class PngSink final : public Sink {
 public:
  PngSink(std::string dir, std::optional<std::array<double, 3>> background)
      : dir_(std::move(dir)), background_(background) {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec || !std::filesystem::is_directory(dir_))
      throw std::runtime_error("png sink: cannot create folder '" + dir_ + "': " + ec.message());
  }

  // The status line is not burnt into files: they stay comparable with reference images.
  void present(const Image8& frame, uint64_t id, const std::string& /*status*/) override {
    char name[40];
    std::snprintf(name, sizeof name, "frame_%06llu.png", (unsigned long long)id);
    writePng((std::filesystem::path(dir_) / name).string(), frame, background_);
  }

 private:
  std::string dir_;
  std::optional<std::array<double, 3>> background_;
};

}  // namespace

std::unique_ptr<Sink> makePngSink(const std::string& dir,
                                  std::optional<std::array<double, 3>> background) {
  return std::make_unique<PngSink>(dir, background);
}

}  // namespace tessera::display
