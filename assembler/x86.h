// ldc assembler: the x86-64 target.
//
// Instruction model, encoder, one-line parser, printer and disassembler for
// the subset of x86-64 the ldc code generator uses. Text is Intel syntax as
// GNU as accepts it under `.intel_syntax noprefix`. See docs/assembler.md.
#pragma once

#include "assembler/assembler.h"

#include <optional>

namespace ldc::as::x86 {

enum class RegClass : uint8_t { None, Gp8, Gp32, Gp64, Xmm, Rip };

// Gp8 numbers 0-15 are al cl dl bl spl bpl sil dil r8b..r15b
// (ah ch dh bh are not in the subset).
struct Reg {
  RegClass cls = RegClass::None;
  uint8_t num = 0;
  bool valid() const { return cls != RegClass::None; }
  friend bool operator==(const Reg&, const Reg&) = default;
};
constexpr Reg r8(unsigned n) { return {RegClass::Gp8, uint8_t(n)}; }
constexpr Reg r32(unsigned n) { return {RegClass::Gp32, uint8_t(n)}; }
constexpr Reg r64(unsigned n) { return {RegClass::Gp64, uint8_t(n)}; }
constexpr Reg xmm(unsigned n) { return {RegClass::Xmm, uint8_t(n)}; }
constexpr Reg rip() { return {RegClass::Rip, 0}; }
enum RegNum : uint8_t { AX, CX, DX, BX, SP, BP, SI, DI, R8, R9, R10, R11, R12, R13, R14, R15 };

enum class Size : uint8_t { None, Byte, Dword, Qword, Word };  // Word: movzx / movsx of a 16-bit value

// [base + index*scale + disp]; base may be a Gp64 register, rip or absent,
// index a Gp64 register other than rsp or absent.
struct Mem {
  Size size = Size::None;
  Reg base;
  Reg index;
  uint8_t scale = 1;
  int32_t disp = 0;
  friend bool operator==(const Mem&, const Mem&) = default;
};

enum class OperandKind : uint8_t { None, Reg, Mem, Imm, Label, Address };

// Label: a named label. Address: an absolute branch target (offset from the
// code start), as the disassembler produces and the parser reads for a
// numeric branch operand.
struct Operand {
  OperandKind kind = OperandKind::None;
  Reg reg;
  Mem mem;
  Name label;         // Label name (interned)
  int64_t imm = 0;    // Imm value, or the Address target
  friend bool operator==(const Operand&, const Operand&) = default;

