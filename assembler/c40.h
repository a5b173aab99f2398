// ldc assembler: the TMS320C40 target.
//
// Instruction model, encoder, one-line parser, printer and disassembler for
// the subset of the TMS320C4x instruction set that the ldc code generator and
// a small interpreter need. Text is TI syntax as GNU as accepts it for tic4x
// with -mcpu=40. Every instruction is one 32-bit word; memory is word
// addressed. The core counts bytes: a word is 4 bytes of code (little-endian)
// and every fixup kind has scale 4. See docs/c40.md.
#pragma once

#include <optional>

#include "assembler/assembler.h"

namespace ldc::as::c40 {

// Register numbers as the hardware encodes them in register fields.
enum class Reg : uint8_t {
  R0, R1, R2, R3, R4, R5, R6, R7,
  AR0, AR1, AR2, AR3, AR4, AR5, AR6, AR7,
  DP, IR0, IR1, BK, SP, ST, DIE, IIE, IIF, RS, RE, RC,
  R8, R9, R10, R11,
};
constexpr unsigned kNumRegs = 32;
// R0-R11: the 40-bit extended-precision registers.
constexpr bool is_extended(Reg r) { return unsigned(r) <= 7 || (unsigned(r) >= 28 && unsigned(r) <= 31); }
constexpr bool is_aux(Reg r) { return unsigned(r) >= 8 && unsigned(r) <= 15; }
constexpr Reg ar(unsigned n) { return Reg(8 + n); }
// R0..R11 by index (R8..R11 are numbers 28..31).
constexpr Reg rx(unsigned n) { return n < 8 ? Reg(n) : Reg(28 + n - 8); }

// Condition codes (the 5-bit cond field). 11 is not a condition.
enum class Cond : uint8_t {
  U = 0, LO = 1, LS = 2, HI = 3, HS = 4, EQ = 5, NE = 6, LT = 7, LE = 8, GT = 9, GE = 10,
  NV = 12, V = 13, NUF = 14, UF = 15, NLV = 16, LV = 17, NLUF = 18, LUF = 19, ZUF = 20,
};
bool valid_cond(unsigned c);

// Indirect addressing: the 5-bit modification field `mod` (0x00-0x19) and
// the auxiliary register. Modes 0-7 use the displacement `disp`; 8-15 use
// IR0, 16-23 IR1; 0x18 is *ARn; 0x19 is *ARn++(IR0)B. A displacement of 0
// is always written as mode 0x18 (*ARn), as GNU as does.
enum IndMod : uint8_t {
  kPreAdd = 0, kPreSub = 1, kPreAddMod = 2, kPreSubMod = 3,
  kPostAdd = 4, kPostSub = 5, kPostAddCirc = 6, kPostSubCirc = 7,
  kIr0 = 8,   // + one of the eight above
  kIr1 = 16,  // + one of the eight above
  kPlain = 0x18, kBitRev = 0x19,
};
struct Ind {
  uint8_t mod = kPlain;
  uint8_t ar = 0;    // 0-7
  uint8_t disp = 0;  // 1-255 for modes 0-7, else 0
  friend bool operator==(const Ind&, const Ind&) = default;
};

enum class OperandKind : uint8_t {
  None,
  Reg,
  Imm,      // integer immediate (value as written, signed or unsigned per form)
  Float,    // 16-bit short floating-point immediate; imm = the raw 16 bits
  Direct,   // @offset: DP:offset; imm = offset 0-0xFFFF
  Ind,      // *... indirect
  Label,    // branch target or .word value
  Address,  // absolute branch target, in words from the code start
};

struct Operand {
  OperandKind kind = OperandKind::None;
  Reg reg = Reg::R0;
  int64_t imm = 0;
  Ind ind;
  std::string label;
  friend bool operator==(const Operand&, const Operand&) = default;

