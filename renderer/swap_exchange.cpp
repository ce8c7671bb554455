#include "renderer/swap_exchange.h"

#include <algorithm>

#include "common/clock.h"
#include "common/net/transport.h"

namespace tessera::renderer {

proto::PixelFormat swapFormat(proto::PixelFormat f) {
  return f == proto::PixelFormat::RGBA8 ? proto::PixelFormat::RGBA16F : f;
}

SwapExchange::SwapExchange(zmq::context_t& ctx, int64_t max_message, size_t max_held_bytes)
    : inbox_(ctx, {proto::Role::Renderer}, max_message, max_held_bytes), max_held_bytes_(max_held_bytes) {}

void SwapExchange::setRoster(const proto::Roster& roster, DropCounter& drops) {
  accept(inbox_.setRoster(roster, drops), drops);
}

void SwapExchange::receive(DropCounter& drops) { accept(inbox_.receive(drops), drops); }

void SwapExchange::accept(std::vector<DataInbox::Message> messages, DropCounter& drops) {
  for (auto& [rank, m, role] : messages) {
    auto t0 = Clock::now();
    auto piece = proto::decodePiece(view(m));
    if (!piece) {
      drops.drop(rank, "swap piece: " + piece.error());
      continue;
    }
    if (piece->renderer != rank) {
      drops.drop(rank, "swap piece claims renderer " + std::to_string(piece->renderer));
      continue;
    }
    if (stale(*piece)) continue;  // a frame given up or cancelled: expected, not a fault
    if (piece->pixels.size() > max_held_bytes_) {
      drops.drop(rank, "swap piece of " + std::to_string(piece->pixels.size()) + " bytes exceeds what may be held");
      continue;
    }
    evictFor(piece->pixels.size(), drops);
    held_bytes_ += piece->pixels.size();
    held_.push_back({std::move(*piece), msSince(t0)});
  }
}

// Room for `bytes` more: stale pieces first, then the farthest frames (the nearest are the
// ones a round waits for now).
void SwapExchange::evictFor(size_t bytes, DropCounter& drops) {
  std::erase_if(held_, [&](const Held& h) {
    if (!stale(h.piece)) return false;
    held_bytes_ -= h.piece.pixels.size();
    return true;
  });
  while (!held_.empty() && (held_.size() >= kMaxHeld || held_bytes_ + bytes > max_held_bytes_)) {
    auto far = std::max_element(held_.begin(), held_.end(), [](const Held& a, const Held& b) {
      return std::pair(a.piece.epoch, a.piece.frame) < std::pair(b.piece.epoch, b.piece.frame);
    });
    drops.drop(far->piece.renderer, "swap piece of frame " + std::to_string(far->piece.frame) + " evicted: too many held");
    held_bytes_ -= far->piece.pixels.size();
    held_.erase(far);
  }
}

std::optional<SwapExchange::Held> SwapExchange::take(const proto::FrameParams& p, uint32_t from, const Rect& region) {
  for (auto it = held_.begin(); it != held_.end(); ++it) {
    const proto::Piece& h = it->piece;
    if (h.frame != p.frame || h.epoch != p.epoch || h.renderer != from || h.region != region) continue;
    Held found = std::move(*it);
    held_bytes_ -= found.piece.pixels.size();
    held_.erase(it);
    return found;
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

void SwapExchange::start(const proto::FrameParams& p, uint32_t me, const SwapPlan& plan, const ImageF& img,
                         const Rect& active) {
  // Pieces of this frame's older issues, and of older frames of this issue, will never be used.
  std::erase_if(held_, [&](const Held& h) {
    const bool old = h.piece.epoch < p.epoch || (h.piece.epoch == p.epoch && h.piece.frame < p.frame);
    if (old) held_bytes_ -= h.piece.pixels.size();
    return old;
  });
  run_.emplace();
  Run& r = *run_;
  r.p = p, r.me = me, r.plan = plan, r.img = &img, r.active = active;
  if (plan.rounds.empty())  // a swap of one: the image is the band
    r.mine = blendLayer(viewOf(img, active, plan.band), {}, Rect{}, swapFormat(p.format), false, takeSpare());
}

std::optional<uint32_t> SwapExchange::advance(const Send& send, proto::StageStats& st, DropCounter& drops) {
  Run& run = *run_;
  const proto::FrameParams& p = run.p;
  const proto::PixelFormat format = swapFormat(p.format);
  for (; run.round < run.plan.rounds.size(); ++run.round, run.sent = false) {
    const SwapRound& r = run.plan.rounds[run.round];
    // Round 0 reads the brick image itself; later rounds, the layer blended last round.
    auto partOf = [&](const Rect& part) {
      return run.round == 0 ? viewOf(*run.img, run.active, part) : viewOf(run.mine, part);
    };
    if (!run.sent && !r.send.empty()) {  // a fold's receiver only receives
      auto t0 = Clock::now();
      proto::Piece out;
      out.frame = p.frame;
      out.epoch = p.epoch;
      out.renderer = run.me;
      out.brick = run.plan.brick;
      out.region = r.send;
      out.format = format;
      out.render_ms = st.work_ms;
      const LayerView sent = partOf(r.send);
      out.active = sent.rect;
      packView(sent, format, packed_);
      out.pixels = std::move(packed_);
      auto bytes = proto::encode(out, run.me, p.codec);
      st.bytes_raw += out.pixels.size();
      st.bytes_encoded += bytes.size();
      packed_ = std::move(out.pixels);
      send(r.endpoint, std::move(bytes));
      st.encode_ms += msSince(t0);
    }
    run.sent = true;
    if (r.keep.empty()) continue;  // a folding renderer only sends

    std::optional<Held> in;
    for (;;) {
      in = take(p, r.partner, r.keep);
      if (!in) return r.partner;
      if (in->piece.format == format) break;
      drops.drop(r.partner, "swap piece in another pixel format than the frame's");
    }
    auto t1 = Clock::now();
    Layer blended = blendLayer(partOf(r.keep), in->piece.pixels, in->piece.active, format, r.partner_in_front, takeSpare());
    recycle(std::move(run.mine));
    run.mine = std::move(blended);
    st.decode_ms += in->decode_ms + msSince(t1);
  }
  return std::nullopt;
}

Layer SwapExchange::finish() {
  Layer band = std::move(run_->mine);
  run_.reset();
  return band;
}

void SwapExchange::abandon() {
  if (run_) recycle(std::move(run_->mine));
  run_.reset();
}

}  // namespace tessera::renderer
