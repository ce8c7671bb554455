// PNG folder sink: one file per frame, <dir>/frame_<id, 6 digits>.png, via writePng, and
// optionally frame_<id>.pam with the premultiplied values (for exact comparisons).
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "common/io/image_io.h"
#include "display/sink.h"

namespace tessera::display {
namespace {

class PngSink final : public Sink {
 public:
  PngSink(std::string dir, std::optional<std::array<double, 3>> background, bool premultiplied)
      : dir_(std::move(dir)), background_(background), premultiplied_(premultiplied) {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec || !std::filesystem::is_directory(dir_))
      throw std::runtime_error("png sink: cannot create folder '" + dir_ + "': " + ec.message());
  }

  // The status line is not burnt into files: they stay comparable with reference images.
  void present(const Image8& frame, const Shown& shown) override {
    char name[40];
    std::snprintf(name, sizeof name, "frame_%06llu", (unsigned long long)shown.id);
    const std::filesystem::path stem = std::filesystem::path(dir_) / name;
    writePng(stem.string() + ".png", frame, background_);
    if (premultiplied_) writePam(stem.string() + ".pam", frame);
  }

 private:
  std::string dir_;
  std::optional<std::array<double, 3>> background_;
  bool premultiplied_;
};

}  // namespace

std::unique_ptr<Sink> makePngSink(const std::string& dir, std::optional<std::array<double, 3>> background,
                                  bool premultiplied) {
  return std::make_unique<PngSink>(dir, background, premultiplied);
}

}  // namespace tessera::display
