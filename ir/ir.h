// ir/ir.h -- the IL of ldc: devices and the memory image layout, the mnemonic
// list (ops.def), its text form, its compact binary form, and the reference
// interpreter that defines what every program means (docs/il.md).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ldc {

// ---------------------------------------------------------------- devices

// Storage areas of the memory image.  A device spelling maps to one area:
// T0 is TQ (done bit) where a bit is wanted and TW (elapsed ms) where a word is.
enum class Area : uint8_t {
  Sys,            // runtime header: dt (ms) of this scan, scan counter
  S,              // system bits: S0 arithmetic error (writable), S1 first scan
  X, Y, M, K,     // bit devices
  TQ, CQ,         // timer / counter done bits
  TI,             // timer input memory (IN at its last execution), hidden
  WX, WY, D,      // INT32 words
  F,              // REAL (IEEE-754 binary32)
  TW, CW,         // timer elapsed ms, counter current value (INT32)
  E,              // edge memory, one byte per edge instruction, hidden
  Count
};
constexpr int kAreaCount = static_cast<int>(Area::Count);

const char* area_name(Area a);         // "X", "TQ", ... (internal name)
// (inline: Layout::addr asks area_is_bit of every operand the code generators address)
constexpr bool area_is_bit(Area a) {   // one byte per element, value 0/1
  switch (a) {
    case Area::Sys: case Area::S: case Area::X: case Area::Y: case Area::M: case Area::K:
    case Area::TQ: case Area::CQ: case Area::TI: case Area::E:
      return true;
    default:
      return false;
  }
}
constexpr bool area_is_real(Area a) { return a == Area::F; }       // F
constexpr bool area_is_word(Area a) { return !area_is_bit(a); }    // 4 bytes per element

// A device as spelled in source: prefix and index ("WX3" -> {WX, 3}).  The area
// depends on use: T and C are a done bit where a bit is wanted, a word elsewhere.
enum class Dev : uint8_t { X, Y, M, K, S, T, C, WX, WY, D, F };
struct DeviceRef {
  Dev dev;
  uint32_t index;
  bool operator==(const DeviceRef&) const = default;
};
// Parses a plain device spelling (case-insensitive); nullopt if it is not one.
// The index is not range-checked (see device_count).
std::optional<DeviceRef> parse_device(std::string_view s);
// An IEC 61131-3 direct address: %IXa.b %QXa.b %MXa.b (bit b of byte a),
// %IWn %QWn %MWn (INT32 words) and %MDn (REAL), as docs/format.md maps them.
// nullopt if `s` is not one; `why` says what is wrong when it looks like one.
std::optional<DeviceRef> parse_iec_address(std::string_view s, std::string& why);
const char* dev_name(Dev d);
constexpr uint32_t device_count(Dev d);  // X: 8192, WX: 1024, T: 256 ...
constexpr Area bit_area(Dev d);          // X->X, T->TQ, C->CQ; Area::Count if not a bit
constexpr Area word_area(Dev d);         // WX->WX, T->TW, C->CW, F->F; Area::Count if not a word

// Byte offsets of every area in the memory image.  Bits take one byte (0/1),
// words four (little-endian INT32 or IEEE binary32).  The edge area is last so
// that the rest of the layout does not depend on the program.
struct Layout {
  uint32_t count[kAreaCount] = {};
  uint32_t offset[kAreaCount] = {};
  uint32_t size = 0;  // total bytes

  static Layout standard(uint32_t edge_slots);
  uint32_t elem_size(Area a) const { return area_is_bit(a) ? 1 : 4; }
  uint32_t addr(Area a, uint32_t index) const { return offset[int(a)] + index * elem_size(a); }
  bool operator==(const Layout&) const = default;
};

// Fixed addresses inside the Sys area.
constexpr uint32_t kSysDt = 0;      // INT32: ms elapsed before this scan
constexpr uint32_t kSysScan = 4;    // UINT32: scans completed
constexpr uint32_t kSysSize = 64;   // bytes 8..23: the fault record (kSysFault, below); 24..27 kSysLoops; 28..63 reserved (0)

