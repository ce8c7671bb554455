// Binary swap's plan and blend, radix-k for any count (renderer/swap_plan.h): for any
// visibility order a round's group holds the same part of the image, the finished bands tile
// the image, and blending bands round by round gives what compositing every brick front to
// back does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <bit>
#include <numeric>
#include <random>

#include "common/wire/pixels.h"
#include "common/wire/strips.h"
#include "common/wire/swap_rule.h"
#include "renderer/swap_layer.h"
#include "renderer/swap_plan.h"

namespace tessera::renderer {
namespace {

proto::FrameParams swapFrame(int renderers, std::vector<int> order, int w, int h) {
  proto::FrameParams p;
  p.width = w;
  p.height = h;
  proto::SortLastWork work;
  for (int r = 0; r < renderers; ++r) {
    work.bricks.push_back({(uint32_t)(10 + r), BrickBox{{r, 0, 0}, {r + 1, 1, 1}}});
    work.swap.push_back({(uint32_t)(10 + r), "ipc:///tmp/r" + std::to_string(r)});
  }
  work.order = std::move(order);
  p.work = work;
  return p;
}

// Every round has its mirror in each partner's plan (what one sends the other keeps, from
// the same part), the bands tile the image once, and the rounds are the count's prime factors.
TEST(SwapPlan, PartnersHoldTheSamePartAndBandsTileTheImage) {
  std::mt19937 rng(7);
  EXPECT_EQ(proto::swapRadices(1), (std::vector<size_t>{}));
  EXPECT_EQ(proto::swapRadices(8), (std::vector<size_t>{2, 2, 2}));
  EXPECT_EQ(proto::swapRadices(12), (std::vector<size_t>{2, 2, 3}));
  EXPECT_EQ(proto::swapRadices(7), (std::vector<size_t>{7}));
  for (int renderers : {1, 2, 3, 4, 5, 6, 7, 8, 9, 12}) {
    for (int trial = 0; trial < 5; ++trial) {
      std::vector<int> order(renderers);
      std::iota(order.begin(), order.end(), 0);
      std::shuffle(order.begin(), order.end(), rng);
      const int h = trial == 4 ? 3 : 83;  // fewer rows than bands: some finish none
      const auto p = swapFrame(renderers, order, 97, h);
      std::map<uint32_t, SwapPlan> plans;
      for (int r = 0; r < renderers; ++r) {
        auto plan = planSwap(p, 10 + r);
        ASSERT_TRUE(plan);
        EXPECT_EQ(p.sortLast()->bricks[plan->brick].renderer, (uint32_t)(10 + r));
        plans[10 + r] = *plan;
      }
      std::vector<int> covered(97 * h, 0);
      for (const auto& [me, plan] : plans) {
        if (h >= renderers) {
          EXPECT_FALSE(plan.band.empty()) << "only an image of fewer rows than bands leaves one without rows";
        }
        EXPECT_EQ(plan.rounds.size(), proto::swapRadices(renderers).size());
        for (size_t j = 0; j < plan.rounds.size(); ++j) {
          const SwapRound& mine = plan.rounds[j];
          const size_t k = proto::swapRadices(renderers)[j];
          ASSERT_EQ(mine.partners.size(), k - 1);
          std::vector<Rect> bands{mine.keep};
          int offset = -(int)k;
          for (const SwapPartner& q : mine.partners) {
            EXPECT_GT(q.offset, offset) << "partners by digit, front to back";
            offset = q.offset;
            EXPECT_NE(q.offset, 0);
            const SwapRound& theirs = plans.at(q.rank).rounds[j];
            EXPECT_EQ(theirs.keep, q.send) << "it keeps what this one sends it";
            auto back = std::find_if(theirs.partners.begin(), theirs.partners.end(),
                                     [&](const SwapPartner& t) { return t.rank == me; });
            ASSERT_NE(back, theirs.partners.end()) << renderers << ": partners name each other";
            EXPECT_EQ(back->send, mine.keep);
            EXPECT_EQ(back->offset, -q.offset);
            bands.push_back(q.send);
          }
          // The k bands are rows of one part, one after another, top to bottom by digit.
          std::sort(bands.begin(), bands.end(), [](const Rect& a, const Rect& b) { return std::pair(a.y, a.h) < std::pair(b.y, b.h); });
          Rect part = bands[0];
          for (size_t i = 1; i < bands.size(); ++i) {
            EXPECT_EQ(bands[i].y, part.y + part.h) << "bands of one part neither overlap nor leave gaps";
            EXPECT_EQ(bands[i].x, part.x);
            EXPECT_EQ(bands[i].w, part.w);
            part.h += bands[i].h;
          }
          if (j > 0) {
            EXPECT_EQ(part, plan.rounds[j - 1].keep) << "a round splits what the one before kept";
          } else {
            EXPECT_EQ(part, (Rect{0, 0, 97, h})) << "round 0 splits the whole image";
          }
        }
        const auto band = proto::swapBand(p, me);
        EXPECT_EQ(band.has_value(), !plan.band.empty()) << "the display expects a band exactly when one is sent";
        if (band) {
          EXPECT_EQ(*band, plan.band);
        }
        for (int y = plan.band.y; y < plan.band.y + plan.band.h; ++y)
          for (int x = plan.band.x; x < plan.band.x + plan.band.w; ++x) ++covered[y * 97 + x];
      }
      EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; })) << renderers;
    }
  }
  // No plan: a frame without one, or a renderer without a brick.
  auto p = swapFrame(2, {0, 1}, 8, 8);
  EXPECT_FALSE(planSwap(p, 99));
  std::get<proto::SortLastWork>(p.work).swap.clear();
  EXPECT_FALSE(planSwap(p, 10));
}

