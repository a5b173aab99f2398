// x86-64 target: form table, encoder, decoder.
#include "assembler/x86_forms.h"

namespace ldc::as::x86 {
namespace detail {
namespace {

using M = Mnemonic;
constexpr OT N = OT::None;

// The effects column: what each form reads and writes (Effects, x86.h).
// fx(uses of the explicit operands), then what it does besides.
constexpr Use R = Use::R, W = Use::W, RW = Use::RW, A = Use::Addr, _ = Use::None;
constexpr Effects fx(Use a = _, Use b = _, Use c = _) { return Effects{{a, b, c}}; }
constexpr Effects flags_out(Effects e) { return e.writes_flags = true, e; }  // writes the flags
constexpr Effects flags_in(Effects e) { return e.reads_flags = true, e; }    // reads them (a condition)
constexpr Effects implicit(Effects e, uint16_t reads, uint16_t writes) { return e.reads = reads, e.writes = writes, e; }
constexpr Effects stack(Effects e, StackUse s) { return e.stack = s, e; }
constexpr uint16_t kEax = reg_bit(AX), kEdx = reg_bit(DX);
constexpr Effects kMove = fx(W, R);                // mov, movzx, movd, cvt..: the destination written whole or in part
constexpr Effects kAlu = flags_out(fx(RW, R));     // add, or, and, sub, xor, shifts: op0 = op0 . op1
constexpr Effects kCompare = flags_out(fx(R, R));  // cmp, test, ucomiss: both read, only the flags written

constexpr Form F(M mn, OT a, OT b, OT c, Effects fx, uint8_t pfx, uint8_t len, uint8_t o0, uint8_t o1,
                 Enc e, int8_t digit = -1, bool w = false, bool cc = false) {
  return Form{mn, {a, b, c}, pfx, len, {o0, o1}, e, digit, w, cc, fx};
}
// One-byte opcode.
constexpr Form F1(M mn, OT a, OT b, Effects fx, uint8_t o, Enc e, int8_t d = -1, bool w = false) {
  return F(mn, a, b, N, fx, 0, 1, o, 0, e, d, w);
}
// 0F-prefixed opcode.
constexpr Form F2(M mn, OT a, OT b, Effects fx, uint8_t o, Enc e, int8_t d = -1, bool cc = false) {
  return F(mn, a, b, N, fx, 0, 2, 0x0F, o, e, d, false, cc);
}
// SSE: mandatory prefix + 0F opcode (w: REX.W, a 64-bit general register or memory operand).
constexpr Form FS(M mn, uint8_t pfx, OT a, OT b, Effects fx, uint8_t o, Enc e, bool w = false) {
  return F(mn, a, b, N, fx, pfx, 2, 0x0F, o, e, -1, w);
}
// 0F-prefixed opcode with REX.W.
constexpr Form F2W(M mn, OT a, OT b, OT c, Effects fx, uint8_t o, Enc e, bool cc = false) {
  return F(mn, a, b, c, fx, 0, 2, 0x0F, o, e, -1, true, cc);
}

// The order matters: the encoder takes the first form that fits, which
// reproduces GNU as's choices (imm8 before the accumulator form before
// imm32, the store direction 89 for register moves, ...).
#define ALU(MN, D, FX)                                           \
  F1(MN, OT::RM32, OT::R32, FX, (D) * 8 + 1, Enc::MR),           \
  F1(MN, OT::R32, OT::RM32, FX, (D) * 8 + 3, Enc::RM),           \
  F1(MN, OT::RM64, OT::R64, FX, (D) * 8 + 1, Enc::MR, -1, true), \
  F1(MN, OT::R64, OT::RM64, FX, (D) * 8 + 3, Enc::RM, -1, true), \
  F1(MN, OT::RM32, OT::I8, FX, 0x83, Enc::M, D),                 \
  F1(MN, OT::Eax, OT::I32, FX, (D) * 8 + 5, Enc::ZO),            \
  F1(MN, OT::RM32, OT::I32, FX, 0x81, Enc::M, D),                \
  F1(MN, OT::RM64, OT::I8, FX, 0x83, Enc::M, D, true),           \
  F1(MN, OT::Rax, OT::I32, FX, (D) * 8 + 5, Enc::ZO, -1, true),  \
  F1(MN, OT::RM64, OT::I32, FX, 0x81, Enc::M, D, true),          \
  F1(MN, OT::RM8, OT::R8, FX, (D) * 8 + 0, Enc::MR),             \
  F1(MN, OT::R8, OT::RM8, FX, (D) * 8 + 2, Enc::RM),             \
  F1(MN, OT::Al, OT::IB, FX, (D) * 8 + 4, Enc::ZO),              \
  F1(MN, OT::RM8, OT::IB, FX, 0x80, Enc::M, D)

#define SHIFT(MN, D)                                      \
  F1(MN, OT::RM32, OT::One, kAlu, 0xD1, Enc::M, D),       \
  F1(MN, OT::RM32, OT::Cl, kAlu, 0xD3, Enc::M, D),        \
  F1(MN, OT::RM32, OT::IB, kAlu, 0xC1, Enc::M, D),        \
  F1(MN, OT::RM64, OT::One, kAlu, 0xD1, Enc::M, D, true), \
  F1(MN, OT::RM64, OT::Cl, kAlu, 0xD3, Enc::M, D, true),  \
  F1(MN, OT::RM64, OT::IB, kAlu, 0xC1, Enc::M, D, true)

#define SSE_ARITH(MN, O, FX) FS(MN, 0xF3, OT::X, OT::XM32, FX, O, Enc::RM)
#define SSE2_ARITH(MN, O, FX) FS(MN, 0xF2, OT::X, OT::XM64, FX, O, Enc::RM)

constexpr Form kForms[] = {
    F1(M::Mov, OT::RM32, OT::R32, kMove, 0x89, Enc::MR),
    F1(M::Mov, OT::R32, OT::RM32, kMove, 0x8B, Enc::RM),
    F1(M::Mov, OT::RM64, OT::R64, kMove, 0x89, Enc::MR, -1, true),
    F1(M::Mov, OT::R64, OT::RM64, kMove, 0x8B, Enc::RM, -1, true),
    F1(M::Mov, OT::R32, OT::I32, kMove, 0xB8, Enc::O),
    F1(M::Mov, OT::RM32, OT::I32, kMove, 0xC7, Enc::M, 0),
    F1(M::Mov, OT::RM8, OT::R8, kMove, 0x88, Enc::MR),
    F1(M::Mov, OT::R8, OT::RM8, kMove, 0x8A, Enc::RM),
    F1(M::Mov, OT::R8, OT::IB, kMove, 0xB0, Enc::O),
    F1(M::Mov, OT::RM8, OT::IB, kMove, 0xC6, Enc::M, 0),
    F2(M::Movzx, OT::R32, OT::RM8, kMove, 0xB6, Enc::RM),
    F2(M::Movsx, OT::R32, OT::RM8, kMove, 0xBE, Enc::RM),
    F1(M::Lea, OT::R32, OT::MA, fx(W, A), 0x8D, Enc::RM),
    F1(M::Lea, OT::R64, OT::MA, fx(W, A), 0x8D, Enc::RM, -1, true),
    ALU(M::Add, 0, kAlu), ALU(M::Or, 1, kAlu), ALU(M::And, 4, kAlu), ALU(M::Sub, 5, kAlu), ALU(M::Xor, 6, kAlu),
    ALU(M::Cmp, 7, kCompare),
    F1(M::Test, OT::RM32, OT::R32, kCompare, 0x85, Enc::MR),
    F1(M::Test, OT::RM64, OT::R64, kCompare, 0x85, Enc::MR, -1, true),
    F1(M::Test, OT::Eax, OT::I32, kCompare, 0xA9, Enc::ZO),
    F1(M::Test, OT::RM32, OT::I32, kCompare, 0xF7, Enc::M, 0),
    F1(M::Test, OT::Rax, OT::I32, kCompare, 0xA9, Enc::ZO, -1, true),
    F1(M::Test, OT::RM64, OT::I32, kCompare, 0xF7, Enc::M, 0, true),
    F1(M::Test, OT::RM8, OT::R8, kCompare, 0x84, Enc::MR),
    F1(M::Test, OT::Al, OT::IB, kCompare, 0xA8, Enc::ZO),
    F1(M::Test, OT::RM8, OT::IB, kCompare, 0xF6, Enc::M, 0),
    SHIFT(M::Shl, 4), SHIFT(M::Shr, 5), SHIFT(M::Sar, 7),
    F1(M::Not, OT::RM32, N, fx(RW), 0xF7, Enc::M, 2),  // the one ALU form that leaves the flags
    F1(M::Neg, OT::RM32, N, flags_out(fx(RW)), 0xF7, Enc::M, 3),
    F2(M::Imul, OT::R32, OT::RM32, kAlu, 0xAF, Enc::RM),
    F(M::Imul, OT::R32, OT::RM32, OT::I8, flags_out(fx(W, R, R)), 0, 1, 0x6B, 0, Enc::RM),
    F(M::Imul, OT::R32, OT::RM32, OT::I32, flags_out(fx(W, R, R)), 0, 1, 0x69, 0, Enc::RM),
    // edx:eax = eax * r/m32, signed (division by a constant)
    F1(M::Imul, OT::RM32, N, implicit(flags_out(fx(R)), kEax, kEax | kEdx), 0xF7, Enc::M, 5),
    F1(M::Cdq, N, N, implicit(fx(), kEax, kEdx), 0x99, Enc::ZO),  // edx = the sign of eax
    // eax, edx = edx:eax / r/m32, edx:eax % r/m32 (the flags undefined)
    F1(M::Idiv, OT::RM32, N, implicit(flags_out(fx(R)), kEax | kEdx, kEax | kEdx), 0xF7, Enc::M, 7),
    F2(M::Setcc, OT::RM8, N, flags_in(fx(W)), 0x90, Enc::M, 0, true),
    // a 32-bit cmov writes its destination even when the condition is false:
    // bits 63..32 become 0 (tests/assembler: X86Effects.CmovZeroExtendsWhenTheConditionIsFalse)
    F2(M::Cmovcc, OT::R32, OT::RM32, flags_in(fx(RW, R)), 0x40, Enc::RM, -1, true),
    F(M::Jcc, OT::Rel8, N, N, flags_in(fx(A)), 0, 1, 0x70, 0, Enc::D, -1, false, true),
    F2(M::Jcc, OT::Rel32, N, flags_in(fx(A)), 0x80, Enc::D, -1, true),
    F1(M::Jmp, OT::Rel8, N, fx(A), 0xEB, Enc::D),
    F1(M::Jmp, OT::Rel32, N, fx(A), 0xE9, Enc::D),
    F1(M::Jmp, OT::RM64, N, fx(R), 0xFF, Enc::M, 4),  // reads its target
    F1(M::Call, OT::Rel32, N, stack(fx(A), StackUse::Call), 0xE8, Enc::D),
    F1(M::Call, OT::RM64, N, stack(fx(R), StackUse::Call), 0xFF, Enc::M, 2),
    F1(M::Ret, N, N, stack(fx(), StackUse::Ret), 0xC3, Enc::ZO),
    F1(M::Push, OT::R64, N, stack(fx(R), StackUse::Push), 0x50, Enc::O),
    F1(M::Pop, OT::R64, N, stack(fx(W), StackUse::Pop), 0x58, Enc::O),
    F1(M::Nop, N, N, fx(), 0x90, Enc::ZO),
    FS(M::Movss, 0xF3, OT::X, OT::XM32, kMove, 0x10, Enc::RM),
    FS(M::Movss, 0xF3, OT::M32, OT::X, kMove, 0x11, Enc::MR),
    FS(M::Movd, 0x66, OT::X, OT::RM32, kMove, 0x6E, Enc::RM),
    FS(M::Movd, 0x66, OT::RM32, OT::X, kMove, 0x7E, Enc::MR),
    FS(M::Cvtsi2ss, 0xF3, OT::X, OT::RM32, kMove, 0x2A, Enc::RM),
    FS(M::Cvttss2si, 0xF3, OT::R32, OT::XM32, kMove, 0x2C, Enc::RM),
    SSE_ARITH(M::Addss, 0x58, fx(RW, R)), SSE_ARITH(M::Subss, 0x5C, fx(RW, R)), SSE_ARITH(M::Mulss, 0x59, fx(RW, R)),
    SSE_ARITH(M::Divss, 0x5E, fx(RW, R)), SSE_ARITH(M::Sqrtss, 0x51, fx(W, R)), SSE_ARITH(M::Minss, 0x5D, fx(RW, R)),
    SSE_ARITH(M::Maxss, 0x5F, fx(RW, R)),
    FS(M::Ucomiss, 0, OT::X, OT::XM32, kCompare, 0x2E, Enc::RM),
    FS(M::Andps, 0, OT::X, OT::X, fx(RW, R), 0x54, Enc::RM),
    FS(M::Xorps, 0, OT::X, OT::X, fx(RW, R), 0x57, Enc::RM),
    // the typed instructions' forms (docs/x86.md, "Typed instructions")
    F2(M::Movzx, OT::R32, OT::M16, kMove, 0xB7, Enc::RM),
    F2(M::Movsx, OT::R32, OT::M16, kMove, 0xBF, Enc::RM),
    F2W(M::Movsx, OT::R64, OT::RM8, N, kMove, 0xBE, Enc::RM),   // an index sign-extended to 64 bits at once
    F2W(M::Movsx, OT::R64, OT::M16, N, kMove, 0xBF, Enc::RM),
    F1(M::Movsxd, OT::R64, OT::RM32, kMove, 0x63, Enc::RM, -1, true),
    F1(M::Mov, OT::RM64, OT::I32, kMove, 0xC7, Enc::M, 0, true),   // sign-extended: before the imm64 form
    F1(M::Mov, OT::R64, OT::I64, kMove, 0xB8, Enc::O, -1, true),   // movabs
    F1(M::Cwde, N, N, implicit(fx(), kEax, kEax), 0x98, Enc::ZO),            // eax = the sign extension of ax
    F1(M::Cdqe, N, N, implicit(fx(), kEax, kEax), 0x98, Enc::ZO, -1, true),  // rax = the sign extension of eax
    F1(M::Cqo, N, N, implicit(fx(), kEax, kEdx), 0x99, Enc::ZO, -1, true),   // rdx = the sign of rax
    F1(M::Not, OT::RM64, N, fx(RW), 0xF7, Enc::M, 2, true),
    F1(M::Neg, OT::RM64, N, flags_out(fx(RW)), 0xF7, Enc::M, 3, true),
    F2W(M::Imul, OT::R64, OT::RM64, N, kAlu, 0xAF, Enc::RM),
    F(M::Imul, OT::R64, OT::RM64, OT::I8, flags_out(fx(W, R, R)), 0, 1, 0x6B, 0, Enc::RM, -1, true),
    F(M::Imul, OT::R64, OT::RM64, OT::I32, flags_out(fx(W, R, R)), 0, 1, 0x69, 0, Enc::RM, -1, true),
    // rax, rdx = rdx:rax / r/m64, rdx:rax % r/m64; div: unsigned (edx:eax, rdx:rax)
    F1(M::Idiv, OT::RM64, N, implicit(flags_out(fx(R)), kEax | kEdx, kEax | kEdx), 0xF7, Enc::M, 7, true),
    F1(M::Div, OT::RM32, N, implicit(flags_out(fx(R)), kEax | kEdx, kEax | kEdx), 0xF7, Enc::M, 6),
    F1(M::Div, OT::RM64, N, implicit(flags_out(fx(R)), kEax | kEdx, kEax | kEdx), 0xF7, Enc::M, 6, true),
    F2W(M::Cmovcc, OT::R64, OT::RM64, N, flags_in(fx(RW, R)), 0x40, Enc::RM, true),
    SHIFT(M::Rol, 0), SHIFT(M::Ror, 1),
    FS(M::Movsd, 0xF2, OT::X, OT::XM64, kMove, 0x10, Enc::RM),
    FS(M::Movsd, 0xF2, OT::M64, OT::X, kMove, 0x11, Enc::MR),
    SSE2_ARITH(M::Addsd, 0x58, fx(RW, R)), SSE2_ARITH(M::Subsd, 0x5C, fx(RW, R)), SSE2_ARITH(M::Mulsd, 0x59, fx(RW, R)),
    SSE2_ARITH(M::Divsd, 0x5E, fx(RW, R)), SSE2_ARITH(M::Sqrtsd, 0x51, fx(W, R)), SSE2_ARITH(M::Minsd, 0x5D, fx(RW, R)),
    SSE2_ARITH(M::Maxsd, 0x5F, fx(RW, R)),
    FS(M::Ucomisd, 0x66, OT::X, OT::XM64, kCompare, 0x2E, Enc::RM),
    FS(M::Cvtss2sd, 0xF3, OT::X, OT::XM32, kMove, 0x5A, Enc::RM),
    FS(M::Cvtsd2ss, 0xF2, OT::X, OT::XM64, kMove, 0x5A, Enc::RM),
    FS(M::Cvtsi2sd, 0xF2, OT::X, OT::RM64, kMove, 0x2A, Enc::RM, true),
    FS(M::Cvtsi2sd, 0xF2, OT::X, OT::RM32, kMove, 0x2A, Enc::RM),  // a signed 32-bit value
    FS(M::Cvtsi2ss, 0xF3, OT::X, OT::RM64, kMove, 0x2A, Enc::RM, true),
    FS(M::Cvttsd2si, 0xF2, OT::R64, OT::XM64, kMove, 0x2C, Enc::RM, true),
    FS(M::Cvtsd2si, 0xF2, OT::R64, OT::XM64, kMove, 0x2D, Enc::RM, true),  // rounds by MXCSR: to nearest, ties to even
    // registers only: GNU as spells movq from memory F3 0F 7E
    FS(M::Movq, 0x66, OT::X, OT::R64, kMove, 0x6E, Enc::RM, true),
    FS(M::Movq, 0x66, OT::R64, OT::X, kMove, 0x7E, Enc::MR, true),
};
#undef ALU
#undef SHIFT
#undef SSE_ARITH
#undef SSE2_ARITH

// Every form has its effects row, and the row fits the form: an effect for
// each operand and none past them; branch targets and lea's address not
// accessed, immediates read; the condition forms read the flags; the stack
// column is the stack instructions'.  A form added without its row does not
// compile (the column has no default), one with a row that does not fit it
// stops here.  tests/assembler/x86_effects_test.cpp checks the rows against
// the CPU.
constexpr bool row_fits(const Form& f) {
  for (int i = 0; i < 3; i++) {
    const OT t = f.ops[i];
    const Use u = f.effects.ops[size_t(i)];
    if ((t == OT::None) != (u == Use::None)) return false;
    const bool addr = t == OT::Rel8 || t == OT::Rel32 || t == OT::MA;
    if (addr != (u == Use::Addr)) return false;
    const bool imm = t == OT::I8 || t == OT::IB || t == OT::I32 || t == OT::I64 || t == OT::One;
    if (imm && u != Use::R) return false;
  }
  if (f.cc != f.effects.reads_flags) return false;
  const StackUse s = f.effects.stack;
  return (f.mn == M::Push) == (s == StackUse::Push) && (f.mn == M::Pop) == (s == StackUse::Pop) &&
         (f.mn == M::Call) == (s == StackUse::Call) && (f.mn == M::Ret) == (s == StackUse::Ret);
}
constexpr bool every_row_fits() {
  for (const Form& f : kForms)
    if (!row_fits(f)) return false;
  return true;
}
static_assert(every_row_fits(), "x86 form table: a form whose effects row does not fit it (assembler/x86.h, Effects)");

}  // namespace

std::span<const Form> forms() { return kForms; }

unsigned num_ops(const Form& f) {
  unsigned n = 0;
  while (n < 3 && f.ops[n] != OT::None) ++n;
  return n;
}

namespace {

constexpr bool is_imm_type(OT t) { return t == OT::I8 || t == OT::IB || t == OT::I32 || t == OT::I64; }
constexpr bool is_rel_type(OT t) { return t == OT::Rel8 || t == OT::Rel32; }
bool is_mem_only(OT t) { return t == OT::M8 || t == OT::M16 || t == OT::M32 || t == OT::M64 || t == OT::MA; }
bool is_reg_only(OT t) {
  return t == OT::R8 || t == OT::R32 || t == OT::R64 || t == OT::X;
}

// The register class of a register-or-memory type's register half.
RegClass reg_class_of(OT t) {
  switch (t) {
    case OT::R8: case OT::RM8: case OT::Al: case OT::Cl: return RegClass::Gp8;
    case OT::R32: case OT::RM32: case OT::Eax: return RegClass::Gp32;
    case OT::R64: case OT::RM64: case OT::Rax: return RegClass::Gp64;
    case OT::X: case OT::XM32: case OT::XM64: return RegClass::Xmm;
    default: return RegClass::None;
  }
}

Size mem_size_of(OT t) {
  switch (t) {
    case OT::M8: case OT::RM8: return Size::Byte;
    case OT::M16: return Size::Word;
    case OT::M32: case OT::RM32: case OT::XM32: return Size::Dword;
    case OT::M64: case OT::RM64: case OT::XM64: return Size::Qword;
    default: return Size::None;
  }
}

bool accepts_mem(OT t) {
  return is_mem_only(t) || t == OT::RM8 || t == OT::RM32 || t == OT::RM64 || t == OT::XM32 || t == OT::XM64;
}
bool accepts_reg(OT t) {
  return is_reg_only(t) || t == OT::RM8 || t == OT::RM32 || t == OT::RM64 || t == OT::XM32 || t == OT::XM64;
}

bool has_reg_operand(const Instruction& in) {
  for (unsigned i = 0; i < in.num_operands; ++i)
    if (in.ops[i].kind == OperandKind::Reg && in.ops[i].reg != r8(CX)) return true;
  return false;
}

// Immediate in range for an operand of the form's size.
bool imm_fits(OT t, int64_t v, bool w) {
  switch (t) {
    case OT::IB: return v >= -128 && v <= 255;
    case OT::One: return v == 1;
    case OT::I64: return true;
    case OT::I32:
      return w ? (v >= INT32_MIN && v <= INT32_MAX) : (v >= INT32_MIN && v <= int64_t(UINT32_MAX));
    case OT::I8: {
      if (!imm_fits(OT::I32, v, w)) return false;
      int64_t s = w ? v : int64_t(int32_t(uint32_t(v)));
      return s >= -128 && s <= 127;
    }
    default: return false;
  }
}

bool matches(OT t, const Operand& o, const Form& f, const Instruction& in, bool long_form) {
  switch (o.kind) {
    case OperandKind::Reg:
      switch (t) {
        case OT::Al: return o.reg == r8(AX);
        case OT::Eax: return o.reg == r32(AX);
        case OT::Rax: return o.reg == r64(AX);
        case OT::Cl: return o.reg == r8(CX);
        default: return accepts_reg(t) && o.reg.cls == reg_class_of(t);
      }
    case OperandKind::Mem:
      if (!accepts_mem(t)) return false;
      if (t == OT::MA) return true;
      if (o.mem.size == Size::None)
        return has_reg_operand(in) || in.mnemonic == Mnemonic::Jmp || in.mnemonic == Mnemonic::Call;
      return o.mem.size == mem_size_of(t);
    case OperandKind::Imm:
      return (is_imm_type(t) || t == OT::One) && imm_fits(t, o.imm, f.w);
    case OperandKind::Label:
    case OperandKind::Address:
      if (t == OT::Rel8) return !long_form && !in.long_branch;
      return t == OT::Rel32;
    case OperandKind::None:
      return false;
  }
  return false;
}

// The forms of each mnemonic and operand count, in table order (find_form
// looks at these only).
struct FormIndex {
  std::array<std::array<std::vector<const Form*>, 4>, size_t(Mnemonic::Count_)> forms;
  FormIndex() {
    for (const Form& f : kForms) forms[size_t(f.mn)][num_ops(f)].push_back(&f);
  }
};

const Form* find_form_in_table(const Instruction& in, bool long_form) {
  static const FormIndex index;
  if (size_t(in.mnemonic) >= index.forms.size() || in.num_operands > 3) return nullptr;
  for (const Form* fp : index.forms[size_t(in.mnemonic)][in.num_operands]) {
    const Form& f = *fp;
    bool ok = true;
    for (unsigned i = 0; i < in.num_operands && ok; ++i)
      ok = matches(f.ops[i], in.ops[i], f, in, long_form);
    if (ok) return &f;
  }
  return nullptr;
}

// The ranges of imm_fits that v falls in, one bit each.
uint64_t imm_ranges(int64_t v) {
  return uint64_t(imm_fits(OT::IB, v, false)) | uint64_t(imm_fits(OT::One, v, false)) << 1 |
         uint64_t(imm_fits(OT::I32, v, true)) << 2 | uint64_t(imm_fits(OT::I32, v, false)) << 3 |
         uint64_t(imm_fits(OT::I8, v, true)) << 4 | uint64_t(imm_fits(OT::I8, v, false)) << 5;
}

// Everything of an instruction that matches() looks at, packed: the mnemonic,
// the operand count, whether a rel8 may be taken, and per operand its kind and
// its register (class and number), memory size or immediate ranges (14 bits).
uint64_t form_key(const Instruction& in, bool long_form) {
  uint64_t k = uint64_t(in.mnemonic) | uint64_t(in.num_operands) << 8 | uint64_t(!long_form && !in.long_branch) << 10;
  for (unsigned i = 0; i < in.num_operands; ++i) {
    const Operand& o = in.ops[i];
    uint64_t part = uint64_t(o.kind);
    if (o.kind == OperandKind::Reg) part |= uint64_t(o.reg.cls) << 3 | uint64_t(o.reg.num) << 6;
    else if (o.kind == OperandKind::Mem) part |= uint64_t(o.mem.size) << 3;
    else if (o.kind == OperandKind::Imm) part |= imm_ranges(o.imm) << 3;
    k |= part << (11 + 14 * i);
  }
  return k;
}

uint8_t hi(Reg r) { return (r.num >> 3) & 1; }
uint8_t lo(Reg r) { return r.num & 7; }
bool needs_rex(Reg r) { return r.cls == RegClass::Gp8 && r.num >= 4 && r.num <= 7; }

void check_mem(const Mem& m) {
  if (m.base.valid() && m.base.cls != RegClass::Gp64 && m.base.cls != RegClass::Rip)
    throw AsmError("memory base must be a 64-bit register or rip");
  if (m.index.valid()) {
    if (m.index.cls != RegClass::Gp64) throw AsmError("memory index must be a 64-bit register");
    if (m.index.num == SP) throw AsmError("rsp cannot be an index register");
    if (m.base.cls == RegClass::Rip) throw AsmError("rip-relative address cannot have an index");
  }
  if (m.scale != 1 && m.scale != 2 && m.scale != 4 && m.scale != 8)
    throw AsmError("scale must be 1, 2, 4 or 8");
  if (!m.index.valid() && m.scale != 1) throw AsmError("scale without an index register");
}

// One instruction's bytes, written into the Encoding's buffer with their
// count kept here (in a register) and stored once at the end: a byte stored
// through Encoding::put may alias its size (both uint8_t), so every put
// reloaded and stored the size.  (Gathering them in a local buffer and copying
// 16 bytes at once stalls on that load of bytes just stored one by one.)
struct Bytes {
  uint8_t* b;
  unsigned n = 0;
  explicit Bytes(Encoding& e) : b(e.bytes.data()) {}
  void put(uint8_t v) {
    if (n >= sizeof(Encoding::bytes)) Encoding::too_long();
    b[n++] = v;
  }
  void put32(uint32_t v) {
    for (int i = 0; i < 4; ++i) put(uint8_t(v >> (8 * i)));
  }
};

void put_mod_rm(Bytes& out, uint8_t reg, const Operand& rm) {
  if (rm.kind == OperandKind::Reg) {
    out.put(uint8_t(0xC0 | (reg & 7) << 3 | lo(rm.reg)));
    return;
  }
  const Mem& m = rm.mem;
  uint8_t r = uint8_t((reg & 7) << 3);
  uint8_t ss = m.scale == 8 ? 3 : m.scale == 4 ? 2 : m.scale == 2 ? 1 : 0;
  if (m.base.cls == RegClass::Rip) {
    out.put(uint8_t(0x05 | r));
    out.put32(uint32_t(m.disp));
    return;
  }
  if (!m.base.valid()) {  // [index*scale + disp32] or [disp32]
    out.put(uint8_t(0x04 | r));
    uint8_t idx = m.index.valid() ? lo(m.index) : 4;
    out.put(uint8_t(ss << 6 | idx << 3 | 5));
    out.put32(uint32_t(m.disp));
    return;
  }
  uint8_t mod;
  if (m.disp == 0 && lo(m.base) != BP) mod = 0;
  else if (m.disp >= -128 && m.disp <= 127) mod = 1;
  else mod = 2;
  if (m.index.valid() || lo(m.base) == SP) {
    out.put(uint8_t(mod << 6 | r | 4));
    uint8_t idx = m.index.valid() ? lo(m.index) : 4;
    out.put(uint8_t(ss << 6 | idx << 3 | lo(m.base)));
  } else {
    out.put(uint8_t(mod << 6 | r | lo(m.base)));
  }
  if (mod == 1) out.put(uint8_t(int8_t(m.disp)));
  if (mod == 2) out.put32(uint32_t(m.disp));
}

// What an instruction's encoding takes from its form and its registers
// alone, both of which form_key holds: the prefix, the REX bits but a memory
// operand's, the opcode bytes but a condition code, and where the operands
// go.  Worked out once a key (find_plan's cache); encode_hook adds the rest.
struct Plan {
  uint8_t prefix = 0;      // mandatory prefix, 0 none
  uint8_t rex = 0;         // W, and R and B of register operands
  bool force_rex = false;  // spl bpl sil dil: a REX prefix even with no bit set
  bool cc = false;         // the condition code is added to the last opcode byte
  uint8_t len = 0;         // opcode bytes (an O form's register added to the last)
  std::array<uint8_t, 2> op{};
  int8_t rm = -1;          // the operand in ModRM.rm, -1 none
  uint8_t reg_field = 0;   // ModRM.reg: the register operand's number or the form's digit
  int8_t imm = -1;         // the immediate operand, -1 none
  uint8_t imm_bytes = 0;   // 1 (I8, IB), 4 (I32) or 8 (I64)
  int8_t rel = -1;         // the branch displacement operand, -1 none
  uint16_t rel_kind = 0;   // Rel8 or Rel32
};

// At most one immediate or displacement a form: the plan has room for one.
static_assert([] {
  for (const Form& f : kForms) {
    int n = 0;
    for (OT t : f.ops) n += is_imm_type(t) || is_rel_type(t);
    if (n > 1) return false;
  }
  return true;
}());

Plan make_plan(const Form& f, const Instruction& in) {
  Plan p;
  const Operand* reg_op = nullptr;  // goes in ModRM.reg (or the opcode, Enc::O)
  switch (f.enc) {
    case Enc::MR: p.rm = 0; reg_op = &in.ops[1]; break;
    case Enc::RM: reg_op = &in.ops[0]; p.rm = 1; break;
    case Enc::M: p.rm = 0; p.reg_field = uint8_t(f.digit); break;
    case Enc::O: reg_op = &in.ops[0]; break;
    default: break;
  }
  if (reg_op) p.reg_field = reg_op->reg.num;
  p.rex = f.w ? 0x08 : 0;
  if (f.enc == Enc::O) p.rex |= hi(reg_op->reg);
  else if (reg_op) p.rex |= uint8_t(hi(reg_op->reg) << 2);
  if (p.rm >= 0 && in.ops[size_t(p.rm)].kind == OperandKind::Reg) p.rex |= hi(in.ops[size_t(p.rm)].reg);
  for (unsigned i = 0; i < in.num_operands; ++i)
    if (in.ops[i].kind == OperandKind::Reg && needs_rex(in.ops[i].reg)) p.force_rex = true;
  p.prefix = f.prefix;
  p.len = f.len;
  p.op = {f.op[0], f.op[1]};
  if (f.enc == Enc::O) p.op[f.len - 1] = uint8_t(p.op[f.len - 1] + lo(reg_op->reg));
  p.cc = f.cc;
  for (unsigned i = 0; i < in.num_operands; ++i) {
    const OT t = f.ops[i];
    if (t == OT::I8 || t == OT::IB) p.imm = int8_t(i), p.imm_bytes = 1;
    else if (t == OT::I32) p.imm = int8_t(i), p.imm_bytes = 4;
    else if (t == OT::I64) p.imm = int8_t(i), p.imm_bytes = 8;
    else if (is_rel_type(t)) p.rel = int8_t(i), p.rel_kind = t == OT::Rel8 ? Rel8 : Rel32;
  }
  return p;
}

// The plan of an instruction's form, by form_key, in a direct-mapped cache of
// the thread's own (the code generators encode few shapes, over and over);
// nullptr if no form fits.
const Plan* find_plan(const Instruction& in, bool long_form) {
  static_assert(sizeof(Mnemonic) == 1 && sizeof(OperandKind) == 1 && sizeof(RegClass) == 1 && sizeof(Size) == 1);
  if (in.num_operands > 3) return nullptr;
  constexpr size_t kSlots = 1024;
  struct Slot {
    uint64_t key = 0;  // form_key + 1, 0 empty
    Plan plan;
  };
  thread_local std::array<Slot, kSlots> cache;
  const uint64_t key = form_key(in, long_form) + 1;
  Slot& slot = cache[size_t((key * 0x9E3779B97F4A7C15ull) >> 54)];
  if (slot.key == key) return &slot.plan;
  const Form* f = find_form_in_table(in, long_form);
  if (!f) return nullptr;
  slot = {key, make_plan(*f, in)};
  return &slot.plan;
}

[[noreturn]] void no_form(const Instruction& in) {
  if (in.num_operands > 3) throw AsmError("too many operands");
  throw AsmError("invalid operands for '" + print(in) + "'");
}

void put_fixup(const Plan& p, const Operand& o, Bytes& out, Encoding& enc) {
  Fixup fx;
  fx.offset = out.n;
  fx.kind = p.rel_kind;
  if (o.kind == OperandKind::Label) fx.label = o.label;
  else fx.addend = o.imm;
  if (p.rel_kind == Rel8) out.put(0);
  else out.put32(0);
  enc.add_fixup(fx);
}

void encode_hook(const Instruction& in, bool long_form, Encoding& out) {
  const Plan* p = find_plan(in, long_form);
  if (!p) no_form(in);
  const Operand* rm = p->rm >= 0 ? &in.ops[size_t(p->rm)] : nullptr;
  uint8_t rex = p->rex;
  if (rm && rm->kind == OperandKind::Mem) {
    check_mem(rm->mem);
    if (rm->mem.index.valid()) rex |= uint8_t(hi(rm->mem.index) << 1);
    if (rm->mem.base.cls == RegClass::Gp64) rex |= hi(rm->mem.base);
  }
  Bytes bytes(out);
  if (p->prefix) bytes.put(p->prefix);
  if (rex || p->force_rex) bytes.put(uint8_t(0x40 | rex));
  if (p->len == 2) bytes.put(p->op[0]);
  bytes.put(uint8_t(p->op[p->len - 1] + (p->cc ? uint8_t(in.cond) : 0)));
  if (rm) put_mod_rm(bytes, p->reg_field, *rm);
  if (p->imm >= 0) {
    const int64_t v = in.ops[size_t(p->imm)].imm;
    if (p->imm_bytes == 1) bytes.put(uint8_t(v));
    else bytes.put32(uint32_t(v));
    if (p->imm_bytes == 8) bytes.put32(uint32_t(uint64_t(v) >> 32));
  }
  if (p->rel >= 0) put_fixup(*p, in.ops[size_t(p->rel)], bytes, out);
  out.size = uint8_t(bytes.n);
}

constexpr FixupKind kFixupKinds[] = {
    // name   bytes shift width pcrel  signed  pc base                  bias scale relax_to
    {"rel8", 1, 0, 8, true, true, PcBase::InstructionEnd, 0, 1, Rel32},
    {"rel32", 4, 0, 32, true, true, PcBase::InstructionEnd, 0, 1, -1},
};

const Target<Instruction> kTarget = [] {
  Target<Instruction> t;
  t.name = "x86-64";
  t.fixup_kinds = kFixupKinds;
  t.encode = encode_hook;
  return t;
}();

}  // namespace
}  // namespace detail

using namespace detail;

Instruction make(Mnemonic m, std::initializer_list<Operand> ops) {
  return make_cc(m, Cond::O, ops);
}

Instruction make_cc(Mnemonic m, Cond c, std::initializer_list<Operand> ops) {
  Instruction in;
  in.mnemonic = m;
  in.cond = c;
  if (ops.size() > 3) throw AsmError("too many operands");
  in.num_operands = uint8_t(ops.size());  // set once: a count bumped in memory is reloaded after each operand stored
  for (size_t k = 0; k < ops.size(); k++) in.ops[k] = ops.begin()[k];
  return in;
}

const Target<Instruction>& target() { return kTarget; }

Effects effects(const Instruction& inst) {
  const Form* f = find_form_in_table(inst, inst.long_branch);
  if (!f) no_form(inst);
  return f->effects;
}

Encoding encode(const Instruction& inst, bool long_form) {
  Encoding e;
  encode_hook(inst, long_form, e);
  return e;
}

namespace {
// encode_at's bytes in a fixed buffer: the decoder re-encodes every
// instruction it reads, and the loader decodes every instruction of an image.
Encoding encode_at_fixed(const Instruction& inst, uint64_t address) {
  for (bool long_form : {false, true}) {
    Encoding e = encode(inst, long_form);
    bool relax = false;
    for (unsigned i = 0; i < e.num_fixups; ++i) {
      const Fixup& fx = e.fixups[i];
      if (!fx.label.empty())
        throw AsmError("label '" + std::string(fx.label) + "' needs the assembler core");
      const FixupKind& k = kFixupKinds[fx.kind];
      int64_t v;
      if (!fixup_value(k, 0, fx.addend, int64_t(address), e.size, v) || !fixup_fits(k, v)) {
        if (k.relax_to >= 0 && !long_form) {
          relax = true;
          break;
        }
        throw AsmError("branch target out of range");
      }
      apply_fixup(k, std::span<uint8_t>(e.bytes.data(), e.size), fx.offset, v);
    }
    if (!relax) return e;
  }
  throw AsmError("branch target out of range");
}
}  // namespace

std::vector<uint8_t> encode_at(const Instruction& inst, uint64_t address) {
  Encoding e = encode_at_fixed(inst, address);
  return std::vector<uint8_t>(e.bytes.begin(), e.bytes.begin() + e.size);
}

// ------------------------------------------------------------------ decoder

namespace {

struct Reader {
  std::span<const uint8_t> code;
  size_t pos;
  bool ok = true;
  uint8_t u8() {
    if (pos >= code.size()) {
      ok = false;
      return 0;
    }
    return code[pos++];
  }
  uint32_t u32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= uint32_t(u8()) << (8 * i);
    return v;
  }
};

bool opcode_matches(const Form& f, const uint8_t* op, unsigned len) {
  if (f.len != len) return false;
  for (unsigned i = 0; i + 1 < len; ++i)
    if (op[i] != f.op[i]) return false;
  uint8_t last = op[len - 1], want = f.op[len - 1];
  if (f.cc) return (last & 0xF0) == want;
  if (f.enc == Enc::O) return (last & 0xF8) == want;
  return last == want;
}

// The forms whose prefix and opcode bytes match, in table order, looked up by
// the prefix, the opcode length and the last opcode byte (a two-byte opcode
// is always 0F xx): the decoder tries these instead of every form, so decoding
// costs the same for the first form and the last (the loader decodes every
// instruction of an image; docs/image-format.md, "The x86-64 code check").
struct DecodeIndex {
  static int prefix_slot(uint8_t prefix) {
    return prefix == 0 ? 0 : prefix == 0x66 ? 1 : prefix == 0xF3 ? 2 : prefix == 0xF2 ? 3 : -1;
  }
  std::array<std::array<std::array<std::vector<const Form*>, 256>, 2>, 4> by;
  DecodeIndex() {
    for (const Form& f : kForms) {
      int slot = prefix_slot(f.prefix);
      if (slot < 0 || f.len < 1 || f.len > 2 || (f.len == 2 && f.op[0] != 0x0F))
        throw std::logic_error("x86 form table: a prefix or opcode the decoder cannot index");
      for (unsigned last = 0; last < 256; last++) {
        uint8_t op[2] = {f.op[0], f.op[1]};
        op[f.len - 1] = uint8_t(last);
        if (opcode_matches(f, op, f.len)) by[size_t(slot)][f.len - 1u][last].push_back(&f);
      }
    }
  }
};

std::span<const Form* const> decode_candidates(uint8_t prefix, const uint8_t* op, unsigned len) {
  static const DecodeIndex index;
  int slot = DecodeIndex::prefix_slot(prefix);
  if (slot < 0 || len < 1 || len > 2 || (len == 2 && op[0] != 0x0F)) return {};
  return index.by[size_t(slot)][len - 1][op[len - 1]];
}

// Decodes with one form; returns false if the bytes do not fit it.
bool decode_with(const Form& f, Reader rd, size_t start, uint8_t rex, const uint8_t* op,
                Instruction& in, size_t& end, bool& truncated) {
  bool has_mod_rm = f.enc == Enc::MR || f.enc == Enc::RM || f.enc == Enc::M;
  in = Instruction{};
  in.mnemonic = f.mn;
  in.cond = f.cc ? Cond(op[f.len - 1] & 0x0F) : Cond::O;
  in.num_operands = uint8_t(num_ops(f));
  unsigned rm_idx = 9, reg_idx = 9;
  if (f.enc == Enc::MR) rm_idx = 0, reg_idx = 1;
  if (f.enc == Enc::RM) rm_idx = 1, reg_idx = 0;
  if (f.enc == Enc::M) rm_idx = 0;
  Operand rm_op;
  uint8_t reg_num = 0;
  if (has_mod_rm) {
    uint8_t modrm = rd.u8();
    if (!rd.ok) return truncated = true, false;
    uint8_t mod = modrm >> 6, reg = (modrm >> 3) & 7, rm = modrm & 7;
    if (f.enc == Enc::M && reg != uint8_t(f.digit)) return false;
    reg_num = uint8_t(reg | ((rex >> 2) & 1) << 3);
    OT rm_type = f.ops[rm_idx];
    if (mod == 3) {
      if (!accepts_reg(rm_type)) return false;
      rm_op = Operand::r(Reg{reg_class_of(rm_type), uint8_t(rm | (rex & 1) << 3)});
    } else {
      if (!accepts_mem(rm_type)) return false;
      Mem m;
      m.size = mem_size_of(rm_type);
      if (rm == 4) {
        uint8_t sib = rd.u8();
        uint8_t idx = uint8_t(((sib >> 3) & 7) | ((rex >> 1) & 1) << 3);
        if (idx != SP) m.index = r64(idx), m.scale = uint8_t(1 << (sib >> 6));
        else if (sib >> 6) return false;
        if ((sib & 7) == 5 && mod == 0) {
          m.disp = int32_t(rd.u32());
        } else {
          m.base = r64((sib & 7) | (rex & 1) << 3);
        }
      } else if (rm == 5 && mod == 0) {
        m.base = rip();
        m.disp = int32_t(rd.u32());
      } else {
        m.base = r64(rm | (rex & 1) << 3);
      }
      if (mod == 1) m.disp = int8_t(rd.u8());
      if (mod == 2) m.disp = int32_t(rd.u32());
      rm_op = Operand::m(m);
    }
  }
  for (unsigned i = 0; i < in.num_operands; ++i) {
    OT t = f.ops[i];
    Operand& o = in.ops[i];
    if (i == rm_idx) {
      o = rm_op;
    } else if (i == reg_idx) {
      o = Operand::r(Reg{reg_class_of(t), reg_num});
    } else if (f.enc == Enc::O && i == 0) {
      o = Operand::r(Reg{reg_class_of(t), uint8_t((op[f.len - 1] & 7) | (rex & 1) << 3)});
    } else if (t == OT::Al || t == OT::Eax || t == OT::Rax) {
      o = Operand::r(Reg{reg_class_of(t), AX});
    } else if (t == OT::Cl) {
      o = Operand::r(r8(CX));
    } else if (t == OT::One) {
      o = Operand::i(1);
    } else if (t == OT::IB) {
      o = Operand::i(rd.u8());
    } else if (t == OT::I8) {
      int64_t v = int8_t(rd.u8());
      o = Operand::i(f.w ? v : int64_t(uint32_t(int32_t(v))));
    } else if (t == OT::I32) {
      int64_t v = int32_t(rd.u32());
      o = Operand::i(f.w ? v : int64_t(uint32_t(v)));
    } else if (t == OT::I64) {
      uint64_t low = rd.u32();
      o = Operand::i(int64_t(low | uint64_t(rd.u32()) << 32));
    } else if (t == OT::Rel8) {
      int64_t d = int8_t(rd.u8());
      o = Operand::a(int64_t(rd.pos) + d);
    } else if (t == OT::Rel32) {
      int64_t d = int32_t(rd.u32());
      int64_t target = int64_t(rd.pos) + d;
      o = Operand::a(target);
      // Record a long form the short one could have expressed.
      bool has_short = in.mnemonic == Mnemonic::Jmp || in.mnemonic == Mnemonic::Jcc;
      int64_t short_disp = target - (int64_t(start) + 2);
      in.long_branch = has_short && short_disp >= -128 && short_disp <= 127;
    }
  }
  if (!rd.ok) return truncated = true, false;
  end = rd.pos;
  return true;
}

}  // namespace

