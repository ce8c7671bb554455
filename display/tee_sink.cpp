// Several sinks as one: a window or PNG files, and the web view beside them.
#include "display/sink.h"

namespace tessera::display {
namespace {

class TeeSink final : public Sink {
 public:
  explicit TeeSink(std::vector<std::unique_ptr<Sink>> sinks) : sinks_(std::move(sinks)) {}
  void present(const Image8& frame, const Shown& shown) override {
    for (auto& s : sinks_) s->present(frame, shown);
  }
  std::vector<InputEvent> poll() override {
    std::vector<InputEvent> all;
    for (auto& s : sinks_) {
      auto events = s->poll();
      all.insert(all.end(), events.begin(), events.end());
    }
    return all;
  }
  bool interactive() const override {
    for (const auto& s : sinks_)
      if (s->interactive()) return true;
    return false;
  }

 private:
  std::vector<std::unique_ptr<Sink>> sinks_;
};

}  // namespace

std::unique_ptr<Sink> makeTeeSink(std::vector<std::unique_ptr<Sink>> sinks) {
  return std::make_unique<TeeSink>(std::move(sinks));
}

}  // namespace tessera::display
