// backend-c40sim/c40layout.h -- the word-addressed memory image of the C40
// target and the simulated board's memory map (docs/c40.md, "Code generation").
//
// The TMS320C40 addresses 32-bit words.  On the C40 every device element is
// one word: bits are 0/1 words, INT32 words are words, REAL words hold the
// IEEE-754 binary32 bit pattern (generated code converts with FRIEEE on load
// and TOIEEE on store, so the image means the same on every engine).  The
// areas come in the order of Layout::standard, each element one word, at a
// fixed base in a region with one wait state (the paper's I/O table in 50 ns
// SRAM on a 40 MHz C40); code, stack and the math ROM are zero-wait.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc::c40gen {

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

// Word offsets of the areas, in Layout::standard order, one word per element.
struct C40Layout {
  uint32_t count[kAreaCount] = {};
  uint32_t offset[kAreaCount] = {};  // words from kDataBase
  uint32_t words = 0;                // total

  static C40Layout of(const Layout& bytes) {  // inline: the loader uses it without the backend
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

// The byte image of docs/il.md <-> the C40 word image (words.size() ==
// layout.words).  Sys: dt and the scan counter only (the x86 call table is
// not part of the C40 image).  Bits: a byte b becomes the word b != 0; a bit
// word other than 0/1 comes back as the byte 0xEE, so a differential test
// sees it.  Words: the 4 little-endian bytes.
void bytes_to_words(const Layout& l, const C40Layout& w, const uint8_t* bytes, uint32_t* words);
void words_to_bytes(const Layout& l, const C40Layout& w, const uint32_t* words, uint8_t* bytes);

}  // namespace ldc::c40gen
