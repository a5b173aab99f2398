// backend-c40sim/machine/c40layout.h -- the word-addressed memory image of the C40
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
#include "loader/c40_map.h"

namespace ldc::c40gen {

// The memory map, the Sys words, C40Layout and the math ROM's entries are the
// image format's (loader/c40_map.h).
using namespace c40map;

// The byte image of docs/il.md <-> the C40 word image (words.size() ==
// layout.words).  Sys: dt, the scan counter and the fault record (the x86 call table is
// not part of the C40 image).  Bits: a byte b becomes the word b != 0; a bit
// word other than 0/1 comes back as the byte 0xEE, so a differential test
// sees it.  Words: the 4 little-endian bytes.
void bytes_to_words(const Layout& l, const C40Layout& w, const uint8_t* bytes, uint32_t* words);
void words_to_bytes(const Layout& l, const C40Layout& w, const uint32_t* words, uint8_t* bytes);

}  // namespace ldc::c40gen