// Native code calls the REAL functions that have no instruction (float f(float))
// through a table of 8-byte pointers that lies OUTSIDE the memory image, in the
// last 40 bytes of a read-only page right below it (ImageBytes): slot k is at
// image + kCallTableDisp + 8k, `call qword ptr [rbx-0x40]` for sin.  Generated
// code can write only inside the image, so it can never redirect these calls
// (docs/image-format.md, "Threat model").
// The REAL functions of the Special instructions (ops.def's fn column and FN table).
enum class RealFn : uint8_t {
#define FN(name, libm, called, ints) name,
#include "ops.def"
  None
};
struct RealFnInfo {
  const char* name;  // "Sin"
  const char* libm;  // "sinf": the C library function that defines it
  bool called;       // native code calls it through the table; its slot is int(RealFn)
  bool ints;         // an INT32 operand gives an INT32 result (ABS)
};
inline constexpr RealFnInfo kRealFns[] = {
#define FN(name, libm, called, ints) {#name, #libm, called != 0, ints != 0},
#include "ops.def"
};
constexpr const RealFnInfo& real_fn_info(RealFn f) { return kRealFns[int(f)]; }
// Slots of the call table: the called functions, which come first in the FN table.
constexpr int kCallSlots = [] {
  int n = 0;
  while (n < int(RealFn::None) && kRealFns[n].called) n++;
  return n;
}();
static_assert([] {
  for (int k = kCallSlots; k < int(RealFn::None); k++)
    if (kRealFns[k].called) return false;
  return true;
}(), "ops.def: the called REAL functions come first in the FN table");
constexpr int32_t kCallTableDisp = -64;
// The displacement from the image of f's slot in the call table (f must be called).
constexpr int32_t call_slot_disp(RealFn f) { return kCallTableDisp + 8 * int32_t(f); }
// f(x), as the C library computes it (inline, for interpreters).
inline float apply_real_fn(RealFn f, float x) {
  switch (f) {
#define FN(name, libm, called, ints) case RealFn::name: return ::libm(x);
#include "ops.def"
    case RealFn::None: break;
  }
  return x;
}
using RealFnPtr = float (*)(float);
RealFnPtr real_fn(RealFn f);  // the libm function: sinf cosf tanf expf logf sqrtf fabsf

// System bits.
constexpr uint32_t kBitError = 0;      // S0
constexpr uint32_t kBitFirstScan = 1;  // S1
constexpr uint32_t kSysBits = 16;

// (inline: the IL readers ask these of every device operand)
constexpr uint32_t device_count(Dev d) {
  switch (d) {
    case Dev::X: case Dev::Y: case Dev::M: case Dev::K: case Dev::D: return 8192;
    case Dev::S: return kSysBits;
    case Dev::T: case Dev::C: return 256;
    case Dev::WX: case Dev::WY: case Dev::F: return 1024;
  }
  return 0;
}
constexpr Area bit_area(Dev d) {
  switch (d) {
    case Dev::X: return Area::X;
    case Dev::Y: return Area::Y;
    case Dev::M: return Area::M;
    case Dev::K: return Area::K;
    case Dev::S: return Area::S;
    case Dev::T: return Area::TQ;
    case Dev::C: return Area::CQ;
    default: return Area::Count;
  }
}
constexpr Area word_area(Dev d) {
  switch (d) {
    case Dev::WX: return Area::WX;
    case Dev::WY: return Area::WY;
    case Dev::D: return Area::D;
    case Dev::F: return Area::F;
    case Dev::T: return Area::TW;
    case Dev::C: return Area::CW;
    default: return Area::Count;
  }
}

// ---------------------------------------------------------------- elementary types
// The IEC 61131-3 elementary types of the typed instructions (types.def).
enum class Ty : uint8_t {
#define TYPE(name, bits, kind, cells, c) name,
#include "types.def"
  None
};
constexpr int kTyCount = static_cast<int>(Ty::None);
enum class TyKind : uint8_t { Bool, Signed, Unsigned, Bits, Real, Time, Date, String };
struct TyInfo {
  const char* name;  // "INT"
  int bits;          // 16
  TyKind kind;
  int cells;         // words of a word area (0: BOOL, one bit device)
  const char* c;     // "int16_t"
};
inline constexpr TyInfo kTys[] = {
#define TYPE(name, bits, kind, cells, c) {#name, bits, TyKind::kind, cells, #c},
#include "types.def"
};
constexpr const TyInfo& ty_info(Ty t) { return kTys[int(t)]; }
// The letter of an op's types column for t's kind (ops.def).
constexpr char ty_letter(Ty t) {
  switch (ty_info(t).kind) {
    case TyKind::Bool: return 'B';
    case TyKind::Signed: case TyKind::Unsigned: return 'i';
    case TyKind::Bits: return 'b';
    case TyKind::Real: return 'f';
    case TyKind::Time: return 't';
    case TyKind::Date: return 'd';
    case TyKind::String: return 's';
  }
  return '?';
}
std::optional<Ty> ty_from_name(std::string_view name);  // case-insensitive; also the IEC long names (TIME_OF_DAY)