  static Operand r(Reg x) { Operand o; o.kind = OperandKind::Reg; o.reg = x; return o; }
  static Operand m(Mem x) { Operand o; o.kind = OperandKind::Mem; o.mem = x; return o; }
  static Operand i(int64_t v) { Operand o; o.kind = OperandKind::Imm; o.imm = v; return o; }
  static Operand l(Name n) { Operand o; o.kind = OperandKind::Label; o.label = n; return o; }
  static Operand a(int64_t t) { Operand o; o.kind = OperandKind::Address; o.imm = t; return o; }
};

enum class Mnemonic : uint8_t {
  Mov, Movzx, Movsx, Lea,
  Add, Or, And, Sub, Xor, Cmp, Test,
  Shl, Shr, Sar, Not, Neg, Imul, Cdq, Idiv,
  Setcc, Cmovcc, Jcc, Jmp, Call, Ret, Push, Pop, Nop,
  Movss, Movd, Cvtsi2ss, Cvttss2si,
  Addss, Subss, Mulss, Divss, Sqrtss, Minss, Maxss, Ucomiss, Andps, Xorps,
  // the typed instructions (docs/x86.md, "Typed instructions"): 64-bit
  // integers, binary64, the conversions, unsigned division, rotations
  Movsd, Addsd, Subsd, Mulsd, Divsd, Sqrtsd, Minsd, Maxsd, Ucomisd,
  Cvtss2sd, Cvtsd2ss, Cvtsi2sd, Cvttsd2si, Cvtsd2si, Movq,
  Cwde, Cdqe, Cqo, Div, Rol, Ror, Movsxd,
  Count_
};

// Condition codes in encoding order (the low nibble of Jcc/SETcc/CMOVcc).
enum class Cond : uint8_t { O, NO, B, AE, E, NE, BE, A, S, NS, P, NP, L, GE, LE, G };

struct Instruction {
  Mnemonic mnemonic = Mnemonic::Nop;
  Cond cond = Cond::O;  // for Setcc, Cmovcc, Jcc
  uint8_t num_operands = 0;
  // Always use the rel32 form of jmp/jcc (printed as `{disp32}`).
  bool long_branch = false;
  std::array<Operand, 3> ops{};
  friend bool operator==(const Instruction&, const Instruction&) = default;
};

Instruction make(Mnemonic m, std::initializer_list<Operand> ops = {});
Instruction make_cc(Mnemonic m, Cond c, std::initializer_list<Operand> ops = {});

// What an instruction form reads and writes: a column of the form table
// (assembler/x86.cpp), one row per form, so an instruction's effects are its
// form's, never guessed from its mnemonic (docs/x86.md, "What each form reads
// and writes").  The loader's code check takes every register an instruction
// writes from here.
enum class Use : uint8_t {
  None,  // no such operand
  R,     // read (an immediate, a source, a compared operand, a divisor)
  W,     // written, whatever it held: a 32-bit register write clears bits 63..32;
         // an 8-bit register or an xmm scalar write keeps the rest of the register
  RW,    // read, then written (add, cmov: written even when the condition is false)
  Addr,  // not accessed: lea's memory operand (an address computed), a branch target
};
// How an instruction moves rsp and touches the stack ([rsp]).
enum class StackUse : uint8_t {
  None,
  Push,  // rsp -= 8, then writes [rsp]
  Pop,   // reads [rsp], then rsp += 8
  Call,  // pushes the return address; the callee runs and returns: what it writes, the caller does not know here
  Ret,   // pops the return address into rip
};
struct Effects {
  std::array<Use, 3> ops{};  // explicit operands; a memory operand's Use is the memory's
  uint16_t reads = 0;        // general registers read implicitly, bit RegNum (cdq: eax)
  uint16_t writes = 0;       // general registers written implicitly (cdq: edx), in their 32-bit width or more
  bool reads_flags = false;
  bool writes_flags = false;  // may write: a shift by 0 leaves them
  StackUse stack = StackUse::None;
  friend constexpr bool operator==(const Effects&, const Effects&) = default;
};
constexpr uint16_t reg_bit(RegNum r) { return uint16_t(1u << r); }
constexpr bool writes_operand(Use u) { return u == Use::W || u == Use::RW; }
constexpr bool reads_operand(Use u) { return u == Use::R || u == Use::RW; }

// The effects of the form encode() takes for `inst`; throws AsmError if the
// instruction is not in the subset.
Effects effects(const Instruction& inst);

// Fixup kinds of the x86-64 target (indices into target().fixup_kinds).
enum FixupKindId : uint16_t { Rel8 = 0, Rel32 = 1 };

// The target description for the core.
const Target<Instruction>& target();

// Encodes one instruction: bytes plus fixups for label/address operands.
// Throws AsmError if the instruction is not in the subset.
Encoding encode(const Instruction& inst, bool long_form = false);

// Encodes one instruction placed at `address`, resolving Address operands
// (short form if it reaches, as GNU as does). Throws AsmError for Label
// operands or unencodable instructions.
std::vector<uint8_t> encode_at(const Instruction& inst, uint64_t address = 0);

// Parses one instruction line (Intel syntax; `#` or `;` starts a comment).
// Also reads objdump's spelling (`DWORD PTR`, `ds:0x10`, `+0x0`).
// Throws AsmError with a message naming the problem.
Instruction parse(std::string_view line);

// Prints in the syntax parse() and GNU as accept. force_long prints jmp/jcc
// with the `{disp32}` pseudo-prefix, as inst.long_branch does.
// address_base, if given, prints Address operands as `address_base+0x12`.
std::string print(const Instruction& inst, bool force_long = false,
                  std::string_view address_base = {});
std::string_view mnemonic_name(Mnemonic m, Cond c = Cond::O);
std::string_view reg_name(Reg r);

// ------------------------------------------------------------ disassembly

struct Decoded {
  Instruction inst;
  uint32_t offset = 0;
  uint32_t length = 0;
  Effects effects;  // its form's
};
struct DecodeError {
  uint32_t offset = 0;
  std::string message;
};

// Decodes the instruction at code[offset]. Branch targets become Address
// operands (absolute offsets from code[0]). Accepts exactly the encodings
// encode() produces; anything else is a DecodeError. Never reads past the
// end of `code`.
std::optional<Decoded> decode(std::span<const uint8_t> code, size_t offset,
                              DecodeError* error = nullptr);

struct Disassembly {
  std::vector<Decoded> insts;
  std::optional<DecodeError> error;  // set if decoding stopped early
};
Disassembly disassemble(std::span<const uint8_t> code);

// ------------------------------------------------------- the scan frame
// The frame of ldc's scan function `void scan(uint8_t* image)`: the prologue
// at its entry and the epilogue at scan_exit, the only pushes, pops and ret
// that generated code contains (docs/x86.md).  with_slots is the -O2 frame,
// which also saves r12-r15 for the bit-stack slots.  The backend emits these;
// the loader's validator accepts nothing else.
std::span<const Instruction> scan_prologue(bool with_slots);
std::span<const Instruction> scan_epilogue(bool with_slots);
// The register holding the memory image: rbx in the -O0/-O1 frame (ebp the
// bit stack), rbp in the -O2 frame, so that bl, which needs no REX prefix,
// can be the first bit-stack slot (ebx then also the bit stack of the rungs
// whose stack does not fit the slots).
constexpr RegNum image_reg(bool with_slots) { return with_slots ? BP : BX; }
// The -O2 frame's image register points kImageBias bytes into the memory
// image (`lea rbp, [rdi+0x40]`), so that [rbp+d8] reaches image offsets
// [-0x40, 0xbf]: the REAL function table below the image, the system words
// and bits, and X0..X111; the device at image offset a is [rbp + a - 0x40].
constexpr int32_t kImageBias = 0x40;
// The -O2 prologue of images made before the bias (`mov rbp, rdi`): their
// operands, leas and routines take image offsets.  The loader still accepts it.
std::span<const Instruction> scan_prologue_unbiased();
// The -O2 prologue of images made before bl became a slot: rbx the image,
// r12b r13b bpl the slots (`mov rbx, rdi; xor ebp, ebp`), its routines and
// leas based on rbx.  The loader still accepts it; ldc no longer makes it.
std::span<const Instruction> scan_prologue_rbx_slots();

// The -O2 frame's base registers (docs/x86.md, "Compact addressing"): right
// after the -O2 prologue, `lea rdi, [rbp+K0]; lea r15, [rbp+K1]; lea r14,
// [rbp+K2]` point them into the memory image, and the body may point them
// again (`lea reg, [rbp+K]`, the only write of a base register it contains),
// region by region, so that devices near K take [rdi+disp8] / [r15+disp8] /
// [r14+disp8] instead of [rbp+disp32].  Each call through the REAL function
// table (which may clobber the caller-saved rdi) is followed at once by the
// leas of the caller-saved base registers.  r15 and r14 are callee-saved (they
// were bit-stack slots before); the shared routines use none of the three.
// The loader's validator accepts any K in [128, size-135] and base-register
// operands with a disp8 only, so every access stays inside the image.
constexpr int kNumBases = 3;
// That range of K as image offsets: K-128 >= 0 and K+127+8 <= size.
constexpr int64_t kBaseKMin = 128, kBaseKTop = 135;
constexpr RegNum kBaseRegs[kNumBases] = {DI, R15, R14};
// System V: may a called function change the register?
constexpr bool caller_saved(RegNum r) { return !(r == BX || r == SP || r == BP || r >= R12); }
Instruction base_lea(RegNum reg, int32_t k, RegNum image = image_reg(true));  // lea reg, [image+k]

// The -O2 division's guard (docs/x86.md, "Branch-free division"): before
// `cdq; idiv ecx`, a divisor of 0 or -1 (ecx+1 unsigned <= 1) becomes 1, so
// the division cannot fault; the code then fixes the results with cmov.
// `lea edx, [rcx+1]; cmp edx, 1; mov edx, 1; cmovbe ecx, edx`.  The loader's
// code check accepts this guard or the `test/je, cmp/je` one before an idiv.
std::span<const Instruction> safe_divisor();

// ------------------------------------------------------ shared routines
// Timers and counters at -O2 call one routine per kind, placed after the
// epilogue (docs/x86.md, "Shared routines").  A routine is branch-free and
// ends with its one `ret`; it takes
//   edx  the timer or counter number; the routine's first instruction masks it
//        (`movzx edx, dl`), so whatever the caller passes, every access
//        [image + rdx*k + area] stays inside areas of 256 elements (the
//        routines run in the -O2 frame: image is rbp, rbx in its old form)
//   ecx  the preset (timers clamp a negative one to 0)
//   esi  the input: the rung's power, 0 or 1
//   r8d  counters: the number of the edge slot that keeps the input for the
//        rising edge; one outside the image's e_count counts as slot 0, so
//        [image + r8 + e] stays inside the edge area (in the older -O2 frame
//        the call site computed the edge and passed it in esi)
// and clobbers eax ecx edx r8-r11 and the flags.  The areas' offsets are the
// memory layout's; the loader builds the same bodies and accepts a call only
// to the entry of one of them.
enum class Routine : uint8_t { Ton, Tof, Tp, Ctu, Ctd, Count };
struct RoutineAreas {
  int32_t tw = 0, tq = 0, ti = 0, cw = 0, cq = 0, dt = 0;  // offsets of T0's ET, Q, IN memory; C0's CV, Q; dt
  int32_t e = 0, e_count = 0;                              // the edge slots: offset and count (at least 1)
};
// bias: the frame's (kImageBias in ldc's -O2 frame, 0 in the older ones)
std::vector<Instruction> scan_routine(Routine r, const RoutineAreas& areas, RegNum image = image_reg(true),
                                      int32_t bias = kImageBias);
std::string_view routine_name(Routine r);  // the assembly label: rt_ton, rt_tof, rt_tp, rt_ctu, rt_ctd

// ---------------------------------------------------------- whole programs

using X86Program = Program<Instruction>;

// GNU as source for a program (`.intel_syntax noprefix`): local labels are
// renamed `.L<block>_<name>`, jumps to global labels and addresses get
// `{disp32}` so as picks the same rel32 forms as the core.
std::string to_gnu_as(const X86Program& program);

// A listing: offset, bytes, text and comment of every item.
std::string listing(const X86Program& program, const Result& result);

}  // namespace ldc::as::x86

