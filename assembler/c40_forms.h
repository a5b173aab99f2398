// C40 target internals shared by the encoder and the text code.
#pragma once

#include "assembler/c40.h"

namespace ldc::as::c40::detail {

// Instruction word classes. The names follow the operand classes of GNU
// binutils' tic4x opcode table (include/opcode/tic4x.h); the encodings are
// those of the TMS320C4x User's Guide, chapter "Assembly Language
// Instructions".
enum class Cls : uint8_t {
  A,     // integer src (reg/@/*/signed imm16), dst any reg
  AU,    // same with an unsigned imm16
  AF,    // FIX: float src (R0-R11/@/*/short float), dst any reg
  BI,    // FLOAT: integer src (any reg/@/*/signed imm16), dst R0-R11
  B,     // float src (R0-R11/@/*/short float), dst R0-R11
  BA,    // RCPF: src any reg/@/*/short float, dst R0-R11
  B6,    // FRIEEE: src @/*, dst R0-R11
  AB,    // LDIcond: like A, cond in bits 23-27
  BB,    // LDFcond: like B, cond in bits 23-27
  A7,    // STI: src any reg (bits 16-20), dst @/*
  B7,    // STF: src R0-R11
  AY,    // LDA: src like A, dst AR0-7/DP/IR0/IR1/BK/SP
  Ldhi,  // LDHI imm16, reg
  Ldpk,  // LDPK imm16
  T,     // 3-operand integer
  T2,    // 3-operand integer compare/test (no dst)
  S,     // 3-operand float
  S2,    // 3-operand float compare (no dst)
  I,     // BR/BRD/CALL: 24-bit PC-relative
  J,     // Bcond/BcondD: reg or 16-bit PC-relative
  JS,    // CALLcond
  Rets,  // RETScond
  D,     // DBcond/DBcondD ARn, 16-bit PC-relative
  R,     // PUSH/POP any reg
  RF,    // PUSHF/POPF R0-R11
  Nop,   // NOP or NOP *ind
  Word,  // .word
};

enum class ImmKind : uint8_t { None, S16, U16, F16 };

struct Spec {
  std::string_view name;  // without the condition
  Cls cls;
  uint32_t base;
};

const Spec& spec(Mnemonic m);
ImmKind imm_kind(Cls c);
bool is_float_src(Cls c);

}  // namespace ldc::as::c40::detail