// ---------------------------------------------------------------- the IL

enum class Op : uint8_t {
#define OP(name, opds, push, pop, klass, rel, fn, typed, types) name,
#include "ops.def"
  Count
};
constexpr int kOpCount = static_cast<int>(Op::Count);

enum class OpClass : uint8_t { Basic, Compare, Move, Arith, Logic, Special, Timer, Counter, Flow, Typed };
constexpr int kOpClassCount = 10;

// The relation of a compare (ops.def's rel column and REL table).
enum class Rel : uint8_t {
#define REL(name, c, ld, negation, swapped) name,
#include "ops.def"
  None
};
struct RelInfo {
  const char* name;  // "Eq"
  const char* c;     // "==": the C operator
  const char* ld;    // "==", "<>": the ladder grid's spelling
  Rel negation;      // holds exactly when this one does not (INT32 operands)
  Rel swapped;       // the same with the operands exchanged
};
inline constexpr RelInfo kRels[] = {
#define REL(name, c, ld, negation, swapped) {#name, c, ld, Rel::negation, Rel::swapped},
#include "ops.def"
};
constexpr const RelInfo& rel_info(Rel r) { return kRels[int(r)]; }
constexpr Rel negate(Rel r) { return rel_info(r).negation; }
constexpr Rel swap_operands(Rel r) { return rel_info(r).swapped; }
// Does `x r y` hold?  (IEEE for floats: with a NaN only Ne holds.)
template <class T>
constexpr bool rel_holds(Rel r, T x, T y) {
  switch (r) {
    case Rel::Eq: return x == y;
    case Rel::Ne: return x != y;
    case Rel::Lt: return x < y;
    case Rel::Le: return x <= y;
    case Rel::Gt: return x > y;
    case Rel::Ge: return x >= y;
    case Rel::None: break;
  }
  return false;
}

struct OpInfo {
  const char* name;
  const char* operands;  // signature letters, see ops.def
  int push, pop;
  OpClass klass;
  Rel rel;               // Compare: its relation; else None
  RealFn fn;             // Special: its REAL function; else None
  int nopd;              // the number of operands: strlen(operands)
  int typed;             // 0 untyped, 1 a type T (ADD.INT), 2 and a source type U
  const char* types;     // the kinds T may have ("ift"), after '|' those of U
};
constexpr int count_operands(const char* s) { return *s ? 1 + count_operands(s + 1) : 0; }
inline constexpr OpInfo kOps[kOpCount] = {
#define OP(name, opds, push, pop, klass, rel, fn, typed, types) {#name, opds, push, pop, OpClass::klass, Rel::rel, RealFn::fn, count_operands(opds), typed, types},
#include "ops.def"
};
constexpr const OpInfo& op_info(Op op) { return kOps[int(op)]; }
// The compare instruction of a relation (LDEQ for Eq).
Op compare_op(Rel r);
std::optional<Op> op_from_name(std::string_view name);  // case-insensitive
// ---- typed instructions (ops.def class Typed, ir/typed.h, ir/typed.cpp)
// The op of a typed instruction's spelling ("ADD" -> TADD); nullopt if none.
std::optional<Op> typed_op_from_name(std::string_view spelling);
// Does op take type t and source type u (ops.def's typed and types columns)?
bool op_takes(Op op, Ty t, Ty u);
struct Instr;
std::string op_spelling(const Instr& in);  // "ADD.INT", "CONV.DINT.REAL", "LOAD"
Ty operand_type(const Instr& in, int i);   // the type of a typed instruction's operand i; None if untyped
struct Layout;
// May a device of area a, index idx, be typed operand `sig` (s x r a) of type t?
// (A 64-bit type takes two words: idx + 1 must be in the area too.)
bool typed_area_ok(char sig, Ty t, Area a, uint32_t idx, const Layout& L);
std::string typed_const_text(Ty t, uint64_t v);  // "-5", "1.5", "1.0000000000000001e-09"
// The canonical bits (typed.h) of constant s of type t; nullopt and `why` if
// it is not one or does not fit.
std::optional<uint64_t> parse_typed_const(Ty t, std::string_view s, std::string& why);
const char* op_class_name(OpClass c);
// May a device of area `a`, index `idx`, stand for signature letter `sig`?
constexpr bool operand_area_ok(char sig, Area a, uint32_t idx) {
  switch (sig) {
    case 'b': return a == Area::S || a == Area::X || a == Area::Y || a == Area::M || a == Area::K || a == Area::TQ || a == Area::CQ;
    case 'w': return a == Area::Y || a == Area::M || a == Area::K || (a == Area::S && idx == kBitError);
    case 'v': return a == Area::WX || a == Area::WY || a == Area::D || a == Area::F || a == Area::TW || a == Area::CW;
    case 'i': return a == Area::WX || a == Area::WY || a == Area::D || a == Area::TW || a == Area::CW;
    case 'd': return a == Area::WY || a == Area::D || a == Area::F || a == Area::TW || a == Area::CW;
    case 't': return a == Area::TW;
    case 'c': return a == Area::CW;
  }
  return false;
}

