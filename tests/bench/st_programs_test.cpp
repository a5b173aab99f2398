// tests/bench/st_programs_test.cpp -- the Structured Text programs that
// docs/BENCHMARKS.md times (bench/st/*.st, "Issue 26: Structured Text
// programs"): each compiled as ldc compiles it (compile_source) and run on
// every engine (the fast interpreter, native x86-64 at -O0, -O1 and -O2, the
// C route) beside the reference interpreter, the whole memory image compared
// after every scan, as ldrun runs a trace (dt 10 ms, S1 on the first scan, the
// fault record cleared).  Then values of the reference run are checked
// against values derived without ldc: a published CRC check value and an
// independent CRC routine, the sorted order of the C standard's rand()
// numbers, a PID step computed by hand, the integers of the parsed line as
// its text reads, and the steps of the batch sequence counted by hand.  A
// benchmark that timed a wrong program would be worth nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <numeric>
#include <string>
#include <vector>

#include "driver/driver.h"
#include "runtime/runtime.h"
#include "tests/diff/harness.h"

namespace {

using namespace ldc;
using namespace ldc::diff;

const std::string kDir = LDC_BENCH_ST_DIR;

// StRun: one program's run; the reference image after each scan goes to `check`.
struct StRun {
  Program prog;
  Layout L;
  Trace trace;  // inputs, or no columns
  explicit StRun(const std::string& name) : prog(compile_source(kDir + "/" + name).il), L(prog.layout()) {}

  // A variable's bytes in `img` (a --watch name: "loops[1].out", "s1.step").
  uint32_t addr(const std::string& name) const {
    Probe p = resolve_probe(name, prog.aliases);
    return L.addr(p.area, p.index);
  }
  template <class T>
  T at(const ImageBytes& img, uint32_t offset) const {
    T v;
    std::memcpy(&v, img.data() + offset, sizeof v);
    return v;
  }
  template <class T>
  T get(const ImageBytes& img, const std::string& name) const {
    return at<T>(img, addr(name));
  }

  void write_inputs(ImageBytes& img, int scan) const {
    if (size_t(scan - 1) >= trace.rows.size()) return;
    const auto& row = trace.rows[size_t(scan - 1)];
    for (size_t i = 0; i < row.size(); i++)
      if (!row[i].empty()) put_trace_cell(img.data(), L, trace.columns[i], row[i]);
  }

  // `scans` scans on the reference and every engine of `engines`; "" or what differs.
  std::string compare(int scans, const std::vector<std::pair<const char*, EngineFactory>>& engines,
                      const std::function<void(int, const ImageBytes&)>& check) const {
    std::vector<std::unique_ptr<Engine>> eng;
    eng.push_back(make_interp(prog));
    for (auto& [what, make] : engines) eng.push_back(make(prog));
    std::vector<ImageBytes> img(eng.size(), ImageBytes(L.size));
    const int32_t dt = 10;
    for (int k = 1; k <= scans; k++) {
      for (size_t e = 0; e < eng.size(); e++) {
        write_inputs(img[e], k);
        std::memcpy(img[e].data() + kSysDt, &dt, 4);
        std::memset(img[e].data() + kSysFault, 0, 4);
        uint8_t* s1 = img[e].data() + L.addr(Area::S, kBitFirstScan);
        *s1 = k == 1;
        eng[e]->scan(img[e]);
        uint32_t n = uint32_t(k);
        std::memcpy(img[e].data() + kSysScan, &n, 4);
      }
      if (auto f = read_scan_fault(img[0].data())) return "scan " + std::to_string(k) + ": the reference faulted";
      for (size_t e = 1; e < eng.size(); e++)
        for (uint32_t b = 0; b < L.size; b++)
          if (img[e].data()[b] != img[0].data()[b])
            return std::string(engines[e - 1].first) + ", scan " + std::to_string(k) + ": " +
                   describe(L, b).name + " is " + value_at(L, img[e], b) + ", the reference's " +
                   value_at(L, img[0], b);
      check(k, img[0]);
    }
    return "";
  }
};

const std::vector<std::pair<const char*, EngineFactory>> kEvery = {
    {"fast", make_fast_interp}, {"native -O0", make_native}, {"native -O1", make_native_o1},
    {"native -O2", make_native_o2}, {"the C route", make_c_route}};

// CRC-16/MODBUS written from its definition (reflected polynomial 16#A001,
// initial 16#FFFF, no final XOR), one bit at a time: not ldc's code.
uint16_t crc16_modbus(const uint8_t* p, size_t n) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < n; i++) {
    crc ^= p[i];
    for (int b = 0; b < 8; b++) crc = (crc & 1) ? uint16_t((crc >> 1) ^ 0xA001) : uint16_t(crc >> 1);
  }
  return crc;
}

