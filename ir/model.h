// ir/model.h -- the typed program model of IEC 61131-3 programs (issue 25):
// the types, the program organisation units (POUs) with their variable
// sections, and the memory layout that places every variable, member, array
// element and function block instance in the devices of the typed IL (BOOL in
// M bits, every other type in D word cells; docs/il.md "Typed instructions").
//
// A front end fills it from its syntax (docs/architecture.md, "The typed
// program model"): it declares the types and the POUs, asks the model to lay
// out the program's variables, and lowers expressions through the model's
// access paths (Ref) to typed IL operands.  Nothing downstream of ir/ sees a
// front end's syntax; a POU's body stays with the front end, which expands it
// inline at each call site with the instance's places (Model::expand_guard
// refuses recursion by name).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ir/ir.h"

namespace ldc::model {

using TypeId = int32_t;      // an index into Model::types
constexpr TypeId kNoType = -1;

// The room a value takes: bits of the M area (one per BOOL) and word cells of
// the D area (one up to 32 bits, two for a 64-bit type).  A composite value
// takes both: its BOOLs in a row of M bits and its other members in a row of
// D cells, so a member's place is the container's place plus its offsets in
// each area, and an array's element k is the first element's place plus
// k * the element's size (in each area): the stride of an LDX/STX.
struct Size {
  uint32_t bits = 0, cells = 0;
  Size operator+(Size o) const { return {bits + o.bits, cells + o.cells}; }
  Size operator*(uint32_t n) const { return {bits * n, cells * n}; }
  bool operator==(const Size&) const = default;
};
// Where a value lives: its first M bit and its first D cell (absolute device
// indices once placed).  Only the area its type uses is meaningful.
struct Place {
  uint32_t bit = 0, cell = 0;
  Place operator+(Size s) const { return {bit + s.bits, cell + s.cells}; }
  bool operator==(const Place&) const = default;
};

// ---------------------------------------------------------------- initial values
// A typed constant: an elementary type and its 64 canonical bits (ir/typed.h).
struct Lit {
  Ty ty = Ty::None;
  uint64_t bits = 0;
};
// An IEC literal with MatIEC's meaning (docs/iec-il.md "Literals"): TRUE FALSE,
// 42 -7 1_000 16#FF 2#1010_0101 8#17, 1.5 1.0E-3, typed INT#5 DWORD#16#FF
// LREAL#1e-9 BOOL#1, durations T#1h2m3.5s TIME#-2ms LTIME#5d14h12m18s3.5ms (in
// nanoseconds), DATE#2024-01-31 D#..., TOD#12:00:00.5, DT#2024-01-31-12:00:00.
// An untyped integer is LINT-valued with ty None and `untyped_int` set (it takes the
// type of its use), an untyped real LREAL with ty None and `untyped_real` set.
struct ParsedLit {
  Lit lit;              // lit.ty is None for an untyped number; STRING for a string literal
  std::string str;      // a string literal's bytes ('a$Nb' is "a\nb"), lit.ty STRING
  bool untyped_int = false, untyped_real = false;
  int64_t ival = 0;     // an untyped integer's value
  double rval = 0;      // an untyped real's value
};
// nullopt with `why` empty: not a literal; with `why` set: a malformed one.
// A string literal 'text' (STRING#'text' too) has MatIEC's escapes: $$ $' $L $N
// (both LF) $P $R $T and $hh, in either case; more than 126 bytes is an error.
std::optional<ParsedLit> parse_literal(std::string_view text, std::string& why);
// The bytes of string literal 'text' (quotes included); nullopt and `why` if malformed.
std::optional<std::string> string_literal_bytes(std::string_view text, std::string& why);
// The 33 cells of a STRING holding `bytes` (at most 126): the length, then the
// bytes four to a cell, first byte lowest (docs/il.md, "Strings").
std::vector<uint32_t> string_cells(const std::string& bytes);
// A parsed literal as a value of type t (untyped ones take t; nullopt and
// `why` if it does not fit or is of another type).
std::optional<Lit> literal_as(const ParsedLit& p, Ty t, std::string& why);

// An initial value as written, apart from its syntax:
//   Value   a literal (an enumerator already resolved: Lit{DINT, k})
//   List    an array's elements: [1, 2, 3(0)] is {{1, 1}, {1, 2}, {3, 0}}
//           (a repeat count and the value; missing elements keep their default)
//   Fields  a structure's members: (x := 1, y := 2)
// (Item and Field are declared inside and defined after it: a std::pair of
// the incomplete Init is refused by clang's libstdc++ checks, a vector of an
// incomplete type is allowed.)
struct Init {
  struct Item;
  struct Field;
  enum Kind : uint8_t { None, Value, List, Fields } kind = None;
  ParsedLit value;
  std::vector<Item> list;
  std::vector<Field> fields;
  SrcLoc loc;
};
struct Init::Item {
  uint32_t count = 1;
  Init value;
};
struct Init::Field {
  std::string name;  // upper-case
  Init value;
};

// ---------------------------------------------------------------- types
enum class TypeKind : uint8_t {
  Elem,      // an elementary type (types.def)
  Enum,      // an enumeration: held as a DINT, enumerator k is k (MatIEC: a C enum)
  Subrange,  // INT(0..100): its elementary type, the bounds (not checked at run time, as MatIEC)
  Array,     // ARRAY[a..b, c..d] OF T
  Struct,    // STRUCT ... END_STRUCT
  Block      // a FUNCTION_BLOCK's instance (or a FUNCTION's frame): the POU's variables
};
struct Dim {
  int32_t lo = 0, hi = 0;
  uint32_t count() const { return uint32_t(int64_t(hi) - lo + 1); }
};
struct Member {
  std::string name;   // as declared
  TypeId type = kNoType;
  Size offset;        // from the container's place
  Init init;          // the member's own initial value (may be None)
};
struct Type {
  TypeKind kind = TypeKind::Elem;
  std::string name;                  // "INT", "MOTOR" (a TYPE's name), "" for an anonymous type
  Ty elem = Ty::None;                // Elem, Enum (DINT), Subrange: the elementary type of the value
  int64_t lo = 0, hi = 0;            // Subrange
  std::vector<std::string> enumerators;  // Enum: upper-case, enumerator k has value k
  std::vector<Dim> dims;             // Array: the dimensions, the last one varies fastest
  TypeId of = kNoType;               // Array: the element type
  std::vector<Member> members;       // Struct, Block (a Block's members are its POU's variables)
  int pou = -1;                      // Block: the POU (index into Model::pous)
  Size size;                         // set by Model::finish_type
  Init init;                         // a derived type's initial value (TYPE t : INT := 5;)
  bool scalar() const { return kind == TypeKind::Elem || kind == TypeKind::Enum || kind == TypeKind::Subrange; }
};

// ---------------------------------------------------------------- POUs
enum class PouKind : uint8_t { Program, FunctionBlock, Function };
enum class VarClass : uint8_t { Input, Output, InOut, Local, Temp, External, Global };
const char* var_class_name(VarClass c);  // "VAR_INPUT" ...
struct Var {
  std::string name;
  TypeId type = kNoType;
  VarClass cls = VarClass::Local;
  bool constant = false, retain = false;
  Init init;
  std::optional<DeviceRef> at;  // a located variable (AT %IX0.1): its device, as the front end maps it
  SrcLoc loc;
};
struct Pou {
  std::string name;
  PouKind kind = PouKind::Program;
  TypeId result = kNoType;   // a FUNCTION's result type
  std::vector<Var> vars;     // in declaration order
  TypeId block = kNoType;    // the instance type (FB, FUNCTION's frame, PROGRAM's variables): set by finish_pou
  SrcLoc loc;
  int body = -1;             // the front end's handle of the body (the model does not read it)
};

// ---------------------------------------------------------------- access paths
// A value reached from a variable: its type and place, and -- for elements
// whose index is not a constant -- the index steps that a front end lowers to
// IDX + LDX/STX (docs/il.md "Index faults").  With steps, `at` is the place of
// the element whose variable indices are all at their lower bounds; element
// (i1..in) is at + sum((ik - lo_k) * stride_k).
struct IndexStep {
  Operand index;     // the index's typed operand (a device or a typed constant)
  Ty index_ty = Ty::DINT;
  Dim dim;
  Size stride;       // the size of one step of this index
};
struct Ref {
  TypeId type = kNoType;
  Place at;
  std::vector<IndexStep> steps;
  bool writable = true;  // false: an input device, a CONSTANT
  Area bits = Area::M;   // the areas of `at`: the variable area is M and D; a located
  Area cells = Area::D;  // variable may be elsewhere (X Y for bits, WX WY F for cells)
  bool direct() const { return steps.empty(); }
};

// ---------------------------------------------------------------- the model
struct ModelError {
  SrcLoc loc;
  std::string message;
};

class Model {
 public:
  Model();  // the elementary types are types 0 .. kTyCount-1, in types.def order