// ConstT: a typed instruction's constant, of the instruction's type (or its
// source type for an `x` operand): its 64 bits are ival (low) and index (high).
enum class OpdKind : uint8_t { None, Bit, Int, Real, ConstInt, ConstReal, Edge, Timer, Counter, Label, ConstT };

// A label operand's name (only JMP has one): an interned 4-byte id, equal ids
// for equal text, so that an Operand is 20 bytes and not 24 or 48 (an IL
// instruction holds three).  The text lives in a process-wide table (never
// freed, safe to intern from several threads), so str() stays valid for the
// life of the process.  Id 0 is the empty name.
class LabelText {
 public:
  LabelText() = default;  // trivial (an Operand keeps it in a union): LabelText{} is the empty name
  LabelText(const std::string& s) : id_(s.empty() ? 0 : intern(s)) {}  // NOLINT: implicit on purpose
  LabelText(const char* s) : LabelText(std::string(s)) {}              // NOLINT
  const std::string& str() const;
  operator const std::string&() const { return str(); }  // NOLINT
  bool empty() const { return id_ == 0; }
  friend bool operator==(LabelText a, LabelText b) { return a.id_ == b.id_; }

 private:
  static uint32_t intern(const std::string& s);
  uint32_t id_;
};

// The value of a constant and a label's name share their 4 bytes: an operand
// has at most one of them (by its kind), and one not set reads as 0 / empty.
struct Operand {
  OpdKind kind = OpdKind::None;
  Area area = Area::Sys;  // Bit / Int / Real
  uint32_t index = 0;     // device index, edge slot, timer/counter number, label target
  union {
    int32_t ival = 0;     // ConstInt
    float fval;           // ConstReal
    LabelText label;      // Label name
  };

  bool is_real() const { return kind == OpdKind::Real || kind == OpdKind::ConstReal; }
  // A ConstT's 64 bits (typed.h: the canonical value of its type).
  uint64_t bits() const { return (uint64_t(index) << 32) | uint32_t(ival); }
  static Operand typed_const(uint64_t v) {
    Operand o;
    o.kind = OpdKind::ConstT;
    o.index = uint32_t(v >> 32);
    o.ival = int32_t(uint32_t(v));
    return o;
  }
  // Kind, area, index, and the value the kind has (REAL constants as floats).
  bool operator==(const Operand& o) const {
    if (kind != o.kind || area != o.area || index != o.index) return false;
    if (kind == OpdKind::ConstReal) return fval == o.fval;
    if (kind == OpdKind::Label) return label == o.label;
    return ival == o.ival;
  }
};
static_assert(sizeof(Operand) == 12, "an IL instruction holds three: keep it small (docs/architecture.md)");

