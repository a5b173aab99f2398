// frontend/plcopen/plcopen.cpp -- the PLCopen TC6 XML importer (docs/plcopen.md).
//
// A PLCopen <LD> body is a graph: every element has a localId, and every input
// names the outputs that feed it (<connection refLocalId=.. formalParameter=..>;
// several connections on one input are a wired OR).  We run it the way Beremiz
// and OpenPLC (the tools that write these files) compile it to Structured Text:
//   * one statement per coil, output variable and block, in their order:
//     executionOrderId first, then coils and output variables, then the
//     remaining blocks, each in document order (Beremiz on Python 3) or by
//     position (on Python 2; see saved_by_python2);
//     a block feeding a statement is generated just before it;
//   * a statement's condition is the power flow from the left rail through the
//     contacts feeding it, which we reduce to a series/parallel tree (and refuse
//     when it does not reduce);
//   * standard function blocks keep their state in our devices (timers, counters,
//     relays), functions compute into temporary devices; edges on contacts and
//     coils are R_TRIG / F_TRIG instances of their own, as Beremiz makes them.
// POUs written in ST or IL are compiled by the ST and IEC IL readers as units
// of their own (st_call, st_program, st_condition; frontend/plcopen/st_text.h),
// whose IL is spliced in as raw rungs.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iterator>
#include <map>
#include <optional>
#include <set>

#include "frontend/diag.h"
#include "frontend/frontend.h"
#include "frontend/operands.h"
#include "frontend/treebuild.h"
#include "frontend/iecil/iecil.h"
#include "frontend/plcopen/st_text.h"
#include "frontend/plcopen/xml.h"
#include "ir/model.h"
#include "ir/time_scale.h"
#include "ir/typed.h"

namespace ldc {
namespace {

using K = TreeNode::Kind;
using namespace treebuild;
using xml::Element;

[[noreturn]] void fail_at(const Element* e, const std::string& msg) {
  throw CompileError(e ? e->line : 1, e ? e->col : 1, msg);
}

// "contact localId 13 (/project/types/pous/pou/body/LD/contact[7])", or for a
// block's pin "input PT of block TON localId 3 (.../block/inputVariables/variable[2])"
std::string where(const Element* e) {
  const Element* blk = e->parent && e->parent->parent ? e->parent->parent : nullptr;
  if (e->local_name() == "variable" && e->attr("formalParameter") && blk && blk->local_name() == "block") {
    std::string s = "input " + *e->attr("formalParameter") + " of block " + (blk->attr("typeName") ? *blk->attr("typeName") : "?");
    if (auto id = blk->attr("localId")) s += " localId " + *id;
    return s + " (" + e->path() + ")";
  }
  std::string s(e->local_name());
  if (auto id = e->attr("localId")) s += " localId " + *id;
  return s + " (" + e->path() + ")";
}

std::string trim(std::string_view s) {
  size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
  return a == std::string_view::npos ? std::string() : std::string(s.substr(a, b - a + 1));
}

// ------------------------------------------------------------------ conditions

TreeNode then_node(Cond c, TreeNode action, SrcLoc loc) {
  if (c.k == Cond::True) return action;
  TreeNode t;
  t.kind = K::Then;
  t.kids.push_back(c.k == Cond::False ? false_leaf(loc, "FALSE") : std::move(c.n));
  t.kids.push_back(std::move(action));
  return t;
}

bool is_leaf(const Cond& c) { return c.k == Cond::Expr && c.n.kind == K::Leaf; }

// ------------------------------------------------------------------ types

using IT = ::ldc::Ty;  // an IEC elementary type (ir/types.def)

// How the translation holds a value of each IEC type:
//   Bool  a bit device (M, X, Y)
//   Int   an integer or bit string of up to 32 bits in an INT32 word (D, WX,
//         WY, TW, CW), kept canonical for its type (ir/typed.h: sign- or
//         zero-extended); the untyped instructions compute on it and a result
//         narrower than 32 bits is wrapped to its type after (MatIEC computes
//         in the type: INT 32767 + 1 is -32768)
//   Real  REAL in a binary32 word (F)
//   Wide  a 64-bit type (LINT ULINT LWORD LREAL TIME LTIME DATE TOD DT) in two
//         D words, low word first, computed by typed instructions only
enum class Ty { None, Bool, Int, Real, Wide };

Ty kind_of(IT t) {
  if (t == IT::None) return Ty::None;
  if (t == IT::BOOL) return Ty::Bool;
  if (t == IT::REAL) return Ty::Real;
  if (ty_info(t).cells == 2) return Ty::Wide;
  return Ty::Int;
}

const char* ty_name(Ty t) {
  return t == Ty::Bool ? "BOOL" : t == Ty::Int ? "integer" : t == Ty::Real ? "REAL" : t == Ty::Wide ? "a 64-bit value" : "?";
}

// Integers, bit strings, times and dates: the types whose values wrap.
bool is_int_type(IT t) { return t != IT::None && typed::is_int_kind(t); }
// UDINT and DWORD: 32 bits unsigned, so an INT32 compare, division or
// conversion to REAL would read them wrong; the typed instructions do them.
bool unsigned32(IT t) { return t == IT::UDINT || t == IT::DWORD; }

// An IEC literal as the importer holds it: its type and canonical bits
// (ir/typed.h), read by the typed model's parser (ir/model.h parse_literal,
// MatIEC's meaning: TIME in ns, T#3.5ms exact).
struct IecLiteral {
  IT type = IT::None;  // the type it is written in; an untyped integer is LINT (ULINT above INT64_MAX), an untyped real LREAL
  bool typed = false;  // written with its type (INT#5, T#1s, D#2024-01-01, TRUE)
  uint64_t bits = 0;   // canonical bits of `type`
  bool based = false;  // an untyped integer written in base 2, 8 or 16 (a bit pattern)
  bool is_real() const { return type == IT::REAL || type == IT::LREAL; }
  double real() const { return typed::real_value(type, bits); }
  int64_t integer() const { return int64_t(bits); }
};

std::optional<IecLiteral> parse_iec_literal(std::string_view text, std::string& why) {
  auto p = model::parse_literal(text, why);
  if (!p) {
    std::string tail = ": " + std::string(text);  // the model's message ends with the text
    if (why.size() > tail.size() && why.compare(why.size() - tail.size(), tail.size(), tail) == 0) why.resize(why.size() - tail.size());
    if (!why.empty()) why = "malformed literal '" + std::string(text) + "': " + why;
    return std::nullopt;
  }
  IecLiteral l;
  if (p->untyped_int) {
    bool big = p->lit.ty == IT::ULINT;
    l.type = big ? IT::ULINT : IT::LINT;
    l.bits = big ? p->lit.bits : uint64_t(p->ival);
    std::string u = upper(text);
    size_t h = u.find('#');
    l.based = h != std::string::npos && (u.compare(0, h, "2") == 0 || u.compare(0, h, "8") == 0 || u.compare(0, h, "16") == 0);
  } else if (p->untyped_real) {
    l.type = IT::LREAL;
    l.bits = typed::real_bits(IT::LREAL, p->rval);
  } else {
    l.type = p->lit.ty;
    l.typed = true;
    l.bits = p->lit.bits;
  }
  return l;
}

// The IEC elementary type named `name` (TIME_OF_DAY is TOD ...); IT::None if none.
IT iec_type_named(std::string_view name) { return ty_from_name(name).value_or(IT::None); }

// A value: a device or a constant, with how it is held and its IEC type
// (None: an untyped literal or a direct address, an INT32 as before).
struct Val {
  Operand o;
  Ty ty = Ty::Int;
  IT it = IT::None;
  bool ms = false;                 // a TIME held as INT32 milliseconds (a timer's ET)
  std::optional<IecLiteral> lit;   // a literal's exact value
};

// The type a value computes in: its own, or DINT / REAL / BOOL for untyped ones.
IT type_of(const Val& v) {
  if (v.ms) return IT::DINT;
  if (v.it != IT::None) return v.it;
  return v.ty == Ty::Real ? IT::REAL : v.ty == Ty::Bool ? IT::BOOL : v.ty == Ty::Wide ? IT::LINT : IT::DINT;
}

// A constant value's canonical bits in its own type (type_of).
uint64_t const_bits(const Val& v) {
  if (v.lit) return v.lit->bits;
  IT t = type_of(v);
  if (v.o.kind == OpdKind::ConstT) return v.o.bits();
  if (v.o.kind == OpdKind::ConstReal) return typed::bits_of(v.o.fval);
  return typed::norm(t, uint64_t(int64_t(v.o.ival)));
}
bool is_const(const Operand& o) { return o.kind == OpdKind::ConstInt || o.kind == OpdKind::ConstReal || o.kind == OpdKind::ConstT; }

// ------------------------------------------------------------------ declarations

enum class FbKind { None, Timer, Counter, Latch, Trig, Typed };

struct Var {
  std::string name;  // as declared
  std::string type;  // upper-case elementary type, or the derived type name as written
  bool derived = false;
  Ty ty = Ty::None;
  IT it = IT::None;              // its IEC type, when elementary
  bool constant = false;
  Operand cval;                  // constant
  std::optional<DeviceRef> dev;  // data: the device; FB: T / C / M of its state
  uint32_t aux = 0, aux2 = 0;    // CTUD: QU, QD relays
  std::string init;              // initialValue/simpleValue/@value
  std::string address;
  const Element* el = nullptr;
  std::string pou;  // "" for globals
  // An instance of one of the project's FUNCTION_BLOCKs (or a FUNCTION call's
  // frame): its own variables, each a Var named INSTANCE.MEMBER (upper member
  // name -> member); its VAR_IN_OUT names, bound to the caller's variable at
  // each call (by reference).
  std::map<std::string, Var*> members;
  std::vector<Var*> member_order;  // a structure's members as declared
  std::set<std::string> inouts;
  std::string section;   // the interface section it is declared in (inputVars ...)
  bool frame = false;    // a member of a function call's frame: no alias
  bool refused = false;  // its location was refused (error recovery): its uses say nothing more
  const Element* init_el = nullptr;    // <initialValue> (or a structValue's <value>)
  const Element* struct_el = nullptr;  // a structure's <struct> (its type in <dataTypes>)
  bool container() const { return struct_el || !members.empty() || !inouts.empty(); }
  // An array of an elementary type: its elements VAR[i] (VAR[i,j]) in a row of
  // devices (the last index varies fastest), so that IDX + LDX reach element i.
  const Element* array_el = nullptr;
  std::vector<std::pair<int32_t, int32_t>> dims;
  std::vector<Var*> elems;
};

// MatIEC's counters of a width other than INT (lib/counter.txt): CTU_DINT,
// CTD_LINT, CTUD_ULINT ...: their CV's and PV's type; None for other names.
IT counter_width(const std::string& t) {
  size_t u = t.find('_');
  if (u == std::string::npos) return IT::None;
  std::string kind = t.substr(0, u), w = t.substr(u + 1);
  if (kind != "CTU" && kind != "CTD" && kind != "CTUD") return IT::None;
  if (w == "DINT") return IT::DINT;
  if (w == "LINT") return IT::LINT;
  if (w == "UDINT") return IT::UDINT;
  if (w == "ULINT") return IT::ULINT;
  return IT::None;
}

FbKind fb_kind(const std::string& t) {
  if (counter_width(t) != IT::None || t == "SEMA" || t == "RTC") return FbKind::Typed;
  if (t == "TON" || t == "TOF" || t == "TP") return FbKind::Timer;
  if (t == "CTU" || t == "CTD" || t == "CTUD") return FbKind::Counter;
  if (t == "SR" || t == "RS") return FbKind::Latch;
  if (t == "R_TRIG" || t == "F_TRIG") return FbKind::Trig;
  return FbKind::None;
}

// ------------------------------------------------------------------ LD body

struct Conn {
  int ref = 0;
  std::string param;
  bool has_param = false;
  const Element* el = nullptr;
  bool has_pos = false;
  double px = 0, py = 0;  // the last <position> of the connection: its source end
};

struct Pin {
  std::string name;
  bool negated = false;
  std::string edge;
  std::vector<Conn> conns;
  const Element* el = nullptr;
  double rx = 0, ry = 0;  // output pins: relPosition of the connection point
};

struct Node {
  const Element* el = nullptr;
  std::string kind;  // local name: contact, coil, block, ...
  int id = 0;
  double x = 0, y = 0;
  int order = 0;  // executionOrderId
  std::vector<Conn> in;
  std::vector<Pin> inputs, outputs;  // block
  std::string text;  // variable, expression, connector name
  bool negated = false, negated_in = false;
  std::string edge, storage;
  std::string type, instance;  // block
  std::vector<Pin> inouts;     // block: in-out parameters (VAR_IN_OUT of a user POU)
};

struct Out {  // a block output as its consumers see it
  bool boolean = false;
  Cond cond;  // boolean: a leaf (or a constant)
  Val val;
};

// ------------------------------------------------------------------ importer

// Error recovery (frontend/diag.h): a use of something whose error was
// reported throws a Cascade (nothing more is said); an error after which
// everything would fail the same way (the devices or the variables ran out)
// is a Stop, which ends the import, recovery or not.
using Refused = Cascade;
using Fatal = Stop;

class Importer {
 public:
  Importer(std::string_view text, std::string file, Diagnostics* diag = nullptr)
      : text_(text), file_(std::move(file)), diag_(diag), errors0_(diag ? diag->errors() : 0) {}
  TreeProgram run();
  // -Wunused (docs/diagnostics.md): a VAR or VAR_TEMP of a translated LD,
  // FBD or SFC POU that no element, block or action names.
  void warn_unused() const {
    if (!diag_ || !diag_->wants("unused")) return;
    for (const Var* v : locals_)
      if (!used_vars_.count(v) && v->el)
        diag_->warning("unused", file_, v->el->line, v->el->col, "variable '" + v->name + "' of POU '" + v->pou + "' is never used");
  }

 private:
  std::string_view text_;
  std::string file_;
  xml::Document doc_;

  // Error recovery (docs/diagnostics.md): with a Diagnostics, an error in a
  // variable declaration, an interface section, a variable's location or
  // initial value, a statement of an LD/FBD body (a coil, an output variable,
  // a block, with all that feeds it) or a POU body is reported there, and the
  // import goes on with the next one.  A use of what was refused throws
  // Refused: it follows from an error already reported, so nothing more is.
  Diagnostics* diag_;
  std::set<const Element*> failed_blocks_;                 // blocks whose statement was refused
  std::set<std::string> failed_names_;                     // upper names whose declaration was refused
  std::set<std::pair<std::string, std::string>> unknown_;  // (POU, upper name) reported unknown
  std::set<std::pair<int, int>> reported_;                 // one report per place (an XML element)
  std::vector<const Var*> locals_;                         // VAR and VAR_TEMP of the translated POUs (-Wunused)
  std::set<const Var*> used_vars_;                         // every variable a name found
  template <class F>
  bool recover(F&& f);
  void report(const CompileError& e);
  // A block whose error was reported: it failed, or an error was reported at its element.
  bool block_refused(const Node& b) const {
    return failed_blocks_.count(b.el) || (diag_ && reported_.count({b.el->line, b.el->col}));
  }
  [[noreturn]] void unknown_name(const Element* el, const std::string& name, const std::string& msg);
  int errors0_;
  // Ends the import when errors were reported (before checks that what was
  // refused would fail too, such as "no coils").
  void end_of_recovery() const {
    if (diag_ && errors0_ < diag_->errors()) throw ErrorsReported();
  }

  // declarations
  std::vector<std::unique_ptr<Var>> vars_;
  std::map<std::string, Var*> globals_;  // upper-case name
  std::map<std::string, const Element*> pou_lang_el_;
  std::map<std::string, std::string> pou_lang_;  // upper POU name -> body language
  std::map<std::string, const Element*> pou_el_;  // upper POU name -> <pou>
  std::set<std::string> called_;                  // upper POU names some block calls
  std::vector<std::string> call_stack_;           // POUs being expanded, outermost first (as written)
  std::set<std::pair<int, uint32_t>> used_;
  uint32_t next_[11] = {};

  // program
  std::vector<TreeRung> rungs_;
  std::vector<std::string> pending_labels_;
  std::string pending_title_;
  int labels_ = 0;
  std::vector<TreeNode> init_;

  // the POU being translated
  std::string pou_;
  std::map<std::string, Var*> scope_;
  std::map<int, Node> nodes_;
  std::map<std::string, int> connectors_;  // name -> localId
  std::set<int> computed_;
  std::map<std::pair<int, std::string>, Out> outs_;
  std::set<std::pair<int, std::string>> consumed_;  // block outputs someone reads
  std::set<int> generating_;
  // Located BOOL inputs the program writes (MatIEC allows it): the input is
  // copied into a relay at the start of the scan, and from the first write on
  // the variable is that relay, X index -> M index.
  // Input words the same way: WX index -> D index.
  std::map<uint32_t, uint32_t> shadow_, shadow_w_;
  Operand shadowed(Operand o) const {
    if (o.kind == OpdKind::Bit && o.area == Area::X)
      if (auto it = shadow_.find(o.index); it != shadow_.end()) return bit_opd(Area::M, it->second);
    if (o.kind == OpdKind::Int && o.area == Area::WX)
      if (auto it = shadow_w_.find(o.index); it != shadow_w_.end()) return Operand{OpdKind::Int, Area::D, it->second};
    return o;
  }
  // A write to an input: from here on it is its relay or word.
  Val written(Val v, const Element* el) {
    if (v.o.kind == OpdKind::Bit && v.o.area == Area::X) {
      uint32_t m = take(Dev::M, el);
      shadow_[v.o.index] = m;
      v.o = bit_opd(Area::M, m);
    } else if (v.o.kind == OpdKind::Int && v.o.area == Area::WX) {
      uint32_t d = take(Dev::D, el);
      shadow_w_[v.o.index] = d;
      v.o = Operand{OpdKind::Int, Area::D, d};
    }
    return v;
  }
  // The native stack: bool_expr recurses once per power-flow element it
  // follows, block_out once per block that feeds a block being generated.  A
  // block's frames are about ten times a flow element's, so it costs
  // kBlockNest; the total stays under kMaxNest (docs/fuzzing.md has the
  // measured stack: about 4 MiB at the limit under ASan, 1 MiB without).
  int nest_ = 0;
  static constexpr int kMaxNest = 500, kBlockNest = 10;
  struct Nest {
    int& n;
    int cost;
    ~Nest() { n -= cost; }
  };

  // declarations
  void declare(const Element* list, const std::string& pou, bool global);
  // Every variable, instance member, structure member and array element is a
  // Var: nested instances multiply them, so their number is bounded (a
  // hostile file must not exhaust memory before the devices run out).
  static constexpr size_t kMaxVars = 65536;
  void keep(std::unique_ptr<Var> u) {
    if (vars_.size() >= kMaxVars)
      throw Fatal(u->el ? u->el->line : 1, u->el ? u->el->col : 1, "more than " + std::to_string(kMaxVars) + " variables, counting every member of every instance, structure and array ('" +
                         u->name + "' is one too many); ldc's devices hold fewer");
    vars_.push_back(std::move(u));
  }
  std::unique_ptr<Var> make_var(const Element* v, const std::string& name, const std::string& pou, bool constant);
  void instantiate(Var& inst, const Element* fb, std::vector<std::string>& stack);
  void type_of_var(Var& u, const Element* te, int depth);
  void struct_members(Var& s, std::vector<std::string>& stack);
  void expand(Var& v, std::vector<std::string>& stack);
  void array_elements(Var& a, std::vector<std::string>& stack);
  void place_struct_elements(Var& a);
  Val element(Var& a, const std::string& idx, const std::string& member, const Element* el, bool write);
  Var& element_member(Var& e, const std::string& member, const std::string& expr, const Element* el);
  std::function<void()> pending_store_;  // a write at a variable index: the statement's last rung
  void statement_of(const Node& n);
  Val fb_output(Var& inst, const std::string& e, const std::string& m, const Element* el, bool write);
  Var* instance_named(const std::string& name, const Element* el);
  Var& instance_element(Var& a, const std::string& idx, const Element* el);
  bool fb_instance_type(const std::string& type) const {
    const Element* u = user_pou(type);
    return fb_kind(upper(type)) != FbKind::None || (u && pou_type(u) == "functionBlock");
  }
  void recovered_statement(const Node& n);
  void interface_section(const Element* sec, const std::string& pou);
  void block_of(const Node& b);
  // The state of the body being translated, kept aside while a callee's body
  // is, and put back however that ends (an error recovered from too).
  struct CallerState {
    Importer& im;
    std::map<int, Node> nodes;
    std::map<std::string, int> connectors;
    std::set<int> computed;
    std::map<std::pair<int, std::string>, Out> outs;
    std::set<std::pair<int, std::string>> consumed;
    std::set<int> generating;
    std::map<std::string, Var*> scope;
    std::string pou;
    size_t calls;
    bool sfc;
    explicit CallerState(Importer& i)
        : im(i), nodes(std::move(i.nodes_)), connectors(std::move(i.connectors_)), computed(std::move(i.computed_)),
          outs(std::move(i.outs_)), consumed(std::move(i.consumed_)), generating(std::move(i.generating_)),
          scope(std::move(i.scope_)), pou(i.pou_), calls(i.call_stack_.size()), sfc(i.sfc_mode_) {
      i.nodes_.clear(), i.connectors_.clear(), i.computed_.clear(), i.outs_.clear(), i.consumed_.clear(), i.generating_.clear();
    }
    ~CallerState() {
      im.nodes_ = std::move(nodes), im.connectors_ = std::move(connectors), im.computed_ = std::move(computed);
      im.outs_ = std::move(outs), im.consumed_ = std::move(consumed), im.generating_ = std::move(generating);
      im.scope_ = std::move(scope), im.pou_ = pou, im.sfc_mode_ = sfc;
      im.call_stack_.resize(calls);
    }
  };
  bool eno_gated(const Node& n);
  std::string eno_skip(const Node& n);
  std::map<std::string, const Element*> data_types_;  // upper name -> <dataType>
  const Element* user_pou(const std::string& type) const;
  std::string pou_type(const Element* pou) const { return pou->attr("pouType") ? *pou->attr("pouType") : "program"; }
  void place(Var& v);
  Var* member_path(const std::string& expr, const Element* el, std::string* last);
  void allocate();
  uint32_t take(Dev d, const Element* el);
  uint32_t temp_m(const Element* el) {
    uint32_t m = take(Dev::M, el);
    temps_.insert(m);
    return m;
  }
  std::set<uint32_t> temps_;  // relays holding a value computed once per scan
  std::optional<DeviceRef> location(const Var& v);
  Var* lookup(const std::string& name);
  void aliases(TreeProgram& p);

  // expressions
  std::optional<Val> literal(const std::string& s, const Element* el);
  uint64_t const_as(const Val& v, IT t);
  Val const_val(const Val& v, IT t);
  Val var_val(const Var& v);
  Val value_of(const std::string& expr, const Element* el, bool write = false);
  Val read_of(const std::string& expr, const Element* el, bool write);
  Operand bit_of(const std::string& expr, const Element* el, bool write);
  std::string spell(const Operand& o) const;
  Spellings spelled_;

  // tree pieces
  TreeNode leaf(Op op, std::vector<Operand> a, const Element* el, std::string text = "");
  TreeNode out(Op op, std::vector<Operand> a, const Element* el, const std::string& text = "");
  Cond bit_leaf(Op op, Operand o, const Element* el) { return Cond::of(leaf(op, {o}, el)); }
  // typed values
  Operand temp_of(IT t, const Element* el);
  std::string spell_typed(const Operand& o, IT t) const;
  Instr typed_instr(Op op, IT t, IT u, std::vector<Operand> a, const Element* el, std::string& text) const;
  TreeNode tout(Op op, IT t, IT u, std::vector<Operand> a, const Element* el);
  Cond tcmp(Op op, IT t, Operand a, Operand b, const Element* el);
  Operand as_type(const Val& v, IT t, const Element* el);
  void wrap(Operand r, IT t, const Cond& en, const Element* el);
  TreeNode assign_node(const Val& k, const Val& dst, const Element* el);
  void assign(const Val& v, const Val& dst, const std::string& dst_text, const Element* el);
  Operand preset_ms(const Val& v, const Element* el);
  Val ns_of_ms(const Val& v, const Element* el);
  void rung(TreeNode root, const Element* el);
  void rung(Cond c, TreeNode action, const Element* el) { rung(then_node(std::move(c), std::move(action), {el->line, el->col}), el); }
  Cond materialize(Cond c, const Element* el);
  Cond negate(Cond c, const Element* el);
  Cond trigger(Cond c, bool rising, const Element* el, std::optional<Operand> into = std::nullopt);
  void typed_counter(const std::string& t, IT w, const Var& inst, const std::function<Cond(const std::string&)>& in,
                     const Val& pv, const Element* el);
  // RTC's clock (docs/stdlib.md): a hidden timer and the DT it sums, in a rung
  // first in the program (finish)
  std::optional<std::pair<uint32_t, uint32_t>> clock_;  // timer, first D word
  Operand scan_clock(const Element* el) {
    if (!clock_) clock_ = {take(Dev::T, el), take_run(Dev::D, 4, el)};  // the clock and a LINT temporary
    return Operand{OpdKind::Int, Area::D, clock_->second};
  }
  std::string new_label();

  // the body
  void body(const Element* ld, const std::string& title);
  void read_node(const Element* e);
  void read_conns(const Element* cpi, std::vector<Conn>& out);
  const Node& node(const Conn& c);
  bool is_bool_source(const Conn& c, int depth = 0);
  bool out_is_bool(const Node& b, const std::string& pin, int depth = 0);
  void refuse_user_pou(const Node& b);
  void user_call(const Node& b, const Element* callee);
  bool user_out_is_bool(const Node& b, const Element* callee, const std::string& pin);
  const Element* callee_var(const Element* callee, const std::string& name, std::string* section);
  const Element* callee_graph(const Node& b, const Element* callee);
  // The project's ST and IL POUs (docs/plcopen.md, "ST and IL POUs"): compiled
  // by the typed reader as a unit of their own, behind a small ST program that
  // copies the call's values between the instance and its pins here.
  // a POU the typed reader compiles from its text: ST, IL, or an SFC chart
  // that is text alone (plcopen::text_chart, written as ST) in a function
  // block, or in a program with action bodies (which a chart of section 1b
  // does not take)
  bool st_pou(const std::string& name) const {
    auto it = pou_lang_.find(upper(name));
    if (it != pou_lang_.end() && it->second.starts_with("SFC")) {
      const Element* pe = pou_el_.at(upper(name));
      return plcopen::text_chart(pe) && (pou_type(pe) == "functionBlock" || plcopen::chart_action_bodies(pe));
    }
    return it != pou_lang_.end() && (it->second == "ST" || it->second == "IL");
  }
  void st_program(const Element* pou);
  void st_call(const Node& b, const Element* callee, Var& inst, const std::map<std::string, Var*>& bound);
  // `lines` of ST placed at `at`; a line kInlineText is the text of `text`.
  iecil::Unit st_unit(const std::vector<std::string>& lines, const Element* at, const Element* program = nullptr, const Element* text = nullptr);
  static constexpr const char* kInlineText = "\x01";
  void st_condition(const Element* cond, uint32_t m);
  void st_action(const Element* text, uint32_t m, const Element* at);
  std::vector<std::string> unit_header(const std::string& flag, uint32_t m);
  void splice(const iecil::Unit& u, const Element* at);
  void unit_init(const iecil::Unit& u, const std::string& whose, const Element* at);
  uint32_t first_free(Dev d) const;
  void globals_for_units(std::vector<std::string>& decl, const char* section);
  // an FB instance's, compiled at its first call, with the variables its in-outs are bound to
  std::map<const Var*, std::pair<std::string, iecil::Unit>> units_;
  std::vector<TreeRung> unit_init_;          // the units' first-scan rungs, first in the program
  int splices_ = 0;
  std::vector<Alias> unit_aliases_;  // inst.member of an ST or IL instance (the unit's ldc__i.member)
  const Element* data_types_el_ = nullptr;
  template <typename E>
  Cond node_values(std::vector<E*>& left, int nn, int sink, const Element* consumer);
  Cond bool_expr(const std::vector<Conn>& conns, bool order, const Element* consumer);
  Val value_expr(const std::vector<Conn>& conns, bool order, const Element* consumer, int depth = 0);
  Out block_out(const Node& b, const Conn& c, bool order);
  const Pin* out_pin(const Node& b, const Conn& c);
  void statement(const Node& n);
  void tasks(const Element* root);
  // SFC (section 1b): the chart of the POU being translated, at most one per program
  bool sfc_mode_ = false;
  // Which generator's order of statements (docs/plcopen.md, section 3): Beremiz
  // and OpenPLC Editor on Python 2 sorted coils and blocks by position; on
  // Python 3 their sort leaves them in document order.
  bool position_order_ = false;
 public:
  // A PLCopen TC6 XML 1.0 file (namespace http://www.plcopen.org/xml/tc6.xsd):
  // read where it agrees with 2.01, its own spellings translated as Beremiz's
  // LoadProjectXML does (docs/plcopen.md, "TC6 XML 1.0").
  bool tc6_v1_ = false;
 private:
  std::optional<Chart> chart_;
  std::vector<TreeRung> after_;  // the chart's actions, after its steps
  std::vector<std::string> after_end_labels_;  // labels after its last rung
  std::string chart_pou_;
  void take_chart(std::optional<PlcopenChart>& into) {
    if (!chart_) return;
    into.emplace();
    into->chart = std::move(*chart_);
    into->after.source = file_;
    into->after.rungs = std::move(after_);
    into->after.end_labels = std::move(after_end_labels_);
    chart_.reset();
    after_.clear();
    after_end_labels_.clear();
  }
  static const std::set<std::string>& sfc_kinds() {
    static const std::set<std::string> k = {"step", "transition", "selectionDivergence", "selectionConvergence",
                                            "simultaneousDivergence", "simultaneousConvergence", "jumpStep", "macroStep", "actionBlock"};
    return k;
  }
  void sfc_body(const Element* pou, const Element* sfc);
  uint32_t take_run(Dev d, uint32_t n, const Element* el);
  struct CfgTask {
    const Element* el = nullptr;
    std::string name, resource, interval, priority_text;
    uint32_t resource_index = 0;
    bool no_task = false;  // a resource's pouInstance outside any task
    std::vector<std::string> pous, instances;  // upper POU names, instance names
    std::vector<const Element*> instance_els;
  };
  std::vector<CfgTask> cfg_tasks_;
  std::string config_name_;
  int task_ = -1;  // the task being translated (several tasks), else -1
  std::map<Var*, std::set<int>> global_users_;  // global -> tasks whose programs use it
  std::vector<const Element*> ld_pous_;
  std::map<const Element*, std::map<std::string, Var*>> scopes_;
  void prepare();
  void emit_init(const std::function<bool(const Var&)>& which, const Element* root);
  void emit_bodies(const std::vector<const Element*>& pous);
  TreeProgram run_prepared(const Element* root);
  void finish(TreeProgram& p, const Element* root);
  PlcopenTask task_program(size_t i, const Element* root);