TEST(StPrograms, Crc16) {
  // The check value of CRC-16/MODBUS over the ASCII '123456789' is 16#4B37
  // (Greg Cook's CRC RevEng catalogue); the routine above agrees with it.
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  ASSERT_EQ(crc16_modbus(check, 9), 0x4B37);
  StRun r("crc16.st");
  std::string why = r.compare(20, kEvery, [&](int k, const ImageBytes& img) {
    EXPECT_EQ(r.template get<uint16_t>(img, "self_crc"), 0x4B37) << "scan " << k;
    EXPECT_EQ(r.template get<uint8_t>(img, "self_ok"), 1) << "scan " << k;
    uint8_t frame[64];
    for (int i = 0; i < 64; i++) frame[i] = r.template get<uint8_t>(img, "frame[" + std::to_string(i) + "]");
    EXPECT_EQ(frame[2], uint8_t(k)) << "the sequence number";
    EXPECT_EQ(r.template get<uint16_t>(img, "crc"), crc16_modbus(frame, 64)) << "scan " << k;
  });
  EXPECT_EQ(why, "");
}

TEST(StPrograms, Sort) {
  // The C standard's example rand() (C11 7.22.2.2): next = next * 1103515245
  // + 12345; return next / 65536 % 32768.  Its first value from seed 1 is 16838.
  uint32_t next = 1;
  auto rand15 = [&] { next = next * 1103515245u + 12345u; return int32_t(next / 65536 % 32768); };
  {
    uint32_t keep = next;
    ASSERT_EQ(rand15(), 16838);
    next = keep;
  }
  StRun r("sort.st");
  std::string why = r.compare(20, kEvery, [&](int k, const ImageBytes& img) {
    std::vector<int32_t> want(64);
    for (int32_t& v : want) v = rand15() - 16384;
    std::sort(want.begin(), want.end());
    for (int i = 0; i < 64; i++)
      ASSERT_EQ(r.template get<int32_t>(img, "a[" + std::to_string(i + 1) + "]"), want[size_t(i)]) << "scan " << k << ", a[" << i + 1 << "]";
    EXPECT_EQ(r.template get<int32_t>(img, "median"), (want[31] + want[32]) / 2) << "scan " << k;
    EXPECT_EQ(r.template get<int32_t>(img, "spread"), want[63] - want[0]) << "scan " << k;
    EXPECT_EQ(r.template get<uint8_t>(img, "sorted"), 1) << "scan " << k;
  });
  EXPECT_EQ(why, "");
}

TEST(StPrograms, Pid) {
  StRun r("pid.st");
  // By hand (every number a binary fraction, so exact in REAL):
  // loop 1: sp = 10 + 1 * 2.5 = 12.5, kp = 2 + (1 MOD 4) * 0.5 = 2.5, ki = 0.5, kd = 0.25, pv = 0.
  //  scan 1: err = 12.5; integral = 0.5 * 12.5 * 0.125 = 0.78125; deriv = 12.5 / 0.125 = 100;
  //          out = 2.5 * 12.5 + 0.78125 + 0.25 * 100 = 57.03125; pv = 57.03125 / 8 = 7.12890625.
  //  scan 2: err = 12.5 - 7.12890625 = 5.37109375; integral = 0.78125 + 0.5 * 5.37109375 * 0.125
  //          = 1.116943359375; deriv = (5.37109375 - 12.5) / 0.125 = -57.03125;
  //          out = 13.427734375 + 1.116943359375 - 14.2578125 = 0.286865234375.
  // loop 2 (sp 15, kp 3), scan 1: out = 45 + 0.9375 + 30 = 75.9375.
  // loop 7 (sp 27.5, kp 3.5), scan 1: 96.25 + 1.71875 + 55 = 152.96875, clamped to out_max = 100.
  // At scan 200 (scans MOD 200 = 0) every setpoint becomes 100 - sp: loop 1's 87.5.
  // --watch names only the first 64 scalars of a variable (docs/iec-il.md),
  // five loops here: the others are found from the stride between loops[1]
  // and loops[2].
  const uint32_t stride = r.addr("loops[2].sp") - r.addr("loops[1].sp");
  std::string why = r.compare(230, kEvery, [&](int k, const ImageBytes& img) {
    auto f = [&](int loop, const std::string& field) {
      return r.template at<float>(img, r.addr("loops[1]." + field) + uint32_t(loop - 1) * stride);
    };
    if (k == 1) {
      EXPECT_EQ(f(1, "integral"), 0.78125f);
      EXPECT_EQ(f(1, "out"), 57.03125f);
      EXPECT_EQ(f(1, "pv"), 7.12890625f);
      EXPECT_EQ(f(2, "out"), 75.9375f);
      EXPECT_EQ(f(7, "out"), 100.0f);
    }
    if (k == 2) {
      EXPECT_EQ(f(1, "integral"), 1.116943359375f);
      EXPECT_EQ(f(1, "out"), 0.286865234375f);
    }
    EXPECT_EQ(f(1, "sp"), k < 200 ? 12.5f : 87.5f) << "scan " << k;
    for (int i = 1; i <= 32; i++) {  // the clamps hold in every scan, in every loop
      float out = f(i, "out");
      EXPECT_TRUE(out >= 0.0f && out <= 100.0f) << "scan " << k << ", loop " << i << ": " << out;
    }
  });
  EXPECT_EQ(why, "");
}