// Fixed addresses inside the Sys area for a fault that ends a scan (an
// array index out of its bounds, docs/il.md "Index faults"): every engine
// writes the same record and ends the scan there; the runtime then stops the
// PLC with outputs off.
constexpr uint32_t kSysFault = 8;        // UINT32: 0 none, 1 index out of range, 2 loop budget spent
constexpr uint32_t kSysFaultAt = 12;     // UINT32: the IL byte offset of the IDX (LOOP) instruction
constexpr uint32_t kSysFaultValue = 16;  // INT64: the index (the budget)
enum : uint32_t { kFaultNone = 0, kFaultIndex = 1, kFaultLoop = 2 };
// Writes the fault record (kind, the faulting instruction's IL offset, its
// value) that ends a scan; the interpreters' one writer of it.
void write_scan_fault(uint8_t* mem, uint32_t kind, uint32_t il_offset, uint64_t value);
// The loops of a scan (LOOP, docs/il.md "Loops"): every engine sets the
// counter to 0 as a scan of a program with a LOOP starts, and each LOOP that
// jumps back adds 1; the one that would make it kLoopBudget ends the scan with
// the fault kFaultLoop instead, so a scan takes at most kLoopBudget - 1 back
// edges, whatever the program.
constexpr uint32_t kSysLoops = 24;       // UINT32: back edges taken in this scan
constexpr uint32_t kLoopBudget = 100000;

struct SrcLoc {
  int line = 0, col = 0;
  bool operator==(const SrcLoc&) const = default;
};

// An error in a source file at line:col (1-based); the driver prints it with the
// source line and a caret.
struct CompileError : std::runtime_error {
  int line, col;
  CompileError(int l, int c, const std::string& m) : std::runtime_error(m), line(l), col(c) {}
};
using IlError = CompileError;

struct Instr {
  Op op{};
  Ty ty = Ty::None;   // a typed instruction's type T (ADD.INT)
  Ty src = Ty::None;  // and its source type U (CONV.DINT.REAL), where it has one
  Operand a[3];
  SrcLoc loc;  // the element (or rung) this instruction came from
  int nopd() const { return kOps[int(op)].nopd; }
  bool operator==(const Instr& o) const;  // op and operands; loc ignored
};

struct Rung {
  std::vector<std::string> labels;  // `label NAME` lines directly before this rung
  std::string title;                // `rung "text"`
  int line = 0;                     // first source line of the rung
  std::vector<Instr> code;
};

// `alias NAME = DEVICE`: kept so traces, --watch and listings can use the names.
// A typed front end also says the variable's type, so that a watch shows the
// value at its width (a LINT's two cells, a UDINT unsigned, an LREAL).
struct Alias {
  std::string name;
  DeviceRef dev;
  Ty ty = Ty::None;
  bool operator==(const Alias&) const = default;
};
// Why a typed alias cannot name its device ("" if it can): a BOOL names a bit
// device (T and C their done bit), every other type the first of its cells in
// a word device (T and C their word), all of them inside the device's range.
std::string alias_type_problem(const Alias& a);

// A variable's whole place, for an online download that carries it by name
// (the image's `vars` section, docs/image-format.md): its BOOL parts in a row
// of bits and its other parts in a row of word cells (model.h, Size), either
// row possibly empty, and a text that changes when its layout does.  A typed
// front end lists its program's unlocated variables and its hidden state.
struct VarPlace {
  std::string name;   // "tank", "p1", "__rtc_clock"
  std::string type;   // "INT", "Tank#3f2a9c0e11d4b726" (a composite's name and the hash of its layout)
  Area bits = Area::Count;   // M (K); Count: no bits
  uint32_t bit_first = 0, bit_count = 0;
  Area cells = Area::Count;  // D or F; Count: no cells
  uint32_t cell_first = 0, cell_count = 0;
  bool operator==(const VarPlace&) const = default;
};

struct Program {
  std::string source;                   // file name, for messages
  std::vector<Alias> aliases;
  std::vector<VarPlace> vars;           // a typed program's variables as wholes (VarPlace)
  std::vector<Rung> rungs;
  std::vector<std::string> end_labels;  // labels after the last rung
  uint32_t edge_slots = 0;
  std::vector<DeviceRef> retain;        // D words kept across restarts (.retain, docs/il.md)
  Layout layout() const { return Layout::standard(edge_slots); }
};
// Does the program have a LOOP (a backward jump, docs/il.md "Loops")?
bool has_loop(const Program& p);
// q's rungs moved after p's, q's edge slots numbered after p's (a program
// lowered in pieces: a PLCopen program and its chart, ldbench's large plant).
void append_rungs(Program& p, Program& q);