// A brick image: translucent colour inside `active`, transparent outside.
ImageF brickImage(int w, int h, const Rect& active, std::mt19937& rng) {
  ImageF img(w, h);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int y = active.y; y < active.y + active.h; ++y)
    for (int x = active.x; x < active.x + active.w; ++x) {
      const float a = u(rng);
      float* px = img.at(x, y);
      for (int c = 0; c < 3; ++c) px[c] = a * u(rng);
      px[3] = a;
    }
  return img;
}

// The swap's result, driven here without sockets (each renderer sends, then blends its
// partners' pieces as they are there), against every brick composited front to back.
TEST(SwapPlan, RoundsOfBlendsEqualFrontToBackCompositing) {
  const int w = 61, h = 45;
  const auto f = proto::PixelFormat::RGBA16F;
  std::mt19937 rng(3);
  for (int renderers : {3, 4, 5, 6, 12}) {
    std::vector<int> order(renderers);
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng);
    const auto p = swapFrame(renderers, order, w, h);
    std::vector<ImageF> images;
    std::vector<Rect> actives;
    for (int r = 0; r < renderers; ++r) {
      std::uniform_int_distribution<int> x(0, w - 10), y(0, h - 10);
      const int x0 = x(rng), y0 = y(rng);
      actives.push_back({x0, y0, std::uniform_int_distribution<int>(5, w - x0)(rng), std::uniform_int_distribution<int>(5, h - y0)(rng)});
      images.push_back(brickImage(w, h, actives.back(), rng));
    }
    ImageF expected(w, h);  // front to back, in float
    for (int b : order)
      for (size_t i = 0; i < expected.px.size(); i += 4) {
        const float t = 1.0f - expected.px[i + 3];
        for (int c = 0; c < 4; ++c) expected.px[i + c] += t * images[b].px[i + c];
      }
    std::map<uint32_t, SwapPlan> plans;
    std::map<uint32_t, Layer> held;
    std::map<uint32_t, size_t> next_round;
    std::map<uint32_t, bool> sent_this;
    std::map<uint32_t, int> front, back;  // partners blended this round
    std::map<std::pair<uint32_t, uint32_t>, std::pair<Rect, std::vector<std::byte>>> mail;  // (to, from)
    for (int r = 0; r < renderers; ++r) plans[10 + r] = *planSwap(p, 10 + r);
    for (int step = 0; step < 4 * renderers; ++step) {
      for (auto& [me, plan] : plans) {
        const size_t j = next_round[me];
        if (j == plan.rounds.size()) continue;
        const int b = (int)plan.brick;
        const SwapRound& r = plan.rounds[j];
        auto partOf = [&](const Rect& part) {
          return j == 0 && front[me] + back[me] == 0 ? viewOf(images[b], actives[b], part) : viewOf(held[me], part);
        };
        if (!sent_this[me]) {
          for (const SwapPartner& q : r.partners) {
            if (q.send.empty()) continue;
            const LayerView out = partOf(q.send);
            auto& m = mail[{q.rank, me}];
            ASSERT_TRUE(m.second.empty()) << "one piece at a time between two renderers";
            packView(out, f, m.second);
            m.first = out.rect;
          }
        }
        sent_this[me] = true;
        if (!r.keep.empty()) {
          // Blend what is there, in the order it came (here: by partner, front or back first
          // by the step), each adjacent to the run blended so far, as SwapExchange does.
          const int n_front = (int)std::count_if(r.partners.begin(), r.partners.end(), [](auto& q) { return q.offset < 0; });
          const int n_back = (int)r.partners.size() - n_front;
          for (bool progress = true; progress;) {
            progress = false;
            for (int side : {step % 2, 1 - step % 2}) {
              const bool in_front = side == 0;
              if (in_front ? front[me] == n_front : back[me] == n_back) continue;
              const SwapPartner& q = r.partners[in_front ? n_front - 1 - front[me] : n_front + back[me]];
              auto it = mail.find({me, q.rank});
              if (it == mail.end()) continue;
              held[me] = blendLayer(partOf(r.keep), it->second.second, it->second.first, f, in_front);
              mail.erase(it);
              ++(in_front ? front[me] : back[me]);
              progress = true;
            }
          }
          if (front[me] < n_front || back[me] < n_back) continue;  // not all there yet
        }
        ++next_round[me], sent_this[me] = false, front[me] = back[me] = 0;
      }
    }
    float worst = 0;
    int pixels = 0;
    for (auto& [me, plan] : plans) {
      ASSERT_EQ(next_round[me], plan.rounds.size()) << renderers << ": every round done";
      const Layer& band = held[me];
      for (int y = plan.band.y; y < plan.band.y + plan.band.h; ++y)
        for (int x = plan.band.x; x < plan.band.x + plan.band.w; ++x, ++pixels)
          for (int c = 0; c < 4; ++c) {
            const bool inside = x >= band.rect.x && x < band.rect.x + band.rect.w && y >= band.rect.y &&
                                y < band.rect.y + band.rect.h;
            const float got = inside ? band.img.at(x - band.rect.x, y - band.rect.y)[c] : 0.0f;
            worst = std::max(worst, std::abs(got - expected.at(x, y)[c]));
          }
    }
    EXPECT_TRUE(mail.empty());
    EXPECT_EQ(pixels, w * h);
    // A rounding to half floats per round (2^-11 relative each), far inside the contract's 1/255.
    EXPECT_LT(worst, 3e-3f) << renderers;
    EXPECT_GT(worst, 0.0f);  // the pieces really were rounded to half floats
  }
}

