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
  const auto renderers = (size_t)std::count_if(roster.members.begin(), roster.members.end(),
                                               [](const auto& m) { return m.role == proto::Role::Renderer; });
  max_held_ = std::max(kMaxHeld, 4 * renderers);  // two frames of a round of all of them, twice over
  accept(inbox_.setRoster(roster, drops), drops);
}

void SwapExchange::receive(DropCounter& drops) { accept(inbox_.receive(drops), drops); }

void SwapExchange::accept(std::vector<DataInbox::Message> messages, DropCounter& drops) {
  for (auto& [rank, m, role] : messages) {
    auto t0 = Clock::now();
    auto piece = proto::decodePiece(view(m), max_held_bytes_);  // larger could not be held: not decoded
    if (!piece) {
      drops.drop(rank, "swap piece: " + piece.error());
      continue;
    }
    if (piece->renderer != rank) {
      drops.drop(rank, "swap piece claims renderer " + std::to_string(piece->renderer));
      continue;
    }
    if (stale(*piece)) continue;  // a frame given up or cancelled: expected, not a fault
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
  while (!held_.empty() && (held_.size() >= max_held_ || held_bytes_ + bytes > max_held_bytes_)) {
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
    r.mine = blendLayer(viewOf(img, active, plan.band), {}, Rect{}, swapFormat(p.format), false, takeSpare(), maximum_);
}

std::optional<uint32_t> SwapExchange::advance(const Send& send, proto::StageStats& st, DropCounter& drops) {
  Run& run = *run_;
  const proto::FrameParams& p = run.p;
  const proto::PixelFormat format = swapFormat(p.format);
  for (; run.round < run.plan.rounds.size(); ++run.round, run.sent = false, run.front = run.back = 0) {
    const SwapRound& r = run.plan.rounds[run.round];
    // Round 0 reads the brick image itself until its first blend; later, the layer blended last.
    auto partOf = [&](const Rect& part) {
      return run.round == 0 && run.front + run.back == 0 ? viewOf(*run.img, run.active, part) : viewOf(run.mine, part);
    };
    if (!run.sent) {
      auto t0 = Clock::now();
      for (const SwapPartner& to : r.partners) {
        if (to.send.empty()) continue;  // fewer rows than bands: it keeps none
        proto::Piece out;
        out.frame = p.frame;
        out.epoch = p.epoch;
        out.renderer = run.me;
        out.brick = run.plan.brick;
        out.region = to.send;
        out.format = format;
        out.render_ms = st.work_ms;
        const LayerView sent = partOf(to.send);
        out.active = sent.rect;
        packView(sent, format, packed_);
        out.pixels = std::move(packed_);
        auto bytes = proto::encode(out, run.me, p.codec);
        st.bytes_raw += out.pixels.size();
        st.bytes_encoded += bytes.size();
        packed_ = std::move(out.pixels);
        send(to.endpoint, std::move(bytes));
      }
      st.encode_ms += msSince(t0);
      run.sent = true;
    }
    if (r.keep.empty()) continue;  // fewer rows than bands: nothing to receive

    // Partners' pieces are blended as they come, each next to the run blended so far: the
    // partner just in front of it or just behind it (partners are by digit, front to back).
    const size_t n_front = (size_t)std::count_if(r.partners.begin(), r.partners.end(),
                                                 [](const SwapPartner& q) { return q.offset < 0; });
    const size_t n_back = r.partners.size() - n_front;
    while (run.front < n_front || run.back < n_back) {
      const SwapPartner* front = run.front < n_front ? &r.partners[n_front - 1 - run.front] : nullptr;
      const SwapPartner* back = run.back < n_back ? &r.partners[n_front + run.back] : nullptr;
      std::optional<Held> in;
      const SwapPartner* from = nullptr;
      for (const SwapPartner* q : {front, back}) {
        if (q && (in = takeIn(p, q->rank, r.keep, format, drops))) {
          from = q;
          break;
        }
      }
      if (!in) return (front ? front : back)->rank;
      auto t1 = Clock::now();
      Layer blended =
          blendLayer(partOf(r.keep), in->piece.pixels, in->piece.active, format, from->offset < 0, takeSpare(), maximum_);
      recycle(std::move(run.mine));
      run.mine = std::move(blended);
      ++(from->offset < 0 ? run.front : run.back);
      st.decode_ms += in->decode_ms + msSince(t1);
    }
  }
  return std::nullopt;
}

// The held piece of `from` for `region`, in the frame's pixel format (others are dropped).
std::optional<SwapExchange::Held> SwapExchange::takeIn(const proto::FrameParams& p, uint32_t from, const Rect& region,
                                                      proto::PixelFormat format, DropCounter& drops) {
  for (;;) {
    auto in = take(p, from, region);
    if (!in || in->piece.format == format) return in;
    drops.drop(from, "swap piece in another pixel format than the frame's");
  }
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