// ---------------------------------------------------------------- the rung tree
// The series/parallel tree of one rung (paper 003, Fig. 5), built by a front end
// and lowered to IL by lower_to_il().  Conditions (Bool) and actions:
//   Leaf      an input element: elem.op is its push form (LOAD, LOADN, LOADP,
//             LOADF, LDEQ..LDGE); LOADP/LOADF/CTU/CTD get their edge slot when lowered
//   Series    AND of kids, left to right        Parallel  OR of kids, top to bottom
//   Output    an output element (OUT, SET, TON, MOV, JMP, ...)
//   Then      kids[0] (Bool) gates kids[1] (an action)
//   Fork      actions sharing the power flow that reaches them, top to bottom
struct TreeNode {
  enum class Kind : uint8_t { Leaf, Series, Parallel, Output, Then, Fork } kind = Kind::Leaf;
  Instr elem;  // Leaf / Output
  std::string text;  // the element as written, for --emit=tree
  std::vector<TreeNode> kids;
};
struct TreeRung {
  std::vector<std::string> labels;
  std::string title;
  int line = 0;
  TreeNode root;  // an action
  // Or, when not empty, the rung as IL already (a POU body another reader
  // compiled: the PLCopen reader's ST and IL POUs): lowered as it is, its edge
  // slots numbered from the program's next one.
  std::vector<Instr> raw;
};
struct TreeProgram {
  std::string source;
  std::vector<Alias> aliases;
  std::vector<VarPlace> vars;  // as Program::vars
  std::vector<TreeRung> rungs;
  std::vector<std::string> end_labels;
  std::vector<DeviceRef> retain;  // D words kept across restarts
};
std::string print_tree(const TreeProgram& p);
// Tree -> IL.  Throws CompileError if a rung needs more than 32 bit-stack entries.
Program lower_to_il(const TreeProgram& p);
// One rung of it, appended to p: its edge slots follow p.edge_slots, which it
// advances.  A front end that lowers each rung as it reads it (and then frees
// the tree) builds the same Program as lower_to_il.
void lower_rung(const TreeRung& r, Program& p);
constexpr int kMaxStackDepth = 32;

// Can a code generator keep this rung's bit stack in `slots` registers, stack
// position p (0 = the rung's first push) in register p % slots?  True when
// the rung reads no entry below its own first push, never holds more than
// kMaxStackDepth entries (the shift register would lose the deepest), and at
// every point between instructions the positions read again before they are
// written lie within one window of `slots` (what lies deeper is never read
// again).  Such a rung does not depend on the stack the rungs before it left.
bool stack_fits_slots(const std::vector<Instr>& code, int slots);

// The stack positions one instruction writes and reads, at depth d before it
// (position 0 is the rung's first push): a push writes d; AND..ORN read and
// write d-1; ANDBLK/ORBLK read d-1 and d-2 and write d-2; MPS reads d-1 and
// writes d; MRD reads d-2 and writes d-1; MPP nothing; every other
// instruction (outputs, applications, timers, counters, JMP, END) reads the
// top, d-1.
struct StackUse {
  bool writes = false;
  int write = 0;
  int nreads = 0;
  int reads[2] = {};
};
inline StackUse stack_use(Op op, int d) {
  StackUse u;
  switch (op) {
    case Op::AND: case Op::ANDN: case Op::OR: case Op::ORN:
      u.writes = true, u.write = d - 1, u.nreads = 1, u.reads[0] = d - 1;
      return u;
    case Op::ANDBLK: case Op::ORBLK:
      u.writes = true, u.write = d - 2, u.nreads = 2, u.reads[0] = d - 1, u.reads[1] = d - 2;
      return u;
    case Op::MPS: u.writes = true, u.write = d, u.nreads = 1, u.reads[0] = d - 1; return u;
    case Op::MRD: u.writes = true, u.write = d - 1, u.nreads = 1, u.reads[0] = d - 2; return u;
    case Op::MPP: return u;
    default: break;
  }
  if (op_info(op).push == 1) u.writes = true, u.write = d;  // contacts, edges, TRUE, compares
  else u.nreads = 1, u.reads[0] = d - 1;                    // outputs, applications, timers, counters, JMP, END
  return u;
}
// The first instruction of a rung that reads or pops a stack entry the rung
// did not push itself, or -1.  IL text may do that (a rung reading what the
// rung before it left); the optimizing code generators keep a rung's stack
// to the rung only in programs where no rung does.
int foreign_stack_use(const std::vector<Instr>& code);
// Does any rung of p read or pop what an earlier rung left on the stack?
bool shares_stack(const Program& p);