 public:
  PlcopenImport import();

 private:
  void block(const Node& b);
  void fb_block(const Node& b, Var& inst);
  void fn_block(const Node& b);
  void real_to_int(Operand x, Operand res, const Cond& en, const Element* el);
  Val typed_fn(const std::string& t, const std::string& time_op, const std::vector<Val>& v, const Pin* g, IT T, const Cond& en, Cond& eno,
               const Element* el, const Node& b);
  Val typed_conv(IT to, IT from, const Val& v, const Cond& en, bool trunc, const Element* el);
  Val date_fn(const std::string& t, const std::vector<Val>& v, const Cond& en, const Element* el, const Node& b);
  Val bcd_fn(const std::string& t, const std::vector<Val>& v, const Cond& en, Cond& eno, const Element* el, const Node& b);
  void bit_shift(const std::string& t, const Pin& in_pin, Operand in, Operand n, Operand res, const Cond& en, const Element* el);
};

// ------------------------------------------------------------------ declarations

uint32_t Importer::take(Dev d, const Element* el) {
  uint32_t& n = next_[int(d)];
  while (n < device_count(d) && used_.count({int(d), n})) n++;
  if (n >= device_count(d))
    throw Fatal(el ? el->line : 1, el ? el->col : 1, std::string("out of ") + dev_name(d) + " devices for this project");
  used_.insert({int(d), n});
  return n++;
}

// A variable of an interface section (or a member of an instance): its type,
// initial value and address as written.
std::unique_ptr<Var> Importer::make_var(const Element* v, const std::string& name, const std::string& pou, bool constant) {
  auto u = std::make_unique<Var>();
  u->name = name;
  u->el = v;
  u->pou = pou;
  u->constant = constant;
  if (auto a = v->attr("address")) u->address = *a;
  const Element* t = v->child("type");
  if (!t || t->children.empty()) fail_at(v, "variable '" + name + "' has no type");
  u->init_el = v->child("initialValue");
  if (u->init_el)
    if (const Element* sv = u->init_el->child("simpleValue"))
      if (auto val = sv->attr("value")) u->init = *val;
  type_of_var(*u, t->children[0].get(), 0);
  return u;
}

// A variable's type: elementary, a standard or user FB, or one of the
// project's <dataTypes>: a derived type or subrange is its base type (with the
// derived type's initial value when the variable has none; a subrange's
// bounds are not checked, as MatIEC), a structure gets members (expand).
void Importer::type_of_var(Var& u, const Element* te, int depth) {
  std::string k(te->local_name());
  if (depth > 32) fail_at(te, "data type '" + u.type + "' is defined through itself (" + te->path() + ")");
  if (k == "derived") {
    std::string name = te->attr("name") ? *te->attr("name") : "";
    auto dt = data_types_.find(upper(name));
    if (dt == data_types_.end()) {
      u.derived = true;
      u.type = name;
      u.it = IT::None;
      u.ty = Ty::None;
      return;
    }
    const Element* base = dt->second->child("baseType");
    if (!base || base->children.empty()) fail_at(dt->second, "data type '" + name + "' has no baseType (" + dt->second->path() + ")");
    if (!u.init_el)
      if (const Element* iv = dt->second->child("initialValue")) {
        u.init_el = iv;
        if (const Element* sv = iv->child("simpleValue"))
          if (auto val = sv->attr("value")) u.init = *val;
      }
    const Element* b = base->children[0].get();
    if (b->local_name() == "struct") {
      u.derived = true;
      u.type = name;
      u.struct_el = b;
      return;
    }
    return type_of_var(u, b, depth + 1);
  }
  if (k == "subrangeSigned" || k == "subrangeUnsigned") {
    const Element* base = te->child("baseType");
    if (!base || base->children.empty()) fail_at(te, "subrange without a baseType (" + te->path() + ")");
    return type_of_var(u, base->children[0].get(), depth + 1);
  }
  if (k == "struct") fail_at(te, "variable '" + u.name + "' has a structure written in its declaration; ldc takes structures declared in <dataTypes> (" + te->path() + ")");
  if (k == "array") {
    const Element* base = te->child("baseType");
    if (!base || base->children.empty()) fail_at(te, "array without a baseType (" + te->path() + ")");
    u.derived = true;
    u.array_el = te;
    u.type = "an array";
    u.ty = Ty::None;
    return;
  }
  if (k == "enum" || k == "string" || k == "wstring" || k == "pointer")
    u.derived = true, u.type = k == "enum" ? "an enumeration" : k == "array" ? "an array" : upper(k);
  else
    u.type = upper(k), u.it = iec_type_named(u.type);
  u.ty = kind_of(u.it);
}

// The members of a structure variable: each a variable STRUCT.MEMBER (nested
// structures too), their initial values the structure's <structValue>, else
// the members' own.
void Importer::struct_members(Var& s, std::vector<std::string>& stack) {
  if (std::find(stack.begin(), stack.end(), "TYPE " + upper(s.type)) != stack.end())
    fail_at(s.el, "structure '" + s.type + "' contains itself (through '" + s.name + "')");
  stack.push_back("TYPE " + upper(s.type));
  const Element* sv = s.init_el ? s.init_el->child("structValue") : nullptr;
  for (const Element* v : s.struct_el->children_named("variable")) {
    const std::string* nm = v->attr("name");
    if (!nm || nm->empty()) fail_at(v, "structure member without a name (" + v->path() + ")");
    std::string key = upper(*nm);
    if (s.members.count(key)) fail_at(v, "member '" + *nm + "' is declared twice in structure '" + s.type + "'");
    auto u = make_var(v, s.name + "." + *nm, s.pou, s.constant);
    u->section = "struct";
    u->frame = s.frame;
    if (sv)
      for (const Element* mv : sv->children_named("value"))
        if (mv->attr("member") && upper(*mv->attr("member")) == key) {
          u->init_el = mv;
          u->init.clear();
          if (const Element* simple = mv->child("simpleValue"))
            if (auto val = simple->attr("value")) u->init = *val;
        }
    Var* raw = u.get();
    keep(std::move(u));
    s.members[key] = raw;
    s.member_order.push_back(raw);
    expand(*raw, stack);
  }
  stack.pop_back();
}

// The elements of an array of an elementary type or of a structure, a[lo] ..
// a[hi] (a[i,j] for several dimensions; a structure's members a[i].m), with
// the initial values of its <arrayValue> (a value with repetitionValue="n"
// counts n times; a structure's a <structValue>) in order.
void Importer::array_elements(Var& a, std::vector<std::string>& stack) {
  uint64_t count = 1;
  for (const Element* d : a.array_el->children_named("dimension")) {
    auto num = [&](const char* at) -> int32_t {
      const std::string* t = d->attr(at);
      char* end = nullptr;
      long long x = t ? std::strtoll(t->c_str(), &end, 10) : 0;
      if (!t || t->empty() || *end || x < INT32_MIN || x > INT32_MAX) fail_at(d, "array dimension needs integer bounds lower and upper (" + d->path() + ")");
      return int32_t(x);
    };
    int32_t lo = num("lower"), hi = num("upper");
    if (hi < lo) fail_at(d, "array dimension " + std::to_string(lo) + ".." + std::to_string(hi) + " is empty (" + d->path() + ")");
    a.dims.push_back({lo, hi});
    count *= uint64_t(int64_t(hi) - lo + 1);
    if (count > 8192) fail_at(d, "array '" + a.name + "' has more than 8192 elements; ldc's devices hold 8192 words");
  }
  if (a.dims.empty()) fail_at(a.array_el, "array without a dimension (" + a.array_el->path() + ")");
  const Element* bt = a.array_el->child("baseType")->children[0].get();
  std::vector<std::string> inits;
  std::vector<const Element*> struct_inits;  // an element's <value> holding its <structValue>
  if (const Element* av = a.init_el ? a.init_el->child("arrayValue") : nullptr)
    for (const Element* v : av->children_named("value")) {
      long long rep = v->attr("repetitionValue") ? std::atoll(v->attr("repetitionValue")->c_str()) : 1;
      const Element* sv = v->child("simpleValue");
      const bool st = v->child("structValue") != nullptr;
      if ((!st && (!sv || !sv->attr("value"))) || rep < 1)
        fail_at(v, "ldc takes arrayValue elements that are simple values or structValues (" + v->path() + ")");
      for (long long r = 0; r < rep && inits.size() < count; r++) inits.push_back(st ? "" : *sv->attr("value")), struct_inits.push_back(st ? v : nullptr);
      if (inits.size() >= count && rep > 0) break;
    }
  for (uint64_t k = 0; k < count; k++) {
    std::string idx;
    uint64_t rest = k;
    std::vector<int64_t> ix(a.dims.size());
    for (size_t j = a.dims.size(); j-- > 0;) {
      uint64_t n = uint64_t(int64_t(a.dims[j].second) - a.dims[j].first + 1);
      ix[j] = a.dims[j].first + int64_t(rest % n), rest /= n;
    }
    for (size_t j = 0; j < ix.size(); j++) idx += (j ? "," : "") + std::to_string(ix[j]);
    auto e = std::make_unique<Var>();
    e->name = a.name + "[" + idx + "]";
    e->el = a.el;
    e->pou = a.pou;
    e->constant = false;
    e->frame = a.frame;
    e->section = "array";
    type_of_var(*e, bt, 0);
    if (e->struct_el) {  // an array of structures: each element's members, a[k].m
      if (k < struct_inits.size() && struct_inits[k]) e->init_el = struct_inits[k];
      Var* raw = e.get();
      a.elems.push_back(raw);
      keep(std::move(e));
      expand(*raw, stack);
      continue;
    }
    if (e->derived && fb_instance_type(e->type)) {  // an array of FB instances: each an instance, a[k].Q
      if (k < inits.size() || (k < struct_inits.size() && struct_inits[k]))
        fail_at(a.array_el, "array '" + a.name + "' of " + e->type + " has initial values; an instance has none (" + a.array_el->path() + ")");
      Var* raw = e.get();
      a.elems.push_back(raw);
      keep(std::move(e));
      expand(*raw, stack);
      continue;
    }
    if (e->ty == Ty::None || e->derived)
      fail_at(a.array_el, "array '" + a.name + "' of " + e->type + ": ldc takes arrays of elementary types, structures and function-block instances (" +
                              a.array_el->path() + ")");
    if (k < inits.size()) e->init = inits[k];
    a.elems.push_back(e.get());
    keep(std::move(e));
  }
}

// Element `idx` ("3", "i", "1,2") of array a: a constant index is checked
// here and names its element; a variable one (one dimension) is checked at
// run time by IDX (a scan fault naming the POU, the line and the index, every
// engine alike; docs/faults.md) and read by LDX into a temporary.
// Member `member` (".m.n", or "") of array element e, as `expr` names it.
Var& Importer::element_member(Var& e, const std::string& member, const std::string& expr, const Element* el) {
  Var* v = &e;
  for (size_t at = 0; at < member.size();) {
    size_t next = member.find('.', at + 1);
    std::string seg = trim(member.substr(at + 1, next == std::string::npos ? std::string::npos : next - at - 1));
    auto it = v->members.find(upper(seg));
    if (!v->struct_el || it == v->members.end()) {
      std::string known;
      for (const auto& [k, mv] : v->members) known += (known.empty() ? "" : ", ") + mv->name.substr(mv->name.rfind('.') + 1);
      fail_at(el, "'" + expr + "': " + (v->struct_el ? v->type + " has no variable '" + seg + "' (it has " + known + ")"
                                                     : "'" + v->name + "' is " + v->type + ", not a structure") +
                      " in " + where(el));
    }
    v = it->second;
    at = next == std::string::npos ? member.size() : next;
  }
  if (v->struct_el) fail_at(el, "'" + expr + "' is a whole structure; name one of its members (" + where(el) + ")");
  return *v;
}

Val Importer::element(Var& a, const std::string& idx, const std::string& member, const Element* el, bool write) {
  const std::string expr = a.name + "[" + idx + "]" + member;
  if (member.empty() && !a.elems.empty() && a.elems[0]->struct_el)
    fail_at(el, "'" + expr + "' is a whole structure; name one of its members (" + where(el) + ")");
  if (!a.elems.empty() && a.elems[0]->derived && !a.elems[0]->struct_el) {  // an array of FB instances: a[i].OUT at constant indices
    if (member.empty()) fail_at(el, "'" + expr + "' is a whole instance; name one of its outputs (" + where(el) + ")");
    Var& inst = instance_element(a, idx, el);
    if (inst.container()) return var_val(element_member(inst, member, expr, el));
    return fb_output(inst, expr, upper(member.substr(1)), el, write);
  }
  if (!member.empty() && !a.elems.empty() && !a.elems[0]->struct_el)
    fail_at(el, "'" + expr + "': the elements of '" + a.name + "' are " + a.elems[0]->type + ", not structures (" + where(el) + ")");
  std::vector<std::string> parts;
  for (size_t p = 0;;) {
    size_t c = idx.find(',', p);
    parts.push_back(trim(idx.substr(p, c == std::string::npos ? std::string::npos : c - p)));
    if (c == std::string::npos) break;
    p = c + 1;
  }
  if (parts.size() != a.dims.size())
    fail_at(el, "'" + a.name + "[" + idx + "]': the array has " + std::to_string(a.dims.size()) + " dimension" + (a.dims.size() == 1 ? "" : "s") + " (" + where(el) + ")");
  uint64_t k = 0;
  bool constant = true;
  std::vector<Val> vals;
  for (size_t j = 0; j < parts.size(); j++) {
    Val v = read_of(parts[j], el, false);
    vals.push_back(v);
    if (v.ty != Ty::Int || !is_int_type(type_of(v)) || ty_info(type_of(v)).kind == TyKind::Time)
      fail_at(el, "index '" + parts[j] + "' of '" + a.name + "' is not an integer (" + where(el) + ")");
    if (!is_const(v.o)) {
      constant = false;
      continue;
    }
    int64_t i = int64_t(const_bits(v));
    auto [lo, hi] = a.dims[j];
    if (i < lo || i > hi)
      fail_at(el, "index " + std::to_string(i) + " is outside " + std::to_string(lo) + ".." + std::to_string(hi) + " of array '" + a.name + "' (" + where(el) + ")");
    k = k * uint64_t(int64_t(hi) - lo + 1) + uint64_t(i - lo);
  }
  if (constant) {
    Var& e = element_member(*a.elems[k], member, expr, el);
    if (!e.dev) fail_at(el, "array '" + a.name + "' has no devices");
    Val r = var_val(e);
    return r;
  }
  if (a.dims.size() != 1)
    fail_at(el, "'" + a.name + "[" + idx + "]': ldc takes a variable index into one-dimensional arrays only (" + where(el) + ")");
  if (write && pending_store_) fail_at(el, "'" + a.name + "[" + idx + "]': one element at a variable index per statement (" + where(el) + ")");
  Var& first = element_member(*a.elems[0], member, expr, el);
  IT t = first.it;
  Operand base = var_val(first).o;
  uint32_t stride = first.ty == Ty::Wide ? 2 : 1;
  if (!member.empty() && a.elems.size() > 1) {  // the member of every element, a stride apart
    stride = element_member(*a.elems[1], member, expr, el).dev->index - first.dev->index;
    for (size_t j = 0; j < a.elems.size(); j++) {
      const Var& m = element_member(*a.elems[j], member, expr, el);
      if (!m.dev || m.dev->dev != first.dev->dev || m.dev->index != first.dev->index + uint32_t(j) * stride)
        fail_at(el, "'" + expr + "': member " + member.substr(1) + " of its elements does not lie a fixed stride apart, as a variable index needs (" +
                        where(el) + ")");
    }
  }
  Operand r = temp_of(t, el);
  IT it = type_of(vals[0]);
  std::vector<TreeNode> acts;
  Operand at = is_const(vals[0].o) ? Operand::typed_const(const_bits(vals[0])) : vals[0].o;
  acts.push_back(tout(Op::TIDX, it, IT::None, {at, const_opd(a.dims[0].first), const_opd(a.dims[0].second)}, el));
  acts.push_back(tout(Op::TLDX, t, IT::None, {base, const_opd(int32_t(stride)), r}, el));
  // the power first, then both: nothing may come between an IDX and its LDX
  rung(Cond::of(leaf(Op::TRUE, {}, el, "TRUE")), fork_of(std::move(acts)), el);
  // a write: the statement writes the copy (a set or reset coil keeps the rest
  // of its value), and store() puts it back, through IDX + STX again
  if (write) pending_store_ = [this, at, it, lo = a.dims[0].first, hi = a.dims[0].second, t, base, stride, r, el] {
    std::vector<TreeNode> st;
    st.push_back(tout(Op::TIDX, it, IT::None, {at, const_opd(lo), const_opd(hi)}, el));
    st.push_back(tout(Op::TSTX, t, IT::None, {r, base, const_opd(int32_t(stride))}, el));
    rung(Cond::of(leaf(Op::TRUE, {}, el, "TRUE")), fork_of(std::move(st)), el);
  };
  return Val{r, first.ty, t};
}

// A variable with members: a structure's, or an instance's of the project's FB.
void Importer::expand(Var& v, std::vector<std::string>& stack) {
  if (v.struct_el) return struct_members(v, stack);
  if (v.array_el) return array_elements(v, stack);
  if (!v.derived) return;
  if (const Element* fb = user_pou(v.type)) {
    if (pou_type(fb) != "functionBlock") fail_at(v.el, "variable '" + v.name + "' has the type of FUNCTION '" + v.type + "'; only a FUNCTION_BLOCK has instances");
    instantiate(v, fb, stack);
  }
}

// The project's FUNCTION_BLOCK or FUNCTION named `type`, else nullptr.
const Element* Importer::user_pou(const std::string& type) const {
  auto it = pou_el_.find(upper(type));
  if (it == pou_el_.end()) return nullptr;
  std::string k = pou_type(it->second);
  return k == "functionBlock" || k == "function" ? it->second : nullptr;
}

// The members of an instance of the project's FUNCTION_BLOCK `fb` (or of a
// FUNCTION's frame): every variable of its interface, named INSTANCE.MEMBER,
// nested instances too (`stack`: the FBs being instantiated, to refuse an FB
// that contains itself).  VAR_IN_OUT members are bound at each call; a
// VAR_EXTERNAL is the global of that name.
void Importer::instantiate(Var& inst, const Element* fb, std::vector<std::string>& stack) {
  std::string fname = *fb->attr("name");
  if (std::find(stack.begin(), stack.end(), upper(fname)) != stack.end()) {
    std::string cycle;
    for (auto it = std::find(stack.begin(), stack.end(), upper(fname)); it != stack.end(); ++it) cycle += *pou_el_.at(*it)->attr("name") + " -> ";
    fail_at(inst.el, "recursion: " + cycle + fname + " (function block '" + fname + "' contains an instance of itself, through '" + inst.name +
                         "'; an instance's memory would be infinite)");
  }
  stack.push_back(upper(fname));
  const Element* itf = fb->child("interface");
  if (!itf) {
    stack.pop_back();
    return;
  }
  for (const auto& sec : itf->children) {
    std::string s(sec->local_name());
    bool constant = sec->attr("constant") && (*sec->attr("constant") == "true" || *sec->attr("constant") == "1");
    if (s == "returnType") {
      if (sec->children.empty()) continue;
      auto u = std::make_unique<Var>();
      u->name = inst.name + "." + fname;
      u->el = sec.get();
      u->pou = inst.pou;
      const Element* te = sec->children[0].get();
      u->derived = te->local_name() == "derived";
      u->type = u->derived ? (te->attr("name") ? *te->attr("name") : "") : upper(te->local_name());
      u->it = u->derived ? IT::None : iec_type_named(u->type);
      u->ty = kind_of(u->it);
      u->section = s;
      u->frame = inst.frame;
      inst.members[upper(fname)] = u.get();
      keep(std::move(u));
      continue;
    }
    if (s != "inputVars" && s != "outputVars" && s != "inOutVars" && s != "localVars" && s != "tempVars" && s != "externalVars") {
      if (s != "documentation" && s != "addData") fail_at(sec.get(), "unknown interface section <" + sec->name + "> (" + sec->path() + ")");
      continue;
    }
    if (st_pou(fname) && s != "inputVars" && s != "outputVars" && s != "inOutVars") continue;  // the rest lives in the ST unit
    for (const Element* v : sec->children_named("variable")) {
      const std::string* nm = v->attr("name");
      if (!nm || nm->empty()) fail_at(v, "variable without a name (" + v->path() + ")");
      std::string key = upper(*nm);
      if (inst.members.count(key) || inst.inouts.count(key)) fail_at(v, "variable '" + *nm + "' is declared twice in POU '" + fname + "'");
      if (s == "inOutVars") {
        inst.inouts.insert(key);
        continue;
      }
      if (s == "externalVars") {
        auto g = globals_.find(key);
        if (g == globals_.end()) fail_at(v, "external variable '" + *nm + "' of POU '" + fname + "' is not a global variable of the project");
        inst.members[key] = g->second;
        continue;
      }
      auto u = make_var(v, inst.name + "." + *nm, inst.pou, constant);
      if (!u->address.empty())
        fail_at(v, "variable '" + *nm + "' of " + pou_type(fb) + " '" + fname + "' is located at " + u->address +
                       "; ldc locates the variables of programs and globals only");
      u->section = s;
      u->frame = inst.frame;
      Var* raw = u.get();
      keep(std::move(u));
      inst.members[key] = raw;
      expand(*raw, stack);
    }
  }
  stack.pop_back();
}

void Importer::declare(const Element* list, const std::string& pou, bool global) {
  bool constant = list->attr("constant") && (*list->attr("constant") == "true" || *list->attr("constant") == "1");
  for (const Element* v : list->children_named("variable")) {
    size_t kept = vars_.size();
    Var* raw = nullptr;
    bool ok = recover([&] {
      const std::string* nm = v->attr("name");
      if (!nm || nm->empty()) fail_at(v, "variable without a name (" + v->path() + ")");
      auto u = make_var(v, *nm, global ? "" : pou, constant);
      u->section = std::string(list->local_name());
      keep(std::move(u));
      std::string key = upper(*nm);
      if (global) {
        if (globals_.count(key)) fail_at(v, "global variable '" + *nm + "' is declared twice");
        globals_[key] = raw = vars_.back().get();
      } else {
        if (scope_.count(key)) fail_at(v, "variable '" + *nm + "' is declared twice in POU '" + pou + "'");
        scope_[key] = raw = vars_.back().get();
      }
      std::vector<std::string> stack;
      if (!global) stack.push_back(upper(pou));
      expand(*raw, stack);
    });
    if (ok) {
      if (!global && (list->local_name() == "localVars" || list->local_name() == "tempVars")) locals_.push_back(raw);
      continue;
    }
    // refused: forget it and what it made, and keep its uses quiet
    if (const std::string* nm = v->attr("name")) {
      std::string key = upper(*nm);
      auto& names = global ? globals_ : scope_;
      if (raw && names.count(key) && names[key] == raw) names.erase(key);
      failed_names_.insert(key);
    }
    vars_.resize(kept);
  }
}

// %IX0.1 %QX0.0 %MX1.2 %IW3 %QW0 %MW5 %MD2, and %I0.1 (no size: a bit).
std::optional<DeviceRef> Importer::location(const Var& v) {
  std::string a = upper(v.address);
  if (a.size() >= 3 && a[0] == '%' && (a[1] == 'I' || a[1] == 'Q' || a[1] == 'M') && std::isdigit((unsigned char)a[2]))
    a.insert(2, "X");
  std::string why;
  auto d = parse_iec_address(a, why);
  if (!d) fail_at(v.el, "variable '" + v.name + "': " + (why.empty() ? "unsupported location " + v.address : why));
  if (d->index >= device_count(d->dev))
    fail_at(v.el, "variable '" + v.name + "' at " + v.address + " is outside " + dev_name(d->dev) + "0.." + dev_name(d->dev) +
                      std::to_string(device_count(d->dev) - 1));
  bool bit = d->dev == Dev::X || d->dev == Dev::Y || d->dev == Dev::M;
  if (v.ty == Ty::Bool && !bit) fail_at(v.el, "BOOL variable '" + v.name + "' at " + v.address + ": a BOOL is located at a bit address (%IX, %QX, %MX)");
  if (v.ty == Ty::Int && (bit || d->dev == Dev::F))
    fail_at(v.el, v.type + " variable '" + v.name + "' at " + v.address + ": integers are located at %IW, %QW or %MW");
  if (v.ty == Ty::Real && d->dev != Dev::F) fail_at(v.el, "REAL variable '" + v.name + "' at " + v.address + ": a REAL is located at %MD");
  if (v.ty == Ty::Wide)
    fail_at(v.el, v.type + " variable '" + v.name + "' at " + v.address + ": ldc locates BOOL, integers of up to 32 bits and REAL; a 64-bit " +
                      "value takes two words, which no %I, %Q or %M address of ldc names");
  return d;
}

void Importer::allocate() {
  // located variables first, so the rest avoid their devices
  for (auto& v : vars_) {
    if (v->address.empty() || v->constant) continue;
    v->refused = !recover([&] {
      if (v->ty == Ty::None) fail_at(v->el, "variable '" + v->name + "' of type " + v->type + " cannot be located at " + v->address);
      v->dev = location(*v);
      used_.insert({int(v->dev->dev), v->dev->index});
    });
  }
  for (auto& v : vars_)
    if (!v->refused) place(*v);
}

// An unlocated variable's devices (a standard FB instance: its T, C or M).
void Importer::place(Var& v) {
  if (!v.elems.empty() && v.elems[0]->struct_el) return place_struct_elements(v);
  if (!v.elems.empty() && v.elems[0]->derived) return;  // FB instances: each placed as a variable of its own
  if (!v.elems.empty() && !v.elems[0]->dev) {  // an array: its elements in a row
    Var& e0 = *v.elems[0];
    uint32_t n = uint32_t(v.elems.size()), w = e0.ty == Ty::Wide ? 2 : 1;
    Dev d = e0.ty == Ty::Bool ? Dev::M : e0.ty == Ty::Real ? Dev::F : Dev::D;
    uint32_t at = take_run(d, n * w, v.el);
    for (uint32_t k = 0; k < n; k++) v.elems[k]->dev = DeviceRef{d, at + k * w};
    return;
  }
  if (v.dev || v.constant) return;
  if (v.derived) {
    FbKind k = fb_kind(v.type);
    if (k == FbKind::Timer) v.dev = DeviceRef{Dev::T, take(Dev::T, v.el)};
    else if (k == FbKind::Counter) {
      v.dev = DeviceRef{Dev::C, take(Dev::C, v.el)};
      if (v.type == "CTUD") v.aux = take(Dev::M, v.el), v.aux2 = take(Dev::M, v.el);
    } else if (k == FbKind::Typed && v.type != "SEMA") {  // CV's cells (RTC: CDT, OFFSET); Q (QU) and QD (PREV_IN) in M
      uint32_t cells = v.type == "RTC" ? 4 : ty_info(counter_width(v.type)).cells;
      v.dev = DeviceRef{Dev::D, take_run(Dev::D, cells, v.el)};
      v.aux = take(Dev::M, v.el), v.aux2 = take(Dev::M, v.el);
    } else if (k != FbKind::None) v.dev = DeviceRef{Dev::M, take(Dev::M, v.el)};
    return;  // other derived types get nothing (a user FB's instance: its members do); using them is an error
  }
  if (v.ty == Ty::Bool) v.dev = DeviceRef{Dev::M, take(Dev::M, v.el)};
  else if (v.ty == Ty::Int) v.dev = DeviceRef{Dev::D, take(Dev::D, v.el)};
  else if (v.ty == Ty::Wide) v.dev = DeviceRef{Dev::D, take_run(Dev::D, 2, v.el)};
  else if (v.ty == Ty::Real) v.dev = DeviceRef{Dev::F, take(Dev::F, v.el)};
}

// The scalars of a structure (or an array in one), in declaration order.
static void scalars(Var& v, std::vector<Var*>& out) {
  if (v.struct_el) {
    for (Var* m : v.member_order) scalars(*m, out);
  } else if (!v.elems.empty()) {
    for (Var* e : v.elems) scalars(*e, out);
  } else {
    out.push_back(&v);
  }
}

// An array of structures: each scalar member of every element in a row, one
// run per member (a[1].m, a[2].m ... a stride of one or two cells apart), so
// that an IDX + LDX at a variable index reaches the member of any element.
void Importer::place_struct_elements(Var& a) {
  std::vector<std::vector<Var*>> of(a.elems.size());
  for (size_t k = 0; k < a.elems.size(); k++) scalars(*a.elems[k], of[k]);
  const uint32_t n = uint32_t(a.elems.size());
  for (size_t j = 0; j < of[0].size(); j++) {
    const Var& m0 = *of[0][j];
    if (m0.dev || m0.constant || m0.ty == Ty::None || m0.derived) continue;  // (a standard FB in a structure: placed alone)
    const uint32_t w = m0.ty == Ty::Wide ? 2 : 1;
    const Dev d = m0.ty == Ty::Bool ? Dev::M : m0.ty == Ty::Real ? Dev::F : Dev::D;
    const uint32_t at = take_run(d, n * w, a.el);
    for (uint32_t k = 0; k < n; k++) of[k][j]->dev = DeviceRef{d, at + k * w};
  }
}

Var* Importer::lookup(const std::string& name) {
  std::string k = upper(name);
  Var* v = nullptr;
  if (auto it = scope_.find(k); it != scope_.end()) v = it->second;
  else if (auto it = globals_.find(k); it != globals_.end()) v = it->second;
  if (v && v->pou.empty() && task_ >= 0) global_users_[v].insert(task_);
  if (v) used_vars_.insert(v);
  return v;
}

// Aliases: each variable's name, or POU_name when the name is declared in more
// than one translated POU; names that spell an ldc device get none.
void Importer::aliases(TreeProgram& p) {
  std::map<std::string, int> count;
  for (auto& v : vars_)
    if (v->dev && !v->frame) count[upper(v->name)]++;
  std::set<std::string> seen;
  for (auto& v : vars_) {
    if (!v->dev || v->frame) continue;
    std::string name = count[upper(v->name)] > 1 && !v->pou.empty() ? v->pou + "_" + v->name : v->name;
    std::string why, u = upper(name);
    if (!is_alias_name(name) || u == "DT" || seen.count(u) || parse_device(name) || parse_iec_address(name, why)) continue;
    seen.insert(u);
    Alias a{name, *v->dev, v->it};  // typed: a watch shows it at its width (a BOOL is its bit either way)
    if (a.ty == IT::BOOL || !alias_type_problem(a).empty()) a.ty = IT::None;  // an FB's state: as its device
    p.aliases.push_back(std::move(a));
  }
  for (Alias& a : unit_aliases_)  // the members of ST and IL instances that have no variable here
    if (seen.insert(upper(a.name)).second) p.aliases.push_back(std::move(a));
  unit_aliases_.clear();
}

// ------------------------------------------------------------------ expressions

// A literal as a value (parse_iec_literal: TRUE, 42, 16#FF, 1.5, INT#5, T#1.5ms,
// LREAL#1e-9, D#2024-01-31 ...).  Untyped integers that fit INT32 (and based
// ones up to 32 bits, bit patterns: 16#FFFFFFFF is -1) and untyped reals stay
// the INT32 and REAL constants they always were, and take the type of what
// they meet; a typed literal has its type, held as that type is (kind_of).
std::optional<Val> Importer::literal(const std::string& s0, const Element* el) {
  std::string why;
  auto l = parse_iec_literal(trim(s0), why);
  if (!l) {
    if (!why.empty()) fail_at(el, why);
    return std::nullopt;
  }
  Val v;
  v.lit = *l;
  if (l->type == IT::BOOL) {
    v.ty = Ty::Bool, v.it = IT::BOOL, v.o = const_opd(int32_t(l->bits));
    return v;
  }
  if (!l->typed && l->is_real()) {
    v.ty = Ty::Real;
    v.o = Operand{OpdKind::ConstReal};
    v.o.fval = float(l->real());
    return v;
  }
  int64_t x = l->integer();
  bool int32 = x >= INT32_MIN && x <= INT32_MAX && l->type != IT::ULINT;
  if (!l->typed && (int32 || (l->based && l->bits <= 0xFFFFFFFFull))) {
    v.ty = Ty::Int, v.o = const_opd(int32_t(uint32_t(l->bits)));
    return v;
  }
  v.it = l->type;
  v.ty = kind_of(l->type);
  if (v.ty == Ty::Int) v.o = const_opd(int32_t(uint32_t(l->bits)));
  else if (v.ty == Ty::Real) v.o = Operand{OpdKind::ConstReal}, v.o.fval = typed::f32(l->bits);
  else v.o = Operand::typed_const(l->bits);
  return v;
}

// A constant of IEC type t (a constant's value converted as MatIEC's *_TO_*
// converts it): the canonical bits.
uint64_t Importer::const_as(const Val& v, IT t) {
  if (v.lit && !v.lit->typed && v.lit->is_real()) return typed::conv(t, IT::LREAL, v.lit->bits);  // an untyped real, exactly
  return typed::conv(t, type_of(v), const_bits(v));
}

// A constant held as type t is (the Val of a constant variable, an initial value).
Val Importer::const_val(const Val& v, IT t) {
  if (t == IT::None) return v;
  uint64_t b = const_as(v, t);
  Val r;
  r.it = t;
  r.ty = kind_of(t);
  r.lit = IecLiteral{t, true, b};
  if (r.ty == Ty::Bool || r.ty == Ty::Int) r.o = const_opd(int32_t(uint32_t(b)));
  else if (r.ty == Ty::Real) r.o = Operand{OpdKind::ConstReal}, r.o.fval = typed::f32(b);
  else r.o = Operand::typed_const(b);
  return r;
}

// A variable reference: NAME, INSTANCE.OUTPUT (TON0.Q, CTU0.CV, SR0.Q1) or a
// direct address; or a literal.
Val Importer::value_of(const std::string& expr, const Element* el, bool write) {
  Val v = read_of(expr, el, write);
  return write ? written(v, el) : v;
}

// value_of without the inputs' relays for writes (reads see them).
Val Importer::read_of(const std::string& expr, const Element* el, bool write) {
  std::string e = trim(expr);
  if (auto c = literal(e, el)) {
    if (write) fail_at(el, "'" + e + "' is a literal; it cannot be written (" + where(el) + ")");
    return *c;
  }
  if (!e.empty() && e[0] == '%') {
    std::string a = upper(e);
    std::string why;
    if (a.size() >= 3 && std::isdigit((unsigned char)a[2])) a.insert(2, "X");
    auto d = parse_iec_address(a, why);
    if (!d) fail_at(el, why.empty() ? "unsupported address " + e : why);
    if (d->index >= device_count(d->dev)) fail_at(el, "address " + e + " is out of range");
    Area ar = bit_area(d->dev);
    if (ar != Area::Count) return {shadowed(bit_opd(ar, d->index)), Ty::Bool};
    Area w = word_area(d->dev);
    return {shadowed(Operand{w == Area::F ? OpdKind::Real : OpdKind::Int, w, d->index}), w == Area::F ? Ty::Real : Ty::Int};
  }
  if (size_t lb = e.find('['), rb = e.find(']'); lb != std::string::npos && rb != std::string::npos && rb > lb &&
                                                 (rb + 1 == e.size() || e[rb + 1] == '.')) {  // an array element (a[i], a[i].m)
    std::string base = trim(e.substr(0, lb));
    Var* a = nullptr;
    if (base.find('.') == std::string::npos) a = lookup(base);
    else {
      std::string last;
      Var* c = member_path(base, el, &last);
      if (c && c->container() && c->members.count(upper(last))) a = c->members.at(upper(last));
    }
    if (!a) unknown_name(el, base, "unknown variable '" + base + "' in " + where(el));
    if (a->elems.empty()) fail_at(el, "'" + base + "' is not an array; '" + e + "' indexes it (" + where(el) + ")");
    return element(*a, e.substr(lb + 1, rb - lb - 1), e.substr(rb + 1), el, write);
  }
  size_t dot = e.find('.');
  Var* v = nullptr;
  if (dot != std::string::npos) {
    std::string last;
    Var* inst = member_path(e, el, &last);
    if (inst && inst->container()) {  // a member of a structure or of an instance of the project's own FB
      auto it = inst->members.find(upper(last));
      if (it == inst->members.end()) {
        if (inst->inouts.count(upper(last)))
          fail_at(el, "'" + e + "' is a VAR_IN_OUT of " + inst->type + ", bound to the caller's variable only during a call (" + where(el) + ")");
        std::string known;
        for (const auto& [k, mv] : inst->members) known += (known.empty() ? "" : ", ") + mv->name.substr(mv->name.rfind('.') + 1);
        fail_at(el, "'" + e + "': " + inst->type + " has no variable '" + last + "' (it has " + known + ") in " + where(el));
      }
      v = it->second;
      if (write && v->section == "outputVars")
        fail_at(el, "'" + e + "' is an output of " + inst->type + "; only its body writes it (" + where(el) + ")");
    }
  }
  if (!v && dot != std::string::npos) {
    std::string m;
    Var* inst = member_path(e, el, &m);
    m = upper(m);
    if (!inst)  // member_path found no variable named as the path's first part
      unknown_name(el, e.substr(0, dot), "'" + e + "' is not a variable ldc knows, nor an output of a function block instance, in " + where(el));
    return fb_output(*inst, e, m, el, write);
  }
  if (!v) v = lookup(e);
  if (!v) unknown_name(el, e, "unknown variable '" + e + "' in " + where(el));
  if (v->refused) throw Refused();
  if (v->constant) {
    if (write) fail_at(el, "'" + e + "' is a constant; it cannot be written (" + where(el) + ")");
    auto c = literal(v->init, v->el);
    if (!c) fail_at(v->el, "constant '" + v->name + "' needs a literal initial value");
    return v->it == IT::None ? *c : const_val(*c, v->it);
  }
  if (v->ty == Ty::None || !v->dev)
    fail_at(el, "variable '" + v->name + "' has type " + v->type + ", which ldc cannot hold (" + where(el) + ")");
  Val r = var_val(*v);
  r.o = shadowed(r.o);
  return r;
}

// Output `m` (upper case) of a standard FB instance, read as `e` (tmr.Q, ts[2].ET).
Val Importer::fb_output(Var& inst, const std::string& e, const std::string& m, const Element* el, bool write) {
  if (!inst.derived || fb_kind(inst.type) == FbKind::None || !inst.dev)
    fail_at(el, "'" + e + "' is not a variable ldc knows, nor an output of a function block instance, in " + where(el));
  if (write) fail_at(el, "'" + e + "' is a function block output; it cannot be written (" + where(el) + ")");
  FbKind k = fb_kind(inst.type);
  uint32_t i = inst.dev->index;
  if (k == FbKind::Timer && m == "Q") return {bit_opd(Area::TQ, i), Ty::Bool};
  if (k == FbKind::Timer && m == "ET") return {Operand{OpdKind::Int, Area::TW, i}, Ty::Int, IT::TIME, true};
  if (k == FbKind::Counter && m == "CV") return {Operand{OpdKind::Int, Area::CW, i}, Ty::Int, IT::INT};
  if (k == FbKind::Counter && (m == "Q" || m == "QU") && inst.type != "CTUD") return {bit_opd(Area::CQ, i), Ty::Bool};
  if (inst.type == "CTUD" && m == "QU") return {bit_opd(Area::M, inst.aux), Ty::Bool};
  if (inst.type == "CTUD" && m == "QD") return {bit_opd(Area::M, inst.aux2), Ty::Bool};
  if ((k == FbKind::Latch && m == "Q1") || (k == FbKind::Trig && m == "Q") || (inst.type == "SEMA" && m == "BUSY"))
    return {bit_opd(Area::M, i), Ty::Bool};
  if (inst.type == "RTC" && m == "Q") return {bit_opd(Area::M, inst.aux), Ty::Bool};
  if (inst.type == "RTC" && m == "CDT") return {Operand{OpdKind::Int, Area::D, i}, Ty::Wide, IT::DT};
  if (IT w = counter_width(inst.type); w != IT::None) {
    bool updown = inst.type.rfind("CTUD", 0) == 0;
    if (m == "CV") return {Operand{OpdKind::Int, Area::D, i}, kind_of(w), w};
    if (m == (updown ? "QU" : "Q")) return {bit_opd(Area::M, inst.aux), Ty::Bool};
    if (updown && m == "QD") return {bit_opd(Area::M, inst.aux2), Ty::Bool};
  }
  fail_at(el, "'" + e + "': " + inst.type + " has no output " + m);
}

// The instance a block names: a variable, or an element of an array of
// instances at constant indices (ts[2], grid[1, 3]); nullptr for an unknown name.
Var* Importer::instance_named(const std::string& name, const Element* el) {
  size_t lb = name.find('[');
  if (lb == std::string::npos) return lookup(name);
  Var* a = lookup(trim(name.substr(0, lb)));
  if (!a) return nullptr;
  size_t rb = name.rfind(']');
  if (rb == std::string::npos || rb < lb || trim(name.substr(rb + 1)) != "")
    fail_at(el, "instance '" + name + "' is not a variable or an element of an array (" + where(el) + ")");
  if (a->elems.empty() || !a->elems[0]->derived || a->elems[0]->struct_el)
    fail_at(el, "instance '" + name + "': '" + a->name + "' is not an array of function-block instances (" + where(el) + ")");
  return &instance_element(*a, name.substr(lb + 1, rb - lb - 1), el);
}

// Element `idx` ("2", "1, 3": constants only) of an array of instances.
Var& Importer::instance_element(Var& a, const std::string& idx, const Element* el) {
  uint64_t k = 0;
  size_t j = 0;
  for (size_t p = 0;; j++) {
    size_t c = idx.find(',', p);
    std::string part = trim(idx.substr(p, c == std::string::npos ? std::string::npos : c - p));
    auto lit = literal(part, el);
    if (!lit || !is_const(lit->o) || lit->ty != Ty::Int || !is_int_type(type_of(*lit)))
      fail_at(el, "'" + a.name + "[" + idx + "]': an instance of an array is chosen by constant indices in LD and FBD ('" + part +
                      "' is not one; ST takes a variable index) (" + where(el) + ")");
    if (j >= a.dims.size()) break;
    int64_t i = int64_t(const_bits(*lit));
    auto [lo, hi] = a.dims[j];
    if (i < lo || i > hi)
      fail_at(el, "index " + std::to_string(i) + " is outside " + std::to_string(lo) + ".." + std::to_string(hi) + " of array '" + a.name + "' (" + where(el) + ")");
    k = k * uint64_t(int64_t(hi) - lo + 1) + uint64_t(i - lo);
    if (c == std::string::npos) break;
    p = c + 1;
  }
  if (j + 1 != a.dims.size())
    fail_at(el, "'" + a.name + "[" + idx + "]': the array has " + std::to_string(a.dims.size()) + " dimension" + (a.dims.size() == 1 ? "" : "s") + " (" + where(el) + ")");
  return *a.elems[k];
}

// The instance whose member `expr` (A.B.C) names, following the members of
// the project's own FB instances: A.B, with *last = "C"; nullptr when A is no
// variable.
Var* Importer::member_path(const std::string& expr, const Element* el, std::string* last) {
  size_t dot = expr.find('.');
  Var* v = lookup(expr.substr(0, dot));
  while (v) {
    size_t next = expr.find('.', dot + 1);
    if (next == std::string::npos) {
      *last = expr.substr(dot + 1);
      return v;
    }
    std::string seg = expr.substr(dot + 1, next - dot - 1);
    auto it = v->members.find(upper(seg));
    if (!v->container() || it == v->members.end())
      fail_at(el, "'" + expr + "': '" + v->name + "' has no member '" + seg + "' (" + where(el) + ")");
    v = it->second;
    dot = next;
  }
  *last = expr.substr(dot + 1);
  return nullptr;
}

// A variable's device as a value.
Val Importer::var_val(const Var& v) {
  if (v.ty == Ty::Bool) return {bit_opd(bit_area(v.dev->dev), v.dev->index), Ty::Bool, IT::BOOL};
  Area w = word_area(v.dev->dev);
  return {Operand{v.ty == Ty::Real ? OpdKind::Real : OpdKind::Int, w, v.dev->index}, v.ty, v.it};
}

Operand Importer::bit_of(const std::string& expr, const Element* el, bool write) {
  Val v = value_of(expr, el, write);
  if (v.ty != Ty::Bool) fail_at(el, "'" + trim(expr) + "' is " + ty_name(v.ty) + "; a BOOL is needed for " + where(el));
  if (v.o.kind == OpdKind::ConstInt) fail_at(el, "a literal cannot be used by " + where(el));
  if (write) {
    if (v.o.area != Area::Y && v.o.area != Area::M) fail_at(el, "'" + trim(expr) + "' cannot be written (" + where(el) + ")");
  }
  return v.o;
}

std::string Importer::spell(const Operand& o) const { return spell_operand(o, spelled_); }

// ------------------------------------------------------------------ tree pieces

TreeNode Importer::leaf(Op op, std::vector<Operand> a, const Element* el, std::string text) {
  TreeNode n;
  n.kind = K::Leaf;
  n.elem.op = op;
  n.elem.loc = {el->line, el->col};
  for (size_t i = 0; i < a.size(); i++) n.elem.a[i] = a[i];
  if (!text.empty()) n.text = text;
  else {
    static const std::map<Op, const char*> cmp = {{Op::LDEQ, "=="}, {Op::LDNE, "<>"}, {Op::LDLT, "<"},
                                                  {Op::LDLE, "<="}, {Op::LDGT, ">"},  {Op::LDGE, ">="}};
    if (auto it = cmp.find(op); it != cmp.end()) n.text = spell(a[0]) + " " + it->second + " " + spell(a[1]);
    else n.text = std::string(op == Op::LOADN ? "/" : op == Op::LOADP ? "P " : op == Op::LOADF ? "N " : "") + spell(a[0]);
  }
  return n;
}

TreeNode Importer::out(Op op, std::vector<Operand> a, const Element* el, const std::string& text) {
  TreeNode n;
  n.kind = K::Output;
  n.elem.op = op;
  n.elem.loc = {el->line, el->col};
  std::string t = op == Op::OUT ? "" : op == Op::OUTN ? "/" : std::string(op_info(op).name) + " ";
  for (size_t i = 0; i < a.size(); i++) {
    n.elem.a[i] = a[i];
    t += (i ? " " : "") + (a[i].kind == OpdKind::Label ? a[i].label.str() : i == 0 && !text.empty() ? text : spell(a[i]));
  }
  n.text = t;
  return n;
}

// ------------------------------------------------------------------ typed values

// A temporary of IEC type t, as kind_of holds it.
Operand Importer::temp_of(IT t, const Element* el) {
  switch (kind_of(t)) {
    case Ty::Bool: return bit_opd(Area::M, temp_m(el));
    case Ty::Real: return Operand{OpdKind::Real, Area::F, take(Dev::F, el)};
    case Ty::Wide: return Operand{OpdKind::Int, Area::D, take_run(Dev::D, 2, el)};
    default: return Operand{OpdKind::Int, Area::D, take(Dev::D, el)};
  }
}

// An operand of a typed instruction of type t, as the IL text spells it.
std::string Importer::spell_typed(const Operand& o, IT t) const {
  if (o.kind == OpdKind::ConstT) return typed_const_text(t, o.bits());
  return spell(o);
}

// A typed instruction (ops.def class Typed): T is t, the source type u.
Instr Importer::typed_instr(Op op, IT t, IT u, std::vector<Operand> a, const Element* el, std::string& text) const {
  Instr in;
  in.op = op;
  in.ty = t;
  in.src = op_info(op).typed == 2 ? u : IT::None;
  in.loc = {el->line, el->col};
  text = std::string(op_info(op).name + 1) + "." + ty_info(t).name + (in.src != IT::None ? std::string(".") + ty_info(u).name : "");
  for (size_t i = 0; i < a.size(); i++) {
    in.a[i] = a[i];
    char sig = op_info(op).operands[i];
    text += " " + spell_typed(a[i], sig == 'x' ? u : t);
  }
  return in;
}
TreeNode Importer::tout(Op op, IT t, IT u, std::vector<Operand> a, const Element* el) {
  TreeNode n;
  n.kind = K::Output;
  n.elem = typed_instr(op, t, u, std::move(a), el, n.text);
  return n;
}
Cond Importer::tcmp(Op op, IT t, Operand a, Operand b, const Element* el) {
  TreeNode n;
  n.kind = K::Leaf;
  n.elem = typed_instr(op, t, IT::None, {a, b}, el, n.text);
  return Cond::of(std::move(n));
}

// v as an operand of type t: a constant of t; the device itself when a typed
// load of it as t is the value (an INT32 word holds every integer type of up
// to 32 bits canonically, so loading it as another such type is MatIEC's
// conversion); else converted into a temporary first (CONV.t.u).
Operand Importer::as_type(const Val& v, IT t, const Element* el) {
  if (is_const(v.o)) return Operand::typed_const(const_as(v, t));
  if (v.ms) return as_type(ns_of_ms(v, el), t, el);
  IT u = type_of(v);
  if (u == t && !v.ms) return v.o;
  if (kind_of(t) == Ty::Int && v.ty == Ty::Int && !v.ms && ty_info(t).kind != TyKind::Time) return v.o;
  Operand tmp = temp_of(t, el);
  rung(Cond::yes(), tout(Op::TCONV, t, u, {v.o, tmp}, el), el);
  return tmp;
}

// MatIEC computes in the type: a result narrower than 32 bits held in an
// INT32 word is wrapped to it (INT: the low 16 bits, sign-extended), with the
// untyped word instructions so that every engine runs it.
void Importer::wrap(Operand r, IT t, const Cond& en, const Element* el) {
  if (!is_int_type(t) || kind_of(t) != Ty::Int || ty_info(t).bits >= 32) return;
  int bits = ty_info(t).bits;
  uint32_t mask = (1u << bits) - 1, sign = 1u << (bits - 1);
  std::vector<TreeNode> acts;
  acts.push_back(out(Op::WAND, {r, const_opd(int32_t(mask)), r}, el));
  if (typed::is_signed(t)) {  // ((r & mask) ^ sign) - sign sign-extends
    acts.push_back(out(Op::WXOR, {r, const_opd(int32_t(sign)), r}, el));
    acts.push_back(out(Op::SUB, {r, const_opd(int32_t(sign)), r}, el));
  }
  rung(en, fork_of(std::move(acts)), el);
}

// Does every value of integer type a fit in b, so that no wrap is needed?
bool fits_in(IT a, IT b) {
  if (a == b) return true;
  if (kind_of(a) != Ty::Int || kind_of(b) != Ty::Int) return false;
  int ab = ty_info(a).bits, bb = ty_info(b).bits;
  bool as = typed::is_signed(a), bs = typed::is_signed(b);
  if (as == bs) return ab <= bb;
  return !as && bs && ab < bb;
}

// dst := a constant (folded to dst's type already).
TreeNode Importer::assign_node(const Val& k, const Val& dst, const Element* el) {
  if (dst.ty == Ty::Wide) return tout(Op::TMOVE, dst.it, IT::None, {k.o, dst.o}, el);
  return out(Op::MOV, {k.o, dst.o}, el);
}

// dst := v, converted to dst's type as MatIEC converts it.
void Importer::assign(const Val& v, const Val& dst, const std::string& dst_text, const Element* el) {
  IT dt = type_of(dst);
  if (is_const(v.o)) {
    Val k = dst.it == IT::None ? v : const_val(v, dst.it);
    if (dst.ty != Ty::Wide && k.ty == Ty::Wide) k = const_val(v, dt);
    TreeNode mv = assign_node(k, dst, el);
    if (dst.ty != Ty::Wide) mv.text = "MOV " + spell(k.o) + " " + dst_text;
    return rung(Cond::yes(), std::move(mv), el);
  }
  if (v.ms && dst.ty == Ty::Wide) return assign(ns_of_ms(v, el), dst, dst_text, el);
  IT st = type_of(v);
  if (dst.ty == Ty::Wide || v.ty == Ty::Wide || (dst.ty == Ty::Real && unsigned32(v.it))) {
    if (st == dt && !v.ms) return rung(Cond::yes(), tout(Op::TMOVE, dt, IT::None, {v.o, dst.o}, el), el);
    return rung(Cond::yes(), tout(Op::TCONV, dt, st, {v.o, dst.o}, el), el);
  }
  TreeNode mv = out(Op::MOV, {v.o, dst.o}, el);
  mv.text = "MOV " + spell(v.o) + " " + dst_text;
  rung(Cond::yes(), std::move(mv), el);
  if (dst.it != IT::None && !v.ms && v.ty == Ty::Int && !fits_in(st, dst.it)) wrap(dst.o, dst.it, Cond::yes(), el);
}

// A timer's preset in ms (ldc's timers count whole ms): a TIME of ns rounded
// up, so that the timer is done at the scan where MatIEC's elapsed time,
// which advances by whole ms here, reaches the preset.
Operand Importer::preset_ms(const Val& v, const Element* el) {
  if (v.ty == Ty::Int) return v.o;  // an untyped integer: ms, as before
  if (type_of(v) != IT::TIME) fail_at(el, "a timer's PT must be a TIME, not " + std::string(ty_info(type_of(v)).name) + " (" + el->path() + ")");
  if (is_const(v.o)) {
    int64_t ns = int64_t(const_bits(v));
    int64_t ms = ns <= 0 ? 0 : (ns + typed::kNsPerMs - 1) / typed::kNsPerMs;
    if (ms > INT32_MAX) fail_at(el, "a timer's PT is at most 2147483647 ms (" + el->path() + ")");
    return const_opd(int32_t(ms));
  }
  Operand up = temp_of(IT::TIME, el), ms{OpdKind::Int, Area::D, take(Dev::D, el)};
  rung(Cond::yes(), tout(Op::TADD, IT::TIME, IT::None, {v.o, Operand::typed_const(uint64_t(typed::kNsPerMs - 1)), up}, el), el);
  rung(Cond::yes(), tout(Op::TDIV, IT::LINT, IT::None, {up, Operand::typed_const(uint64_t(typed::kNsPerMs)), up}, el), el);
  rung(Cond::yes(), tout(Op::TCONV, IT::DINT, IT::LINT, {up, ms}, el), el);
  return ms;
}

// A timer's ET (INT32 ms) as a TIME of ns in a temporary: ms times 10^6, in
// LINT instructions on the TIME's two words (TIME_TO_DINT and DINT_TO_TIME
// are MatIEC's conversions, in seconds; this one is ldc's own unit change).
Val Importer::ns_of_ms(const Val& v, const Element* el) {
  Operand ns = temp_of(IT::TIME, el);
  rung(Cond::yes(), tout(Op::TCONV, IT::LINT, IT::DINT, {v.o, ns}, el), el);
  rung(Cond::yes(), tout(Op::TMUL, IT::LINT, IT::None, {ns, Operand::typed_const(uint64_t(typed::kNsPerMs)), ns}, el), el);
  return Val{ns, Ty::Wide, IT::TIME};
}

void Importer::rung(TreeNode root, const Element* el) {
  if (rungs_.size() >= kMaxRungs)  // calls expanded inline can multiply them
    fail_at(el, "the program needs more than " + std::to_string(kMaxRungs) + " rungs (calls of the project's POUs are expanded at each call) at " + where(el));
  TreeRung r;
  r.line = el->line;
  r.labels = std::move(pending_labels_);
  pending_labels_.clear();
  r.title = std::move(pending_title_);
  pending_title_.clear();
  r.root = std::move(root);
  rungs_.push_back(std::move(r));
}

// The condition's value now, in a relay of its own.
Cond Importer::materialize(Cond c, const Element* el) {
  if (c.k != Cond::Expr) return c;
  if (is_leaf(c) && c.n.elem.op == Op::LOAD && c.n.elem.a[0].area == Area::M && temps_.count(c.n.elem.a[0].index))
    return c;  // already a value of its own
  uint32_t m = temp_m(el);
  rung(std::move(c), out(Op::OUT, {bit_opd(Area::M, m)}, el), el);
  return bit_leaf(Op::LOAD, bit_opd(Area::M, m), el);
}

Cond Importer::negate(Cond c, const Element* el) {
  if (c.k == Cond::True) return Cond::no();
  if (c.k == Cond::False) return Cond::yes();
  if (is_leaf(c) && (c.n.elem.op == Op::LOAD || c.n.elem.op == Op::LOADN)) {
    c.n.elem.op = c.n.elem.op == Op::LOAD ? Op::LOADN : Op::LOAD;
    c.n.text = c.n.elem.op == Op::LOADN ? "/" + c.n.text : c.n.text.substr(1);
    return c;
  }
  Cond m = materialize(std::move(c), el);
  m.n.elem.op = Op::LOADN;
  m.n.text = "/" + m.n.text;
  return m;
}

// R_TRIG / F_TRIG of a condition, as a statement of its own (Beremiz calls the
// trigger instance before the statement that reads it).
//   R_TRIG: Q := CLK AND NOT M; M := CLK          (M starts FALSE)
//   F_TRIG: Q := NOT CLK AND NOT M; M := NOT CLK  (M starts TRUE in MatIEC as
//           OpenPLC ships it, so there is no pulse on the first scan)
// R_TRIG is LOADP of CLK; F_TRIG is LOADF of CLK (its edge memory holds CLK,
// starting FALSE, which is NOT M).  A constant CLK never falls; TRUE rises on
// the first scan.
Cond Importer::trigger(Cond c, bool rising, const Element* el, std::optional<Operand> into) {
  if (c.k != Cond::Expr) {
    Cond k = rising && c.k == Cond::True ? bit_leaf(Op::LOAD, bit_opd(Area::S, kBitFirstScan), el) : Cond::no();
    if (!into) return k;
    rung(std::move(k), out(Op::OUT, {*into}, el), el);
    return bit_leaf(Op::LOAD, *into, el);
  }
  uint32_t q = into ? into->index : temp_m(el);
  Cond x = is_leaf(c) && c.n.elem.op == Op::LOAD ? std::move(c) : materialize(std::move(c), el);
  x.n.elem.op = rising ? Op::LOADP : Op::LOADF;
  x.n.text = (rising ? "P " : "N ") + x.n.text;
  Operand qo = into ? *into : bit_opd(Area::M, q);
  rung(std::move(x), out(Op::OUT, {qo}, el), el);
  return bit_leaf(Op::LOAD, qo, el);
}

std::string Importer::new_label() { return "en" + std::to_string(++labels_); }

// ------------------------------------------------------------------ the body

void Importer::read_conns(const Element* cpi, std::vector<Conn>& outv) {
  if (!cpi) return;
  for (const Element* c : cpi->children_named("connection")) {
    Conn k;
    k.el = c;
    const std::string* r = c->attr("refLocalId");
    if (!r) fail_at(c, "connection without refLocalId (" + c->path() + ")");
    try {
      size_t used = 0;
      k.ref = std::stoi(*r, &used);
      if (used != r->size()) throw std::invalid_argument("");
    } catch (...) { fail_at(c, "bad refLocalId '" + *r + "' (" + c->path() + ")"); }
    if (auto p = c->attr("formalParameter")) k.param = *p, k.has_param = true;
    auto pos = c->children_named("position");
    if (!pos.empty()) {
      const Element* last = pos.back();
      if (last->attr("x") && last->attr("y")) {
        k.has_pos = true;
        k.px = std::atof(last->attr("x")->c_str());
        k.py = std::atof(last->attr("y")->c_str());
      }
    }
    outv.push_back(k);
  }
}

void Importer::read_node(const Element* e) {
  std::string k(e->local_name());
  if (sfc_mode_ && sfc_kinds().count(k)) return;  // the chart's own elements (sfc_body)
  static const std::set<std::string> known = {"leftPowerRail", "rightPowerRail", "contact", "coil", "block", "inVariable",
                                              "outVariable", "inOutVariable", "connector", "continuation", "comment"};
  if (!known.count(k)) {
    if (k == "jump" || k == "label" || k == "return")
      fail_at(e, "LD element '" + k + "' is not supported: ldc runs every statement of a POU on every scan (" + e->path() + ")");
    fail_at(e, "unknown LD element '" + k + "' (" + e->path() + ")");
  }
  if (k == "comment") return;
  Node n;
  n.el = e;
  n.kind = k;
  const std::string* id = e->attr("localId");
  if (!id) fail_at(e, k + " without a localId (" + e->path() + ")");
  try {
    size_t used = 0;
    n.id = std::stoi(*id, &used);
    if (used != id->size()) throw std::invalid_argument("");
  } catch (...) { fail_at(e, "bad localId '" + *id + "' (" + e->path() + ")"); }
  if (nodes_.count(n.id)) fail_at(e, "localId " + *id + " is used twice (" + e->path() + " and " + nodes_[n.id].el->path() + ")");
  if (auto o = e->attr("executionOrderId")) n.order = std::atoi(o->c_str());
  if (const Element* p = e->child("position")) {
    if (auto x = p->attr("x")) n.x = std::atof(x->c_str());
    if (auto y = p->attr("y")) n.y = std::atof(y->c_str());
  }
  auto flag = [&](const char* a) { auto v = e->attr(a); return v && (*v == "true" || *v == "1"); };
  n.negated = flag("negated");
  if (auto v = e->attr("edge")) n.edge = *v;
  if (auto v = e->attr("storage")) n.storage = *v;
  if (k == "contact" || k == "coil") {
    const Element* v = e->child("variable");
    if (!v || trim(v->text).empty()) fail_at(e, k + " localId " + *id + " has no variable (" + e->path() + ")");
    n.text = trim(v->text);
  } else if (k == "inVariable" || k == "outVariable" || k == "inOutVariable") {
    const Element* x = e->child("expression");
    if (!x || trim(x->text).empty()) fail_at(e, k + " localId " + *id + " has no expression (" + e->path() + ")");
    n.text = trim(x->text);
    if (k == "inOutVariable") {
      n.negated = flag("negatedOut");
      n.negated_in = flag("negatedIn");
    }
  } else if (k == "connector" || k == "continuation") {
    if (!e->attr("name")) fail_at(e, k + " localId " + *id + " has no name (" + e->path() + ")");
    n.text = *e->attr("name");
  }
  if (k == "block") {
    if (!e->attr("typeName")) fail_at(e, "block localId " + *id + " has no typeName (" + e->path() + ")");
    n.type = *e->attr("typeName");
    if (auto in = e->attr("instanceName")) n.instance = *in;
    auto pins = [&](const char* list, std::vector<Pin>& v, bool input) {
      if (const Element* l = e->child(list))
        for (const Element* pv : l->children_named("variable")) {
          Pin p;
          p.el = pv;
          if (!pv->attr("formalParameter")) fail_at(pv, "block variable without formalParameter (" + pv->path() + ")");
          p.name = *pv->attr("formalParameter");
          p.negated = pv->attr("negated") && (*pv->attr("negated") == "true" || *pv->attr("negated") == "1");
          if (auto ed = pv->attr("edge")) p.edge = *ed;
          if (input) read_conns(pv->child("connectionPointIn"), p.conns);
          else if (const Element* cpo = pv->child("connectionPointOut"))
            if (const Element* rp = cpo->child("relPosition")) {
              if (auto x = rp->attr("x")) p.rx = std::atof(x->c_str());
              if (auto y = rp->attr("y")) p.ry = std::atof(y->c_str());
            }
          v.push_back(std::move(p));
        }
    };
    pins("inputVariables", n.inputs, true);
    pins("outputVariables", n.outputs, false);
    pins("inOutVariables", n.inouts, true);
  } else {
    for (const Element* cpi : e->children_named("connectionPointIn")) read_conns(cpi, n.in);
  }
  if (k == "connector") connectors_[upper(n.text)] = n.id;
  nodes_[n.id] = std::move(n);
}

const Node& Importer::node(const Conn& c) {
  auto it = nodes_.find(c.ref);
  if (it == nodes_.end()) fail_at(c.el, "connection to localId " + std::to_string(c.ref) + ", which is not in this body (" + c.el->path() + ")");
  return it->second;
}

const Pin* Importer::out_pin(const Node& b, const Conn& c) {
  if (c.has_param) {
    for (const Pin& p : b.outputs)
      if (p.name == c.param) return &p;
    for (const Pin& p : b.inouts)
      if (p.name == c.param) return &p;
    if (c.param == "ENO") return nullptr;  // ENO need not be declared
    fail_at(c.el, "block " + b.type + " localId " + std::to_string(b.id) + " has no output '" + c.param + "' (" + c.el->path() + ")");
  }
  // Beremiz: an unnamed connection takes the output whose connection point is at its end
  const Pin* found = nullptr;
  for (const Pin& p : b.outputs)
    if (!c.has_pos || (b.x + p.rx == c.px && b.y + p.ry == c.py)) found = &p;
  if (!found) fail_at(c.el, "cannot tell which output of block " + b.type + " localId " + std::to_string(b.id) + " this connection uses; give it a formalParameter (" + c.el->path() + ")");
  return found;
}

// Does this source deliver power flow (BOOL) rather than a value?
bool Importer::is_bool_source(const Conn& c, int depth) {
  if (depth > 64) fail_at(c.el, "connectors or blocks nested too deeply, or in a loop (" + c.el->path() + ")");
  const Node& n = node(c);
  if (n.kind == "leftPowerRail" || n.kind == "contact" || n.kind == "coil") return true;
  if (n.kind == "inVariable" || n.kind == "inOutVariable") return value_of(n.text, n.el).ty == Ty::Bool;
  if (n.kind == "continuation") {
    auto it = connectors_.find(upper(n.text));
    if (it == connectors_.end()) fail_at(n.el, "continuation '" + n.text + "' has no connector of that name (" + n.el->path() + ")");
    const Node& k = nodes_.at(it->second);
    if (k.in.empty()) fail_at(k.el, "connector '" + k.text + "' is not connected (" + k.el->path() + ")");
    return is_bool_source(k.in[0], depth + 1);
  }
  if (n.kind == "block") {
    const Pin* p = out_pin(n, c);
    return out_is_bool(n, p ? p->name : "ENO", depth + 1);
  }
  fail_at(c.el, n.kind + " localId " + std::to_string(n.id) + " has no output to connect (" + c.el->path() + ")");
}

// A block calling one of the project's own POUs is refused by name, wherever
// it is first met (generating it, or asking the type of its output).
void Importer::refuse_user_pou(const Node& b) {
  auto lang = pou_lang_.find(upper(b.type));
  if (lang != pou_lang_.end())
    fail_at(b.el, "block '" + b.type + "' localId " + std::to_string(b.id) + (b.instance.empty() ? "" : " (instance " + b.instance + ")") +
                      " calls POU '" + b.type + "', written in " + lang->second +
                      "; ldc translates the standard blocks only, not calls of the project's own POUs (" + b.el->path() + ")");
}

bool Importer::out_is_bool(const Node& b, const std::string& pin, int depth) {
  std::string t = upper(b.type);
  if (pin == "ENO") return true;
  if (const Element* callee = user_pou(t); callee && fb_kind(t) == FbKind::None) return user_out_is_bool(b, callee, pin);
  if (fb_kind(t) == FbKind::None) refuse_user_pou(b);
  if (fb_kind(t) != FbKind::None) return !(pin == "ET" || pin == "CV");  // (CTU_ULINT ... too)
  static const std::set<std::string> cmp = {"GT", "GE", "EQ", "NE", "LE", "LT"};
  if (cmp.count(t)) return true;
  size_t to = t.find("_TO_");
  if (to != std::string::npos) return t.substr(to + 4) == "BOOL";
  if (t == "AND" || t == "OR" || t == "XOR" || t == "NOT" || t == "MOVE" || t == "SEL") {
    for (const Pin& p : b.inputs)
      if (p.name != "EN" && p.name != "G" && !p.conns.empty()) return is_bool_source(p.conns[0], depth + 1);
  }
  return false;
}

// The power flow from the left rail to `conns` (one input's connections), as a
// series/parallel tree.  Contacts are edges between junction nodes, every other
// source is an edge from the rail, several connections meet in a junction of
// their own; series/parallel reduction must leave one rail-to-input edge.
Cond Importer::bool_expr(const std::vector<Conn>& conns, bool order, const Element* consumer) {
  if (conns.empty()) fail_at(consumer, "nothing is connected to " + where(consumer));
  struct E {
    int from, to;
    Cond label;
    const Element* el;  // the contact, or nullptr for wires and sources
    bool alive = true;
  };
  std::vector<E> edges;
  int nn = 1;  // node 0: the left rail
  std::map<std::pair<int, std::string>, int> memo;
  std::set<int> visiting;
  std::function<int(const Conn&)> out_of;
  std::function<int(const std::vector<Conn>&, const Element*)> input_of = [&](const std::vector<Conn>& cs, const Element* who) {
    if (cs.empty()) fail_at(who, where(who) + " has no input connection");
    Nest leave{++nest_, 1};
    if (nest_ > kMaxNest) fail_at(who, "power flow too long (more than " + std::to_string(kMaxNest) + " elements in a row, a block counting as " + std::to_string(kBlockNest) + ") at " + where(who));
    if (cs.size() == 1) return out_of(cs[0]);
    int j = nn++;
    for (const Conn& c : cs) {
      int f = out_of(c);
      edges.push_back({f, j, Cond::yes(), nullptr});
    }
    return j;
  };
  out_of = [&](const Conn& c) -> int {
    const Node& n = node(c);
    std::pair<int, std::string> key{n.id, n.kind == "block" ? c.param : ""};
    if (auto it = memo.find(key); it != memo.end()) return it->second;
    int r;
    if (n.kind == "leftPowerRail") {
      r = 0;
    } else if (n.kind == "contact" || n.kind == "coil" || n.kind == "continuation") {
      if (visiting.count(n.id)) fail_at(n.el, "power flow loops back through " + where(n.el));
      visiting.insert(n.id);
      if (n.kind == "contact") {
        // Beremiz: NOT(var), else R_TRIG / F_TRIG of var, computed before the statement
        Operand b = bit_of(n.text, n.el, false);
        Cond lab = Cond::of(leaf(n.negated ? Op::LOADN : Op::LOAD, {b}, n.el, (n.negated ? "/" : "") + n.text));
        if (!n.negated && (n.edge == "rising" || n.edge == "falling")) lab = trigger(std::move(lab), n.edge == "rising", n.el);
        int from = input_of(n.in, n.el);
        r = nn++;
        edges.push_back({from, r, std::move(lab), n.el});
      } else if (n.kind == "coil") {
        r = input_of(n.in, n.el);  // power passes through a coil
      } else {
        auto it = connectors_.find(upper(n.text));
        if (it == connectors_.end()) fail_at(n.el, "continuation '" + n.text + "' has no connector of that name (" + n.el->path() + ")");
        const Node& k = nodes_.at(it->second);
        r = input_of(k.in, k.el);
      }
      visiting.erase(n.id);
    } else {
      Cond lab;
      if (n.kind == "inVariable" || n.kind == "inOutVariable") {
        Val v = value_of(n.text, n.el);
        bool untyped_01 = v.o.kind == OpdKind::ConstInt && (v.o.ival == 0 || v.o.ival == 1) &&
                          upper(n.text).find('#') == std::string::npos && literal(n.text, n.el);
        if (untyped_01) v.ty = Ty::Bool;  // MatIEC reads the literals 0 and 1 as BOOL where a BOOL is wanted
        if (v.ty != Ty::Bool) fail_at(n.el, "'" + n.text + "' is " + ty_name(v.ty) + " but feeds the power flow of " + where(consumer));
        if (v.o.kind == OpdKind::ConstInt) lab = (v.o.ival != 0) != n.negated ? Cond::yes() : Cond::no();
        else lab = Cond::of(leaf(n.negated ? Op::LOADN : Op::LOAD, {v.o}, n.el, (n.negated ? "/" : "") + n.text));
      } else if (n.kind == "block") {
        Out o = block_out(n, c, order);
        if (!o.boolean) fail_at(c.el, "a value output of block " + n.type + " localId " + std::to_string(n.id) + " feeds the power flow of " + where(consumer));
        lab = o.cond;
      } else {
        fail_at(c.el, n.kind + " localId " + std::to_string(n.id) + " has no output to connect (" + c.el->path() + ")");
      }
      r = nn++;
      edges.push_back({0, r, std::move(lab), nullptr});
    }
    memo[key] = r;
    return r;
  };
  int sink = nn++;
  for (const Conn& c : conns) edges.push_back({out_of(c), sink, Cond::yes(), nullptr});
  // Series/parallel reduction: the merges, in the order, of "join all parallel
  // edges, else the series node of lowest number, until nothing changes", kept
  // incremental so that a long power flow costs O(E log E), not O(E^3).
  {
    std::vector<int> indeg(nn), outdeg(nn);
    std::vector<std::vector<size_t>> ins(nn), outs(nn);  // edges by end; dead ones are skipped
    std::map<std::pair<int, int>, size_t> between;        // the alive edge of each (from, to)
    auto join_parallel = [&](size_t a, size_t b) {       // a < b, same ends: b joins a
      edges[a].label = c_or(std::move(edges[a].label), std::move(edges[b].label));
      if (!edges[a].el) edges[a].el = edges[b].el;
      edges[b].alive = false;
      outdeg[edges[a].from]--;
      indeg[edges[a].to]--;
    };
    for (size_t e = 0; e < edges.size(); e++) {
      outdeg[edges[e].from]++;
      indeg[edges[e].to]++;
      ins[edges[e].to].push_back(e);
      outs[edges[e].from].push_back(e);
      auto [it, fresh] = between.try_emplace({edges[e].from, edges[e].to}, e);
      if (!fresh) join_parallel(it->second, e);
    }
    auto series_node = [&](int v) { return v != 0 && v != sink && indeg[v] == 1 && outdeg[v] == 1; };
    std::set<int> ready;
    for (int v = 1; v < nn; v++)
      if (series_node(v)) ready.insert(v);
    auto alive = [&](const std::vector<size_t>& list, bool in, int v) {
      for (size_t e : list)
        if (edges[e].alive && (in ? edges[e].to : edges[e].from) == v) return e;
      return edges.size();  // not reached: degree 1 means one alive edge
    };
    while (!ready.empty()) {
      int v = *ready.begin();
      ready.erase(ready.begin());
      size_t i = alive(ins[v], true, v), o = alive(outs[v], false, v);
      int from = edges[i].from, to = edges[o].to;
      between.erase({from, v});
      between.erase({v, to});
      edges[i].label = c_and(std::move(edges[i].label), std::move(edges[o].label));
      edges[i].to = to;
      if (!edges[i].el) edges[i].el = edges[o].el;
      edges[o].alive = false;
      indeg[v] = outdeg[v] = 0;
      ins[to].push_back(i);
      auto [it, fresh] = between.try_emplace({from, to}, i);
      if (fresh) continue;
      size_t a = std::min(it->second, i), b = std::max(it->second, i);
      join_parallel(a, b);
      it->second = a;
      for (int x : {from, to})
        if (series_node(x)) ready.insert(x);
    }
  }
  std::vector<E*> left;
  for (auto& e : edges)
    if (e.alive) left.push_back(&e);
  if (left.size() == 1 && left[0]->from == 0 && left[0]->to == sink) return std::move(left[0]->label);
  return node_values(left, nn, sink, consumer);
}

// A power flow that does not reduce to series and parallel blocks (a bridge, a
// wired OR shared by several forks): each junction's value, in an order where
// every junction comes after those feeding it, goes into a relay of its own,
// the OR over its inputs of (value of the junction it comes from AND the
// contact).  The left rail is TRUE.  The statement then reads the sink's
// inputs the same way.  The graph is acyclic (loops were refused above).
template <typename E>
Cond Importer::node_values(std::vector<E*>& left, int nn, int sink, const Element* consumer) {
  std::vector<std::vector<E*>> into(nn);
  for (E* e : left) into[e->to].push_back(e);
  std::vector<int> order;
  std::vector<char> seen(nn);
  std::vector<std::pair<int, size_t>> stack{{sink, 0}};  // iterative depth-first walk towards the rail
  seen[sink] = 1;
  while (!stack.empty()) {
    auto& [v, k] = stack.back();
    if (k < into[v].size()) {
      int f = into[v][k++]->from;
      if (!seen[f]) { seen[f] = 1; stack.push_back({f, 0}); }
    } else {
      order.push_back(v);
      stack.pop_back();
    }
  }
  std::map<int, Operand> relay;
  auto edge_cond = [&](E* e) {
    Cond c = std::move(e->label);
    if (e->from == 0) return c;
    return c_and(bit_leaf(Op::LOAD, relay.at(e->from), consumer), std::move(c));
  };
  for (int v : order) {
    if (v == 0 || v == sink) continue;
    Cond c = Cond::no();
    for (E* e : into[v]) c = c_or(std::move(c), edge_cond(e));
    Operand m = bit_opd(Area::M, temp_m(consumer));
    rung(std::move(c), out(Op::OUT, {m}, consumer), consumer);
    relay[v] = m;
  }
  Cond r = Cond::no();
  for (E* e : into[sink]) r = c_or(std::move(r), edge_cond(e));
  return r;
}

Val Importer::value_expr(const std::vector<Conn>& conns, bool order, const Element* consumer, int depth) {
  if (depth > 64) fail_at(consumer, "connectors nested too deeply, or in a loop, at " + where(consumer));
  if (conns.empty()) fail_at(consumer, "nothing is connected to " + where(consumer));
  if (conns.size() > 1)
    fail_at(conns[1].el, where(consumer) + " takes a value: one connection, not " + std::to_string(conns.size()));
  const Conn& c = conns[0];
  const Node& n = node(c);
  if (n.kind == "inVariable" || n.kind == "inOutVariable") {
    Val v = value_of(n.text, n.el);
    if (v.ty == Ty::Bool) fail_at(n.el, "'" + n.text + "' is BOOL but " + where(consumer) + " takes a value");
    return v;
  }
  if (n.kind == "block") {
    Out o = block_out(n, c, order);
    if (o.boolean)
      fail_at(c.el, "a BOOL output of block " + n.type + " localId " + std::to_string(n.id) + " feeds " + where(consumer) + ", which takes a value");
    return o.val;
  }
  if (n.kind == "continuation") {
    auto it = connectors_.find(upper(n.text));
    if (it == connectors_.end()) fail_at(n.el, "continuation '" + n.text + "' has no connector of that name (" + n.el->path() + ")");
    const Node& k = nodes_.at(it->second);
    return value_expr(k.in, order, k.el, depth + 1);
  }
  fail_at(c.el, "power flow from " + where(n.el) + " feeds " + where(consumer) + ", which takes a value");
}

// A block output, generating the block first (Beremiz: on demand, unless the
// reading statement has its own execution order).
Out Importer::block_out(const Node& b, const Conn& c, bool order) {
  if (block_refused(b)) throw Refused();
  if (!order && !computed_.count(b.id)) {
    if (generating_.count(b.id)) fail_at(b.el, "block " + b.type + " localId " + std::to_string(b.id) + " feeds its own input through a loop of blocks");
    block(b);
  }
  const Pin* p = out_pin(b, c);
  std::string name = p ? p->name : "ENO";
  auto it = outs_.find({b.id, name});
  bool in_loop = generating_.count(b.id) > 0;
  const Element* callee = fb_kind(upper(b.type)) == FbKind::None ? user_pou(b.type) : nullptr;
  if (it == outs_.end() && (!computed_.count(b.id) || in_loop) && callee && pou_type(callee) == "functionBlock" && name != "ENO") {
    // the same for an instance of the project's own FB: its output variable
    Var* inst = b.instance.empty() ? nullptr : instance_named(b.instance, b.el);
    if (inst && inst->members.count(upper(name)) && inst->members.at(upper(name))->dev) {
      Val v = var_val(*inst->members.at(upper(name)));
      outs_[{b.id, name}] = v.ty == Ty::Bool ? Out{true, bit_leaf(Op::LOAD, v.o, b.el), {}} : Out{false, {}, v};
      it = outs_.find({b.id, name});
    }
  }
  if (it == outs_.end() && (!computed_.count(b.id) || in_loop) && fb_kind(upper(b.type)) != FbKind::None && name != "ENO") {
    // read before its execution order runs it, or where a loop of blocks closes
    // (Beremiz reads the instance's output there): a function block's outputs
    // are its devices, as they stand from the previous scan
    Var* inst = b.instance.empty() ? nullptr : instance_named(b.instance, b.el);
    if (inst && inst->dev) {
      Val v = fb_output(*inst, b.instance + "." + name, upper(name), b.el, false);
      outs_[{b.id, name}] = v.ty == Ty::Bool ? Out{true, bit_leaf(Op::LOAD, v.o, b.el), {}} : Out{false, {}, v};
      it = outs_.find({b.id, name});
    }
  }
  if (it == outs_.end()) {
    if (in_loop)
      fail_at(c.el, "block " + b.type + " localId " + std::to_string(b.id) + " feeds its own input through a loop of functions; only a function block's output can close a loop (" + c.el->path() + ")");
    if (!computed_.count(b.id))
      fail_at(c.el, "block " + b.type + " localId " + std::to_string(b.id) + " is read before its executionOrderId computes it (" + c.el->path() + ")");
    fail_at(c.el, "block " + b.type + " localId " + std::to_string(b.id) + " has no output '" + name + "' (" + c.el->path() + ")");
  }
  Out o = it->second;
  if (p && p->negated) {
    if (!o.boolean) fail_at(p->el, "a negated output must be BOOL (" + p->el->path() + ")");
    o.cond = negate(std::move(o.cond), b.el);
  }
  return o;
}

// ------------------------------------------------------------------ calls of the project's own POUs

// The pins of a block by name; absent pins have no connections.
struct Pins {
  const Node& b;
  const Pin* get(const std::string& n) const {
    for (const Pin& p : b.inputs)
      if (p.name == n) return &p;
    return nullptr;
  }
  bool has(const std::string& n) const {
    const Pin* p = get(n);
    return p && !p->conns.empty();
  }
};


// The declaration of variable `name` of POU `callee` (a FUNCTION's result:
// its returnType), with its section; nullptr if it has none of that name.
const Element* Importer::callee_var(const Element* callee, const std::string& name, std::string* section) {
  const Element* itf = callee->child("interface");
  if (!itf) return nullptr;
  for (const auto& sec : itf->children) {
    if (sec->local_name() == "returnType") {
      if (upper(name) == "OUT" || upper(name) == upper(*callee->attr("name"))) {
        *section = "returnType";
        return sec.get();
      }
      continue;
    }
    for (const Element* v : sec->children_named("variable"))
      if (v->attr("name") && upper(*v->attr("name")) == upper(name)) {
        *section = std::string(sec->local_name());
        return v;
      }
  }
  return nullptr;
}

// The LD or FBD body of the project's POU that block b calls; another
// language is refused, naming it.
const Element* Importer::callee_graph(const Node& b, const Element* callee) {
  if (st_pou(*callee->attr("name"))) return nullptr;  // compiled by the ST reader (st_call)
  const Element* body_el = callee->child("body");
  const Element* graph = body_el ? (body_el->child("LD") ? body_el->child("LD") : body_el->child("FBD")) : nullptr;
  if (!graph)
    fail_at(b.el, "block '" + b.type + "' localId " + std::to_string(b.id) + (b.instance.empty() ? "" : " (instance " + b.instance + ")") + " calls " +
                      (pou_type(callee) == "function" ? "function '" : "function block '") + *callee->attr("name") + "', written in " + pou_lang_[upper(*callee->attr("name"))] +
                      (pou_lang_[upper(*callee->attr("name"))].starts_with("SFC")
                           ? "; ldc compiles an SFC function block whose chart is text alone: conditions in inline ST, actions in ST or variables (" + b.el->path() + ")"
                           : "; ldc expands calls of the project's POUs written in LD, FBD, SFC, ST or IL (" + b.el->path() + ")"));
  return graph;
}

// Is output `pin` of a call of the project's POU `callee` BOOL?  (Its
// declared type; an in-out's is the variable's it is bound to.)
bool Importer::user_out_is_bool(const Node& b, const Element* callee, const std::string& pin) {
  callee_graph(b, callee);  // a body ldc does not expand is refused first, by name
  std::string section;
  const Element* d = callee_var(callee, pin, &section);
  if (!d) fail_at(b.el, "block " + b.type + " localId " + std::to_string(b.id) + ": POU '" + *callee->attr("name") + "' has no output '" + pin + "' (" + b.el->path() + ")");
  const Element* t = section == "returnType" ? d : d->child("type");
  return t && !t->children.empty() && t->children[0]->local_name() == "BOOL";
}

// A call of the project's own FUNCTION_BLOCK or FUNCTION, expanded inline as
// MatIEC runs it (docs/plcopen.md, section 5b): the connected inputs are
// copied into the instance (a FUNCTION's frame starts from its initial values
// at every call), EN off skips the body (ENO FALSE; an FB keeps its outputs, a
// FUNCTION returns its result's initial value), the body runs with the
// instance's variables for its names and VAR_IN_OUT bound to the caller's
// variables, and the outputs are the instance's variables after it.
void Importer::user_call(const Node& b, const Element* callee) {
  const Element* el = b.el;
  std::string cname = *callee->attr("name");
  std::string what = "block '" + b.type + "' localId " + std::to_string(b.id);
  bool is_fb = pou_type(callee) == "functionBlock";
  // recursion, by name (the bodies are expanded inline)
  if (auto it = std::find_if(call_stack_.begin(), call_stack_.end(), [&](const std::string& n) { return upper(n) == upper(cname); });
      it != call_stack_.end()) {
    std::string cycle;
    for (; it != call_stack_.end(); ++it) cycle += *it + " -> ";
    fail_at(el, "recursion: " + cycle + cname + " (" + what + "; POUs are expanded inline at each call, so a POU cannot call itself, directly or through others) (" +
                    el->path() + ")");
  }
  const Element* graph = callee_graph(b, callee);
  // the instance, or a fresh frame for this call of a FUNCTION
  Var* inst = nullptr;
  if (is_fb) {
    inst = b.instance.empty() ? nullptr : instance_named(b.instance, b.el);
    if (!inst) unknown_name(el, b.instance, what + " calls function block '" + cname + "' and needs an instance declared in the POU ('" + b.instance + "' is not) (" + el->path() + ")");
    if (!inst->derived || upper(inst->type) != upper(cname))
      fail_at(el, "instance '" + b.instance + "' is declared as " + inst->type + ", but " + what + " is a " + cname);
  } else {
    auto f = std::make_unique<Var>();
    f->name = cname + "@" + std::to_string(b.id);
    f->derived = true;
    f->type = cname;
    f->el = el;
    f->pou = pou_;
    f->frame = true;
    inst = f.get();
    keep(std::move(f));
    std::vector<std::string> stack;
    instantiate(*inst, callee, stack);
    std::vector<Var*> all;
    std::function<void(Var&)> walk = [&](Var& c) {
      for (auto& [k, m] : c.members)
        if (m->frame) all.push_back(m), walk(*m);  // not the globals its VAR_EXTERNAL names
    };
    walk(*inst);
    for (Var* m : all) place(*m);
    // MatIEC: a FUNCTION's variables (its result too) start from their initial values at every call
    for (Var* m : all) {
      if (!m->dev || m->constant) continue;
      Val zero{const_opd(0), Ty::Int};
      auto c = m->init.empty() ? std::optional<Val>(zero) : literal(m->init, m->el);
      if (!c) fail_at(m->el, "initial value '" + m->init + "' of '" + m->name + "' is not a literal");
      Val k = const_val(*c, m->it);
      if (m->ty == Ty::Bool) rung(Cond::yes(), out(k.o.ival ? Op::SET : Op::RST, {var_val(*m).o}, el), el);
      else rung(Cond::yes(), assign_node(k, var_val(*m), el), el);
    }
  }
  Pins pins{b};
  bool order = b.order > 0;
  Cond en = Cond::yes();
  if (pins.has("EN")) {
    const Pin* p = pins.get("EN");
    Cond c = bool_expr(p->conns, order, p->el);
    if (p->negated) c = negate(std::move(c), p->el);
    en = materialize(std::move(c), el);
  }
  // the connected inputs, in the order of the pins
  for (const Pin& p : b.inputs) {
    if (p.name == "EN" || p.conns.empty()) continue;
    auto it = inst->members.find(upper(p.name));
    std::string section;
    callee_var(callee, p.name, &section);
    if (it == inst->members.end() || section != "inputVars")
      fail_at(p.el, cname + " has no input '" + p.name + "' (" + p.el->path() + ")");
    Var& m = *it->second;
    if (!m.dev) fail_at(p.el, "input '" + p.name + "' of " + cname + " has type " + m.type + ", which ldc cannot hold (" + p.el->path() + ")");
    Val dst = var_val(m);
    if (m.ty == Ty::Bool) {
      if (!is_bool_source(p.conns[0])) fail_at(p.el, "input '" + p.name + "' of " + cname + " is BOOL but a value feeds it (" + p.el->path() + ")");
      Cond c = bool_expr(p.conns, order, p.el);
      if (p.negated) c = negate(std::move(c), p.el);
      else if (p.edge == "rising" || p.edge == "falling") c = trigger(std::move(c), p.edge == "rising", p.el);
      rung(std::move(c), out(Op::OUT, {dst.o}, p.el, m.name), p.el);
    } else {
      if (p.negated) fail_at(p.el, "a negated input must be BOOL (" + p.el->path() + ")");
      assign(value_expr(p.conns, order, p.el), dst, m.name, p.el);
    }
  }
  // VAR_IN_OUT: the caller's variable itself
  std::map<std::string, Var*> bound;
  for (const Pin& p : b.inouts) {
    if (!inst->inouts.count(upper(p.name))) fail_at(p.el, cname + " has no VAR_IN_OUT '" + p.name + "' (" + p.el->path() + ")");
    if (p.conns.size() != 1) fail_at(p.el, "in-out '" + p.name + "' of " + what + " needs one connection, a variable (" + p.el->path() + ")");
    const Node& src = node(p.conns[0]);
    if (src.kind != "inVariable" && src.kind != "inOutVariable")
      fail_at(p.el, "in-out '" + p.name + "' of " + what + " is passed by reference: connect a variable, not " + where(src.el));
    std::string last;
    Var* v = src.text.find('.') == std::string::npos ? lookup(src.text) : nullptr;
    if (!v && src.text.find('.') != std::string::npos)
      if (Var* c = member_path(src.text, src.el, &last); c && user_pou(c->type) && c->members.count(upper(last))) v = c->members.at(upper(last));
    if (!v || v->constant || (!v->dev && v->members.empty()))
      fail_at(p.el, "in-out '" + p.name + "' of " + what + " is passed by reference: '" + src.text + "' is not a variable ldc holds (" + p.el->path() + ")");
    bound[upper(p.name)] = v;
  }
  for (const std::string& io : inst->inouts)
    if (!bound.count(io)) fail_at(el, what + " leaves VAR_IN_OUT '" + io + "' of " + cname + " unconnected; MatIEC needs every in-out connected (" + el->path() + ")");
  std::string skip;
  if (en.k != Cond::True) {
    skip = new_label();
    Operand l{OpdKind::Label};
    l.label = skip;
    rung(negate(en, el), out(Op::JMP, {l}, el), el);
  }
  // the body, with the instance's variables for its names
  {
    Nest leave{nest_ += kBlockNest, kBlockNest};
    if (nest_ > kMaxNest) fail_at(el, "calls nested too deeply at " + where(el));
    CallerState caller(*this);
    scope_.clear();
    for (auto& [k, m] : inst->members) scope_[k] = m;
    for (auto& [k, v] : bound) scope_[k] = v;
    call_stack_.push_back(cname);
    pou_ = cname;
    sfc_mode_ = false;
    if (graph) body(graph, "call of " + cname + (is_fb ? " " + inst->name : ""));
    else st_call(b, callee, *inst, bound);
  }
  if (!skip.empty()) pending_labels_.push_back(skip);
  // the outputs: the instance's variables after the call
  for (const Pin& p : b.outputs) {
    if (p.name == "ENO") continue;
    std::string section;
    callee_var(callee, p.name, &section);
    auto it = inst->members.find(upper(section == "returnType" ? cname : p.name));
    if (it == inst->members.end() || (section != "outputVars" && section != "returnType"))
      fail_at(p.el, cname + " has no output '" + p.name + "' (" + p.el->path() + ")");
    Var& m = *it->second;
    if (!m.dev) fail_at(p.el, "output '" + p.name + "' of " + cname + " has type " + m.type + ", which ldc cannot hold (" + p.el->path() + ")");
    Val v = var_val(m);
    outs_[{b.id, p.name}] = v.ty == Ty::Bool ? Out{true, bit_leaf(Op::LOAD, v.o, el), {}} : Out{false, {}, v};
  }
  for (const Pin& p : b.inouts) {
    Var* v = bound.at(upper(p.name));
    if (!v->dev) continue;
    Val r = var_val(*v);
    outs_[{b.id, p.name}] = r.ty == Ty::Bool ? Out{true, bit_leaf(Op::LOAD, r.o, el), {}} : Out{false, {}, r};
  }
  if (consumed_.count({b.id, "ENO"})) outs_[{b.id, "ENO"}] = Out{true, en, {}};
}

// A call of an ST or IL POU: its unit (compiled once per FB instance, once
// per call of a FUNCTION) spliced here.  The unit's program copies each pin
// (the instance's interface variable as this reader holds it) into the
// instance, calls it, and copies the inputs and outputs back, so an input the
// body changes keeps its value, as in MatIEC's instance.
void Importer::st_call(const Node& b, const Element* callee, Var& inst, const std::map<std::string, Var*>& bound) {
  bool is_fb = pou_type(callee) == "functionBlock";
  const std::string& cname = *callee->attr("name");
  std::vector<std::string> decl{"PROGRAM ldc__call", "VAR"}, in, out;
  if (is_fb) decl.push_back("ldc__i : " + cname + ";");
  std::string args, result, binding;
  int k = 0;
  // VAR_IN_OUT: the caller's variable, at its device
  for (const auto& [key, v] : bound) {
    std::string section;
    const Element* d = callee_var(callee, key, &section);
    if (!v->dev || !d || !d->child("type") || d->child("type")->children.empty())
      fail_at(b.el, "in-out '" + key + "' of " + cname + " is bound to '" + v->name + "', which is not a variable of an elementary type; ldc passes such variables to ST and IL POUs (" + b.el->path() + ")");
    std::string pin = "ldc__v" + std::to_string(k++);
    decl.push_back(pin + " AT " + dev_name(v->dev->dev) + std::to_string(v->dev->index) + " : " + plcopen::StText(text_).type(d->child("type")->children[0].get()) + ";");
    args += (args.empty() ? "" : ", ") + *d->attr("name") + " := " + pin;
    binding += v->name + ",";
  }
  if (is_fb) {
    auto it = units_.find(&inst);
    if (it != units_.end() && it->second.first != binding)
      fail_at(b.el, "instance '" + inst.name + "' of " + cname + " is called again with other variables for its in-outs; ldc compiles an ST or IL function block's instance once, so its in-outs must be bound to the same variables at every call (" + b.el->path() + ")");
    if (it != units_.end()) return splice(it->second.second, b.el);
  }
  for (const auto& [key, m] : inst.members) {
    if (!m->dev) continue;  // a type this reader does not hold: never connected (user_call refuses it)
    const Element* te = m->section == "returnType" ? m->el : m->el->child("type");
    std::string pin = "ldc__p" + std::to_string(k++);
    decl.push_back(pin + " AT " + dev_name(m->dev->dev) + std::to_string(m->dev->index) + " : " + plcopen::StText(text_).type(te->children[0].get()) + ";");
    std::string member = m->name.substr(m->name.rfind('.') + 1);
    if (m->section == "returnType") result = pin;
    else if (!is_fb) args += (args.empty() ? "" : ", ") + member + (m->section == "inputVars" ? " := " : " => ") + pin;
    else if (m->section == "inputVars") in.push_back("ldc__i." + member + " := " + pin + ";"), out.push_back(pin + " := ldc__i." + member + ";");
    else out.push_back(pin + " := ldc__i." + member + ";");
  }
  decl.push_back("END_VAR");
  globals_for_units(decl, "VAR");
  std::vector<std::string> lines = decl;
  lines.insert(lines.end(), in.begin(), in.end());
  if (is_fb) lines.push_back("ldc__i(" + args + ");");
  else lines.push_back((result.empty() ? "" : result + " := ") + cname + "(" + args + ");");
  lines.insert(lines.end(), out.begin(), out.end());
  lines.push_back("END_PROGRAM");
  iecil::Unit u = st_unit(lines, b.el);
  unit_init(u, inst.name, b.el);
  for (const Alias& a : u.prog.aliases)
    if (is_fb && a.name.rfind("ldc__i.", 0) == 0) unit_aliases_.push_back({inst.name + a.name.substr(6), a.dev, a.ty});
  splice(u, b.el);
  if (is_fb) units_.emplace(&inst, std::make_pair(binding, std::move(u)));
}

// The globals that the ST and IL POUs name in VAR_EXTERNAL, declared in the
// unit's program at this reader's devices (constants with their values), so
// that both readers use one variable.
void Importer::globals_for_units(std::vector<std::string>& decl, const char* section) {
  std::set<std::string> named;
  for (const auto& [u, pe] : pou_el_)
    if (st_pou(u))
      if (const Element* itf = pe->child("interface"))
        for (const Element* sec : itf->children_named("externalVars"))
          for (const Element* v : sec->children_named("variable"))
            if (v->attr("name")) named.insert(upper(*v->attr("name")));
  std::vector<std::string> vars, constants;
  for (const std::string& n : named) {
    auto g = globals_.find(n);
    if (g == globals_.end()) continue;  // the typed reader says which is missing
    const Var& v = *g->second;
    if (task_ >= 0) global_users_[g->second].insert(task_);  // for the check of globals shared by tasks (import)
    const Element* te = v.el->child("type");
    if (!te || te->children.empty()) continue;
    std::string ty = plcopen::StText(text_).type(te->children[0].get());
    if (v.constant && !v.init.empty()) constants.push_back(v.name + " : " + ty + " := " + v.init + ";");
    else if (v.dev) vars.push_back(v.name + " AT " + dev_name(v.dev->dev) + std::to_string(v.dev->index) + " : " + ty + ";");
  }
  if (!vars.empty()) decl.push_back(section), decl.insert(decl.end(), vars.begin(), vars.end()), decl.push_back("END_VAR");
  if (!constants.empty())
    decl.push_back(section + std::string(" CONSTANT")), decl.insert(decl.end(), constants.begin(), constants.end()), decl.push_back("END_VAR");
}

// An ST or IL program that a task runs: its unit, in a configuration of ours
// that gives it the project's globals it names, at this reader's devices.
void Importer::st_program(const Element* pou) {
  std::vector<std::string> lines{"CONFIGURATION ldc__config"};
  globals_for_units(lines, "VAR_GLOBAL");
  lines.push_back("RESOURCE ldc__resource ON PLC");
  lines.push_back("PROGRAM ldc__main : " + *pou->attr("name") + ";");
  lines.push_back("END_RESOURCE");
  lines.push_back("END_CONFIGURATION");
  iecil::Unit u = st_unit(lines, pou, pou);
  unit_init(u, *pou->attr("name"), pou);
  for (const Alias& a : u.prog.aliases) unit_aliases_.push_back(a);
  pending_title_ = "POU " + *pou->attr("name");
  splice(u, pou);
}

// An inline ST condition of an SFC transition (<inline><ST>).
// A condition written inline in ST computed into relay m by a unit of its
// own, whose names are the POU's variables, located where this reader holds them.
void Importer::st_condition(const Element* cond, uint32_t m) {
  const Element* in = cond->child("inline");
  std::vector<std::string> lines = unit_header("ldc__c", m);
  lines.push_back("ldc__c :=");
  lines.push_back(kInlineText);
  lines.push_back(";");
  lines.push_back("END_PROGRAM");
  splice(st_unit(lines, in, nullptr, plcopen::inline_st_text(cond)), in);
}

// The head of a unit of our own over the POU's variables, located where this
// reader holds them, and a BOOL `flag` at relay m.
std::vector<std::string> Importer::unit_header(const std::string& flag, uint32_t m) {
  std::vector<std::string> lines{"PROGRAM ldc__call", "VAR"};
  for (const auto& [key, v] : scope_) {
    if (!v->dev || v->derived || v->frame || !v->el) continue;
    const Element* te = v->section == "returnType" ? v->el : v->el->child("type");
    if (!te || te->children.empty()) continue;
    lines.push_back(v->name.substr(v->name.rfind('.') + 1) + " AT " + dev_name(v->dev->dev) + std::to_string(v->dev->index) + " : " +
                    plcopen::StText(text_).type(te->children[0].get()) + ";");
  }
  lines.push_back(flag + " AT M" + std::to_string(m) + " : BOOL;");
  lines.push_back("END_VAR");
  return lines;
}

// An SFC action body written in ST (`text`), run while relay m (its state) is on.
void Importer::st_action(const Element* text, uint32_t m, const Element* at) {
  std::vector<std::string> lines = unit_header("ldc__a", m);
  lines.push_back("IF ldc__a THEN");
  lines.push_back(kInlineText);
  lines.push_back("END_IF;");
  lines.push_back("END_PROGRAM");
  splice(st_unit(lines, at, nullptr, text), at);
}

// The first device of area d above every one this reader has taken.
uint32_t Importer::first_free(Dev d) const {
  auto it = used_.lower_bound({int(d) + 1, 0});
  if (it == used_.begin() || std::prev(it)->first != int(d)) return 0;
  return std::prev(it)->second + 1;
}

// The project's ST and IL FUNCTION_BLOCKs and FUNCTIONs, its data types, and
// `lines` (a program of ours, placed at `at`), compiled by the typed reader
// over devices above this reader's, which are then this reader's too.
iecil::Unit Importer::st_unit(const std::vector<std::string>& lines, const Element* at, const Element* program, const Element* text) {
  plcopen::StText st(text_);
  st.data_types(data_types_el_);
  for (const auto& [u, pe] : pou_el_)
    if (st_pou(u) && (pou_type(pe) != "program" || pe == program)) st.pou(pe);
  iecil::UnitBase base{first_free(Dev::M), first_free(Dev::D), first_free(Dev::T), {}};
  for (const std::string& l : lines) {
    if (l == kInlineText) {
      st.text(text);
      continue;
    }
    st.line(l, at);
    if (l.find(" AT ") != std::string::npos) base.callers.insert(upper(l.substr(0, l.find(' '))));  // ours: a pin or a global
  }
  iecil::Unit u;
  try {
    u = iecil::parse_typed_unit(st.tokens(), file_, base);
  } catch (const CompileError& e) {  // a name the ST side does not know: a graphical POU of the project?
    std::string m = e.what();
    if (m.rfind("unknown", 0) == 0)
      for (const auto& [un, pe] : pou_el_)
        if (!st_pou(un) && (m.find("'" + upper(*pe->attr("name")) + "'") != std::string::npos ||
                            m.find("'" + *pe->attr("name") + "'") != std::string::npos))
          throw CompileError(e.line, e.col, m + ": '" + *pe->attr("name") + "' is the project's POU written in " + pou_lang_[un] +
                                                ", which ldc does not call from ST or IL (it expands LD and FBD POUs where LD or FBD calls them)");
    throw;
  }
  for (uint32_t x = base.m; x < u.end.m; x++) used_.insert({int(Dev::M), x});
  for (uint32_t x = base.d; x < u.end.d; x++) used_.insert({int(Dev::D), x});
  for (uint32_t x = base.t; x < u.end.t; x++) used_.insert({int(Dev::T), x});
  return u;
}

// The unit's first rungs (initial values, RTC's clock), for the program's start.
void Importer::unit_init(const iecil::Unit& u, const std::string& whose, const Element* at) {
  for (size_t i = 0; i < u.init_rungs; i++) {
    TreeRung r;
    r.line = at->line;
    r.title = "initial values of " + whose;
    r.raw = u.prog.rungs[i].code;
    unit_init_.push_back(std::move(r));
  }
}

// The unit's call rungs here, its labels made this splice's own.
void Importer::splice(const iecil::Unit& u, const Element* at) {
  std::string pre = "_ldc_st" + std::to_string(++splices_) + "_";
  for (size_t i = u.init_rungs; i < u.prog.rungs.size(); i++) {
    if (rungs_.size() >= kMaxRungs) fail_at(at, "the program needs more than " + std::to_string(kMaxRungs) + " rungs (calls are expanded at each call) at " + where(at));
    const Rung& r = u.prog.rungs[i];
    TreeRung tr;
    tr.line = r.line;
    tr.labels = std::move(pending_labels_);
    pending_labels_.clear();
    for (const std::string& l : r.labels) tr.labels.push_back(pre + l);
    tr.title = std::move(pending_title_);
    pending_title_.clear();
    tr.raw = r.code;
    for (Instr& in : tr.raw)
      for (Operand& o : in.a)
        if (o.kind == OpdKind::Label) o.label = pre + o.label.str();
    rungs_.push_back(std::move(tr));
  }
  for (const std::string& l : u.prog.end_labels) pending_labels_.push_back(pre + l);
}

void Importer::block(const Node& b) {
  if (block_refused(b)) throw Refused();
  try {
    block_of(b);
  } catch (const CompileError&) {
    failed_blocks_.insert(b.el);  // its outputs' readers follow from this error
    throw;
  }
}

void Importer::block_of(const Node& b) {
  Nest leave{nest_ += kBlockNest, kBlockNest};
  if (nest_ > kMaxNest)
    fail_at(b.el, "blocks feed each other too deeply (more than " + std::to_string(kMaxNest / kBlockNest) + ", less with power flow between them) at " + where(b.el));
  computed_.insert(b.id);
  generating_.insert(b.id);
  std::string t = upper(b.type);
  if (fb_kind(t) != FbKind::None) {
    Var* inst = b.instance.empty() ? nullptr : instance_named(b.instance, b.el);
    if (!inst) unknown_name(b.el, b.instance, t + " block localId " + std::to_string(b.id) + " needs an instance declared in the POU ('" + b.instance + "' is not) (" + b.el->path() + ")");
    if (!inst->derived || upper(inst->type) != t)
      fail_at(b.el, "instance '" + b.instance + "' is declared as " + inst->type + ", but block localId " + std::to_string(b.id) + " is a " + t);
    if (!b.inouts.empty())
      fail_at(b.inouts[0].el, "block " + b.type + " localId " + std::to_string(b.id) + " has in-out parameters, which ldc takes for calls of the project's own POUs only (" +
                                  b.inouts[0].el->path() + ")");
    fb_block(b, *inst);
  } else if (const Element* callee = user_pou(t)) {
    user_call(b, callee);
  } else {
    if (!b.inouts.empty())
      fail_at(b.inouts[0].el, "block " + b.type + " localId " + std::to_string(b.id) + " has in-out parameters, which ldc takes for calls of the project's own POUs only (" +
                                  b.inouts[0].el->path() + ")");
    refuse_user_pou(b);
    fn_block(b);
  }
  generating_.erase(b.id);
}

void Importer::fb_block(const Node& b, Var& inst) {
  std::string t = upper(inst.type);
  Pins pins{b};
  bool order = b.order > 0;
  static const std::map<std::string, std::vector<std::string>> known = {
      {"TON", {"EN", "IN", "PT"}}, {"TOF", {"EN", "IN", "PT"}}, {"TP", {"EN", "IN", "PT"}},
      {"CTU", {"EN", "CU", "R", "PV"}}, {"CTD", {"EN", "CD", "LD", "PV"}}, {"CTUD", {"EN", "CU", "CD", "R", "LD", "PV"}},
      {"SR", {"EN", "S1", "R"}}, {"RS", {"EN", "S", "R1"}}, {"R_TRIG", {"EN", "CLK"}}, {"F_TRIG", {"EN", "CLK"}},
      {"SEMA", {"EN", "CLAIM", "RELEASE"}}, {"RTC", {"EN", "IN", "PDT"}}};
  IT width = counter_width(t);
  const std::vector<std::string>& inputs = known.at(width == IT::None ? t : t.substr(0, t.find('_')));
  for (const Pin& p : b.inputs)
    if (std::find(inputs.begin(), inputs.end(), p.name) == inputs.end())
      fail_at(p.el, t + " has no input '" + p.name + "' (" + p.el->path() + ")");
  // input conditions, with the pins' own negation and edge modifiers
  auto cond = [&](const std::string& n) -> Cond {
    const Pin* p = pins.get(n);
    if (!p || p->conns.empty()) return Cond::no();
    Cond c = bool_expr(p->conns, order, p->el);
    if (p->negated) c = negate(std::move(c), p->el);
    else if (p->edge == "rising" || p->edge == "falling") c = trigger(std::move(c), p->edge == "rising", p->el);
    return c;
  };
  auto value = [&](const std::string& n) -> Val {
    const Pin* p = pins.get(n);
    if (!p || p->conns.empty()) return {const_opd(0), Ty::Int};
    Val v = value_expr(p->conns, order, p->el);
    if (v.ty == Ty::Real) fail_at(p->el, n + " of " + t + " must be an integer or TIME, not REAL (" + p->el->path() + ")");
    if (n == "PV" && v.ty == Ty::Wide && width == IT::None)
      fail_at(p->el, "PV of " + t + " is an INT, not " + ty_info(type_of(v)).name + " (" + t + "_" + ty_info(type_of(v)).name +
                         " counts in that type) (" + p->el->path() + ")");
    return v;
  };
  // All inputs are evaluated first (their edge contacts and the blocks feeding
  // them run whatever EN says), then EN decides whether the block runs.
  uint32_t i = inst.dev->index;
  const Element* el = b.el;
  FbKind k = fb_kind(t);
  std::map<std::string, Cond> c;
  std::map<std::string, Val> v;
  Cond en = Cond::yes();
  for (const Pin& p : b.inputs) {
    if (p.name == "PT") v[p.name] = Val{preset_ms(value(p.name), p.el)};
    else if (p.name == "PV" || p.name == "PDT") v[p.name] = value(p.name);
    else if (p.name == "EN") en = materialize(cond("EN"), el);
    else c[p.name] = (k == FbKind::Latch || k == FbKind::Typed || p.name == "R" || p.name == "LD") ? materialize(cond(p.name), el) : cond(p.name);
  }
  auto in = [&](const std::string& n) { return c.count(n) ? c[n] : Cond::no(); };
  auto val = [&](const std::string& n) { return v.count(n) ? v[n] : Val{const_opd(0), Ty::Int}; };
  std::string skip;
  if (pins.has("EN")) {
    if (en.k != Cond::True) {
      skip = new_label();
      Operand l{OpdKind::Label};
      l.label = skip;
      rung(negate(en, el), out(Op::JMP, {l}, el), el);
    }
  }
  auto bool_out = [&](const std::string& pin, Operand o) { outs_[{b.id, pin}] = Out{true, bit_leaf(Op::LOAD, o, el), {}}; };
  // ET: TIME held in ms; CV: INT (MatIEC's CTU/CTD/CTUD)
  auto val_out = [&](const std::string& pin, Operand o) {
    outs_[{b.id, pin}] = Out{false, {}, pin == "ET" ? Val{o, Ty::Int, IT::TIME, true} : Val{o, Ty::Int, IT::INT}};
  };
  Operand cw{OpdKind::Int, Area::CW, i};
  Operand cn{OpdKind::Counter};
  cn.index = i;
  if (k == FbKind::Timer) {
    Operand tm{OpdKind::Timer};
    tm.index = i;
    // MatIEC's timers, as OpenPLC and Beremiz run them (docs/il.md, "MatIEC timers")
    rung(in("IN"), out(t == "TON" ? Op::MTON : t == "TOF" ? Op::MTOF : Op::MTP, {tm, val("PT").o}, el), el);
    bool_out("Q", bit_opd(Area::TQ, i));
    val_out("ET", Operand{OpdKind::Int, Area::TW, i});
  } else if (t == "CTU" || t == "CTD") {
    // MatIEC as OpenPLC ships it: IF R THEN CV := 0 ELSIF (edge of CU) AND CV < PV
    // THEN CV := CV + 1; Q := CV >= PV (CTD: IF LD THEN CV := PV ELSIF (edge of CD)
    // AND CV > 0 THEN CV := CV - 1; Q := CV <= 0).  Our CTU/CTD count on their
    // input's rising edge; the input here is already a one-scan pulse, so they
    // count exactly those edges, and compute Q on every scan.
    bool up = t == "CTU";
    Cond r = in(up ? "R" : "LD");
    Val pv = val("PV");
    if (r.k != Cond::False) rung(r, up ? out(Op::RSTC, {cn}, el) : out(Op::MOV, {pv.o, cw}, el), el);
    Cond pulse = trigger(in(up ? "CU" : "CD"), true, el);
    Cond limit = Cond::of(leaf(up ? Op::LDLT : Op::LDGT, {cw, up ? pv.o : const_opd(0)}, el));
    rung(c_and(c_and(std::move(pulse), negate(r, el)), std::move(limit)), out(up ? Op::CTU : Op::CTD, {cn, pv.o}, el), el);
    bool_out("Q", bit_opd(Area::CQ, i));
    val_out("CV", cw);
  } else if (t == "CTUD") {
    Cond r = in("R"), ld = in("LD");
    Cond eu = materialize(trigger(in("CU"), true, el), el), ed = materialize(trigger(in("CD"), true, el), el);
    Val pv = val("PV");
    if (r.k != Cond::False) rung(r, out(Op::RSTC, {cn}, el), el);
    Cond idle = c_and(negate(r, el), negate(ld, el));
    if (ld.k != Cond::False) rung(c_and(negate(r, el), ld), out(Op::MOV, {pv.o, cw}, el), el);
    // MatIEC: unless both edges come together, count up while CV < PV, else down while CV > 0
    rung(c_and(c_and(idle, c_and(eu, negate(ed, el))), Cond::of(leaf(Op::LDLT, {cw, pv.o}, el))),
         out(Op::ADD, {cw, const_opd(1), cw}, el), el);
    rung(c_and(c_and(idle, c_and(ed, negate(eu, el))), Cond::of(leaf(Op::LDGT, {cw, const_opd(0)}, el))),
         out(Op::SUB, {cw, const_opd(1), cw}, el), el);
    rung(Cond::of(leaf(Op::LDGE, {cw, pv.o}, el)), out(Op::OUT, {bit_opd(Area::M, inst.aux)}, el), el);
    rung(Cond::of(leaf(Op::LDLE, {cw, const_opd(0)}, el)), out(Op::OUT, {bit_opd(Area::M, inst.aux2)}, el), el);
    bool_out("QU", bit_opd(Area::M, inst.aux));
    bool_out("QD", bit_opd(Area::M, inst.aux2));
    val_out("CV", cw);
  } else if (width != IT::None) {
    typed_counter(t, width, inst, in, val("PV"), el);
    Operand cv{OpdKind::Int, Area::D, i};
    bool updown = t.rfind("CTUD", 0) == 0;
    bool_out(updown ? "QU" : "Q", bit_opd(Area::M, inst.aux));
    if (updown) bool_out("QD", bit_opd(Area::M, inst.aux2));
    outs_[{b.id, "CV"}] = Out{false, {}, Val{cv, kind_of(width), width}};
  } else if (t == "RTC") {
    // MatIEC's lib/rtc.txt, CURRENT_TIME the scan clock (docs/stdlib.md, "RTC"):
    // IF IN THEN (IF NOT PREV_IN THEN OFFSET := PDT - CURRENT_TIME); CDT := CURRENT_TIME + OFFSET
    // ELSE CDT := CURRENT_TIME; Q := IN; PREV_IN := IN  (DT and TIME in ns: LINT arithmetic)
    Operand cdt{OpdKind::Int, Area::D, i}, offset{OpdKind::Int, Area::D, i + 2}, clock = scan_clock(el);
    // PDT is a DT (MatIEC's type check refuses any other); unconnected, DT#1970-01-01-00:00:00
    if (const Pin* p = pins.get("PDT"); p && !p->conns.empty() && type_of(val("PDT")) != IT::DT)
      fail_at(p->el, "PDT of RTC must be a DT, not " + std::string(ty_info(type_of(val("PDT"))).name) + " (" + p->el->path() + ")");
    Operand q = bit_opd(Area::M, inst.aux), prev = bit_opd(Area::M, inst.aux2), pdt = as_type(val("PDT"), IT::DT, el);
    Cond on = in("IN");
    rung(c_and(on, bit_leaf(Op::LOADN, prev, el)), tout(Op::TSUB, IT::LINT, IT::None, {pdt, clock, offset}, el), el);
    rung(on, tout(Op::TADD, IT::LINT, IT::None, {clock, offset, cdt}, el), el);
    rung(negate(on, el), tout(Op::TMOVE, IT::DT, IT::None, {clock, cdt}, el), el);
    rung(on, out(Op::OUT, {q}, el), el);
    rung(on, out(Op::OUT, {prev}, el), el);
    bool_out("Q", q);
    outs_[{b.id, "CDT"}] = Out{false, {}, Val{cdt, Ty::Wide, IT::DT}};
  } else if (t == "SEMA") {
    // MatIEC's lib/sema.txt: Q_INTERNAL := CLAIM OR (Q_INTERNAL AND NOT RELEASE); BUSY := Q_INTERNAL
    Operand q = bit_opd(Area::M, i);
    Cond claim = in("CLAIM"), release = in("RELEASE");
    if (release.k != Cond::False) rung(release, out(Op::RST, {q}, el), el);
    if (claim.k != Cond::False) rung(claim, out(Op::SET, {q}, el), el);
    bool_out("BUSY", q);
  } else if (k == FbKind::Latch) {
    // SR: Q1 := S1 OR (NOT R AND Q1)    RS: Q1 := NOT R1 AND (S OR Q1)
    // (both inputs were read into relays before Q1 changes)
    Operand q = bit_opd(Area::M, i);
    Cond s = in(t == "SR" ? "S1" : "S"), r = in(t == "SR" ? "R" : "R1");
    if (t == "SR") {
      if (r.k != Cond::False) rung(r, out(Op::RST, {q}, el), el);
      if (s.k != Cond::False) rung(s, out(Op::SET, {q}, el), el);
    } else {
      if (s.k != Cond::False) rung(s, out(Op::SET, {q}, el), el);
      if (r.k != Cond::False) rung(r, out(Op::RST, {q}, el), el);
    }
    bool_out("Q1", q);
  } else {  // R_TRIG / F_TRIG: the instance's relay holds Q
    Operand q = bit_opd(Area::M, i);
    trigger(in("CLK"), t == "R_TRIG", el, q);
    bool_out("Q", q);
  }
  if (!skip.empty()) pending_labels_.push_back(skip);
  if (consumed_.count({b.id, "ENO"})) outs_[{b.id, "ENO"}] = Out{true, en, {}};
}

// MatIEC's counters of the other widths (lib/counter.txt), in typed
// instructions of their type w on CV's cells:
//   CTU   IF R THEN CV := 0 ELSIF (edge of CU) AND CV < PV THEN CV := CV + 1; Q := CV >= PV
//   CTD   IF LD THEN CV := PV ELSIF (edge of CD) AND CV > 0 THEN CV := CV - 1; Q := CV <= 0
//   CTUD  IF R THEN CV := 0 ELSIF LD THEN CV := PV ELSIF NOT (both edges) THEN
//         (up while CV < PV, else down while CV > 0); QU := CV >= PV; QD := CV <= 0
// CV stops at PV and at 0: it never wraps.  The edges are the counter's own
// R_TRIGs, evaluated at every call.
void Importer::typed_counter(const std::string& t, IT w, const Var& inst, const std::function<Cond(const std::string&)>& in,
                             const Val& pv_val, const Element* el) {
  Operand cv{OpdKind::Int, Area::D, inst.dev->index}, pv = as_type(pv_val, w, el);
  Operand zero = Operand::typed_const(0), one = Operand::typed_const(1);
  auto edge = [&](const char* n) { return materialize(trigger(in(n), true, el), el); };
  auto up = [&](Cond c) { rung(c_and(std::move(c), tcmp(Op::TLT, w, cv, pv, el)), tout(Op::TADD, w, IT::None, {cv, one, cv}, el), el); };
  auto down = [&](Cond c) { rung(c_and(std::move(c), tcmp(Op::TGT, w, cv, zero, el)), tout(Op::TSUB, w, IT::None, {cv, one, cv}, el), el); };
  auto flag = [&](Op rel, Operand b, uint32_t m) { rung(tcmp(rel, w, cv, b, el), out(Op::OUT, {bit_opd(Area::M, m)}, el), el); };
  if (t.rfind("CTUD", 0) == 0) {
    Cond ed = edge("CD"), eu = edge("CU"), r = in("R"), ld = in("LD");
    if (r.k != Cond::False) rung(r, tout(Op::TMOVE, w, IT::None, {zero, cv}, el), el);
    if (ld.k != Cond::False) rung(c_and(negate(r, el), ld), tout(Op::TMOVE, w, IT::None, {pv, cv}, el), el);
    Cond idle = c_and(negate(r, el), negate(ld, el));
    up(c_and(idle, c_and(eu, negate(ed, el))));
    down(c_and(idle, c_and(ed, negate(eu, el))));
    flag(Op::TGE, pv, inst.aux);
    flag(Op::TLE, zero, inst.aux2);
  } else if (t.rfind("CTU", 0) == 0) {
    Cond e = edge("CU"), r = in("R");
    if (r.k != Cond::False) rung(r, tout(Op::TMOVE, w, IT::None, {zero, cv}, el), el);
    up(c_and(e, negate(r, el)));
    flag(Op::TGE, pv, inst.aux);
  } else {
    Cond e = edge("CD"), ld = in("LD");
    if (ld.k != Cond::False) rung(ld, tout(Op::TMOVE, w, IT::None, {pv, cv}, el), el);
    down(c_and(e, negate(ld, el)));
    flag(Op::TLE, zero, inst.aux);
  }
}

// res := x rounded to the nearest integer, ties to even (MatIEC's REAL_TO_INT:
// x +/- 0.5 in LREAL, an exact integer result made even).  The move truncates;
// the fraction x - trunc(x) is exact in REAL below 2^23 (above, x is already
// an integer), and decides one step up or down.
void Importer::real_to_int(Operand x, Operand res, const Cond& en, const Element* el) {
  auto real_k = [](float f) { Operand k{OpdKind::ConstReal}; k.fval = f; return k; };
  Operand fr{OpdKind::Real, Area::F, take(Dev::F, el)};
  Operand odd{OpdKind::Int, Area::D, take(Dev::D, el)};
  rung(en, out(Op::MOV, {x, res}, el), el);
  rung(en, out(Op::SUB, {x, res, fr}, el), el);
  rung(en, out(Op::WAND, {res, const_opd(1), odd}, el), el);
  Cond small = c_and(Cond::of(leaf(Op::LDLT, {x, real_k(8388608.0f)}, el)), Cond::of(leaf(Op::LDGT, {x, real_k(-8388608.0f)}, el)));
  Cond is_odd = Cond::of(leaf(Op::LDNE, {odd, const_opd(0)}, el));
  auto step = [&](Op beyond, float half, Op op) {
    Cond c = c_or(Cond::of(leaf(beyond, {fr, real_k(half)}, el)), c_and(Cond::of(leaf(Op::LDEQ, {fr, real_k(half)}, el)), is_odd));
    rung(c_and(c_and(en, small), std::move(c)), out(op, {res, const_opd(1), res}, el), el);
  };
  step(Op::LDGT, 0.5f, Op::ADD);
  step(Op::LDLT, -0.5f, Op::SUB);
}

// SHL SHR ROL ROR (MatIEC: IN shifted in its own type, N modulo the width for
// the rotations; the result keeps the type's width).  The width comes from the
// declared type of the variable on IN: BYTE 8, WORD 16, else 32 (DWORD, or
// unknown: no mask).  Rotations need a BYTE, WORD or DWORD variable on IN.
void Importer::bit_shift(const std::string& t, const Pin& in_pin, Operand in, Operand n, Operand res, const Cond& en,
                         const Element* el) {
  int width = 32;
  bool known = false;
  if (in_pin.conns.size() == 1) {
    const Node& src = node(in_pin.conns[0]);
    if (src.kind == "inVariable" || src.kind == "inOutVariable")
      if (Var* v = lookup(trim(src.text)); v && !v->derived) {
        std::string ty = upper(v->type);
        known = ty == "BYTE" || ty == "WORD" || ty == "DWORD";
        width = ty == "BYTE" ? 8 : ty == "WORD" ? 16 : 32;
      }
  }
  int32_t mask = width == 32 ? -1 : int32_t((1u << width) - 1);
  if (t == "SHL" || t == "SHR") {
    rung(en, out(t == "SHL" ? Op::SHL : Op::SHR, {in, n, res}, el), el);
  } else {
    if (!known)
      fail_at(el, t + " needs a BYTE, WORD or DWORD variable on IN, to know the width it rotates in (" + el->path() + ")");
    Operand k{OpdKind::Int, Area::D, take(Dev::D, el)}, a{OpdKind::Int, Area::D, take(Dev::D, el)};
    bool left = t == "ROL";
    rung(en, out(Op::MOD, {n, const_opd(width), k}, el), el);  // N %= width
    rung(en, out(left ? Op::SHL : Op::SHR, {in, k, a}, el), el);
    rung(en, out(Op::SUB, {const_opd(width), k, k}, el), el);
    rung(en, out(left ? Op::SHR : Op::SHL, {in, k, res}, el), el);
    rung(en, out(Op::WOR, {a, res, res}, el), el);
  }
  if (width < 32) rung(en, out(Op::WAND, {res, const_opd(mask), res}, el), el);
}

// The type a function computes in (MatIEC: its inputs are of one type; an
// untyped literal takes it): the first typed input's; a timer's ET alone is
// TIME held in ms; None: untyped INT32 and REAL, as before.
IT common_type(const std::vector<Val>& v) {
  for (const Val& x : v)
    if (x.it != IT::None && !x.ms) return x.it;
  for (const Val& x : v)
    if (x.ms) return IT::TIME;
  return IT::None;
}

const std::set<std::string>& real_functions() {
  static const std::set<std::string> f = {"SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN", "EXPT"};
  return f;
}

// A standard function in typed instructions, of type T: every input as a T
// (as_type), the result a temporary of T, 0 when EN is off (as MatIEC's
// functions return).  Used where a 64-bit value takes part, where UDINT and
// DWORD need their unsigned order, for TIME arithmetic and for the REAL
// functions (SQRT ... EXPT).  `eno` is set where the function has its own.
Val Importer::typed_fn(const std::string& t, const std::string& time_op, const std::vector<Val>& v, const Pin* g, IT T, const Cond& en,
                       Cond& eno, const Element* el, const Node& b) {
  auto fail_type = [&](const std::string& what) {
    fail_at(el, t + " localId " + std::to_string(b.id) + " " + what + " (" + el->path() + ")");
  };
  if (!time_op.empty()) {  // MatIEC: TIME times or by a number, in ns
    Val tm = v.at(0), k = v.at(1);
    if (type_of(tm) != IT::TIME) fail_type("needs a TIME on IN1, not " + std::string(ty_info(type_of(tm)).name));
    Operand ns = as_type(tm, IT::TIME, el), res = temp_of(IT::TIME, el);
    if (en.k != Cond::True) rung(negate(en, el), tout(Op::TMOVE, IT::TIME, IT::None, {Operand::typed_const(0), res}, el), el);
    // MatIEC's __time_mul / __time_div, IN2 as an LREAL (ir/time_scale.h)
    Operand y = as_type(k, IT::LREAL, el);
    auto temp = [&](const char*, IT ty) { return temp_of(ty, el); };
    for (const TypedStep& st : time_scale_steps(time_op == "MUL_TIME", ns, y, res, temp))
      rung(en, tout(st.op, st.t, st.u, {st.a, st.b, st.c}, el), el);
    return Val{res, Ty::Wide, IT::TIME};
  }
  if (T == IT::None) T = IT::DINT;
  bool real_fn = real_functions().count(t) > 0;
  if (real_fn && !typed::is_real(T)) fail_type("takes REAL or LREAL inputs, not " + std::string(ty_info(T).name));
  Operand res = temp_of(T, el);
  auto zero = [&] { return Operand::typed_const(typed::conv(T, IT::DINT, 0)); };
  auto opd = [&](const Val& x) { return as_type(x, T, el); };
  if (en.k != Cond::True && t != "SEL") rung(negate(en, el), tout(Op::TMOVE, T, IT::None, {zero(), res}, el), el);
  auto need = [&](size_t n, bool exact) {
    if (v.size() < n || (exact && v.size() != n)) fail_type("takes " + std::to_string(n) + (exact ? "" : " or more") + " inputs");
  };
  static const std::map<std::string, Op> chain = {{"ADD", Op::TADD}, {"MUL", Op::TMUL}, {"MIN", Op::TMIN}, {"MAX", Op::TMAX},
                                                  {"AND", Op::TAND}, {"OR", Op::TOR},   {"XOR", Op::TXOR}};
  static const std::map<std::string, Op> two = {{"SUB", Op::TSUB}, {"DIV", Op::TDIV}, {"MOD", Op::TMOD}, {"EXPT", Op::TEXPT}};
  static const std::map<std::string, Op> one = {{"ABS", Op::TABS},   {"SQRT", Op::TSQRT}, {"LN", Op::TLN},     {"LOG", Op::TLOG},
                                                {"EXP", Op::TEXP},   {"SIN", Op::TSIN},   {"COS", Op::TCOS},   {"TAN", Op::TTAN},
                                                {"ASIN", Op::TASIN}, {"ACOS", Op::TACOS}, {"ATAN", Op::TATAN}, {"NOT", Op::TNOT},
                                                {"MOVE", Op::TMOVE}};
  static const std::map<std::string, Op> shifts = {{"SHL", Op::TSHL}, {"SHR", Op::TSHR}, {"ROL", Op::TROL}, {"ROR", Op::TROR}};
  auto allowed = [&](Op op) {
    if (!op_takes(op, T, op_info(op).typed == 2 ? IT::DINT : IT::None)) fail_type("is not defined on " + std::string(ty_info(T).name));
  };
  if (auto it = chain.find(t); it != chain.end()) {
    need(2, false);
    allowed(it->second);
    rung(en, tout(it->second, T, IT::None, {opd(v[0]), opd(v[1]), res}, el), el);
    for (size_t k = 2; k < v.size(); k++) rung(en, tout(it->second, T, IT::None, {res, opd(v[k]), res}, el), el);
  } else if (auto it2 = two.find(t); it2 != two.end()) {
    need(2, true);
    allowed(it2->second);
    Operand d = opd(v[1]);
    rung(en, tout(it2->second, T, IT::None, {opd(v[0]), d, res}, el), el);
    if (t == "DIV" && !typed::is_real(T)) eno = c_and(en, tcmp(Op::TNE, T, d, zero(), el));  // MatIEC: ENO FALSE by 0
  } else if (auto it3 = one.find(t); it3 != one.end()) {
    need(1, true);
    allowed(it3->second);
    rung(en, tout(it3->second, T, IT::None, {opd(v[0]), res}, el), el);
  } else if (auto it4 = shifts.find(t); it4 != shifts.end()) {
    need(2, true);
    IT u = type_of(v[1]);
    if (!op_takes(it4->second, T, u)) fail_type("shifts a bit string (BYTE WORD DWORD LWORD) by an integer, not " + std::string(ty_info(T).name));
    rung(en, tout(it4->second, T, u, {opd(v[0]), is_const(v[1].o) ? Operand::typed_const(const_as(v[1], u)) : v[1].o, res}, el), el);
  } else if (t == "SEL") {
    if (!g || v.size() != 2) fail_type("needs G, IN0 and IN1");
    if (en.k != Cond::True) rung(negate(en, el), tout(Op::TMOVE, T, IT::None, {zero(), res}, el), el);
    Operand a = opd(v[0]), c = opd(v[1]);
    Cond gc = materialize(bool_expr(g->conns, b.order > 0, g->el), el);
    rung(c_and(en, negate(gc, el)), tout(Op::TMOVE, T, IT::None, {a, res}, el), el);
    rung(c_and(en, gc), tout(Op::TMOVE, T, IT::None, {c, res}, el), el);
  } else if (t == "LIMIT") {  // IN > MN ? (IN < MX ? IN : MX) : MN
    need(3, true);
    Operand mn = opd(v[0]), in = opd(v[1]), mx = opd(v[2]);
    rung(c_and(en, tcmp(Op::TLE, T, in, mn, el)), tout(Op::TMOVE, T, IT::None, {mn, res}, el), el);
    rung(c_and(c_and(en, tcmp(Op::TGT, T, in, mn, el)), tcmp(Op::TGE, T, in, mx, el)), tout(Op::TMOVE, T, IT::None, {mx, res}, el), el);
    rung(c_and(c_and(en, tcmp(Op::TGT, T, in, mn, el)), tcmp(Op::TLT, T, in, mx, el)), tout(Op::TMOVE, T, IT::None, {in, res}, el), el);
  } else if (t == "MUX") {  // K selects IN0, IN1 ...; out of range: 0 and ENO FALSE
    if (v[0].ty != Ty::Int) fail_type("needs an integer K of up to 32 bits");
    rung(en, tout(Op::TMOVE, T, IT::None, {zero(), res}, el), el);
    Cond in_range = Cond::no();
    for (size_t k = 1; k < v.size(); k++) {
      Cond is_k = Cond::of(leaf(Op::LDEQ, {v[0].o, const_opd(int32_t(k - 1))}, el));
      rung(c_and(en, is_k), tout(Op::TMOVE, T, IT::None, {opd(v[k]), res}, el), el);
      in_range = c_or(std::move(in_range), std::move(is_k));
    }
    eno = c_and(en, std::move(in_range));
  } else {
    fail_type("is not defined on " + std::string(ty_info(T).name));
  }
  return Val{res, kind_of(T), T};
}

// X_TO_Y in typed instructions: MatIEC's conversion (ir/typed.h, CONV), and
// TRUNC (toward zero, to DINT).
Val Importer::typed_conv(IT to, IT from, const Val& v, const Cond& en, bool trunc, const Element* el) {
  Operand x = as_type(v, from, el), res = temp_of(to, el);
  if (en.k != Cond::True) rung(negate(en, el), tout(Op::TMOVE, to, IT::None, {Operand::typed_const(0), res}, el), el);
  rung(en, tout(trunc ? Op::TTRUNC : Op::TCONV, to, from, {x, res}, el), el);
  return Val{res, kind_of(to), to};
}

// MatIEC's BCD conversions (docs/stdlib.md): X_TO_BCD_Y, X_TO_BCD (the bit
// string of X's width), X_BCD_TO_Y, BCD_TO_Y (X the input's type).
struct BcdName {
  bool to_bcd = false;
  IT from = IT::None, to = IT::None;
};
std::optional<BcdName> bcd_parse(const std::string& t) {
  auto of_kind = [](const std::string& n, TyKind k) {
    IT x = iec_type_named(n);
    return x != IT::None && ty_info(x).kind == k ? x : IT::None;
  };
  static const std::map<IT, IT> same_width = {{IT::USINT, IT::BYTE}, {IT::UINT, IT::WORD}, {IT::UDINT, IT::DWORD}, {IT::ULINT, IT::LWORD}};
  if (size_t p = t.find("_TO_BCD"); p != std::string::npos && p > 0) {
    IT from = of_kind(t.substr(0, p), TyKind::Unsigned);
    std::string rest = t.substr(p + 7);
    IT to = rest.empty() && from != IT::None ? same_width.at(from) : rest.size() > 1 && rest[0] == '_' ? of_kind(rest.substr(1), TyKind::Bits) : IT::None;
    if (from == IT::None || to == IT::None) return std::nullopt;
    return BcdName{true, from, to};
  }
  if (t.rfind("BCD_TO_", 0) == 0) {
    IT to = of_kind(t.substr(7), TyKind::Unsigned);
    if (to == IT::None) return std::nullopt;
    return BcdName{false, IT::None, to};
  }
  if (size_t p = t.find("_BCD_TO_"); p != std::string::npos && p > 0) {
    IT from = of_kind(t.substr(0, p), TyKind::Bits), to = of_kind(t.substr(p + 8), TyKind::Unsigned);
    if (from == IT::None || to == IT::None) return std::nullopt;
    return BcdName{false, from, to};
  }
  return std::nullopt;
}
bool bcd_name(const std::string& t) { return bcd_parse(t).has_value(); }

// MatIEC's date arithmetic: __time_add / __time_sub of IN1 and IN2 (ns).
struct DateFn {
  IT in1, in2, out;
  bool add;
};
const std::map<std::string, DateFn>& date_fns() {
  static const std::map<std::string, DateFn> k = {
      {"ADD_TOD_TIME", {IT::TOD, IT::TIME, IT::TOD, true}},    {"ADD_DT_TIME", {IT::DT, IT::TIME, IT::DT, true}},
      {"SUB_TOD_TIME", {IT::TOD, IT::TIME, IT::TOD, false}},   {"SUB_DT_TIME", {IT::DT, IT::TIME, IT::DT, false}},
      {"SUB_DATE_DATE", {IT::DATE, IT::DATE, IT::TIME, false}}, {"SUB_TOD_TOD", {IT::TOD, IT::TOD, IT::TIME, false}},
      {"SUB_DT_DT", {IT::DT, IT::DT, IT::TIME, false}},         {"CONCAT_DATE_TOD", {IT::DATE, IT::TOD, IT::DT, true}}};
  return k;
}
bool date_fn_name(const std::string& t) { return date_fns().count(t) > 0; }

Val Importer::date_fn(const std::string& t, const std::vector<Val>& v, const Cond& en, const Element* el, const Node& b) {
  const DateFn& f = date_fns().at(t);
  if (v.size() != 2) fail_at(el, t + " localId " + std::to_string(b.id) + " takes 2 inputs (" + el->path() + ")");
  for (size_t k = 0; k < 2; k++) {
    IT want = k ? f.in2 : f.in1;
    if ((v[k].it != IT::None || v[k].ms) && type_of(v[k]) != want)
      fail_at(el, t + " localId " + std::to_string(b.id) + " takes " + ty_info(want).name + " on IN" + std::to_string(k + 1) + ", not " +
                      ty_info(type_of(v[k])).name + " (" + el->path() + ")");
  }
  Operand a = as_type(v[0], f.in1, el), c = as_type(v[1], f.in2, el), res = temp_of(f.out, el);
  if (en.k != Cond::True) rung(negate(en, el), tout(Op::TMOVE, f.out, IT::None, {Operand::typed_const(0), res}, el), el);
  rung(en, tout(f.add ? Op::TADD : Op::TSUB, IT::LINT, IT::None, {a, c, res}, el), el);  // ns: LINT arithmetic on the words
  return Val{res, Ty::Wide, f.out};
}

// __uint_to_bcd / __bcd_to_uint unrolled over the digits in 64-bit typed
// instructions; an invalid digit gives 0 and ENO FALSE (TEST_EN_COND).
Val Importer::bcd_fn(const std::string& t, const std::vector<Val>& v, const Cond& en, Cond& eno, const Element* el, const Node& b) {
  BcdName n = *bcd_parse(t);
  if (v.size() != 1) fail_at(el, t + " localId " + std::to_string(b.id) + " takes 1 input (" + el->path() + ")");
  IT from = n.from != IT::None ? n.from : v[0].it != IT::None ? type_of(v[0]) : IT::LWORD;
  if (ty_info(from).kind != (n.to_bcd ? TyKind::Unsigned : TyKind::Bits))
    fail_at(el, t + " localId " + std::to_string(b.id) + " takes " + (n.to_bcd ? "an unsigned integer" : "a bit string") + ", not " +
                    ty_info(from).name + " (" + el->path() + ")");
  if (v[0].it != IT::None && type_of(v[0]) != from)
    fail_at(el, t + " localId " + std::to_string(b.id) + " takes " + ty_info(from).name + ", not " + ty_info(type_of(v[0])).name + " (" + el->path() + ")");
  Operand x = temp_of(IT::ULINT, el), res = temp_of(IT::ULINT, el), dig = temp_of(IT::ULINT, el), out_res = temp_of(n.to, el);
  Operand in = as_type(v[0], from, el);
  auto k = [](uint64_t c) { return Operand::typed_const(c); };
  auto step = [&](Op op, IT ty, std::vector<Operand> a, IT u = IT::None) { rung(en, tout(op, ty, u, std::move(a), el), el); };
  if (en.k != Cond::True) rung(negate(en, el), tout(Op::TMOVE, n.to, IT::None, {k(0), out_res}, el), el);
  step(Op::TCONV, IT::ULINT, {in, x}, from);
  step(Op::TMOVE, IT::ULINT, {k(0), res});
  const int bits = ty_info(from).bits;
  if (n.to_bcd) {
    const int digits = bits == 8 ? 3 : bits == 16 ? 5 : bits == 32 ? 10 : 20;
    for (int d = 0; d < digits; d++) {
      step(Op::TMOD, IT::ULINT, {x, k(10), dig});
      step(Op::TDIV, IT::ULINT, {x, k(10), x});
      step(Op::TSHL, IT::LWORD, {dig, k(uint64_t(4 * d)), dig}, IT::USINT);  // a shift of 64 and more gives 0 (docs/stdlib.md)
      step(Op::TOR, IT::LWORD, {res, dig, res});
    }
    step(Op::TCONV, n.to, {res, out_res}, IT::LWORD);
    return Val{out_res, kind_of(n.to), n.to};
  }
  uint32_t bad = temp_m(el);
  rung(Cond::yes(), out(Op::RST, {bit_opd(Area::M, bad)}, el), el);
  for (int d = bits / 4 - 1; d >= 0; d--) {
    step(Op::TSHR, IT::LWORD, {x, k(uint64_t(4 * d)), dig}, IT::USINT);
    step(Op::TAND, IT::LWORD, {dig, k(15), dig});
    rung(c_and(en, tcmp(Op::TGT, IT::ULINT, dig, k(9), el)), out(Op::SET, {bit_opd(Area::M, bad)}, el), el);
    step(Op::TMUL, IT::ULINT, {res, k(10), res});
    step(Op::TADD, IT::ULINT, {res, dig, res});
  }
  step(Op::TCONV, n.to, {res, out_res}, IT::ULINT);
  rung(bit_leaf(Op::LOAD, bit_opd(Area::M, bad), el), tout(Op::TMOVE, n.to, IT::None, {k(0), out_res}, el), el);
  eno = c_and(eno, bit_leaf(Op::LOADN, bit_opd(Area::M, bad), el));
  return Val{out_res, kind_of(n.to), n.to};
}

void Importer::fn_block(const Node& b) {
  std::string t = upper(b.type);
  if (t == "ADD_TIME" || t == "SUB_TIME") t = t.substr(0, 3);  // ADD, SUB on TIME
  // TIME times or by a number (MatIEC: in ns)
  std::string time_op = t == "MUL_TIME" || t == "DIV_TIME" ? t : "";
  if (!time_op.empty()) t = t.substr(0, 3);
  bool trunc = t == "TRUNC";
  Pins pins{b};
  bool order = b.order > 0;
  const Element* el = b.el;
  static const std::set<std::string> cmp = {"GT", "GE", "EQ", "NE", "LE", "LT"};
  static const std::set<std::string> arith = {"ADD", "SUB", "MUL", "DIV", "MOD", "MAX", "MIN"};
  size_t to = t.find("_TO_");
  bool conv = to != std::string::npos || trunc;
  static const std::set<std::string> bits = {"SHL", "SHR", "ROL", "ROR"};
  bool extra = bcd_name(t) || date_fn_name(t);  // docs/stdlib.md
  if (extra) conv = false;
  if (!extra && !cmp.count(t) && !arith.count(t) && !conv && !bits.count(t) && !real_functions().count(t) && t != "MOVE" && t != "SEL" && t != "MUX" &&
      t != "LIMIT" && t != "ABS" && t != "AND" && t != "OR" && t != "XOR" && t != "NOT")
    fail_at(el, "block '" + b.type + "' localId " + std::to_string(b.id) + " is not supported: ldc translates TON TOF TP CTU CTD CTUD (and their _DINT _LINT _UDINT _ULINT forms) SR RS R_TRIG F_TRIG SEMA, "
                "GT GE EQ NE LE LT, ADD SUB MUL DIV MOD MAX MIN LIMIT ABS MOVE SEL MUX, "
                "SQRT LN LOG EXP EXPT SIN COS TAN ASIN ACOS ATAN, ADD_TIME SUB_TIME MUL_TIME DIV_TIME and the date arithmetic, AND OR XOR NOT SHL SHR ROL ROR, "
                "type conversions X_TO_Y, BCD and TRUNC: docs/stdlib.md (" + el->path() + ")");
  // inputs other than EN, in order
  std::vector<const Pin*> ins;
  for (const Pin& p : b.inputs)
    if (p.name != "EN") ins.push_back(&p);
  auto cond_of = [&](const Pin* p) {
    Cond c = bool_expr(p->conns, order, p->el);
    if (p->negated) c = negate(std::move(c), p->el);
    else if (p->edge == "rising" || p->edge == "falling") c = trigger(std::move(c), p->edge == "rising", p->el);
    return c;
  };
  auto val_of = [&](const Pin* p) {
    if (p->negated) fail_at(p->el, "a negated input must be BOOL (" + p->el->path() + ")");
    return value_expr(p->conns, order, p->el);
  };
  Cond en = Cond::yes();
  if (pins.has("EN")) en = materialize(cond_of(pins.get("EN")), el);
  Cond eno = en;
  for (const Pin* p : ins)
    if (p->conns.empty()) fail_at(p->el, "input " + p->name + " of " + t + " localId " + std::to_string(b.id) + " is not connected (" + p->el->path() + ")");
  if (extra) {  // BCD conversions, date arithmetic: typed instructions
    std::vector<Val> v;
    for (const Pin* p : ins) v.push_back(val_of(p));
    Val r = bcd_name(t) ? bcd_fn(t, v, en, eno, el, b) : date_fn(t, v, en, el, b);
    std::string name = "OUT";
    for (const Pin& p : b.outputs)
      if (p.name != "ENO") name = p.name;
    outs_[{b.id, name}] = Out{false, {}, r};
    if (consumed_.count({b.id, "ENO"})) outs_[{b.id, "ENO"}] = Out{true, materialize(eno, el), {}};
    return;
  }
  size_t want = t == "SEL" || t == "LIMIT" ? 3 : (conv || t == "NOT" || t == "MOVE" || t == "ABS" || (real_functions().count(t) && t != "EXPT")) ? 1
                : (t == "SUB" || t == "DIV" || t == "MOD" || t == "EXPT" || bits.count(t) || !time_op.empty()) ? 2 : 0;
  size_t n_in = ins.size();
  if ((want && n_in != want) || (!want && n_in < 2))
    fail_at(el, (time_op.empty() ? t : time_op) + " localId " + std::to_string(b.id) + " takes " + (want ? std::to_string(want) : std::string("two or more")) +
                    " input" + (want == 1 ? "" : "s") + ", not " + std::to_string(n_in) + " (" + el->path() + ")");
  bool boolean = out_is_bool(b, "OUT");
  std::string outname = "OUT";
  if (!b.outputs.empty()) {
    for (const Pin& p : b.outputs)
      if (p.name != "ENO") outname = p.name;
  }
  if (boolean) {
    Cond c;
    if (cmp.count(t)) {
      // GT(a, b, c) = a > b AND b > c; FALSE when EN is off
      static const std::map<std::string, Op> ops = {{"GT", Op::LDGT}, {"GE", Op::LDGE}, {"EQ", Op::LDEQ},
                                                    {"NE", Op::LDNE}, {"LE", Op::LDLE}, {"LT", Op::LDLT}};
      if (ins.size() < 2) fail_at(el, t + " needs two inputs (" + el->path() + ")");
      // on BOOL when an input is BOOL; the untyped literals 0 and 1 go with either
      auto literal01 = [&](const Pin* p) {
        const Node& n = node(p->conns[0]);
        std::optional<Val> k;
        if (n.kind == "inVariable" && upper(n.text).find('#') == std::string::npos) k = literal(n.text, n.el);
        return k && k->ty == Ty::Int && k->o.kind == OpdKind::ConstInt && (k->o.ival == 0 || k->o.ival == 1);
      };
      const Pin *a_bool = nullptr, *a_value = nullptr;
      for (const Pin* p : ins) {
        if (literal01(p)) continue;
        (is_bool_source(p->conns[0]) ? a_bool : a_value) = p;
      }
      if (a_bool && a_value)
        fail_at(el, t + " localId " + std::to_string(b.id) + " compares BOOL input " + a_bool->name + " with the value input " + a_value->name +
                        "; IEC 61131-3 (and MatIEC) compare inputs of one type (" + el->path() + ")");
      bool on_bools = a_bool != nullptr;
      c = en;
      if (on_bools) {
        // on BOOL (FALSE < TRUE): EQ is XNOR, NE XOR, GT a AND NOT b, GE a OR NOT b ...
        std::vector<Cond> x;
        for (const Pin* p : ins) x.push_back(materialize(cond_of(p), el));
        for (size_t k = 0; k + 1 < x.size(); k++) {
          const Cond &a = x[k], &bb = x[k + 1];
          Cond r = t == "EQ"   ? c_or(c_and(a, bb), c_and(negate(a, el), negate(bb, el)))
                   : t == "NE" ? c_or(c_and(a, negate(bb, el)), c_and(negate(a, el), bb))
                   : t == "GT" ? c_and(a, negate(bb, el))
                   : t == "GE" ? c_or(a, negate(bb, el))
                   : t == "LT" ? c_and(negate(a, el), bb)
                               : c_or(negate(a, el), bb);
          c = c_and(std::move(c), std::move(r));
        }
      } else {
        std::vector<Val> v;
        for (const Pin* p : ins) v.push_back(val_of(p));
        IT T = common_type(v);
        bool typed = false;
        for (Val& x : v) {
          if (x.ty == Ty::Wide && is_const(x.o) && T == IT::TIME && x.it == IT::TIME) {
            // a timer's ET (ms) against a TIME literal of whole ms: compared in ms, as before
            int64_t ns = int64_t(const_bits(x));
            if (ns % typed::kNsPerMs == 0 && ns / typed::kNsPerMs >= INT32_MIN && ns / typed::kNsPerMs <= INT32_MAX) {
              x = Val{const_opd(int32_t(ns / typed::kNsPerMs)), Ty::Int, IT::TIME, true};
              continue;
            }
          }
          typed |= x.ty == Ty::Wide;
        }
        typed |= T != IT::None && unsigned32(T);
        static const std::map<std::string, Op> tops = {{"GT", Op::TGT}, {"GE", Op::TGE}, {"EQ", Op::TEQ},
                                                       {"NE", Op::TNE}, {"LE", Op::TLE}, {"LT", Op::TLT}};
        for (size_t k = 0; k + 1 < v.size(); k++) {
          Cond r = typed ? tcmp(tops.at(t), T, as_type(v[k], T, el), as_type(v[k + 1], T, el), el)
                         : Cond::of(leaf(ops.at(t), {v[k].o, v[k + 1].o}, el));
          c = c_and(std::move(c), std::move(r));
        }
      }
    } else if (conv) {  // INT_TO_BOOL & co: the value is not zero
      Val v = val_of(ins.at(0));
      if (v.ty == Ty::Wide) {
        IT ft = type_of(v);
        c = c_and(en, tcmp(Op::TNE, ft, as_type(v, ft, el), Operand::typed_const(0), el));
      } else {
        c = c_and(en, Cond::of(leaf(Op::LDNE, {v.o, v.ty == Ty::Real ? [] { Operand z{OpdKind::ConstReal}; z.fval = 0; return z; }() : const_opd(0)}, el)));
      }
    } else if (t == "NOT") {
      c = c_and(en, negate(cond_of(ins.at(0)), el));
    } else if (t == "AND" || t == "OR") {
      c = t == "AND" ? Cond::yes() : Cond::no();
      for (const Pin* p : ins) c = t == "AND" ? c_and(std::move(c), cond_of(p)) : c_or(std::move(c), cond_of(p));
      c = c_and(en, std::move(c));
    } else if (t == "XOR") {
      Cond acc = materialize(cond_of(ins.at(0)), el);
      for (size_t k = 1; k < ins.size(); k++) {
        Cond x = materialize(cond_of(ins[k]), el);
        acc = materialize(c_or(c_and(acc, negate(x, el)), c_and(negate(acc, el), x)), el);
      }
      c = c_and(en, std::move(acc));
    } else if (t == "MOVE") {
      c = c_and(en, cond_of(ins.at(0)));
    } else if (t == "SEL") {
      const Pin* g = pins.get("G");
      if (!g || ins.size() != 3) fail_at(el, "SEL needs G, IN0 and IN1 (" + el->path() + ")");
      Cond gc = materialize(cond_of(g), el);
      Cond a = cond_of(ins[1]), bb = cond_of(ins[2]);
      c = c_and(en, c_or(c_and(negate(gc, el), std::move(a)), c_and(gc, std::move(bb))));
    } else {
      fail_at(el, t + " with BOOL inputs is not supported (" + el->path() + ")");
    }
    Cond r = materialize(std::move(c), el);  // the function's result, computed here
    if (r.k != Cond::Expr) {  // a constant result still needs its own relay (MatIEC's OUT variable)
      Operand q = bit_opd(Area::M, temp_m(el));
      rung(r, out(Op::OUT, {q}, el), el);
      r = bit_leaf(Op::LOAD, q, el);
    }
    outs_[{b.id, outname}] = Out{true, r, {}};
  } else {
    // values: the result goes to a temporary word; 0 when EN is off (as MatIEC)
    std::vector<Val> v;
    const Pin* g = nullptr;
    bool from_bool = conv && t.rfind("BOOL_TO_", 0) == 0;
    for (const Pin* p : ins) {
      if (t == "SEL" && p->name == "G") { g = p; continue; }
      if (!from_bool) v.push_back(val_of(p));
    }
    bool real = false, wide = false;
    for (const Val& x : v) real |= x.ty == Ty::Real, wide |= x.ty == Ty::Wide;
    IT T = common_type(v);
    std::string target = conv && !trunc ? t.substr(to + 4) : "";
    bool round_real = false;  // REAL_TO_INT & co: IEC rounds to nearest, ties to even
    IT ft = IT::None, tt = IT::None;
    if (conv) {
      if (trunc) {
        ft = v.empty() ? IT::None : type_of(v[0]), tt = IT::DINT;
        if (!typed::is_real(ft)) fail_at(el, "TRUNC localId " + std::to_string(b.id) + " takes a REAL or LREAL (" + el->path() + ")");
      } else {
        ft = iec_type_named(t.substr(0, to)), tt = iec_type_named(target);
        if (ft == IT::None || tt == IT::None || tt == IT::BOOL) fail_at(el, "conversion " + t + " is not supported (" + el->path() + ")");
      }
      // MatIEC's conversion in typed instructions where INT32 words cannot hold it
      if (trunc || kind_of(ft) == Ty::Wide || kind_of(tt) == Ty::Wide || (unsigned32(ft) && tt == IT::REAL)) {
        Val r;
        if (from_bool) {
          Cond in = materialize(cond_of(ins.at(0)), el);
          Val bv = in.k == Cond::Expr ? Val{in.n.elem.a[0], Ty::Bool, IT::BOOL} : Val{const_opd(in.k == Cond::True), Ty::Bool, IT::BOOL};
          if (in.k != Cond::Expr) bv.lit = IecLiteral{IT::BOOL, true, uint64_t(in.k == Cond::True)};
          r = typed_conv(tt, IT::BOOL, bv, en, false, el);
        } else {
          r = typed_conv(tt, ft, v.at(0), en, trunc, el);
        }
        outs_[{b.id, outname}] = Out{false, {}, r};
        if (consumed_.count({b.id, "ENO"})) outs_[{b.id, "ENO"}] = Out{true, materialize(eno, el), {}};
        return;
      }
      round_real = ft == IT::REAL && kind_of(tt) == Ty::Int;
      real = tt == IT::REAL;
    } else if (wide || real_functions().count(t) || !time_op.empty() ||
               (T != IT::None && unsigned32(T) && (t == "DIV" || t == "MOD" || t == "MIN" || t == "MAX" || t == "LIMIT"))) {
      Val r = typed_fn(t, time_op, v, g, T, en, eno, el, b);
      outs_[{b.id, outname}] = Out{false, {}, r};
      if (consumed_.count({b.id, "ENO"})) outs_[{b.id, "ENO"}] = Out{true, materialize(eno, el), {}};
      return;
    }
    Operand res = real ? Operand{OpdKind::Real, Area::F, take(Dev::F, el)} : Operand{OpdKind::Int, Area::D, take(Dev::D, el)};
    Operand zero = real ? [] { Operand z{OpdKind::ConstReal}; z.fval = 0; return z; }() : const_opd(0);
    std::vector<TreeNode> acts;
    Cond when = en;
    if (from_bool) {
      Cond in = materialize(cond_of(ins.at(0)), el);
      rung(Cond::yes(), out(Op::MOV, {zero, res}, el), el);
      rung(c_and(en, in), out(Op::MOV, {real ? [] { Operand z{OpdKind::ConstReal}; z.fval = 1; return z; }() : const_opd(1), res}, el), el);
    } else {
      if (en.k != Cond::True) rung(negate(en, el), out(Op::MOV, {zero, res}, el), el);
      if (round_real) {
        real_to_int(v.at(0).o, res, en, el);
        static const std::set<std::string> unsigned_types = {"USINT", "UINT", "UDINT", "BYTE", "WORD", "DWORD"};
        if (unsigned_types.count(target)) {  // MatIEC: a negative REAL gives 0 for unsigned and bit-string types
          Operand z{OpdKind::ConstReal};
          z.fval = 0;
          rung(c_and(en, Cond::of(leaf(Op::LDLT, {v.at(0).o, z}, el))), out(Op::MOV, {const_opd(0), res}, el), el);
        }
      } else if (conv || t == "MOVE") {
        rung(en, out(Op::MOV, {v.at(0).o, res}, el), el);
      } else if (t == "ABS") {
        rung(en, out(Op::ABS, {v.at(0).o, res}, el), el);
      } else if (t == "SEL") {
        if (!g || v.size() != 2) fail_at(el, "SEL needs G, IN0 and IN1 (" + el->path() + ")");
        Cond gc = materialize(cond_of(g), el);
        rung(c_and(en, negate(gc, el)), out(Op::MOV, {v[0].o, res}, el), el);
        rung(c_and(en, gc), out(Op::MOV, {v[1].o, res}, el), el);
      } else if (t == "MUX") {  // MatIEC: K selects IN0, IN1 ...; K out of range gives 0 (and ENO FALSE)
        rung(en, out(Op::MOV, {zero, res}, el), el);
        Cond in_range = Cond::no();
        for (size_t k = 1; k < v.size(); k++) {
          Cond is_k = Cond::of(leaf(Op::LDEQ, {v[0].o, const_opd(int32_t(k - 1))}, el));
          rung(c_and(en, is_k), out(Op::MOV, {v[k].o, res}, el), el);
          in_range = c_or(std::move(in_range), std::move(is_k));
        }
        eno = c_and(en, std::move(in_range));
      } else if (bits.count(t)) {
        if (real) fail_at(el, t + " of REAL values is not defined (" + el->path() + ")");
        bit_shift(t, *ins[0], v[0].o, v[1].o, res, en, el);
      } else if (t == "LIMIT") {  // IN > MN ? (IN < MX ? IN : MX) : MN
        if (v.size() != 3) fail_at(el, "LIMIT needs MN, IN and MX (" + el->path() + ")");
        rung(c_and(en, Cond::of(leaf(Op::LDLE, {v[1].o, v[0].o}, el))), out(Op::MOV, {v[0].o, res}, el), el);
        rung(c_and(c_and(en, Cond::of(leaf(Op::LDGT, {v[1].o, v[0].o}, el))), Cond::of(leaf(Op::LDGE, {v[1].o, v[2].o}, el))),
             out(Op::MOV, {v[2].o, res}, el), el);
        rung(c_and(c_and(en, Cond::of(leaf(Op::LDGT, {v[1].o, v[0].o}, el))), Cond::of(leaf(Op::LDLT, {v[1].o, v[2].o}, el))),
             out(Op::MOV, {v[1].o, res}, el), el);
      } else if (t == "MAX" || t == "MIN") {
        rung(en, out(Op::MOV, {v.at(0).o, res}, el), el);
        for (size_t k = 1; k < v.size(); k++)
          rung(c_and(en, Cond::of(leaf(t == "MAX" ? Op::LDLT : Op::LDGT, {res, v[k].o}, el))), out(Op::MOV, {v[k].o, res}, el), el);
      } else if (t == "AND" || t == "OR" || t == "XOR" || t == "NOT") {
        if (real) fail_at(el, t + " of REAL values is not defined (" + el->path() + ")");
        if (t == "NOT") rung(en, out(Op::WNOT, {v.at(0).o, res}, el), el);
        else {
          Op op = t == "AND" ? Op::WAND : t == "OR" ? Op::WOR : Op::WXOR;
          rung(en, out(op, {v.at(0).o, v.at(1).o, res}, el), el);
          for (size_t k = 2; k < v.size(); k++) rung(en, out(op, {res, v[k].o, res}, el), el);
        }
      } else if (t == "DIV" || t == "MOD") {
        // MatIEC: a zero divisor gives 0 (and ENO FALSE for DIV), not an error
        if (v.size() != 2) fail_at(el, t + " takes two inputs (" + el->path() + ")");
        if (t == "MOD" && real) fail_at(el, "MOD of REAL values is not defined (" + el->path() + ")");
        Operand z = v[1].ty == Ty::Real ? zero : const_opd(0);
        rung(c_and(en, Cond::of(leaf(Op::LDEQ, {v[1].o, z}, el))), out(Op::MOV, {zero, res}, el), el);
        rung(c_and(en, Cond::of(leaf(Op::LDNE, {v[1].o, z}, el))), out(t == "DIV" ? Op::DIV : Op::MOD, {v[0].o, v[1].o, res}, el), el);
        if (t == "DIV") eno = c_and(en, Cond::of(leaf(Op::LDNE, {v[1].o, z}, el)));
      } else {  // ADD MUL (extensible), SUB
        if (v.size() < 2 || (t == "SUB" && v.size() != 2)) fail_at(el, t + " needs " + (t == "SUB" ? "two" : "two or more") + " inputs (" + el->path() + ")");
        Op op = t == "ADD" ? Op::ADD : t == "SUB" ? Op::SUB : Op::MUL;
        rung(en, out(op, {v[0].o, v[1].o, res}, el), el);
        for (size_t k = 2; k < v.size(); k++) rung(en, out(op, {res, v[k].o, res}, el), el);
      }
    }
    // MatIEC computes in the type: a narrow result wraps
    Val r{res, real ? Ty::Real : Ty::Int};
    if (conv) {
      IT src = from_bool ? IT::BOOL : v.at(0).it != IT::None ? v.at(0).it : ft;
      if (round_real || (kind_of(tt) == Ty::Int && !fits_in(src, tt))) wrap(res, tt, en, el);
      r.it = tt;
    } else if (T != IT::None && (kind_of(T) == Ty::Int || kind_of(T) == Ty::Real)) {
      static const std::set<std::string> arith_ops = {"ADD", "SUB", "MUL", "DIV", "MOD", "ABS", "NOT"};
      if (arith_ops.count(t)) wrap(res, T, en, el);
      r.it = real ? IT::REAL : T;
    } else if (T == IT::TIME) {  // timers' ET: TIME in ms
      r.it = IT::TIME, r.ms = true;
    }
    outs_[{b.id, outname}] = Out{false, {}, r};
  }
  if (consumed_.count({b.id, "ENO"})) outs_[{b.id, "ENO"}] = Out{true, materialize(eno, el), {}};
}

// A statement of the body being translated; in a POU's own body (not a
// callee's, expanded inside a statement) an error is recovered from here.
void Importer::recovered_statement(const Node& n) {
  if (!call_stack_.empty()) return statement(n);
  if (recover([&] { statement(n); })) return;
  pending_store_ = nullptr;  // what the refused statement left half done
  generating_.clear();
}

// A statement, then the store of an array element it wrote at a variable index.
void Importer::statement(const Node& n) {
  auto outer = std::move(pending_store_);  // a statement of a callee's body, expanded inside another statement
  pending_store_ = nullptr;
  statement_of(n);
  if (pending_store_) {
    auto store = std::move(pending_store_);
    pending_store_ = nullptr;
    store();
  }
  pending_store_ = std::move(outer);
}

void Importer::statement_of(const Node& n) {
  const Element* el = n.el;
  if (n.kind == "block") {
    if (!computed_.count(n.id)) block(n);
    return;
  }
  if (n.in.empty()) return;  // an unconnected coil or variable does nothing (Beremiz skips it)
  bool order = n.order > 0 && n.kind != "coil";
  if (n.kind == "coil") {
    Operand q = bit_of(n.text, el, true);
    Cond c = bool_expr(n.in, false, el);
    // Beremiz: NOT(expr), else IF expr THEN var := TRUE/FALSE, else R_TRIG/F_TRIG(expr)
    if (n.negated) return rung(std::move(c), out(Op::OUTN, {q}, el, n.text), el);
    if (n.storage == "set" || n.storage == "reset") return rung(std::move(c), out(n.storage == "set" ? Op::SET : Op::RST, {q}, el, n.text), el);
    if (n.edge == "rising" || n.edge == "falling") c = trigger(std::move(c), n.edge == "rising", el);
    return rung(std::move(c), out(Op::OUT, {q}, el, n.text), el);
  }
  // outVariable / inOutVariable: var := expression
  Val dst = value_of(n.text, el, true);
  bool neg = n.kind == "inOutVariable" ? n.negated_in : n.negated;
  if (dst.ty == Ty::Bool) {
    if (!is_bool_source(n.in[0])) fail_at(el, "'" + n.text + "' is BOOL but a value feeds " + where(el));
    if (dst.o.area != Area::Y && dst.o.area != Area::M) fail_at(el, "'" + n.text + "' cannot be written (" + where(el) + ")");
    Cond c = bool_expr(n.in, order, el);
    std::string skip = eno_skip(n);
    rung(std::move(c), out(neg ? Op::OUTN : Op::OUT, {dst.o}, el, n.text), el);
    if (!skip.empty()) pending_labels_.push_back(skip);
    return;
  }
  if (neg) fail_at(el, "a negated " + n.kind + " must be BOOL (" + el->path() + ")");
  Val v = value_expr(n.in, order, el);
  std::string skip = eno_skip(n);
  assign(v, dst, n.text, el);
  if (!skip.empty()) pending_labels_.push_back(skip);
}

// Beremiz assigns a variable fed directly by a block whose EN is connected
// only while the block's ENO is TRUE (PLCGenerator's GetUsedEno:
// `IF inst.ENO THEN var := inst.OUT; END_IF;`), so it keeps its value while
// EN is off (docs/plcopen.md, section 6).
bool Importer::eno_gated(const Node& n) {
  if ((n.kind != "outVariable" && n.kind != "inOutVariable") || n.in.size() != 1) return false;
  auto it = nodes_.find(n.in[0].ref);
  if (it == nodes_.end() || it->second.kind != "block") return false;
  for (const Pin& p : it->second.inputs)
    if (p.name == "EN" && !p.conns.empty()) return true;
  return false;
}
// After the block ran: a jump over the assignment while its ENO is FALSE
// (the label for after it), or "".
std::string Importer::eno_skip(const Node& n) {
  if (!eno_gated(n)) return "";
  auto it = outs_.find({n.in[0].ref, "ENO"});
  if (it == outs_.end()) return "";
  std::string skip = new_label();
  Operand l{OpdKind::Label};
  l.label = skip;
  rung(negate(it->second.cond, n.el), out(Op::JMP, {l}, n.el), n.el);
  return skip;
}

// Was this project saved by Beremiz or OpenPLC Editor running on Python 2?
// Their XML writer declares the namespaces of <project> in the order of a
// Python dict: Python 2's hash order puts `xmlns:ns1` first and the default
// `xmlns` after it, Python 3's insertion order puts `xmlns` first.  The same
// program generated the project's ST, so this tells which order of statements
// it has (docs/plcopen.md, section 3).
bool saved_by_python2(const Element* project) {
  size_t ns1 = SIZE_MAX, dflt = SIZE_MAX;
  for (size_t i = 0; i < project->attrs.size(); i++) {
    if (project->attrs[i].first == "xmlns:ns1" && ns1 == SIZE_MAX) ns1 = i;
    if (project->attrs[i].first == "xmlns" && dflt == SIZE_MAX) dflt = i;
  }
  return ns1 == 0 && dflt != SIZE_MAX && dflt > ns1;
}

// The namespace an element's name is in, from the declarations on it (the
// root: enough for <project>).
constexpr const char* kTc6V1Namespace = "http://www.plcopen.org/xml/tc6.xsd";
// What an error in such a file adds.
std::string tc6_v1_note() {
  return std::string(" (this is a PLCopen TC6 XML 1.0 file, namespace ") + kTc6V1Namespace + "; ldc reads it where it agrees with TC6 XML 2.01)";
}
std::string namespace_of(const Element* e) {
  size_t colon = e->name.find(':');
  std::string decl = colon == std::string::npos ? "xmlns" : "xmlns:" + e->name.substr(0, colon);
  const std::string* ns = e->attr(decl);
  return ns ? trim(*ns) : "";
}

// A program instance's POU: `typeName` (TC6 2.01), `type` (TC6 1.0).
const std::string* instance_type(const Element* pi) { return pi->attr("typeName") ? pi->attr("typeName") : pi->attr("type"); }

// Beremiz's order of statements under Python 2 (PLCGenerator.ComputeProgram),
// positions compared as its SortInstances does: rows within 10 units, left to right.
bool before(const Node* a, const Node* b) {
  if (std::abs(a->y - b->y) < 10) return a->x < b->x;
  return a->y < b->y;
}

void Importer::body(const Element* ld, const std::string& title) {
  nodes_.clear();
  connectors_.clear();
  computed_.clear();
  outs_.clear();
  consumed_.clear();
  generating_.clear();
  for (const auto& c : ld->children) read_node(c.get());
  for (auto& [id, n] : nodes_) {
    for (const Conn& c : n.in) consumed_.insert({c.ref, c.param});
    for (const Pin& p : n.inputs)
      for (const Conn& c : p.conns) consumed_.insert({c.ref, c.param});
    if (eno_gated(n)) consumed_.insert({n.in[0].ref, "ENO"});
  }
  std::vector<const Node*> ordered, stmts, blocks;
  for (const auto& [id, n] : nodes_) {
    bool stmt = n.kind == "outVariable" || n.kind == "inOutVariable" || n.kind == "block";
    if (stmt && n.order > 0) ordered.push_back(&n);
    else if (n.kind == "outVariable" || n.kind == "inOutVariable" || n.kind == "coil") stmts.push_back(&n);
    else if (n.kind == "block") blocks.push_back(&n);
  }
  // document order first (std::map sorted them by localId), then stable sorts
  auto doc = [&](std::vector<const Node*>& v) {
    std::vector<const Node*> r;
    for (const auto& c : ld->children)
      for (const Node* n : v)
        if (n->el == c.get()) r.push_back(n);
    v = r;
  };
  doc(ordered), doc(stmts), doc(blocks);
  std::stable_sort(ordered.begin(), ordered.end(), [](const Node* a, const Node* b) { return a->order < b->order; });
  auto insertion = [](std::vector<const Node*>& v) {  // stable, and safe for a comparator that is not transitive
    for (size_t i = 1; i < v.size(); i++)
      for (size_t j = i; j > 0 && before(v[j], v[j - 1]); j--) std::swap(v[j], v[j - 1]);
  };
  if (position_order_) {  // under Python 3, SortInstances returns operator.eq: never "less", no move
    insertion(stmts);
    insertion(blocks);
  }
  size_t first = rungs_.size();
  std::string before_title = pending_title_;
  pending_title_ = before_title.empty() ? title : before_title + "; " + title;
  for (auto* list : {&ordered, &stmts, &blocks})
    for (const Node* n : *list) recovered_statement(*n);
  if (rungs_.size() == first) pending_title_ = before_title;
}

// ------------------------------------------------------------------ SFC bodies

// n devices of kind d in a row (a chart's step flags), avoiding every device in use.
uint32_t Importer::take_run(Dev d, uint32_t n, const Element* el) {
  for (uint32_t b = 0; b + n <= device_count(d); b++) {
    uint32_t k = 0;
    while (k < n && !used_.count({int(d), b + k})) k++;
    if (k == n) {
      for (k = 0; k < n; k++) used_.insert({int(d), b + k});
      return b;
    }
    b += k;
  }
  fail_at(el, std::string("out of ") + dev_name(d) + " devices for this chart's steps");
}

// A PLCopen SFC body becomes the chart of ldc's SFC compiler (ir/sfc.cpp): steps
// in one sequence, with selection divergences and convergences and jumps;
// transition conditions drawn in the body's LD/FBD graph (computed into a relay
// each, before the chart); actions that are BOOL variables with the qualifiers
// N, S, R and P.  Everything else is refused by name.
void Importer::sfc_body(const Element* pou, const Element* sfc) {
  std::string pname = *pou->attr("name");
  if (chart_) fail_at(pou, "POU '" + pname + "' is a second SFC program in one task (after '" + chart_pou_ + "'); ldc runs one chart per program");
  // the LD/FBD elements: blocks and variables feeding the conditions.
  // Beremiz writes the blocks into an action of the initial step,
  // COMPUTE_FUNCTION_BLOCKS, qualifier S (PLCGenerator, SFCComputedBlocks):
  // it runs every scan after the chart and its other actions, so a condition
  // reads a block's output of the scan before (and a contact's of this one)
  size_t first_block = rungs_.size();
  sfc_mode_ = true;
  body(sfc, "POU " + pname);
  sfc_mode_ = false;
  std::vector<TreeRung> blocks(std::make_move_iterator(rungs_.begin() + long(first_block)), std::make_move_iterator(rungs_.end()));
  rungs_.resize(first_block);
  std::map<int, const Element*> el_of;
  for (const auto& c : sfc->children) {
    std::string k(c->local_name());
    if (!sfc_kinds().count(k)) continue;
    if (k == "simultaneousDivergence" || k == "simultaneousConvergence" || k == "macroStep")
      fail_at(c.get(), "SFC element '" + k + "' is not supported: ldc translates single sequences with selections and jumps (" + c->path() + ")");
    const std::string* id = c->attr("localId");
    if (!id) fail_at(c.get(), k + " without a localId (" + c->path() + ")");
    int n = std::atoi(id->c_str());
    if (el_of.count(n) || nodes_.count(n)) fail_at(c.get(), "localId " + *id + " is used twice (" + c->path() + ")");
    el_of[n] = c.get();
  }
  auto refs = [&](const Element* e) {
    std::vector<int> r;
    for (const Element* cpi : e->children_named("connectionPointIn"))
      for (const Element* cn : cpi->children_named("connection"))
        if (auto ref = cn->attr("refLocalId")) r.push_back(std::atoi(ref->c_str()));
    return r;
  };
  auto kind = [&](int id) { auto it = el_of.find(id); return it == el_of.end() ? std::string() : std::string(it->second->local_name()); };
  Chart c;
  c.source = file_;
  std::map<int, uint32_t> step_of;        // localId -> step
  std::map<std::string, uint32_t> named;  // upper step name -> step
  bool have_initial = false;
  for (auto& [id, e] : el_of) (void)id, (void)e;
  for (const auto& ch : sfc->children) {
    if (ch->local_name() != "step") continue;
    const Element* e = ch.get();
    SfcStep st;
    if (!e->attr("name")) fail_at(e, "step without a name (" + e->path() + ")");
    st.name = *e->attr("name");
    st.line = e->line;
    if (named.count(upper(st.name))) fail_at(e, "a second step named '" + st.name + "' (" + e->path() + ")");
    uint32_t i = uint32_t(c.steps.size());
    if (auto ini = e->attr("initialStep"); ini && (*ini == "true" || *ini == "1")) {
      if (have_initial) fail_at(e, "step '" + st.name + "' is a second initial step; ldc translates charts with one initial step (" + e->path() + ")");
      c.initial = i, have_initial = true;
    }
    step_of[std::atoi(e->attr("localId")->c_str())] = i;
    named[upper(st.name)] = i;
    c.steps.push_back(std::move(st));
  }
  if (c.steps.empty()) fail_at(sfc, "the SFC body of POU '" + pname + "' has no step");
  if (!have_initial) fail_at(sfc, "the SFC body of POU '" + pname + "' has no initial step");
  // a transition's source step, back through a selection divergence
  auto source_step = [&](const Element* t) -> uint32_t {
    std::vector<int> r = refs(t);
    for (int depth = 0; depth < 64; depth++) {
      if (r.size() != 1) fail_at(t, "transition localId " + *t->attr("localId") + " follows " + std::to_string(r.size()) + " elements; ldc needs one step (" + t->path() + ")");
      std::string k = kind(r[0]);
      if (k == "step") return step_of[r[0]];
      if (k != "selectionDivergence") fail_at(t, "transition localId " + *t->attr("localId") + " follows " + (k.empty() ? "localId " + std::to_string(r[0]) : k) + "; ldc needs a step or a selection divergence (" + t->path() + ")");
      r = refs(el_of[r[0]]);
    }
    fail_at(t, "transition localId " + *t->attr("localId") + ": a loop of divergences (" + t->path() + ")");
  };
  // the step a transition leads to, forward through a selection convergence or a jump
  auto target_step = [&](const Element* t, int tid) -> uint32_t {
    int from = tid;
    for (int depth = 0; depth < 64; depth++) {
      std::vector<const Element*> next;
      for (auto& [id, e] : el_of)
        for (int r : refs(e))
          if (r == from && e->local_name() != "actionBlock") next.push_back(e);
      if (next.size() != 1) fail_at(t, "transition localId " + *t->attr("localId") + " leads to " + std::to_string(next.size()) + " elements; ldc needs one step (" + t->path() + ")");
      const Element* n = next[0];
      std::string k(n->local_name());
      if (k == "step") return step_of[std::atoi(n->attr("localId")->c_str())];
      if (k == "jumpStep") {
        auto target = n->attr("targetName");
        if (!target || !named.count(upper(*target))) fail_at(n, "jump to an unknown step (" + n->path() + ")");
        return named[upper(*target)];
      }
      if (k != "selectionConvergence") fail_at(n, "transition localId " + *t->attr("localId") + " leads to " + k + "; ldc needs a step, a jump or a selection convergence (" + n->path() + ")");
      from = std::atoi(n->attr("localId")->c_str());
    }
    fail_at(t, "transition localId " + *t->attr("localId") + ": a loop of convergences (" + t->path() + ")");
  };
  // transitions: conditions into relays, by priority (left first) per step
  struct Tr { uint32_t from; double x; size_t doc; SfcTransition t; };
  std::vector<Tr> trs;
  for (const auto& ch : sfc->children) {
    if (ch->local_name() != "transition") continue;
    const Element* t = ch.get();
    int tid = std::atoi(t->attr("localId")->c_str());
    std::string what = "transition localId " + std::to_string(tid);
    const Element* cond = t->child("condition");
    if (!cond) fail_at(t, what + " has no condition (" + t->path() + ")");
    const Element* ci = cond->child("connectionPointIn");
    if (!ci && cond->child("connection")) ci = cond;  // TC6 1.0: the connections directly in <condition>
    if (!ci && !plcopen::inline_st_text(cond)) {
      auto inline_lang = [](const Element* in) {  // <inline><ST> (TC6 2.01), or <inline><body><ST>
        const Element* b = in->child("body") ? in->child("body") : in;
        for (const auto& ch : b->children)
          if (ch->local_name() != "documentation" && ch->local_name() != "addData") return std::string(ch->local_name());
        return std::string("empty");
      };
      std::string how = cond->child("inline") ? "an inline " + inline_lang(cond->child("inline")) + " condition"
                        : cond->child("reference") ? "a condition named '" + (cond->child("reference")->attr("name") ? *cond->child("reference")->attr("name") : "?") + "' (a transition of the POU's <transitions>)"
                                                   : "this form of condition";
      fail_at(cond, what + " has " + how + "; ldc translates conditions drawn in the chart's LD/FBD graph (" + cond->path() + ")");
    }
    uint32_t m = take(Dev::M, t);
    if (ci) {
      std::vector<Conn> conns;
      read_conns(ci, conns);
      Cond cc = bool_expr(conns, false, cond);
      rung(std::move(cc), out(Op::OUT, {bit_opd(Area::M, m)}, t), t);
    } else {
      st_condition(cond, m);
    }
    Tr tr;
    tr.from = source_step(t);
    tr.x = 0;
    if (const Element* pos = t->child("position"))
      if (auto x = pos->attr("x")) tr.x = std::atof(x->c_str());
    tr.doc = trs.size();
    tr.t.line = t->line;
    tr.t.text = "localId " + std::to_string(tid);
    Instr ld;
    ld.op = Op::LOAD;
    ld.a[0] = bit_opd(Area::M, m);
    ld.loc = {t->line, t->col};
    tr.t.cond = {ld};
    tr.t.target = target_step(t, tid);
    trs.push_back(std::move(tr));
  }
  std::stable_sort(trs.begin(), trs.end(), [](const Tr& a, const Tr& b) { return a.from != b.from ? a.from < b.from : a.x < b.x; });
  for (Tr& tr : trs) c.steps[tr.from].out.push_back(std::move(tr.t));
  // actions: as MatIEC runs them, after the steps have moved: a variable action
  // is TRUE while a step naming it N is active, or from an S step's activation
  // to an R step's (its stored state, a relay); an action body written in ST
  // (inline, or one of the POU's <actions>) has such a state in a relay of its
  // own and runs while it is on
  struct Act {
    Operand bit;
    std::vector<uint32_t> n, set, reset, pulse;
    const Element* el;
    const Element* text = nullptr;  // a body's ST
    uint32_t step = 0;              // the first step naming it
  };
  std::vector<Act> acts;
  for (const auto& ch : sfc->children) {
    if (ch->local_name() != "actionBlock") continue;
    const Element* ab = ch.get();
    std::vector<int> r = refs(ab);
    if (r.size() != 1 || kind(r[0]) != "step") fail_at(ab, "action block localId " + *ab->attr("localId") + " is not attached to one step (" + ab->path() + ")");
    uint32_t s = step_of[r[0]];
    for (const Element* a : ab->children_named("action")) {
      std::string q = a->attr("qualifier") ? upper(*a->attr("qualifier")) : "N";
      const Element* ref = a->child("reference");
      const Element* text = nullptr;  // an action body's ST
      std::string name;
      auto not_st = [&](const std::string& what) {
        fail_at(a, what + " of step '" + c.steps[s].name + "' is not written in ST; ldc translates action bodies written in ST and actions that are BOOL variables (" + a->path() + ")");
      };
      if (a->child("inline")) {
        name = "an inline action";
        if (!(text = plcopen::inline_st_text(a))) not_st(name);
      } else {
        if (!ref || !ref->attr("name")) fail_at(a, "an action of step '" + c.steps[s].name + "' with neither a reference nor a body (" + a->path() + ")");
        name = *ref->attr("name");
        if (const Element* an = plcopen::pou_action(pou, name)) {
          const Element* body = an->child("body");
          if (!body || !body->child("ST")) not_st("action '" + name + "'");
          text = plcopen::body_text(body->child("ST"));
        }
      }
      if (q != "N" && q != "S" && q != "R" && q != "P")
        fail_at(a, "qualifier " + q + " of action '" + name + "' in step '" + c.steps[s].name + "' is not supported: ldc translates N, S, R and P (" + a->path() + ")");
      if (text) {
        Act* act = nullptr;
        for (Act& x : acts)
          if (x.text == text) act = &x;  // one of the POU's actions, named by several steps: one state
        if (!act) acts.push_back(Act{bit_opd(Area::M, take(Dev::M, a)), {}, {}, {}, {}, a, text, s}), act = &acts.back();
        (q == "N" ? act->n : q == "S" ? act->set : q == "R" ? act->reset : act->pulse).push_back(s);
        continue;
      }
      Var* v = lookup(name);
      if (!v) fail_at(a, "action '" + name + "' of step '" + c.steps[s].name + "' is neither a variable nor an action of POU '" + pname + "' (" + a->path() + ")");
      if (v->ty != Ty::Bool) fail_at(a, "action '" + name + "' of step '" + c.steps[s].name + "' is a " + v->type + " variable; an action variable is BOOL (" + a->path() + ")");
      Operand o = bit_of(name, a, true);
      Act* act = nullptr;
      for (Act& x : acts)
        if (x.bit.area == o.area && x.bit.index == o.index) act = &x;
      if (!act) acts.push_back(Act{o, {}, {}, {}, {}, a}), act = &acts.back();
      (q == "N" ? act->n : q == "S" ? act->set : q == "R" ? act->reset : act->pulse).push_back(s);
    }
  }
  SfcScope sc;
  for (uint32_t i = 0; i < c.steps.size(); i++) sc.steps.push_back(i), c.steps[i].scope = 0;
  c.scopes.push_back(sc);
  c.flag_base = take_run(Dev::M, uint32_t(3 * c.steps.size()), sfc);
  std::vector<TreeRung> saved = std::move(rungs_);
  rungs_.clear();
  std::string saved_title = std::move(pending_title_);
  pending_title_ = "actions of " + pname;
  for (const Act& x : acts) {
    auto flag = [&](uint32_t st) { return bit_leaf(Op::LOAD, bit_opd(Area::M, c.flag(st)), x.el); };
    Cond q = Cond::no();
    if (!x.set.empty() || !x.reset.empty()) {
      Operand stored = bit_opd(Area::M, take(Dev::M, x.el));
      for (uint32_t st : x.set) rung(flag(st), out(Op::SET, {stored}, x.el), x.el);
      for (uint32_t st : x.reset) rung(flag(st), out(Op::RST, {stored}, x.el), x.el);
      q = bit_leaf(Op::LOAD, stored, x.el);
    }
    for (uint32_t st : x.n) q = c_or(std::move(q), flag(st));
    // P: the scan the step is activated in, when its entry bit is still set.
    // Not the initial step's first scan: MatIEC remembers every step's flag
    // before testing anything, so the initial step is active, not activated, then
    for (uint32_t st : x.pulse) q = c_or(std::move(q), bit_leaf(Op::LOAD, bit_opd(Area::M, c.entry(st)), x.el));
    rung(std::move(q), out(Op::OUT, {x.bit}, x.el), x.el);
  }
  // the bodies, after every state: the initial step's first, then the blocks
  // (Beremiz's COMPUTE_FUNCTION_BLOCKS comes after the initial step's own
  // actions), then the others in document order
  for (const Act& x : acts)
    if (x.text && x.step == c.initial) st_action(x.text, x.bit.index, x.el);
  if (!blocks.empty() && !pending_labels_.empty()) {  // a body's labels after its last rung: the blocks' first
    blocks[0].labels.insert(blocks[0].labels.begin(), pending_labels_.begin(), pending_labels_.end());
    pending_labels_.clear();
  }
  after_ = std::move(rungs_);
  after_.insert(after_.end(), std::make_move_iterator(blocks.begin()), std::make_move_iterator(blocks.end()));
  rungs_.clear();
  for (const Act& x : acts)
    if (x.text && x.step != c.initial) st_action(x.text, x.bit.index, x.el);
  after_.insert(after_.end(), std::make_move_iterator(rungs_.begin()), std::make_move_iterator(rungs_.end()));
  after_end_labels_ = std::move(pending_labels_);  // the last body's
  pending_labels_.clear();
  rungs_ = std::move(saved);
  pending_title_ = std::move(saved_title);
  for (uint32_t i = 0; i < c.steps.size(); i++) {
    std::string why;
    const std::string& n = c.steps[i].name;
    if (!lookup(n) && is_identifier(n) && !parse_device(n) && !parse_iec_address(n, why))
      c.aliases.push_back({n, DeviceRef{Dev::M, c.flag(i)}});
  }
  chart_ = std::move(c);
  chart_pou_ = pname;
}

// TC6 1.0 gives a task's interval as an xsd:time, hh:mm:ss[.fraction], which
// is a duration there (Beremiz converts it so): T#...  Anything else is kept.
std::string xsd_time_as_iec(const std::string& v) {
  std::string s = trim(v);
  if (!s.empty() && s.back() == 'Z') s.pop_back();
  auto digits = [&](size_t at, size_t n) {
    if (at + n > s.size()) return false;
    for (size_t i = at; i < at + n; i++)
      if (!std::isdigit((unsigned char)s[i])) return false;
    return true;
  };
  if (s.size() < 8 || !digits(0, 2) || s[2] != ':' || !digits(3, 2) || s[5] != ':' || !digits(6, 2)) return v;
  std::string frac;
  if (s.size() > 8) {
    if (s[8] != '.' || s.size() == 9 || !digits(9, s.size() - 9)) return v;
    frac = s.substr(9);
  }
  return "T#" + std::to_string(std::stoi(s.substr(0, 2))) + "h" + std::to_string(std::stoi(s.substr(3, 2))) + "m" +
         std::to_string(std::stoi(s.substr(6, 2))) + (frac.empty() ? "" : "." + frac) + "s";
}

// A task's interval, T#20ms, T#0.1ms, TIME#1s500ms, in microseconds; nullopt
// if malformed or not a whole number of microseconds.
std::optional<uint64_t> interval_us(const std::string& s0) {
  std::string s = upper(trim(s0));
  size_t hash = s.find('#');
  if (hash == std::string::npos || (s.substr(0, hash) != "T" && s.substr(0, hash) != "TIME")) return std::nullopt;
  std::string b = s.substr(hash + 1);
  double us = 0;
  size_t i = 0;
  if (b.empty()) return std::nullopt;
  while (i < b.size()) {
    if (b[i] == '_') { i++; continue; }
    size_t j = i;
    while (j < b.size() && (std::isdigit((unsigned char)b[j]) || b[j] == '.')) j++;
    if (j == i || j - i > 12) return std::nullopt;
    double v = std::strtod(b.substr(i, j - i).c_str(), nullptr);
    size_t k = j;
    while (k < b.size() && std::isalpha((unsigned char)b[k])) k++;
    std::string u = b.substr(j, k - j);
    double mul = u == "D" ? 86400e6 : u == "H" ? 3600e6 : u == "M" ? 60e6 : u == "S" ? 1e6 : u == "MS" ? 1e3 : u == "US" ? 1 : u == "NS" ? 1e-3 : -1;
    if (mul < 0) return std::nullopt;
    us += v * mul;
    i = k;
  }
  double r = std::round(us);
  if (std::fabs(us - r) > 1e-6 || r > 4e9) return std::nullopt;
  return uint64_t(r);
}

// The configuration's tasks: every program instance must run a POU that ldc
// compiles (an LD or FBD body); what ldc cannot run is refused by name, never
// dropped.  Each task is kept, with its programs, for a configuration of
// several tasks (one ldc task each).
void Importer::tasks(const Element* root) {
  const Element* inst = root->child("instances");
  const Element* cfgs = inst ? inst->child("configurations") : nullptr;
  if (!cfgs) return;
  uint32_t res_index = 0;
  for (const Element* cfg : cfgs->children_named("configuration")) {
    if (config_name_.empty() && cfg->attr("name")) config_name_ = *cfg->attr("name");
    for (const Element* res : cfg->children_named("resource")) {
      std::string rn = res->attr("name") ? *res->attr("name") : "resource" + std::to_string(res_index);
      auto check = [&](const Element* pi, const std::string& task) {
        const std::string* type = instance_type(pi);
        std::string name = pi->attr("name") ? *pi->attr("name") : "?";
        std::string where = "program instance '" + name + "'" + (task.empty() ? "" : " of task '" + task + "'");
        if (!type) fail_at(pi, where + " has no typeName (" + pi->path() + ")");
        auto lang = pou_lang_.find(upper(*type));
        if (lang == pou_lang_.end()) fail_at(pi, where + " runs '" + *type + "', which is not a POU of this project (" + pi->path() + ")");
        if (lang->second != "LD" && lang->second != "FBD" && lang->second != "SFC" && !st_pou(*type))
          fail_at(pi, where + " runs POU '" + *type + "', written in " + lang->second + "; ldc compiles LD, FBD, SFC, ST and IL bodies only (" + pi->path() + ")");
        return upper(*type);
      };
      for (const Element* t : res->children_named("task")) {
        CfgTask ct;
        ct.el = t;
        ct.name = t->attr("name") ? *t->attr("name") : "?";
        ct.resource = rn;
        ct.resource_index = res_index;
        for (const Element* pi : t->children_named("pouInstance")) {
          ct.pous.push_back(check(pi, ct.name));
          ct.instances.push_back(pi->attr("name") ? *pi->attr("name") : ct.name);
          ct.instance_els.push_back(pi);
        }
        const std::string* iv = t->attr("interval");
        if (iv) ct.interval = tc6_v1_ ? xsd_time_as_iec(*iv) : *iv;
        if (auto p = t->attr("priority")) ct.priority_text = *p;
        cfg_tasks_.push_back(std::move(ct));
      }
      for (const Element* pi : res->children_named("pouInstance")) {
        CfgTask ct;  // a program of the resource without a task: runs every cycle of the resource
        ct.el = pi;
        ct.name = pi->attr("name") ? *pi->attr("name") : "?";
        ct.resource = rn;
        ct.resource_index = res_index;
        ct.pous.push_back(check(pi, ""));
        ct.instances.push_back(ct.name);
        ct.instance_els.push_back(pi);
        ct.no_task = true;
        cfg_tasks_.push_back(std::move(ct));
      }
      res_index++;
    }
  }
}

// One section of a translated POU's interface: its variables into scope_.
void Importer::interface_section(const Element* sec, const std::string& name) {
  std::string s(sec->local_name());
  if (s == "returnType") {
    if (sec->children.empty()) return;
    auto u = std::make_unique<Var>();
    u->name = name;
    u->el = sec;
    u->pou = name;
    const Element* te = sec->children[0].get();
    u->derived = te->local_name() == "derived";
    u->type = u->derived ? (te->attr("name") ? *te->attr("name") : "") : upper(te->local_name());
    u->it = u->derived ? IT::None : iec_type_named(u->type);
    u->ty = kind_of(u->it);
    scope_[upper(name)] = u.get();
    keep(std::move(u));
  } else if (s == "externalVars") {
    for (const Element* v : sec->children_named("variable"))
      if (!recover([&] {
            const std::string* nm = v->attr("name");
            if (!nm) fail_at(v, "variable without a name (" + v->path() + ")");
            auto it = globals_.find(upper(*nm));
            if (it == globals_.end()) fail_at(v, "external variable '" + *nm + "' of POU '" + name + "' is not a global variable of the project");
            scope_[upper(*nm)] = it->second;
          }) && v->attr("name"))
        failed_names_.insert(upper(*v->attr("name")));
  } else if (s == "localVars" || s == "inputVars" || s == "outputVars" || s == "inOutVars" || s == "tempVars") {
    declare(sec, name, false);
  } else if (s != "documentation" && s != "addData" && s != "accessVars" && s != "globalVars") {
    fail_at(sec, "unknown interface section <" + sec->name + "> (" + sec->path() + ")");
  }
}

void Importer::prepare() {
  if (text_.size() > kMaxSourceBytes) fail_at(nullptr, "source file too large (at most 64 MiB)");
  doc_ = xml::parse(text_);
  const Element* root = doc_.root.get();
  if (root->local_name() != "project")
    fail_at(root, "expected a PLCopen TC6 <project>, found <" + root->name + ">");
  position_order_ = saved_by_python2(root);
  tc6_v1_ = namespace_of(root) == kTc6V1Namespace;
  // POUs and their languages
  const Element* types = root->child("types");
  data_types_el_ = types ? types->child("dataTypes") : nullptr;
  if (const Element* dts = data_types_el_)
    for (const Element* dt : dts->children_named("dataType")) {
      if (!dt->attr("name")) fail_at(dt, "data type without a name (" + dt->path() + ")");
      if (!data_types_.emplace(upper(*dt->attr("name")), dt).second) fail_at(dt, "data type '" + *dt->attr("name") + "' is declared twice");
    }
  const Element* pous = types ? types->child("pous") : nullptr;
  std::vector<const Element*> all;
  std::vector<const Element*>& ld = ld_pous_;
  if (pous)
    for (const Element* p : pous->children_named("pou")) {
      if (!p->attr("name")) fail_at(p, "POU without a name (" + p->path() + ")");
      const Element* b = p->child("body");
      std::string lang = "no body";
      if (b)
        for (const auto& c : b->children)
          if (c->local_name() != "documentation" && c->local_name() != "addData") {
            lang = std::string(c->local_name());
            break;
          }
      if (lang == "SFC") {  // say so when the LD is only in SFC actions or transitions
        std::vector<std::string> parts;
        for (const char* list : {"actions", "transitions"})
          if (const Element* l = p->child(list))
            for (const auto& a : l->children)
              if (const Element* ab = a->child("body"))
                if (ab->child("LD") && a->attr("name")) parts.push_back(std::string(a->local_name()) + " '" + *a->attr("name") + "'");
        if (!parts.empty()) {
          lang += " (its ";
          for (size_t i = 0; i < parts.size(); i++) lang += (i ? ", " : "") + parts[i];
          lang += parts.size() == 1 ? " is LD, but runs only while its SFC step is active)" : " are LD, but run only while their SFC steps are active)";
        }
      }
      pou_lang_[upper(*p->attr("name"))] = lang;
      pou_el_[upper(*p->attr("name"))] = p;
      all.push_back(p);
    }
  // the project's FUNCTION_BLOCKs and FUNCTIONs that a block calls are expanded
  // at their calls, not compiled as programs of their own (section 5b)
  for (const Element* p : all)
    if (const Element* b = p->child("body"))
      for (const auto& g : b->children)
        for (const Element* blk : g->children_named("block"))
          if (auto t = blk->attr("typeName")) called_.insert(upper(*t));
  // global variables of configurations and resources
  if (const Element* inst = root->child("instances"))
    if (const Element* cfgs = inst->child("configurations"))
      for (const Element* cfg : cfgs->children_named("configuration")) {
        for (const Element* g : cfg->children_named("globalVars")) declare(g, "", true);
        for (const Element* res : cfg->children_named("resource"))
          for (const Element* g : res->children_named("globalVars")) declare(g, "", true);
      }
  tasks(root);
  auto run_by_task = [&](const Element* p) {
    for (const CfgTask& ct : cfg_tasks_)
      for (const std::string& u : ct.pous)
        if (u == upper(*p->attr("name"))) return true;
    return false;
  };
  // LD and FBD POUs (FBD: the same block graph, without rails); ST and IL
  // programs that a task runs (or every one, without a configuration)
  for (const Element* p : all) {
    const std::string& lang = pou_lang_[upper(*p->attr("name"))];
    bool callee = called_.count(upper(*p->attr("name"))) && user_pou(*p->attr("name"));
    if ((lang == "LD" || lang == "FBD") && !callee) ld.push_back(p);
    else if (st_pou(*p->attr("name")) && pou_type(p) == "program" && (lang.starts_with("SFC") ? run_by_task(p) : cfg_tasks_.empty() || run_by_task(p)))
      ld.push_back(p);
  }
  // SFC programs that a task runs: their charts (section 1b)
  for (const Element* p : all)
    if (pou_lang_[upper(*p->attr("name"))] == "SFC" && run_by_task(p) && !st_pou(*p->attr("name"))) ld.push_back(p);
  if (ld.empty()) {
    std::string list;
    for (const Element* p : all) list += std::string(list.empty() ? "" : ", ") + "'" + *p->attr("name") + "' is " + pou_lang_[upper(*p->attr("name"))];
    fail_at(pous ? pous : root, all.empty() ? "the project has no POU" : "no POU of this project has an LD or FBD body, nor an ST or IL program (" + list +
                                                                               "); ldc imports LD and FBD bodies, and ST and IL programs and the POUs they call");
  }
  // declarations of the LD POUs, then devices for all of them
    for (const Element* p : ld_pous_) {
    scope_.clear();
    std::string name = *p->attr("name");
    if (st_pou(name)) continue;  // its variables are its unit's (st_program)
    if (const Element* itf = p->child("interface"))
      for (const auto& sec : itf->children) recover([&] { interface_section(sec.get(), name); });
    scopes_[p] = scope_;
  }
  allocate();
  for (auto& v : vars_)
    if (v->dev) spelled_[{int(v->dev->dev), v->dev->index}] = v->name;
}

// The first-scan rung setting the initial values of the variables `which` selects.
void Importer::emit_init(const std::function<bool(const Var&)>& which, const Element* root) {
  init_.clear();
  for (auto& v : vars_) {
    if (!v->dev || v->init.empty() || v->derived || v->constant || v->frame || !which(*v)) continue;
    if (v->dev->dev == Dev::X || v->dev->dev == Dev::WX) continue;  // inputs belong to the I/O
    recover([&] {
      auto c = literal(v->init, v->el);
      if (!c) fail_at(v->el, "initial value '" + v->init + "' of '" + v->name + "' is not a literal");
      Val k = const_val(*c, v->it);
      if (v->ty == Ty::Bool) {
        if (k.o.ival) init_.push_back(out(Op::SET, {bit_opd(bit_area(v->dev->dev), v->dev->index)}, v->el));
      } else if (const_bits(k) != 0) {
        init_.push_back(assign_node(k, var_val(*v), v->el));
      }
    });
  }
  if (init_.empty()) return;
  TreeRung r;
  r.line = init_[0].elem.loc.line;
  r.title = "initial values";
  r.root = then_node(bit_leaf(Op::LOAD, bit_opd(Area::S, kBitFirstScan), root), fork_of(std::move(init_)), {r.line, 1});
  init_.clear();
  rungs_.push_back(std::move(r));
}

// The rungs of the POUs `pous`, in that order, after the initial values.
void Importer::emit_bodies(const std::vector<const Element*>& pous) {
  for (const Element* pe : pous) {
    pou_ = *pe->attr("name");
    scope_ = scopes_[pe];
    const Element* b = pe->child("body");
    bool ok = recover([&] {
      if (st_pou(pou_)) st_program(pe);
      else if (const Element* sfc = b->child("SFC")) sfc_body(pe, sfc);
      else body(b->child("LD") ? b->child("LD") : b->child("FBD"), "POU " + pou_);
    });
    if (!ok) sfc_mode_ = false, pending_store_ = nullptr, generating_.clear();
  }
  end_of_recovery();
}

// The copies of the inputs the program writes first, then labels and aliases.
void Importer::finish(TreeProgram& p, const Element* root) {
  end_of_recovery();
  std::vector<TreeRung> copies;
  auto copy = [&](TreeNode root_node) {
    TreeRung r;
    r.line = rungs_[0].line;
    if (copies.empty()) r.title = "inputs the program writes";
    r.root = std::move(root_node);
    copies.push_back(std::move(r));
  };
  for (auto [x, m] : shadow_)
    copy(then_node(bit_leaf(Op::LOAD, bit_opd(Area::X, x), root), out(Op::OUT, {bit_opd(Area::M, m)}, root), {rungs_[0].line, 1}));
  for (auto [x, d] : shadow_w_)
    copy(out(Op::MOV, {Operand{OpdKind::Int, Area::WX, x}, Operand{OpdKind::Int, Area::D, d}}, root));
  if (clock_) {  // a TON always on gives this scan's dt in its ET (ms): clock += dt in ns; ET := 0
    Operand tm{OpdKind::Timer}, pt = const_opd(INT32_MAX), et{OpdKind::Int, Area::TW, clock_->first};
    tm.index = clock_->first;
    Operand clock{OpdKind::Int, Area::D, clock_->second}, ns{OpdKind::Int, Area::D, clock_->second + 2};
    std::vector<TreeNode> acts;
    acts.push_back(out(Op::TON, {tm, pt}, root));
    acts.push_back(tout(Op::TCONV, IT::LINT, IT::DINT, {et, ns}, root));
    acts.push_back(tout(Op::TMUL, IT::LINT, IT::None, {ns, Operand::typed_const(1000000), ns}, root));
    acts.push_back(tout(Op::TADD, IT::LINT, IT::None, {clock, ns, clock}, root));
    acts.push_back(tout(Op::TMOVE, IT::DINT, IT::None, {Operand::typed_const(0), et}, root));
    TreeRung r;
    r.line = rungs_[0].line;
    r.title = "RTC's scan clock";
    r.root = then_node(Cond::yes(), fork_of(std::move(acts)), {r.line, 1});
    copies.insert(copies.begin(), std::move(r));
    clock_.reset();
  }
  for (auto& r : unit_init_) copies.push_back(std::move(r));
  unit_init_.clear();
  rungs_.insert(rungs_.begin(), std::make_move_iterator(copies.begin()), std::make_move_iterator(copies.end()));
  p.source = file_;
  p.rungs = std::move(rungs_);
  rungs_.clear();
  p.end_labels = std::move(pending_labels_);
  pending_labels_.clear();
  shadow_.clear();
  shadow_w_.clear();
  aliases(p);
}

// ------------------------------------------------------------------ error recovery

template <class F>
bool Importer::recover(F&& f) {
  if (!diag_) {
    f();
    return true;
  }
  try {
    f();
    return true;
  } catch (const Refused&) {
  } catch (const Fatal&) {
    throw;
  } catch (const CompileError& e) {
    report(e);
  }
  return false;
}

// An error recovered from, once per place: an XML element (a callee's body
// is expanded at each call, and an FB that contains itself is found again
// from each of its instances).
void Importer::report(const CompileError& e) {
  if (!reported_.insert({e.line, e.col}).second) return;
  if (!tc6_v1_) return diag_->error(file_, e);
  const auto* noted = dynamic_cast<const NotedError*>(&e);
  diag_->error(file_, NotedError(e.line, e.col, std::string(e.what()) + tc6_v1_note(), noted ? noted->notes : std::vector<DiagNote>{}));
}

// An unknown name, reported once per POU (as gcc reports an undeclared
// identifier once per function) and not at all when its declaration was
// refused.
void Importer::unknown_name(const Element* el, const std::string& name, const std::string& msg) {
  std::string key = upper(trim(name.substr(0, name.find_first_of("[."))));
  if (diag_ && (failed_names_.count(key) || !unknown_.insert({upper(pou_), key}).second)) throw Refused();
  // "did you mean": a variable of the POU's scope or a global, by edit distance (frontend/diag.h)
  std::vector<std::string> names;
  std::vector<const Var*> vars;
  for (const auto* m : {&scope_, &globals_})
    for (const auto& [k, v] : *m)
      if (v->name.find_first_of(".[") == std::string::npos) names.push_back(v->name), vars.push_back(v);
  std::string near = closest_name(name.substr(0, name.find_first_of("[.")), names);
  if (near.empty() || !el) fail_at(el, msg);
  const Var* v = vars[size_t(std::find(names.begin(), names.end(), near) - names.begin())];
  std::vector<DiagNote> notes;
  if (v->el) notes.push_back({v->el->line, v->el->col, "'" + near + "' is declared here"});
  throw NotedError(el->line, el->col, msg + "; did you mean '" + near + "'?", notes);
}

TreeProgram Importer::run() {
  prepare();
  const Element* root = doc_.root.get();
  if (cfg_tasks_.size() > 1)
    fail_at(cfg_tasks_[1].el, "the configuration has " + std::to_string(cfg_tasks_.size()) +
                                  " tasks: ldc compiles it as a project, one image per task (ldc FILE -o DIR)");
  TreeProgram p = run_prepared(root);
  if (chart_) fail_at(root, "POU '" + chart_pou_ + "' is an SFC program: its chart is compiled through import_plcopen");
  return p;
}

TreeProgram Importer::run_prepared(const Element* root) {
  emit_init([](const Var&) { return true; }, root);
  emit_bodies(ld_pous_);
  if (rungs_.empty()) fail_at(ld_pous_[0], "the LD and FBD bodies of this project have no coils, variables or blocks to run");
  TreeProgram p;
  finish(p, root);
  return p;
}

// One task of several: the programs of its instances, in order, over the
// devices every task shares.
PlcopenTask Importer::task_program(size_t i, const Element* root) {
  const CfgTask& ct = cfg_tasks_[i];
  PlcopenTask t;
  t.name = ct.name, t.resource = ct.resource, t.resource_index = ct.resource_index;
  t.line = ct.el->line, t.col = ct.el->col;
  std::string where = "task '" + ct.name + "' (" + ct.el->path() + ")";
  if (ct.no_task)
    fail_at(ct.el, "program instance '" + ct.name + "' of resource '" + ct.resource +
                       "' belongs to no task; in a configuration of several tasks ldc needs each program's task and interval (" +
                       ct.el->path() + ")");
  auto us = interval_us(ct.interval);
  if (ct.interval.empty()) fail_at(ct.el, where + " has no interval; ldc runs periodic tasks only (an event task, 'single', is not supported)");
  if (!us || *us < 50 || *us > 10000000)
    fail_at(ct.el, where + ": interval '" + ct.interval + "' is not a period ldc can run (a whole number of microseconds, 50us..10s)");
  t.period_us = uint32_t(*us);
  if (!ct.priority_text.empty()) {
    const std::string& pr = ct.priority_text;
    if (pr.find_first_not_of("0123456789") != std::string::npos || pr.size() > 2)
      fail_at(ct.el, where + ": priority '" + pr + "' is not one ldc has (0, the highest, .. 99)");
    t.priority = uint32_t(std::stoul(pr));
  }
  if (ct.instances.empty()) fail_at(ct.el, where + " runs no program");
  t.program = ct.instances.size() == 1 ? ct.instances[0] : ct.name + "_programs";
  std::vector<const Element*> pous;
  for (size_t k = 0; k < ct.pous.size(); k++)
    for (const Element* pe : ld_pous_)
      if (upper(*pe->attr("name")) == ct.pous[k]) pous.push_back(pe);
  task_ = int(i);
  std::set<const Element*> mine(pous.begin(), pous.end());
  emit_bodies(pous);
  if (rungs_.empty()) fail_at(ct.el, where + ": its programs have no coils, variables or blocks to run");
  // the initial values of its POUs' variables and of the globals it uses
  std::vector<TreeRung> bodies = std::move(rungs_);
  rungs_.clear();
  std::set<std::string> my_pous;
  for (const Element* pe : pous) my_pous.insert(*pe->attr("name"));
  emit_init([&](const Var& v) {
    if (v.pou.empty()) return global_users_.count(const_cast<Var*>(&v)) && global_users_[const_cast<Var*>(&v)].count(int(i));
    return my_pous.count(v.pou) > 0;
  }, root);
  for (auto& r : bodies) rungs_.push_back(std::move(r));
  finish(t.tree, root);
  take_chart(t.chart);
  task_ = -1;
  return t;
}

// A configuration of several tasks: a program per task.  A POU runs in one
// program instance only, and a global held in a program's private memory
// (an integer or REAL in D or F, a timer or counter) in one task only.
PlcopenImport Importer::import() {
  PlcopenImport r;
  prepare();
  const Element* root = doc_.root.get();
  if (cfg_tasks_.size() <= 1) {
    r.single = run_prepared(root);
    take_chart(r.single_chart);
    return r;
  }
  std::map<std::string, std::string> owner;  // upper POU -> instance
  for (const CfgTask& ct : cfg_tasks_)
    for (size_t k = 0; k < ct.pous.size(); k++) {
      auto [it, fresh] = owner.emplace(ct.pous[k], ct.instances[k]);
      if (!fresh)
        fail_at(ct.instance_els[k], "program instance '" + ct.instances[k] + "' runs POU '" + *instance_type(ct.instance_els[k]) +
                                        "', as instance '" + it->second + "' does; ldc translates each POU once, so one instance per POU (" +
                                        ct.instance_els[k]->path() + ")");
    }
  r.configuration = config_name_;
  for (size_t i = 0; i < cfg_tasks_.size(); i++) r.tasks.push_back(task_program(i, root));
  for (auto& [v, users] : global_users_) {
    if (users.size() < 2 || !v->dev) continue;
    Dev d = v->dev->dev;
    if (d != Dev::D && d != Dev::F && d != Dev::T && d != Dev::C) continue;
    auto it = users.begin();
    const std::string& a = cfg_tasks_[*it].name;
    const std::string& b = cfg_tasks_[*++it].name;
    fail_at(v->el, "global variable '" + v->name + "' (" + v->type + ") is used by the programs of tasks '" + a + "' and '" + b +
                       "'; ldc keeps it in a program's private memory (" + dev_name(d) +
                       "), so tasks share only BOOL globals (relays, M) and variables located at inputs and outputs (%I, %Q)");
  }
  r.configuration = config_name_;
  return r;
}

// Runs an import; an error in a TC6 1.0 file says which format it is.  With
// `diag`, the errors recovered from are reported there (the import ends with
// ErrorsReported); one the import cannot go on from is thrown as before.
template <class F>
auto importing(std::string_view text, const std::string& filename, Diagnostics* diag, F run) {
  Importer im(text, filename, diag);
  try {
    auto r = run(im);
    im.warn_unused();
    return r;
  } catch (const Refused&) {  // outside any recovery: its cause is reported
    throw ErrorsReported();
  } catch (const CompileError& e) {
    if (!im.tc6_v1_) throw;
    throw CompileError(e.line, e.col, std::string(e.what()) + tc6_v1_note());
  }
}
}  // namespace

TreeProgram parse_plcopen(std::string_view text, const std::string& filename) {
  return importing(text, filename, nullptr, [](Importer& im) { return im.run(); });
}

PlcopenImport import_plcopen(std::string_view text, const std::string& filename) {
  return importing(text, filename, nullptr, [](Importer& im) { return im.import(); });
}

TreeProgram parse_plcopen(std::string_view text, const std::string& filename, Diagnostics& diag) {
  return importing(text, filename, &diag, [](Importer& im) { return im.run(); });
}

PlcopenImport import_plcopen(std::string_view text, const std::string& filename, Diagnostics& diag) {
  return importing(text, filename, &diag, [](Importer& im) { return im.import(); });
}

}  // namespace ldc