  std::vector<Type> types;
  std::vector<Pou> pous;

  // ---- types
  TypeId elem(Ty t) const { return TypeId(t); }
  // A named type (elementary, a TYPE, or a POU that is a FUNCTION_BLOCK);
  // case-insensitive; kNoType if none.
  TypeId find_type(std::string_view name) const;
  // Adds a type (named or anonymous) and computes its size; a named one may
  // be found by name afterwards.  Throws ModelError for a second type of the
  // same name, an empty or inverted dimension, a member twice, a type that
  // contains itself, or a size beyond the devices.
  TypeId add_type(Type t, SrcLoc loc);
  const Type& type(TypeId id) const { return types.at(size_t(id)); }
  // The elementary type a scalar type is held as (Enum: DINT); Ty::None for
  // arrays, structures and instances.
  Ty scalar_ty(TypeId id) const;
  std::string type_name(TypeId id) const;  // "INT", "ARRAY[1..3] OF INT", "MOTOR"
  // Type equality for assignment: the same id, or two scalar types held as the same Ty.
  bool same_type(TypeId a, TypeId b) const;

  // ---- POUs
  // Declares a POU (its variables; result for a FUNCTION) and builds its
  // instance type (a Block named after it).  A FUNCTION_BLOCK is then a type
  // by its name.  Throws ModelError for a second POU or type of that name or
  // a variable declared twice.
  int add_pou(Pou p);
  int find_pou(std::string_view name) const;  // -1 if none
  // Inline expansion refuses recursion: call before expanding the body of
  // POU `callee`; `stack` holds the POUs being expanded (outermost first).
  // Throws ModelError naming the cycle (A -> B -> A).
  static void expand_guard(const Model& m, const std::vector<int>& stack, int callee, SrcLoc at);

