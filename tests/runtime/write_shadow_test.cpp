// The write shadow (runtime/write_shadow.h): client writes merged by element.
// The oracle everywhere is the definition the shadow replaces: applying every
// request's writes one after the other, in request order, to the memory.
#include <gtest/gtest.h>

#include <random>

#include "runtime/write_shadow.h"

namespace ldc::plc {
namespace {

const Layout L = Layout::standard(0);

std::vector<uint8_t> applied(std::vector<uint8_t> mem, const std::vector<ElementWrite>& ws) {
  for (const ElementWrite& w : ws) apply_element(w, mem.data(), L);
  return mem;
}

TEST(WriteShadow, LastWriteOfAnElementWinsBitByBit) {
  WriteShadow s(16);
  // A D word written as two Modbus registers: high half, then low half, then
  // the high half again.
  EXPECT_EQ(s.post(std::vector<ElementWrite>{{Area::D, 3, 0x12340000u, 0xffff0000u}}), 1u);
  EXPECT_EQ(s.post(std::vector<ElementWrite>{{Area::D, 3, 0x00005678u, 0x0000ffffu}}), 2u);
  EXPECT_EQ(s.post(std::vector<ElementWrite>{{Area::D, 3, 0xabcd0000u, 0xffff0000u}}), 3u);
  EXPECT_EQ(s.post(std::vector<ElementWrite>{{Area::Y, 0, 1, 1}, {Area::Y, 0, 0, 1}}), 4u);  // within one request too
  WriteShadow::Batch b;
  ASSERT_TRUE(s.take(b));
  EXPECT_EQ(b.ticket, 4u);
  ASSERT_EQ(b.writes.size(), 2u);  // two elements, in the order first written
  EXPECT_EQ(b.writes[0], (ElementWrite{Area::D, 3, 0xabcd5678u, 0xffffffffu}));
  EXPECT_EQ(b.writes[1], (ElementWrite{Area::Y, 0, 0, 1}));
  EXPECT_EQ(s.size(), 0u);
}

TEST(WriteShadow, ABacklogOfOneElementCostsOneEntry) {
  // 60,000 writes sent while the PLC is stopped (issue #24, item 4): the scan
  // that takes them copies one element, not 60,000.
  WriteShadow s(4);
  for (uint32_t i = 0; i < 60000; i++) ASSERT_NE(s.post(std::vector<ElementWrite>{{Area::WX, 0, i, ~0u}}), 0u);
  WriteShadow::Batch b;
  ASSERT_TRUE(s.take(b));
  ASSERT_EQ(b.writes.size(), 1u);
  EXPECT_EQ(b.writes[0].value, 59999u);
  EXPECT_EQ(b.ticket, 60000u);
}

TEST(WriteShadow, ARequestThatDoesNotFitMergesNothing) {
  WriteShadow s(3);
  ASSERT_EQ(s.post(std::vector<ElementWrite>{{Area::M, 0, 1, 1}, {Area::M, 1, 1, 1}}), 1u);
  // Two new elements where one place is left: refused whole.
  EXPECT_EQ(s.post(std::vector<ElementWrite>{{Area::M, 0, 0, 1}, {Area::M, 2, 1, 1}, {Area::M, 3, 1, 1}}), 0u);
  EXPECT_EQ(s.size(), 2u);
  // Elements it holds can always be written again, and repeats count once.
  EXPECT_EQ(s.post(std::vector<ElementWrite>{{Area::M, 0, 0, 1}, {Area::M, 2, 1, 1}, {Area::M, 2, 0, 1}}), 2u);
  EXPECT_EQ(s.size(), 3u);
  WriteShadow::Batch b;
  ASSERT_TRUE(s.take(b));
  EXPECT_EQ(b.writes, (std::vector<ElementWrite>{{Area::M, 0, 0, 1}, {Area::M, 1, 1, 1}, {Area::M, 2, 0, 1}}));
  // Taken: room again.
  EXPECT_EQ(s.post(std::vector<ElementWrite>{{Area::M, 5, 1, 1}, {Area::M, 6, 1, 1}, {Area::M, 7, 1, 1}}), 3u);
}

TEST(WriteShadow, APutBackBatchGoesBeforeWhatCameSince) {
  WriteShadow s(8);
  s.post(std::vector<ElementWrite>{{Area::D, 0, 0x11110000u, 0xffff0000u}, {Area::M, 4, 1, 1}});
  WriteShadow::Batch b;
  ASSERT_TRUE(s.take(b));
  s.post(std::vector<ElementWrite>{{Area::D, 0, 0x00002222u, 0x0000ffffu}, {Area::M, 4, 0, 1}});
  s.put_back(b);  // the scan that took b was not published
  WriteShadow::Batch again;
  ASSERT_TRUE(s.take(again));
  EXPECT_EQ(again.writes, (std::vector<ElementWrite>{{Area::D, 0, 0x11112222u, 0xffffffffu}, {Area::M, 4, 0, 1}}));
  EXPECT_EQ(again.ticket, 2u);
}

TEST(WriteShadow, AnEmptyShadowTakesNothing) {
  WriteShadow s;
  WriteShadow::Batch b;
  b.writes.push_back({Area::Y, 1, 1, 1});  // a batch applied before: dropped by take
  ASSERT_TRUE(s.take(b));
  EXPECT_TRUE(b.empty());
  EXPECT_EQ(b.ticket, 0u);
}

// Random requests, takes and put-backs against the definition: the memory
// after applying every batch taken equals the memory after applying every
// request in order.
TEST(WriteShadow, AgreesWithApplyingEveryRequestInOrder) {
  std::mt19937 rng(24);
  for (int round = 0; round < 200; round++) {
    WriteShadow s(1 + rng() % 40);
    std::vector<uint8_t> direct(L.size, 0), via(L.size, 0);
    WriteShadow::Batch pending;  // taken, not applied yet
    const Area areas[] = {Area::X, Area::M, Area::WX, Area::D, Area::F};
    for (int step = 0; step < 300; step++) {
      int what = int(rng() % 10);
      if (what < 7) {
        std::vector<ElementWrite> req(1 + rng() % 6);
        for (auto& w : req) {
          Area a = areas[rng() % 5];
          uint32_t mask = rng() % 3 == 0 ? 0xffff0000u : rng() % 2 ? 0x0000ffffu : ~0u;
          w = {a, uint32_t(rng() % 8), uint32_t(rng()), mask};
        }
        if (s.post(req)) direct = applied(direct, req);
      } else if (what < 9 || pending.empty()) {
        via = applied(via, pending.writes);
        ASSERT_TRUE(s.take(pending));
      } else {
        s.put_back(pending);
        pending.writes.clear();
      }
    }
    via = applied(via, pending.writes);
    ASSERT_TRUE(s.take(pending));
    via = applied(via, pending.writes);
    ASSERT_EQ(via, direct) << "round " << round;
  }
}

}  // namespace
}  // namespace ldc::plc
