// backend-c40sim/gen/c40gen.h -- the macro compiler for the TMS320C40 (paper 003,
// step 2, Fig. 6): every IL mnemonic becomes a fixed C40 assembly template.
//
// The generated code is one function, entered at word 0 with CALL and left with
// RETS (docs/c40.md, "Code generation"):
//   R10  the bit stack, top in bit 0 (paper 003's R10)
//   R11  the mask ~1 (0xFFFFFFFE), loaded by the prologue (paper 003's masks in R11)
//   DP   the data page of the memory image: LDPK once at the start of every rung
//        block (-O1, -O2: once in the prologue); an access to another page (edge
//        slots past 64K words) is wrapped in LDPK page / LDPK back
//   R8 R9 R10 AR1-AR5  -O2: the bit stack of a rung that fits, 0/1 words
//   R0-R7, AR0  scratch within one template (and the routines it calls)
// Devices are read and written with direct addressing (@offset), one word per
// element (c40layout.h).  INT32 division and remainder call the shift-subtract
// routine __divi in the last block, REAL division the routine __divf; REAL
// functions without an instruction call the math ROM (mathrom.h).
#pragma once

#include <string>
#include <vector>

#include "assembler/c40.h"
#include "backend-c40sim/machine/c40float.h"
#include "ir/ir.h"
#include "loader/c40_map.h"

namespace ldc::c40gen {

// The image format's memory map, word layout and math ROM entries (loader/c40_map.h).
using namespace c40map;

struct C40Code {
  // block 0 prologue, one block per rung, then the epilogue and the routines
  as::c40::C40Program program;
  // For rung r and its IL instruction i, the item index in block rung_block(r)
  // where the instruction's code starts (a comment item holding the IL text).
  std::vector<std::vector<uint32_t>> il_items;
  // The block of rung r's code (so that no caller counts the blocks).
  static uint32_t rung_block(size_t r) { return uint32_t(r) + 1; }
};

// opt_level 0: paper 003's templates; 1: the templates with the peephole
// rules of docs/c40.md ("Optimization levels"); 2: the bit stack of every
// rung that fits in registers, the -O1 code for the rest.
C40Code generate_c40(const Program& p, const Layout& layout, int opt_level = 0);

// Global labels the backend defines.
inline constexpr const char* kExitLabel = "scan_exit";
inline constexpr const char* kDivLabel = "__divi";
inline constexpr const char* kDivfLabel = "__divf";
// the typed instructions' routines, in the last block when used (docs/c40.md, "Typed instructions")
inline constexpr const char* kDivuLabel = "__divu";  // UDINT division
inline constexpr const char* kF2iLabel = "__f2i";    // IEEE binary32 -> integer, to nearest or truncated
inline constexpr const char* kI2fLabel = "__i2f";    // unsigned integer -> IEEE binary32, to nearest
inline constexpr const char* kFpackLabel = "__fpack";  // IEEE binary32 arithmetic in integer code:
inline constexpr const char* kFaddLabel = "__fadd";    // the rounding and packing; + - * /
inline constexpr const char* kFsubLabel = "__fsub";
inline constexpr const char* kFmulLabel = "__fmul";
inline constexpr const char* kFdivLabel = "__fdiv";
// Why the C40 code generator refuses a typed instruction, "" if it compiles
// it (generate_c40 throws a CompileError "the C40 cannot compile ADD.LINT: ...")
std::string c40_typed_refusal(const Instr& in);
std::string label_name(const std::string& il_label);  // user label -> assembly label

// ---------------------------------------------------------------- REAL on the C40
// What the generated instruction sequences compute, step for step, with the
// simulator's arithmetic (c40sim::fp).  The code generator folds constants with
// these, the C40 semantic model (c40model.h) runs them, and the tests hold the
// simulated code to them bit for bit.
using c40sim::Ext;
Ext real_from_ieee(uint32_t bits);   // FRIEEE
Ext real_from_int(int32_t i);        // FLOAT (exact in the 40-bit register)
uint32_t real_to_ieee(Ext x);        // TOIEEE + STF: the IEEE word stored
int32_t real_to_int32(Ext x);        // FIX with the truncation fix-up (7 instructions)
Ext real_div(Ext a, Ext b);          // b != 0: the __divf routine
Ext real_add(Ext a, Ext b);          // ADDF
Ext real_sub(Ext a, Ext b);          // SUBF: a - b
Ext real_mul(Ext a, Ext b);          // MPYF
int real_compare(Ext a, Ext b);      // CMPF: sign of a - b

}  // namespace ldc::c40gen