std::optional<Decoded> decode(std::span<const uint8_t> code, size_t offset, DecodeError* error) {
  auto fail = [&](std::string msg) -> std::optional<Decoded> {
    if (error) *error = DecodeError{uint32_t(offset), std::move(msg)};
    return std::nullopt;
  };
  if (offset >= code.size()) return fail("offset past the end of the code");
  Reader rd{code, offset};
  uint8_t prefix = 0, rex = 0;
  uint8_t b = rd.u8();
  if (b == 0x66 || b == 0xF3 || b == 0xF2) prefix = b, b = rd.u8();
  if ((b & 0xF0) == 0x40) rex = b, b = rd.u8();
  uint8_t op[2] = {b, 0};
  unsigned len = 1;
  if (b == 0x0F) op[1] = rd.u8(), len = 2;
  if (!rd.ok) return fail("truncated instruction");
  bool saw_opcode = false, truncated = false;
  for (const Form* fp : decode_candidates(prefix, op, len)) {
    const Form& f = *fp;
    if (bool((rex >> 3) & 1) != f.w) continue;
    saw_opcode = true;
    Instruction in;
    size_t end = 0;
    if (!decode_with(f, rd, offset, rex, op, in, end, truncated)) continue;
    // Accept exactly what the encoder produces for this instruction.
    try {
      Encoding again = encode_at_fixed(in, offset);
      if (again.size != end - offset || !std::equal(again.bytes.begin(), again.bytes.begin() + again.size, code.begin() + long(offset)))
        continue;
    } catch (const AsmError&) {
      continue;
    }
    return Decoded{std::move(in), uint32_t(offset), uint32_t(end - offset), f.effects};
  }
  if (truncated) return fail("truncated instruction");
  return fail(saw_opcode ? "invalid or non-canonical encoding"
                        : "unknown opcode (not in the ldc x86-64 subset)");
}

Disassembly disassemble(std::span<const uint8_t> code) {
  Disassembly d;
  size_t pos = 0;
  while (pos < code.size()) {
    DecodeError err;
    auto r = decode(code, pos, &err);
    if (!r) {
      d.error = err;
      break;
    }
    pos += r->length;
    d.insts.push_back(std::move(*r));
  }
  return d;
}

}  // namespace ldc::as::x86