// ---------------------------------------------------------------- SFC charts
// A sequential function chart (paper 001; docs/sfc.md) after the front end has
// resolved it: steps grouped into scopes (the main sequence and every branch of a
// simultaneous sequence; one step of a scope is active at a time), action bodies
// and transition conditions already as IL.  lower_chart() makes the Program every
// backend runs; backend-c prints the same chart as paper 001's switch (step) C.
// Memory: step i (n steps) has its active flag at M[flag_base + i], its run bit
// (active when its scope started this scan) at M[flag_base + n + i] and its entry
// bit (entered, first scan not yet run) at M[flag_base + 2n + i].
struct SfcBody {                       // rungs of a ladder or IL action, labels made unique
  std::vector<Rung> rungs;
  std::vector<std::string> end_labels;
};
struct SfcTransition {
  int line = 0;
  std::string text;                    // the condition as written (for comments)
  std::vector<Instr> cond;             // pushes one bit
  uint32_t target = 0;                 // step entered when it fires
};
struct SfcStep {
  std::string name;
  int line = 0;
  uint32_t scope = 0;
  bool parallel = false;               // a simultaneous sequence: runs `branches`, then its join
  std::vector<uint32_t> branches;      // scopes of a simultaneous sequence
  int32_t timer = -1;                  // Tn: elapsed time since the step's first scan
  std::vector<Instr> bits;             // SET/RST of S/R bit actions, run while active
  SfcBody on_entry, body;              // P and N bodies
  std::vector<SfcTransition> out;      // in priority order
};
struct SfcScope {
  std::vector<uint32_t> steps;         // in source order
  uint32_t first = 0, last = 0;        // entered first / waited on by the join
};
struct SfcNBit {                       // `N bit`: the bit is 1 while any of these steps is active
  Operand bit;
  std::vector<uint32_t> steps;
};
struct Chart {
  std::string source;
  std::vector<Alias> aliases;          // the file's aliases and one per step (its flag)
  uint32_t flag_base = 0;
  uint32_t initial = 0;
  uint32_t edge_slots = 0;
  std::vector<SfcStep> steps;
  std::vector<SfcScope> scopes;        // scopes[0] is the main sequence
  std::vector<SfcNBit> nbits;
  uint32_t flag(uint32_t i) const { return flag_base + i; }
  uint32_t run(uint32_t i) const { return flag_base + uint32_t(steps.size()) + i; }
  uint32_t entry(uint32_t i) const { return flag_base + 2 * uint32_t(steps.size()) + i; }
};
// Chart -> IL (docs/sfc.md, "one scan").
Program lower_chart(const Chart& c);

// Operand spelling in IL text: X3, T0, D5, F1, 42, 1.5, E7, name.
std::string operand_text(const Operand& o);  // a typed constant as its hex bits (it has no type of its own)
std::string operand_text(const Instr& in, int i);  // operand i, a typed constant in its type ("-5", "1.5")
std::string instr_text(const Instr& in);  // "LOAD X1", "ADD D0 5 D1"
std::string real_text(float f);           // %.9g, with ".0" added when needed

// ---- text form (--emit=il); parse_il_text(print_il_text(p)) == p
std::string print_il_text(const Program& p);

Program parse_il_text(std::string_view text, const std::string& filename);  // throws CompileError
// The same with error recovery: each line's error goes to `report` and the
// reader goes on with the next line (the instructions of a rung whose .rung
// line was refused are skipped; an undefined label is said once); the
// program is meaningful only when nothing was reported.
Program parse_il_text(std::string_view text, const std::string& filename, const std::function<void(const CompileError&)>& report);
// An alias's name: a name, or a member path INSTANCE.MEMBER, a[3], grid[1,-2].
bool is_alias_name(std::string_view s);

