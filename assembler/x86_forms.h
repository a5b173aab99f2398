// Internal: the x86-64 form table shared by the encoder, the decoder and
// the documentation. Not a public header.
#pragma once

#include "assembler/x86.h"

namespace ldc::as::x86::detail {

// Operand types of a form.
enum class OT : uint8_t {
  None,
  R8, R32, R64, X,          // registers
  M8, M16, M32, M64, MA,    // memory (MA: an address, for lea)
  RM8, RM32, RM64, XM32, XM64,  // register or memory
  Al, Eax, Rax, Cl,         // fixed registers
  One,                      // the immediate 1 (implicit)
  I8,                       // imm8, sign-extended to the operand size
  IB,                       // imm8 as is (byte operand, shift count)
  I32,                      // imm32 (sign-extended for 64-bit operations)
  I64,                      // imm64 (mov r64, imm64 only)
  Rel8, Rel32,              // branch displacement
};

// How operands are placed.
enum class Enc : uint8_t {
  ZO,  // opcode only (plus an immediate, for the accumulator forms)
  O,   // register in the low 3 bits of the opcode
  MR,  // ModRM.rm = op0, ModRM.reg = op1
  RM,  // ModRM.reg = op0, ModRM.rm = op1
  M,   // ModRM.rm = op0, ModRM.reg = digit
  D,   // relative displacement
};

struct Form {
  Mnemonic mn;
  OT ops[3];
  uint8_t prefix;    // 0, 0x66, 0xF3 or 0xF2 (mandatory prefix)
  uint8_t len;       // opcode length (1, or 2 with 0F)
  uint8_t op[2];
  Enc enc;
  int8_t digit;      // ModRM.reg for Enc::M, else -1
  bool w;            // REX.W
  bool cc;           // condition code added to the last opcode byte
  Effects effects;   // what it reads and writes (x86.h, Effects)
};

std::span<const Form> forms();
unsigned num_ops(const Form& f);

}  // namespace ldc::as::x86::detail