  // ---- access
  // A member of a structure or instance by name (case-insensitive); nullptr if none.
  const Member* member(TypeId t, std::string_view name) const;
  // r.member; throws ModelError (unknown member, naming the type's members) at `at`.
  Ref select_member(const Ref& r, std::string_view name, SrcLoc at) const;
  // r[i1, ..., in]: a constant index is folded into the place (checked against
  // its bounds at compile time); a variable one becomes an IndexStep.  Each
  // index is a typed operand with its type (an integer type, else ModelError).
  Ref select_element(const Ref& r, const std::vector<std::pair<Operand, Ty>>& idx, SrcLoc at) const;

  // ---- layout
  // The variable area: M bits from `bit_base`, D cells from `cell_base`
  // (the front end puts it after the devices the program names itself).
  // place() allocates room of a size and returns its place; a located
  // variable is not allocated.  Throws ModelError when the devices run out
  // (M and D hold 8192 each).
  void set_area(uint32_t bit_base, uint32_t cell_base);
  Place place(Size s, SrcLoc at);
  // The next bits placed lie at `bit` or later (a program of a project
  // keeps its own relays apart from the other tasks' programs').
  void skip_bits_to(uint32_t bit) { next_.bit = std::max(next_.bit, bit); }
  Size used() const { return {next_.bit - base_.bit, next_.cell - base_.cell}; }
  Place area_base() const { return base_; }

  // ---- initial values (written on the first scan, S1)
  struct Store {
    Ty ty;       // the cell's (or bit's) elementary type
    Place at;    // BOOL: at.bit; else at.cell
    uint64_t bits;
  };
  // The stores that give a value of type t at place p its initial value:
  // `init` if given, else the type's own (a derived type's, a structure's
  // members', a Block's variables'), all else 0.  Only nonzero values are
  // stored (the image starts zeroed).  Throws ModelError for a value that
  // does not fit (a list longer than the array, an unknown member, a literal
  // of another type).
  // With `zeros`, every scalar is stored, 0 too (a FUNCTION's variables and
  // VAR_TEMP start from their initial values at every call, as in MatIEC).
  void initial_stores(TypeId t, Place p, const Init* init, std::vector<Store>& out, bool zeros = false) const;

 private:
  static int find_member_index(const Type& t, std::string_view name);  // -1 if none
  void finish_type(Type& t, SrcLoc loc);
  Place base_, next_;
  std::map<std::string, TypeId> by_name_;  // upper-case
};

// ---------------------------------------------------------------- lowering helpers
// The typed IL operand of a scalar of type t at place p: BOOL the bit (of
// area `bits`, M by default), else the cell (of area `cells`, D by default).
Operand operand_at(Ty t, Place p, Area bits = Area::M, Area cells = Area::D);
// The operand of a direct scalar Ref (r.steps empty).
Operand operand_of(const Model& m, const Ref& r);
// The stride of an LDX/STX for elements of type t stepping by `s`: bits for
// BOOL, cells otherwise.
int32_t stride_of(Ty t, Size s);
}  // namespace ldc::model