// The finished band reaches the display as strips: routed into an empty image, it gives
// each pixel quantized once (as a compositor's region), nothing outside the band, and the
// count of visible pixels.
TEST(SwapPlan, AFinishedBandBecomesStripsOfItsRows) {
  Layer band;
  band.rect = {3, 5, 6, 4};
  band.img = ImageF(6, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) {
      float* px = band.img.at(x, y);
      const float a = x == 0 ? 0.0f : 0.1f * (float)x + 0.01f * (float)y;
      px[0] = 0.5f * a, px[1] = 0.25f * a, px[2] = a, px[3] = a;
    }
  Image8 scratch;
  proto::Strips s;
  bandStrips(band, 16, 12, scratch, s);
  EXPECT_EQ(s.active_pixels, 4u * 5u) << "column 0 is transparent";
  Image8 shown(16, 12);
  RouteStats rs = routeStrips(s.stream, shown, 0);
  EXPECT_EQ(rs.strips_rejected, 0);
  EXPECT_EQ(rs.strips_written, 4);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 16; ++x) {
      const bool inside = x >= 3 && x < 9 && y >= 5 && y < 9;
      for (int c = 0; c < 4; ++c) {
        const int want = inside ? (int)std::lround(band.img.at(x - 3, y - 5)[c] * 255.0f) : 0;
        EXPECT_EQ(shown.at(x, y)[c], want) << x << "," << y << " channel " << c;
      }
    }
}

}  // namespace
}  // namespace tessera::renderer
