// The formats of watched typed values (docs/format.md, "Traces"): each
// expected text is derived by hand in its comment, and every shown value,
// written back as a trace cell, gives the same bytes (the round trip the
// docs promise), edge values included.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "runtime/runtime.h"

namespace ldc {
namespace {

// A probe of type t at D0 (BOOL: M0), in a fresh image.
struct Cell {
  Memory mem{Layout::standard(0)};
  Probe p;
  explicit Cell(Ty t) : p{"v", t == Ty::BOOL ? Area::M : Area::D, 0, t} {}
  void set_bits(uint64_t b) { std::memcpy(mem.data() + mem.layout.addr(p.area, 0), &b, ty_info(p.ty).cells == 2 ? 8 : 4); }
  std::string shown() { return format_probe(mem, p); }
  // shown, written back into a zeroed image, shown again: the same bytes
  void round_trip() {
    std::string s = shown();
    ASSERT_EQ(trace_cell_problem(p, s), "") << s;
    Memory back(mem.layout);
    put_trace_cell(back.data(), back.layout, p, s);
    size_t at = mem.layout.addr(p.area, 0), n = p.ty == Ty::BOOL ? 1 : size_t(ty_info(p.ty).cells) * 4;
    EXPECT_EQ(std::memcmp(back.data() + at, mem.data() + at, n), 0) << ty_info(p.ty).name << " " << s;
  }
};

std::string show(Ty t, uint64_t bits) {
  Cell c(t);
  c.set_bits(bits);
  c.round_trip();
  return c.shown();
}
uint64_t fbits(float f) { uint32_t u; std::memcpy(&u, &f, 4); return u; }
uint64_t dbits(double d) { uint64_t u; std::memcpy(&u, &d, 8); return u; }
constexpr int64_t kS = 1000000000, kMin = 60 * kS, kH = 60 * kMin, kD = 24 * kH;

TEST(WatchFormat, IntegersAreDecimalUnsignedOnesUnsigned) {
  EXPECT_EQ(show(Ty::INT, uint32_t(-32768)), "-32768");  // a negative INT held sign-extended in its cell
  EXPECT_EQ(show(Ty::UDINT, 0xFFFFFFFFu), "4294967295");  // 2^32 - 1
  EXPECT_EQ(show(Ty::DWORD, 0x80000000u), "2147483648");  // 2^31, not negative
  EXPECT_EQ(show(Ty::ULINT, ~uint64_t(0)), "18446744073709551615");  // 2^64 - 1
  EXPECT_EQ(show(Ty::LINT, uint64_t(INT64_MIN)), "-9223372036854775808");
  EXPECT_EQ(show(Ty::BOOL, 1), "1");
}

TEST(WatchFormat, RealsInTheFewestDigitsThatReadBack) {
  EXPECT_EQ(show(Ty::REAL, fbits(0.1f)), "0.1");
  EXPECT_EQ(show(Ty::REAL, fbits(1.0f / 3.0f)), "0.33333334");  // 0x3EAAAAAB; 0.3333333 is 0x3EAAAAAA
  EXPECT_EQ(show(Ty::LREAL, dbits(0.1 + 0.2)), "0.30000000000000004");
  EXPECT_EQ(show(Ty::REAL, fbits(1e20f)), "1e+20");
  EXPECT_EQ(show(Ty::REAL, fbits(-0.0f)), "-0");
  EXPECT_EQ(show(Ty::LREAL, dbits(std::numeric_limits<double>::infinity())), "inf");
  EXPECT_EQ(show(Ty::REAL, fbits(std::numeric_limits<float>::denorm_min())), "1e-45");  // 2^-149 = 1.4e-45, 1e-45 rounds to it
  EXPECT_EQ(show(Ty::LREAL, dbits(std::numeric_limits<double>::max())), "1.7976931348623157e+308");
  Cell n(Ty::LREAL);  // a NaN reads back as a NaN (its payload is not kept)
  n.set_bits(dbits(std::nan("")));
  EXPECT_EQ(n.shown(), "nan");
}

TEST(WatchFormat, TimesAsIecLiterals) {
  EXPECT_EQ(show(Ty::TIME, 0), "T#0s");
  EXPECT_EQ(show(Ty::TIME, uint64_t(1 * kH + 2 * kMin + 3 * kS + 500000000)), "T#1h2m3s500ms");
  EXPECT_EQ(show(Ty::TIME, uint64_t(-(kD + 12 * kH))), "T#-1d12h");
  EXPECT_EQ(show(Ty::TIME, 1), "T#1ns");
  EXPECT_EQ(show(Ty::TIME, 1001001), "T#1ms1us1ns");
  // INT64_MIN ns: 106751d 23h 47m 16s 854ms 775us 808ns (9223372036854775808 by hand: / 86400e9 ...)
  EXPECT_EQ(show(Ty::TIME, uint64_t(INT64_MIN)), "T#-106751d23h47m16s854ms775us808ns");
  EXPECT_EQ(show(Ty::LTIME, uint64_t(5 * kD + 14 * kH + 12 * kMin + 18 * kS + 3500000)), "LTIME#5d14h12m18s3ms500us");
}

TEST(WatchFormat, DatesAsIecLiterals) {
  EXPECT_EQ(show(Ty::DATE, uint64_t(19753 * kD)), "D#2024-01-31");  // 19753 days after 1970-01-01
  EXPECT_EQ(show(Ty::DATE, uint64_t(-kD)), "D#1969-12-31");
  EXPECT_EQ(show(Ty::DATE, uint64_t(19753 * kD + 12 * kH)), "DT#2024-01-31-12:00:00");  // not at midnight
  EXPECT_EQ(show(Ty::TOD, uint64_t(12 * kH + 30 * kMin + kS / 2)), "TOD#12:30:00.5");
  EXPECT_EQ(show(Ty::TOD, uint64_t(25 * kH)), "90000000000000");  // beyond a day: its ns
  EXPECT_EQ(show(Ty::DT, uint64_t(19753 * kD + 12 * kH + 30 * kMin + kS / 4)), "DT#2024-01-31-12:30:00.25");
  EXPECT_EQ(show(Ty::DT, uint64_t(-1)), "DT#1969-12-31-23:59:59.999999999");
}

TEST(WatchFormat, StringsQuotedWithEscapes) {
  Cell c(Ty::STRING);
  const char text[] = "a,b'$\"\n";
  uint32_t n = sizeof text - 1;
  std::memcpy(c.mem.data() + c.mem.layout.addr(Area::D, 0), &n, 4);
  std::memcpy(c.mem.data() + c.mem.layout.addr(Area::D, 0) + 4, text, n);
  // , -> $2C; ' -> $'; $ -> $$; " -> $22; LF -> $0A
  EXPECT_EQ(c.shown(), "'a$2Cb$'$$$22$0A'");
  c.round_trip();
}

TEST(WatchFormat, CellsAreRefusedWithTheReason) {
  EXPECT_EQ(trace_cell_problem(Probe{"t", Area::D, 0, Ty::TIME}, "T#1x"), "bad TIME 'T#1x': bad duration part (d h m s ms us ns) for t");
  EXPECT_EQ(trace_cell_problem(Probe{"i", Area::D, 0, Ty::INT}, "T#1s"), "a TIME literal where a INT is wanted: 'T#1s' for i");
  EXPECT_EQ(trace_cell_problem(Probe{"u", Area::D, 0, Ty::UINT}, "-1"), "value out of the UINT range: '-1' for u");
  EXPECT_EQ(trace_cell_problem(Probe{"d", Area::D, 0, Ty::TIME}, "D#2024-01-31"), "a DATE literal where a TIME is wanted: 'D#2024-01-31' for d");
}

TEST(WatchNames, ListsSplitOutsideBracketsAndQuotes) {
  std::vector<std::string> want = {"a[1,2]", "k", "\"m[1, 2]\"", "'x,y'"};
  EXPECT_EQ(split_names("a[1,2],k, \"m[1, 2]\" ,'x,y'"), want);
  std::vector<Alias> al = {{"tank.level", {Dev::D, 4}, Ty::INT}, {"m[1,2]", {Dev::D, 7}, Ty::INT}, {"s2", {Dev::D, 9}, Ty::INT}};
  EXPECT_EQ(resolve_probe("TANK.Level", al).index, 4u);
  EXPECT_EQ(resolve_probe("\"m[1, 2]\"", al).index, 7u);
  Probe s2 = resolve_probe("S2", al);  // the program's name wins over the system bit S2
  EXPECT_EQ(s2.area, Area::D);
  EXPECT_EQ(s2.index, 9u);
  EXPECT_EQ(csv_name("m[1,2]"), "\"m[1,2]\"");
  EXPECT_EQ(csv_name("k"), "k");
}

}  // namespace
}  // namespace ldc