// The integers of the line in parse.st and parse_string.st, as its text
// reads, the first field being the scan number MOD 100.
std::vector<int32_t> line_values(int scan) {
  return {scan % 100, 345, -7, 800, -32768, 1000000, 42, 7, -1, 99999, 0, 31, -250, 65535, 12, 3};
}

void check_parsed(const StRun& r, int k, const ImageBytes& img) {
  std::vector<int32_t> want = line_values(k);
  EXPECT_EQ(r.template get<int16_t>(img, "count"), 16) << "scan " << k;
  for (int i = 0; i < 16; i++)
    EXPECT_EQ(r.template get<int32_t>(img, "values[" + std::to_string(i + 1) + "]"), want[size_t(i)]) << "scan " << k;
  EXPECT_EQ(r.template get<int32_t>(img, "sum"), std::accumulate(want.begin(), want.end(), 0)) << "scan " << k;
}

TEST(StPrograms, ParseBytes) {
  StRun r("parse.st");
  std::string why = r.compare(120, kEvery, [&](int k, const ImageBytes& img) {
    check_parsed(r, k, img);
    EXPECT_EQ(r.template get<int16_t>(img, "bad"), 0) << "scan " << k;
    EXPECT_EQ(r.template get<uint8_t>(img, "ok"), 1) << "scan " << k;
  });
  EXPECT_EQ(why, "");
}

TEST(StPrograms, ParseString) {
  StRun r("parse_string.st");
  std::string why = r.compare(120, kEvery, [&](int k, const ImageBytes& img) { check_parsed(r, k, img); });
  EXPECT_EQ(why, "");
}

TEST(StPrograms, Sequence) {
  StRun r("sequence.st");
  r.trace = read_trace(read_file(kDir + "/sequence.csv"), "sequence.csv", r.prog.aliases);
  ASSERT_EQ(r.trace.rows.size(), 3000u);
  // Station 1 by hand (fill_to 800, heat_to 650; the level +7 a scan while the
  // inlet is open, -11 while the drain is; the temperature +3 while heating;
  // a TON's Q when (scan - the scan IN rose) * 10 ms >= PT, as
  // tests/frontend/st/st_fb_array.st has it):
  //   scan 1: IDLE -> FILLING (auto_run), the inlet opens at the end of the scan;
  //   scan k: level 7 (k - 1); 805 >= 800 at k = 116: HEATING;
  //   temp 200 + 3 (k - 116) >= 650 at k = 266: MIXING, mix_time's IN rises;
  //   mix_time.Q at 266 + 500 = 766, read by the CASE of scan 767: DRAINING;
  //   805 - 11 m <= 0 at m = 74: level 0 at scan 841: IDLE, the batch counted.
  //   Its second batch is in MIXING at scan 1200 (the temperature is still
  //   above 650 from the first), when the stop button (scans 1200-1204) faults
  //   it with alarm 4; reset (1300-1304) returns it to IDLE at 1300 and clears
  //   the batch counter (the CTU's R); it starts filling at 1301, alarm 0.
  enum { IDLE, FILLING, HEATING, MIXING, DRAINING, FAULTED };
  auto step_at = [](int k) -> int {
    if (k <= 115) return FILLING;
    if (k <= 265) return HEATING;
    if (k <= 766) return MIXING;
    if (k <= 840) return DRAINING;
    if (k == 841) return IDLE;
    if (k >= 1200 && k < 1300) return FAULTED;
    if (k == 1300) return IDLE;
    return -1;  // not derived by hand
  };
  std::string why = r.compare(1400, kEvery, [&](int k, const ImageBytes& img) {
    int32_t step = r.template get<int32_t>(img, "s1.step");
    if (step_at(k) >= 0) {
      EXPECT_EQ(step, step_at(k)) << "scan " << k;
    }
    if (k == 1301) {
      EXPECT_EQ(step, FILLING);
    }
    EXPECT_EQ(r.template get<int16_t>(img, "s1.batches"), k >= 841 && k < 1300 ? 1 : 0) << "scan " << k;
    EXPECT_EQ(r.template get<int16_t>(img, "s1.alarm"), k >= 1200 && k <= 1300 ? 4 : 0) << "scan " << k;
    if (k == 841) {
      EXPECT_EQ(r.template get<int16_t>(img, "s1.level"), 0);
    }
  });
  EXPECT_EQ(why, "");
}

}  // namespace
