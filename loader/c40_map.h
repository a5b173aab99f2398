// loader/c40_map.h -- the facts of the C40 image format that the loader, the
// C40 code generator and the simulated board share: the board's memory map,
// the word layout of the memory image, and the math ROM's entry points
// (docs/c40.md, "Code generation" and "Math ROM").  Here, not in the backend,
// so that the loader's C40 code check includes no backend.
#pragma once

#include <cstdint>

#include "ir/ir.h"

namespace ldc::c40map {

// ---------------------------------------------------------------- memory map
// Word addresses of the simulated board (all regions zero-wait but the data).
constexpr uint32_t kCodeBase = 0x000000;   // native scan code, or the C40-hosted interpreter
constexpr uint32_t kCodeMaxWords = 0x100000;
constexpr uint32_t kIlBase = 0x100000;     // the word IL the interpreter runs (zero-wait, as in the paper)
constexpr uint32_t kIlMaxWords = 0x100000;
constexpr uint32_t kStackBase = 0x200000;  // SP starts here; the C4x stack grows upward
constexpr uint32_t kStackWords = 0x400;
constexpr uint32_t kRomBase = 0x300000;    // the math ROM (mathrom.h): one routine every kRomStride words
constexpr uint32_t kRomStride = 0x100;
constexpr uint32_t kRomWords = 0x1000;
constexpr uint32_t kDataBase = 0x800000;   // the memory image, page 0x80 (LDPK 0x80)
constexpr uint32_t kDataPage = kDataBase >> 16;
constexpr unsigned kDataWaitStates = 1;    // 50 ns SRAM at 40 MHz
constexpr double kNsPerCycle = 50.0;       // TMS320C40-40

// Fixed words of the Sys area (16 words).
constexpr uint32_t kSysWords = 16;
constexpr uint32_t kSysDtWord = 0;       // INT32 dt (ms) of this scan
constexpr uint32_t kSysScanWord = 1;     // scans completed
constexpr uint32_t kSysScratchWord = 2;  // generated code builds REAL constants here
// The fault record of docs/il.md ("Index faults"), bytes kSysFault.. of the byte image
constexpr uint32_t kSysFaultWord = 3;       // kind (kFaultIndex)
constexpr uint32_t kSysFaultAtWord = 4;     // the IL byte offset of the IDX
constexpr uint32_t kSysFaultValueWord = 5;  // the index, INT64: low word, then high word (6)

// Word offsets of the areas, in Layout::standard order, one word per element.
struct C40Layout {
  uint32_t count[kAreaCount] = {};
  uint32_t offset[kAreaCount] = {};  // words from kDataBase
  uint32_t words = 0;                // total

  static C40Layout of(const Layout& bytes) {
    C40Layout w;
    uint32_t off = 0;
    for (int i = 0; i < kAreaCount; i++) {
      w.count[i] = Area(i) == Area::Sys ? kSysWords : bytes.count[i];
      w.offset[i] = off;
      off += w.count[i];
    }
    w.words = off;
    return w;
  }
  uint32_t addr(Area a, uint32_t index) const { return kDataBase + offset[int(a)] + index; }
  bool operator==(const C40Layout&) const = default;
};

// The math ROM's routines (backend-c40sim/machine/mathrom.h), one every kRomStride words.
enum class RomFn : uint8_t { Sin, Cos, Tan, Sqrt, Exp, Ln, Count };
constexpr int kRomFnCount = int(RomFn::Count);
constexpr uint32_t rom_entry(RomFn f) { return kRomBase + uint32_t(f) * kRomStride; }

// The ROM routine of each REAL function, keyed by ir's RealFn (the order of
// ops.def's FN table, then None); RomFn::Count: the C40 computes it inline (ABS).
inline constexpr RomFn kRomOfFn[] = {RomFn::Sin, RomFn::Cos, RomFn::Tan,  RomFn::Exp,
                                     RomFn::Ln,  RomFn::Sqrt, RomFn::Count, RomFn::Count};
static_assert(sizeof kRomOfFn / sizeof kRomOfFn[0] == size_t(RealFn::None) + 1);
constexpr RomFn rom_of(RealFn f) { return kRomOfFn[int(f)]; }

}  // namespace ldc::c40map