// ---- binary form (the image's IL section, run by the interpreter)
// Each instruction: op byte, then per operand a tag byte and its payload (docs/il.md).
struct BinaryIl {
  std::vector<uint8_t> code;
  std::vector<uint32_t> rung_offset;  // byte offset of each rung's first instruction
  std::vector<uint32_t> instr_offset; // byte offset of every instruction, in program order
};
BinaryIl encode_il(const Program& p);
// Checks every opcode, tag, index and jump target against the layout; "" if valid,
// else "offset N: reason".
std::string validate_il(std::span<const uint8_t> code, const Layout& layout);
// Decodes one instruction at `off` (code must be valid); returns the next offset.
uint32_t decode_instr(std::span<const uint8_t> code, uint32_t off, Instr& out);

// ---- the reference interpreter
// A classic PLC interpreter (paper 003, Fig. 3): fetch a mnemonic, dispatch to
// its routine through a table, decode each operand with one general routine.
class Interpreter {
 public:
  Interpreter(std::span<const uint8_t> code, const Layout& layout);  // code must be valid
  void scan(uint8_t* mem) const;  // one pass over the program
 private:
  std::span<const uint8_t> code_;
  Layout layout_;
  bool loops_ = false;  // a LOOP: each scan starts with the loop counter at 0
};

// ---- runtime helpers shared by every engine (the semantics of docs/il.md)
int32_t real_to_int(float f);  // truncate toward zero, saturate, NaN -> 0
float int_to_real(int32_t i);

// The bytes of a memory image, on pages of their own:
//   guard page (no access) | table page (read-only; the REAL function table in
//   its last bytes, at image + kCallTableDisp) | the image (read-write, from a
//   page boundary, rounded up to whole pages, the slack after it filled with
//   kSlackByte) | guard page (no access)
// Every engine runs on this storage, so native code always finds its call
// table and a stray access past either end of the pages faults.  Copies are
// deep (and private); == compares the image bytes.  A shared image's pages are
// MAP_SHARED, so a child forked after it sees the parent's writes and the parent
// the child's (the sandbox, runtime/sandbox.h).  Throws std::bad_alloc if it
// cannot map.
class ImageBytes {
 public:
  static constexpr uint8_t kSlackByte = 0xA5;
  enum class Sharing : uint8_t { Private, Shared };
  explicit ImageBytes(size_t size = 0, Sharing sharing = Sharing::Private);
  ImageBytes(const ImageBytes& o);
  ImageBytes(ImageBytes&& o) noexcept;
  ImageBytes& operator=(const ImageBytes& o);
  ImageBytes& operator=(ImageBytes&& o) noexcept;
  ~ImageBytes();

  uint8_t* data() { return image_; }
  const uint8_t* data() const { return image_; }
  size_t size() const { return size_; }
  uint8_t& operator[](size_t i) { return image_[i]; }
  const uint8_t& operator[](size_t i) const { return image_[i]; }
  uint8_t* begin() { return image_; }
  uint8_t* end() { return image_ + size_; }
  const uint8_t* begin() const { return image_; }
  const uint8_t* end() const { return image_ + size_; }
  operator std::span<const uint8_t>() const { return {image_, size_}; }
  bool operator==(const ImageBytes& o) const;
  // The slack between the end of the image and its last page still holds
  // kSlackByte (nothing wrote past the image inside its pages).
  bool slack_intact() const;

 private:
  void map(size_t size, Sharing sharing);
  void unmap();
  uint8_t* base_ = nullptr;   // the first guard page
  size_t mapped_ = 0;         // bytes mapped from base_
  uint8_t* image_ = nullptr;  // the image, one guard page and one table page after base_
  size_t size_ = 0;
};

// Memory image helpers used by runners and tests.
struct Memory {
  Layout layout;
  ImageBytes bytes;
  explicit Memory(const Layout& l) : layout(l), bytes(l.size) {}
  uint8_t* data() { return bytes.data(); }
  int32_t get_int(Area a, uint32_t i) const;
  float get_real(uint32_t i) const;
  uint8_t get_bit(Area a, uint32_t i) const { return bytes[layout.addr(a, i)]; }
  void set_int(Area a, uint32_t i, int32_t v);
  void set_real(uint32_t i, float v);
  void set_bit(Area a, uint32_t i, bool v) { bytes[layout.addr(a, i)] = v ? 1 : 0; }
};

}  // namespace ldc
