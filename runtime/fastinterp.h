// runtime/fastinterp.h -- the fast interpreter: the best an interpreter can
// honestly do with the same binary IL the reference interpreter runs.
//
// The IL is decoded once, when the engine is made, into a compact array of
// 16-byte records: a handler number, a small field (timer/counter number or
// operand kinds) and three 32-bit fields holding resolved byte offsets into the
// memory image or constants.  Each handler is specialized for its operand
// types at decode time ("quickening": an INT32 ADD of two words, of a word and a
// constant, ...; constant compares and moves folded), so the run loop never
// decodes a tag and never asks what type a value has on the common paths.
// The typed instructions of issue 25 likewise: INT, DINT, 64-bit, REAL and
// LREAL arithmetic, compares, moves, IDX/LDX/STX get handlers of their own;
// the rest a routine of their op with resolved operands (docs/runtime.md,
// "Typed instructions: the fast interpreter and the C route").
// Dispatch is threaded: with GCC or Clang every handler ends in its own
// indirect `goto *table[next->op]` (computed goto); other compilers get a
// `switch` in a loop.  The bit stack stays in a local (a register).
//
// Its meaning is the reference interpreter's (docs/il.md); tests/diff/
// fastinterp_test.cpp compares whole memory images after every scan.  Like the
// native code it relies on the image's invariant that bit devices hold 0 or 1.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "ir/typed.h"
#include "runtime/runtime.h"

namespace ldc {

class FastInterpreter : public Engine {
 public:
  // One decoded instruction (16 bytes).
  struct Ins {
    uint16_t op;  // handler number (fastinterp.cpp)
    uint16_t x;   // timer/counter number, or operand kinds and a sub-opcode
    uint32_t a, b, c;
  };
  static_assert(sizeof(Ins) == 16);

  // A typed instruction without a specialized handler (fastinterp.cpp): its
  // operands resolved at load time, its routine chosen by its op.
  struct TypedOperand {
    uint32_t off = 0;     // byte offset of a device
    bool konst = false;   // a constant: k
    uint64_t k = 0;       // canonical bits (ir/typed.h); an LDX / STX stride in bytes
  };
  struct TypedGeneric {
    bool (*run)(uint8_t* m, const TypedGeneric& g, uint32_t& xr, typed::StrArgs& args) = nullptr;  // true: an index fault ended the scan
    Op op{};
    Ty t = Ty::None, u = Ty::None;
    TypedOperand o[3];
    uint32_t s0 = 0;  // byte offset of S0
    uint32_t at = 0;  // the IL byte offset of the instruction (an IDX's fault record)
  };

  // `il` must be valid for `layout` (validate_il), as for Interpreter.
  FastInterpreter(std::span<const uint8_t> il, const Layout& layout);
  void scan(ImageBytes& mem) override;

  size_t il_instructions() const { return il_count_; }
  size_t decoded_bytes() const { return code_.size() * sizeof(Ins); }  // the decoded program
  // How many IL instructions got a specialized handler (not the generic one).
  size_t specialized() const { return specialized_; }

 private:
  std::vector<Ins> code_;  // the program, then one HALT
  bool loops_ = false;                 // a LOOP: each scan starts with the loop counter at 0
  std::vector<uint32_t> il_offset_;    // the IL byte offset of each record (an IDX fault names it)
  std::vector<uint64_t> k64_;          // 64-bit constants of the typed handlers (a field holds the index)
  std::vector<TypedGeneric> generic_;  // the typed instructions without a specialized handler
  size_t il_count_ = 0, specialized_ = 0;
  uint32_t s0_;                          // byte offset of S0 (the error flag)
  uint32_t tw_, tq_, ti_, cw_, cq_;      // offsets of the timer and counter areas
};

}  // namespace ldc
