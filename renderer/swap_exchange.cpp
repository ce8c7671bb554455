#include "renderer/swap_exchange.h"

#include <algorithm>

#include "common/clock.h"
#include "common/net/transport.h"
#include "common/wire/pixels.h"

namespace tessera::renderer {

proto::PixelFormat swapFormat(proto::PixelFormat f) {
  return f == proto::PixelFormat::RGBA8 ? proto::PixelFormat::RGBA16F : f;
}

SwapExchange::SwapExchange(zmq::context_t& ctx, int64_t max_message, size_t max_waiting_bytes)
    : inbox_(ctx, proto::Role::Renderer, max_message, max_waiting_bytes) {}

void SwapExchange::setRoster(const proto::Roster& roster, DropCounter& drops) {
  accept(inbox_.setRoster(roster, drops), drops);
}

void SwapExchange::receive(DropCounter& drops) { accept(inbox_.receive(drops), drops); }

void SwapExchange::accept(std::vector<DataInbox::Message> messages, DropCounter& drops) {
  for (auto& [rank, m] : messages) {
    auto piece = proto::decodePiece(view(m));
    if (!piece) {
      drops.drop(rank, "swap piece: " + piece.error());
      continue;
    }
    if (piece->renderer != rank) {
      drops.drop(rank, "swap piece claims renderer " + std::to_string(piece->renderer));
      continue;
    }
    if (held_.size() >= kMaxHeld) {  // the oldest first: frames move forward
      auto oldest = std::min_element(held_.begin(), held_.end(), [](auto& a, auto& b) { return a.frame < b.frame; });
      drops.drop(oldest->renderer, "swap piece of frame " + std::to_string(oldest->frame) + " evicted: too many held");
      held_.erase(oldest);
    }
    held_.push_back(std::move(*piece));
  }
}

std::optional<proto::Piece> SwapExchange::take(const proto::FrameParams& p, uint32_t from, const Rect& region) {
  for (auto it = held_.begin(); it != held_.end(); ++it) {
    if (it->frame != p.frame || it->epoch != p.epoch || it->renderer != from || it->region != region) continue;
    proto::Piece piece = std::move(*it);
    held_.erase(it);
    return piece;
  }
  return std::nullopt;
}

// Layers' memory goes round: no fresh pages to fault in for every round of every frame.
std::vector<float> SwapExchange::takeSpare() {
  if (spares_.empty()) return {};
  std::vector<float> v = std::move(spares_.back());
  spares_.pop_back();
  return v;
}

void SwapExchange::recycle(Layer&& l) {
  if (spares_.size() < 2 && l.img.px.capacity() > 0) spares_.push_back(std::move(l.img.px));
}

std::optional<Layer> SwapExchange::run(const proto::FrameParams& p, uint32_t me, const SwapPlan& plan,
                                       const ImageF& img, const Rect& active, const Send& send, const Idle& idle,
                                       proto::StageStats& st, DropCounter& drops) {
  // Pieces of frames before this one, or of this frame's older issue, will never be used.
  std::erase_if(held_, [&](const proto::Piece& h) { return h.frame < p.frame || (h.frame == p.frame && h.epoch < p.epoch); });
  const proto::PixelFormat format = swapFormat(p.format);
  Layer mine;
  for (size_t j = 0; j < plan.rounds.size(); ++j) {
    const SwapRound& r = plan.rounds[j];
    auto t0 = Clock::now();
    proto::Piece out;
    out.frame = p.frame;
    out.epoch = p.epoch;
    out.renderer = me;
    out.brick = plan.brick;
    out.region = r.send;
    out.format = format;
    out.render_ms = st.work_ms;
    // Round 0 reads the brick image itself; later rounds, the layer blended last round.
    const LayerView sent = j == 0 ? viewOf(img, active, r.send) : viewOf(mine, r.send);
    out.active = sent.rect;
    packView(sent, format, packed_);
    out.pixels = std::move(packed_);
    auto bytes = proto::encode(out, me, p.codec);
    st.bytes_raw += out.pixels.size();
    st.bytes_encoded += bytes.size();
    packed_ = std::move(out.pixels);
    send(r.endpoint, std::move(bytes));
    st.encode_ms += msSince(t0);

    auto waited = Clock::now();
    std::optional<proto::Piece> in;
    for (;;) {
      in = take(p, r.partner, r.keep);
      if (in && in->format == format) break;
      if (in) drops.drop(r.partner, "swap piece in another pixel format than the frame's");
      if (!idle(50)) return std::nullopt;
      if (msSince(waited) > kWaitS * 1000) {
        spdlog::warn("frame={} epoch={}: no swap piece from renderer {} in {:.0f} s; frame given up", p.frame, p.epoch,
                     r.partner, kWaitS);
        return std::nullopt;
      }
    }
    auto t1 = Clock::now();
    const LayerView kept = j == 0 ? viewOf(img, active, r.keep) : viewOf(mine, r.keep);
    Layer blended = blendLayer(kept, in->pixels, in->active, format, r.partner_in_front, takeSpare());
    recycle(std::move(mine));
    mine = std::move(blended);
    st.decode_ms += msSince(t1);
  }
  return mine;
}

}  // namespace tessera::renderer