  static Operand r(Reg x) { Operand o; o.kind = OperandKind::Reg; o.reg = x; return o; }
  static Operand i(int64_t v) { Operand o; o.kind = OperandKind::Imm; o.imm = v; return o; }
  static Operand f(uint16_t bits) { Operand o; o.kind = OperandKind::Float; o.imm = bits; return o; }
  static Operand d(uint16_t off) { Operand o; o.kind = OperandKind::Direct; o.imm = off; return o; }
  static Operand m(Ind x) { Operand o; o.kind = OperandKind::Ind; o.ind = x; return o; }
  static Operand l(std::string n) { Operand o; o.kind = OperandKind::Label; o.label = std::move(n); return o; }
  static Operand a(int64_t t) { Operand o; o.kind = OperandKind::Address; o.imm = t; return o; }
};

enum class Mnemonic : uint8_t {
  // general 2-operand integer: src, dst
  Absi, Addi, And, Andn, Ash, Cmpi, Ldi, Lsh, Mpyi, Negi, Not, Or, Subi, Tstb, Xor,
  // floating point: src, dst
  Absf, Addf, Cmpf, Ldf, Mpyf, Negf, Subf, Fix, Float, Rcpf, Toieee, Frieee,
  // conditional loads (cond in Instruction::cond; LDIU = Ldic with Cond::U)
  Ldic, Ldfc,
  // stores: src, dst
  Sti, Stf,
  // address and immediate loads
  Lda, Ldhi, Ldpk,
  // 3-operand: src2, src1, dst (compare/test forms: src2, src1)
  Addi3, And3, Andn3, Ash3, Cmpi3, Lsh3, Mpyi3, Or3, Subi3, Tstb3, Xor3,
  Addf3, Cmpf3, Mpyf3, Subf3,
  // control flow
  Br, Brd, Call,  // 24-bit PC-relative
  Bc, Bcd,        // Bcond / BcondD: 16-bit PC-relative or register
  Callc,          // CALLcond: 16-bit PC-relative or register
  Retsc,          // RETScond
  Dbc, Dbcd,      // DBcond / DBcondD ARn, target
  // stack and misc
  Push, Pop, Pushf, Popf, Nop,
  Word,  // .word: a data word (an integer or a label's word address)
  Count_
};

struct Instruction {
  Mnemonic mnemonic = Mnemonic::Nop;
  Cond cond = Cond::U;  // for the conditional forms
  uint8_t num_operands = 0;
  std::array<Operand, 3> ops{};
  friend bool operator==(const Instruction&, const Instruction&) = default;
};

Instruction make(Mnemonic m, std::initializer_list<Operand> ops = {});
Instruction make_cc(Mnemonic m, Cond c, std::initializer_list<Operand> ops = {});
bool has_cond(Mnemonic m);
// True for instructions that change the flow of control (branches, calls,
// returns, DBcond).
bool is_control(Mnemonic m);
bool is_delayed(Mnemonic m);  // BRD, BcondD, DBcondD

// Fixup kinds of the C40 target (indices into target().fixup_kinds).
enum FixupKindId : uint16_t {
  Disp16 = 0,   // Bcond, CALLcond, DBcond: bits 0-15, target = addr + 1 + disp
  Disp16D = 1,  // BcondD, DBcondD: target = addr + 3 + disp
  Disp24 = 2,   // BR, CALL: bits 0-23, target = addr + 1 + disp
  Disp24D = 3,  // BRD: target = addr + 3 + disp
  Abs32 = 4,    // .word label: the label's word address (a relocation)
};

const Target<Instruction>& target();

// Encodes one instruction: 4 bytes (little-endian word) plus at most one
// fixup for a Label or Address operand. long_form is ignored (the C40 is
// fixed width). Throws AsmError for anything outside the subset.
Encoding encode(const Instruction& inst, bool long_form = false);

// The final word of an instruction placed at word address `address`,
// resolving Address operands. Throws AsmError for Label operands, for
// unencodable instructions and for displacements out of range.
uint32_t encode_at(const Instruction& inst, int64_t address = 0);

// Parses one instruction (TI syntax; `;` starts a comment). Mnemonics and
// registers are case-insensitive, labels are not. Throws AsmError.
Instruction parse(std::string_view line);

// One source line: an optional label (`name:`), an optional instruction and
// an optional comment. Throws AsmError.
struct Line {
  std::string label;
  std::optional<Instruction> inst;
  std::string comment;
};
Line parse_line(std::string_view line);

// Text that parse() and GNU as (tic4x, -mcpu=40) accept. address_base, if
// given, prints Address operands as `address_base+N`.
std::string print(const Instruction& inst, std::string_view address_base = {});
// The same for GNU as input (to_gnu_as): GNU as 2.40 reads some exact
// short-float decimals one unit in the last place low, so float immediates
// with a nonzero fraction are written a quarter unit larger in magnitude.
// parse() refuses that text (it is not exact); GNU as gives the same word.
std::string print_gnu_as(const Instruction& inst, std::string_view address_base = {});
std::string mnemonic_name(Mnemonic m, Cond c = Cond::U);
std::string_view reg_name(Reg r);
std::string_view cond_name(Cond c);
std::string ind_text(const Ind& ind);

// 16-bit short floating-point immediates (4-bit exponent, sign, 11-bit
// fraction; exponent -8 is zero). Returns nullopt if v is not exact.
std::optional<uint16_t> short_float_from_double(double v);
double short_float_to_double(uint16_t bits);

// ------------------------------------------------------------ disassembly

struct DecodeError {
  int64_t address = 0;  // word address
  std::string message;
};

// Decodes one word at word address `address`. PC-relative targets become
// Address operands (absolute word addresses). Accepts exactly the words
// encode() produces (e.g. `*+AR0(0)` and alternate 3-operand forms are
// refused); anything else is a DecodeError.
std::optional<Instruction> decode_word(uint32_t word, int64_t address = 0,
                                      DecodeError* error = nullptr);

struct Decoded {
  Instruction inst;
  int64_t address = 0;
  uint32_t word = 0;
};
struct Disassembly {
  std::vector<Decoded> insts;
  std::vector<DecodeError> errors;  // undecodable words (decoding goes on)
};
// Words from `base` on.
Disassembly disassemble(std::span<const uint32_t> words, int64_t base = 0);
// Little-endian bytes (as in Result::code); a trailing partial word is an
// error.
Disassembly disassemble_bytes(std::span<const uint8_t> code, int64_t base = 0);
std::vector<uint32_t> words_of(std::span<const uint8_t> code);

// ---------------------------------------------------------- whole programs

using C40Program = Program<Instruction>;

// GNU as source (tic4x, -mcpu=40) for a program: local labels are renamed
// `L<block>_<name>`, Address operands are printed relative to `Lcode`.
std::string to_gnu_as(const C40Program& program);

// A listing: word address, word, text and comment of every item.
std::string listing(const C40Program& program, const Result& result);

}  // namespace ldc::as::c40

