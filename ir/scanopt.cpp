// ir/scanopt.cpp -- dead stores, unread stack entries, folded constants,
// repeated divisions and typed results already held of one scan (ir/scanopt.h).
#include "ir/scanopt.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <unordered_map>

#include "ir/codegen.h"
#include "ir/typed.h"

namespace ldc {

size_t ScanFacts::count(ScanFlag f) const {
  return size_t(std::count_if(flags.begin(), flags.end(), [f](uint8_t x) { return (x & f) != 0; }));
}

namespace {

bool is_device(const Operand& o) {
  return o.kind == OpdKind::Bit || o.kind == OpdKind::Int || o.kind == OpdKind::Real;
}
bool is_const(const Operand& o) { return o.kind == OpdKind::ConstInt || o.kind == OpdKind::ConstReal; }
// A typed instruction (class Typed) is a barrier to every fact here: its
// operands may take two words, its LDX / STX reach any element of an array,
// and an IDX may end the scan (docs/x86.md, "Typed instructions").
bool is_typed(Op op) { return op_info(op).klass == OpClass::Typed; }
bool is_app(Op op) {
  OpClass k = op_info(op).klass;
  return k == OpClass::Move || k == OpClass::Arith || k == OpClass::Logic || k == OpClass::Special;
}
// DIV and MOD may also set S0 (a zero divisor), and then keep their destination.
bool is_divmod(Op op) { return op == Op::DIV || op == Op::MOD; }

// The devices one instruction reads and writes, by image address (a device's
// first byte: areas never overlap, so the address names the device).
struct Access {
  uint32_t reads[4] = {};
  uint32_t writes[3] = {};
  int nr = 0, nw = 0;
  bool uncond = false;     // its writes happen whatever the power
  bool removable = false;  // its writes are its only effect
  void read(uint32_t a) { reads[nr++] = a; }
  void write(uint32_t a) { writes[nw++] = a; }
};

uint32_t addr(const Layout& l, const Operand& o) { return l.addr(o.area, o.index); }

void timer_access(const Layout& l, const Instr& in, Access& a) {
  uint32_t n = in.a[0].index;
  bool counter = in.a[0].kind == OpdKind::Counter;
  Area w = counter ? Area::CW : Area::TW, q = counter ? Area::CQ : Area::TQ;
  a.read(l.addr(w, n)), a.read(l.addr(q, n));
  a.write(l.addr(w, n)), a.write(l.addr(q, n));
  if (!counter) a.read(l.addr(Area::TI, n)), a.write(l.addr(Area::TI, n));
  for (int k = 1; k < in.nopd(); k++)
    if (is_device(in.a[k])) a.read(addr(l, in.a[k]));
    else if (in.a[k].kind == OpdKind::Edge) a.read(l.addr(Area::E, in.a[k].index));
}

// `on`: the instruction's power is 1 for certain (KnownStack)
Access access(const Layout& l, const Instr& in, bool on) {
  Access a;
  const OpInfo& info = op_info(in.op);
  switch (in.op) {
    case Op::OUT: case Op::OUTN: a.write(addr(l, in.a[0])); a.uncond = a.removable = true; return a;
    case Op::SET: case Op::RST: a.write(addr(l, in.a[0])); a.removable = true; return a;
    case Op::LOADP: case Op::LOADF:
      a.read(addr(l, in.a[0]));
      a.read(l.addr(Area::E, in.a[1].index)), a.write(l.addr(Area::E, in.a[1].index));
      return a;
    default: break;
  }
  if (info.klass == OpClass::Timer || info.klass == OpClass::Counter) {
    timer_access(l, in, a);
    return a;
  }
  for (int k = 0; k < in.nopd(); k++)
    if (is_device(in.a[k]) && !(is_app(in.op) && k == in.nopd() - 1)) a.read(addr(l, in.a[k]));
  if (!is_app(in.op)) return a;
  a.write(addr(l, in.a[in.nopd() - 1]));
  if (is_divmod(in.op)) {  // S0 |= zero divisor, and d kept then
    uint32_t s0 = l.addr(Area::S, kBitError);
    a.read(s0), a.write(s0);
    return a;
  }
  a.uncond = on;
  a.removable = true;
  return a;
}

// Is the power of each instruction 1 for certain?  (per instruction, in order)
std::vector<char> powered(const Program& p, size_t total) {
  std::vector<char> on;
  on.reserve(total);
  KnownStack known;
  for (const Rung& r : p.rungs) {
    known.reset();
    for (const Instr& in : r.code) {
      on.push_back(known.on());
      known.step(in);
    }
  }
  return on;
}

// Backward over the whole program: a store to a device that a later store
// overwrites for certain, with no read, JMP or END between, is dead.  Labels
// need nothing: every jump goes forward, and a JMP forgets what lies after it.
void dead_stores(const Program& p, const Layout& l, const std::vector<char>& on, ScanFacts& f) {
  std::vector<uint32_t> stamp(l.size, 0);  // killed: stamp == gen
  uint32_t gen = 1;
  for (size_t ri = p.rungs.size(); ri-- > 0;) {
    const std::vector<Instr>& code = p.rungs[ri].code;
    for (size_t k = code.size(); k-- > 0;) {
      const Instr& in = code[k];
      uint32_t i = f.first[ri] + uint32_t(k);
      if (in.op == Op::JMP || in.op == Op::END || in.op == Op::LOOP || is_typed(in.op)) { gen++; continue; }
      Access a = access(l, in, on[i]);
      bool dead = a.removable && a.nw > 0;
      for (int w = 0; w < a.nw; w++) dead = dead && stamp[a.writes[w]] == gen;
      if (dead) { f.flags[i] |= kDeadStore; continue; }
      if (a.uncond)
        for (int w = 0; w < a.nw; w++) stamp[a.writes[w]] = gen;
      for (int r = 0; r < a.nr; r++) stamp[a.reads[r]] = 0;
    }
  }
}

// Backward over one rung whose stack is private and fits the slots: an entry
// written and never read before the rung ends or the position is written
// again is unread.  depth: storage kept from rung to rung.
void unread_entries(const std::vector<Instr>& code, uint32_t first, ScanFacts& f, std::vector<int>& depth) {
  depth.resize(code.size());
  int d = 0;
  for (size_t k = 0; k < code.size(); k++) {
    depth[k] = d;
    d += op_info(code[k].op).push - op_info(code[k].op).pop;
  }
  // bit p: position p is read before it is written again; a stack that fits
  // holds at most kMaxStackDepth entries and reads no position below 0
  static_assert(kMaxStackDepth < 64);
  uint64_t live = 0;
  for (size_t k = code.size(); k-- > 0;) {
    if (f.flags[first + k] & kDeadStore) continue;
    StackUse u = stack_use(code[k].op, depth[k]);
    if (u.writes) {
      const uint64_t bit = uint64_t(1) << u.write;
      if (!(live & bit)) { f.flags[first + k] |= kUnread; continue; }
      live &= ~bit;
    }
    for (int r = 0; r < u.nreads; r++) live |= uint64_t(1) << u.reads[r];
  }
}


// The value of an application instruction whose sources are constants, as
// the reference interpreter computes it (`TRUE; in` on a zero image, the
// destination read back and cleared); nullopt where the instruction has
// another effect (S0), calls a C library function, or gives a NaN.
class Folder {
 public:
  explicit Folder(const Layout& l) : layout_(l) {}
  std::optional<Operand> fold(const Instr& in);

 private:
  const Layout& layout_;
  std::optional<Memory> mem_;  // made at the first fold: most programs have none
};

std::optional<Operand> Folder::fold(const Instr& in) {
  RealFn fn = op_info(in.op).fn;
  if (fn != RealFn::None && real_fn_info(fn).called) return std::nullopt;
  if (!mem_) mem_.emplace(layout_);
  Memory& mem = *mem_;
  Program p;
  p.rungs.emplace_back().code = {Instr{Op::TRUE, Ty::None, Ty::None, {}, {}}, in};
  BinaryIl il = encode_il(p);
  Interpreter(il.code, mem.layout).scan(mem.data());
  const Operand& d = in.a[in.nopd() - 1];
  uint8_t* at = mem.data() + mem.layout.addr(d.area, d.index);
  uint8_t& s0 = mem.bytes[mem.layout.addr(Area::S, kBitError)];
  uint32_t bits;
  std::memcpy(&bits, at, 4);
  bool error = s0 != 0;
  std::memset(at, 0, 4), s0 = 0;
  if (error) return std::nullopt;
  Operand c;
  if (d.kind == OpdKind::Real) {
    float v;
    std::memcpy(&v, &bits, 4);
    if (std::isnan(v)) return std::nullopt;
    c.kind = OpdKind::ConstReal, c.fval = v;
  } else {
    c.kind = OpdKind::ConstInt, c.ival = int32_t(bits);
  }
  return c;
}

// Forward over the program: the words a store of a constant with power on
// for certain made known, until something else writes them or a rung that
// jumps land on starts.  Sources known are replaced by their constants, and
// an instruction whose sources are all constants becomes a MOV of its result.
class Propagate {
 public:
  Propagate(const Layout& l, const std::vector<char>& on, ScanFacts& f) : l_(l), on_(on), f_(f), folder_(l) {}
  void rung(const Rung& r, uint32_t first) {
    if (!r.labels.empty()) known_.clear();
    for (size_t k = 0; k < r.code.size(); k++) instr(r.code[k], first + uint32_t(k));
  }

 private:
  void instr(const Instr& in, uint32_t i) {
    const OpInfo& info = op_info(in.op);
    if (is_typed(in.op)) return known_.clear();
    if (info.klass == OpClass::Timer || info.klass == OpClass::Counter) {
      if (!known_.empty()) known_.erase(l_.addr(info.klass == OpClass::Timer ? Area::TW : Area::CW, in.a[0].index));
      return;
    }
    if (!is_app(in.op)) return;
    Instr use = in;
    bool changed = false, all = true;
    int last = in.nopd() - 1;
    for (int k = 0; k < last; k++) {
      if (!known_.empty() && is_device(use.a[k])) {
        auto it = known_.find(addr(l_, use.a[k]));
        if (it != known_.end()) use.a[k] = it->second, changed = true;
      }
      all = all && is_const(use.a[k]);
    }
    bool plain = in.op == Op::MOV && is_const(in.a[0]);  // already what folding makes
    std::optional<Operand> c = plain ? moved(in.a[0], in.a[1]) : all ? folder_.fold(use) : std::nullopt;
    if (c && !plain) use = Instr{Op::MOV, Ty::None, Ty::None, {*c, use.a[last]}, in.loc};
    if ((c && !plain) || changed) f_.replaced.emplace_back(i, use);
    if (c && on_[i]) known_[addr(l_, in.a[last])] = *c;
    else if (!known_.empty()) known_.erase(addr(l_, in.a[last]));
  }

  // what `MOV c d` stores, as the constant of d's type (docs/il.md, MOV)
  static std::optional<Operand> moved(const Operand& c, const Operand& d) {
    Operand v;
    if (d.kind == OpdKind::Real) {
      v.kind = OpdKind::ConstReal, v.fval = c.kind == OpdKind::ConstReal ? c.fval : int_to_real(c.ival);
      if (std::isnan(v.fval)) return std::nullopt;
    } else {
      v.kind = OpdKind::ConstInt, v.ival = c.kind == OpdKind::ConstInt ? c.ival : real_to_int(c.fval);
    }
    return v;
  }

  const Layout& l_;
  const std::vector<char>& on_;
  ScanFacts& f_;
  Folder folder_;
  std::unordered_map<uint32_t, Operand> known_;  // by address
};

// Forward over the program (ScanFacts::reused): the INT32 divisions done with
// power on for certain whose operands and destination nothing has written
// since, until a rung that jumps land on starts; by their operands' pair,
// with the pairs each address takes part in, so a write forgets them at once.
class Divisions {
 public:
  Divisions(const Layout& l, const std::vector<char>& on, ScanFacts& f) : l_(l), on_(on), f_(f) {}
  void rung(const Rung& r, uint32_t first) {
    if (!r.labels.empty()) forget();
    for (size_t k = 0; k < r.code.size(); k++) {
      const Op op = r.code[k].op;
      if (is_typed(op)) {
        forget();
        continue;
      }
      if (pairs_.empty() && !is_divmod(op) && op != Op::JMP && op != Op::END && op != Op::LOOP) continue;  // nothing kept to forget
      uint32_t i = first + uint32_t(k);
      const Instr* alt = entry_at(f_.replaced, i);
      instr(alt ? *alt : r.code[k], i);
    }
  }

 private:
  static constexpr uint32_t kNone = UINT32_MAX;
  struct Done {
    uint32_t a, b, d;
    Operand dst;
    uint32_t at;  // the instruction's index, kNone if it took an earlier result (no idiv to store a quotient)
  };
  struct Pair {
    std::optional<Done> q, r;  // the quotient's and the remainder's
  };
  static uint64_t key(uint32_t a, uint32_t b) { return uint64_t(a) << 32 | b; }

  void instr(const Instr& in, uint32_t i) {
    std::optional<Done> now = division(in, i);
    bool mod = in.op == Op::MOD;
    if (now && reuse(*now, mod, i)) now->at = kNone;
    if (in.op == Op::JMP || in.op == Op::END || in.op == Op::LOOP) exit_ = i;
    if (!pairs_.empty() || now) accessed(in, i);  // a division's own accesses count for a DIV it may serve
    if (!now || now->d == now->a || now->d == now->b) return;
    Pair& p = pairs_[key(now->a, now->b)];
    (mod ? p.r : p.q) = *now;
    for (uint32_t at : {now->a, now->b, now->d}) users_[at].push_back(key(now->a, now->b));
  }
  // an INT32 division of two words into a word, with power on for certain
  std::optional<Done> division(const Instr& in, uint32_t i) const {
    if (!is_divmod(in.op) || !on_[i]) return std::nullopt;
    for (int k = 0; k < 3; k++)
      if (in.a[k].kind != OpdKind::Int) return std::nullopt;
    return Done{addr(l_, in.a[0]), addr(l_, in.a[1]), addr(l_, in.a[2]), in.a[2], i};
  }
  // records what the division takes from an earlier one, if anything (true then)
  bool reuse(const Done& now, bool mod, uint32_t i) {
    auto it = pairs_.find(key(now.a, now.b));
    if (it == pairs_.end()) return false;
    const std::optional<Done>& same = mod ? it->second.r : it->second.q;
    if (same) f_.reused.emplace_back(i, DivReuse{same->dst, false});
    else if (mod && it->second.q) f_.reused.emplace_back(i, DivReuse{it->second.q->dst, true});
    else if (!mod && it->second.r && untouched_since(now.d, it->second.r->at)) {
      // the MOD divided: it stores the quotient here too, and this DIV needs no code
      f_.reused.emplace_back(i, DivReuse{it->second.r->dst, false, true});
      f_.early_quotient.emplace_back(it->second.r->at, now.dst);
    } else {
      return false;
    }
    return true;
  }
  // May the division at `since` store into d already?  Nothing has read or
  // written d since (its own operands and destination included), and no JMP
  // or END could leave before this instruction.
  bool untouched_since(uint32_t d, uint32_t since) const {
    if (since == kNone || d >= access_.size()) return false;
    return (access_[d] == kNone || access_[d] < since) && (exit_ == kNone || exit_ < since);
  }
  // in's reads and writes: the last access of each address, and the kept
  // divisions a write forgets
  void accessed(const Instr& in, uint32_t i) {
    const Access acc = access(l_, in, on_[i]);
    if (access_.empty()) access_.assign(l_.size, kNone);  // the first division kept: from here on
    for (int k = 0; k < acc.nr; k++) access_[acc.reads[k]] = i;
    for (int k = 0; k < acc.nw; k++) access_[acc.writes[k]] = i;
    for (int w = 0; w < acc.nw; w++) {
      const uint32_t at = acc.writes[w];
      if (at == l_.addr(Area::S, kBitError) && !is_divmod(in.op)) return forget();  // a zero divisor's S0 may be gone
      auto u = users_.find(at);
      if (u == users_.end()) continue;
      for (uint64_t k : u->second) {
        auto p = pairs_.find(k);
        if (p == pairs_.end()) continue;
        for (std::optional<Done>* x : {&p->second.q, &p->second.r})
          if (*x && ((*x)->a == at || (*x)->b == at || (*x)->d == at)) x->reset();
        if (!p->second.q && !p->second.r) pairs_.erase(p);
      }
      users_.erase(u);
    }
  }
  void forget() { pairs_.clear(), users_.clear(); }

  const Layout& l_;
  const std::vector<char>& on_;
  ScanFacts& f_;
  std::unordered_map<uint64_t, Pair> pairs_;
  std::unordered_map<uint32_t, std::vector<uint64_t>> users_;  // the pairs whose operands or destinations lie there
  // while any pair is kept: the last instruction that read or wrote each address, and the last JMP or END
  std::vector<uint32_t> access_;  // by image address, kNone: not since the first division
  uint32_t exit_ = kNone;
};

// Forward over the program (kHeld): the typed instructions done with power on
// for certain, by destination, and for every byte of the image the last
// instruction that may have written it.  A later identical instruction whose
// sources nobody has written since the earlier one ran, and whose destination
// only the earlier one has, would store the bits the destination holds: it
// needs no code.  The result is a function of the sources' bits alone (no S0,
// no C library), so identical sources give identical bits, NaNs included.
// A rung that jumps land on forgets all (a jump may come from before the
// earlier instruction ran).  JMP, END and a faulting IDX need nothing: they
// leave the scan or jump over the later instruction too.
class Held {
 public:
  Held(const Layout& l, const std::vector<char>& on, ScanFacts& f) : l_(l), on_(on), f_(f), last_(l.size, 0) {}
  void rung(const Rung& r, uint32_t first) {
    if (!r.labels.empty()) done_.clear();
    for (size_t k = 0; k < r.code.size(); k++) instr(r.code, k, first + uint32_t(k));
  }

 private:
  struct Span {
    uint32_t at = 0, bytes = 0;
  };
  // the bytes typed operand k of `in` reads or writes
  Span span(const Instr& in, int k) const {
    const Operand& o = in.a[k];
    const Ty t = operand_type(in, k);
    return {l_.addr(o.area, o.index), t == Ty::BOOL ? 1u : 4u * uint32_t(ty_info(t).cells)};
  }
  // Does the result of `in` depend on its sources' bits alone, with no other effect?
  static bool pure(const Instr& in) {
    switch (in.op) {
      case Op::TMOVE: case Op::TADD: case Op::TSUB: case Op::TMUL: case Op::TMIN: case Op::TMAX:
      case Op::TAND: case Op::TOR: case Op::TXOR: case Op::TNOT: case Op::TSHL: case Op::TSHR:
      case Op::TROL: case Op::TROR: case Op::TNEG: case Op::TABS: case Op::TSQRT: case Op::TCONV: case Op::TTRUNC:
        return true;
      case Op::TDIV: return typed::is_real(in.ty);  // an integer divisor of 0 sets S0
      default: return false;  // compares push; IDX LDX STX; the C library's functions; MOD sets S0
    }
  }
  bool written_after(Span s, uint32_t t) const {
    for (uint32_t b = s.at; b < s.at + s.bytes && b < l_.size; b++)
      if (last_[b] > t) return true;
    return false;
  }
  bool only_by(Span s, uint32_t t) const {
    for (uint32_t b = s.at; b < s.at + s.bytes && b < l_.size; b++)
      if (last_[b] != t) return false;
    return true;
  }
  void wrote(Span s, uint32_t t) {
    for (uint32_t b = s.at; b < s.at + s.bytes && b < l_.size; b++) last_[b] = t;
  }
  // Is `in` (at stamp t) what an earlier instruction left in its destination?
  bool held(const Instr& in) const {
    const int d = in.nopd() - 1;
    auto it = done_.find(span(in, d).at);
    if (it == done_.end() || !(*it->second.in == in)) return false;
    const uint32_t then = it->second.t;
    for (int k = 0; k < d; k++)
      if (is_device(in.a[k]) && written_after(span(in, k), then - 1)) return false;  // its own write counts
    return only_by(span(in, d), then);
  }
  // What `in` may write, stamped t (untyped: the devices access() names, a word's bytes)
  void writes(const std::vector<Instr>& code, size_t k, uint32_t t, uint32_t i) {
    const Instr& in = code[k];
    if (!is_typed(in.op)) {
      const Access a = access(l_, in, on_[i]);
      for (int w = 0; w < a.nw; w++) wrote({a.writes[w], 4}, t);
      const OpClass c = op_info(in.op).klass;
      if (c == OpClass::Timer || c == OpClass::Counter)  // the edge slot a counter keeps
        for (int j = 1; j < in.nopd(); j++)
          if (in.a[j].kind == OpdKind::Edge) wrote({l_.addr(Area::E, in.a[j].index), 1}, t);
      return;
    }
    const char* sig = op_info(in.op).operands;
    for (int j = 0; j < in.nopd(); j++)
      if (sig[j] == 'r') wrote(span(in, j), t);
    if ((in.op == Op::TDIV || in.op == Op::TMOD) && !typed::is_real(in.ty)) wrote({l_.addr(Area::S, kBitError), 1}, t);
    if (in.op == Op::TSTX) stored_element(code, k, t);
  }
  // STX: any element of its array, base + (0..hi-lo) * stride, the IDX before it gives lo and hi
  void stored_element(const std::vector<Instr>& code, size_t k, uint32_t t) {
    const Instr& in = code[k];
    if (k == 0 || code[k - 1].op != Op::TIDX) {  // (the validator refuses it; forget all the same)
      done_.clear();
      return;
    }
    // (the bounds and the stride are 32-bit, as the interpreter reads them; anything odd forgets all)
    auto value = [](const Operand& o) { return int64_t(int32_t(o.kind == OpdKind::ConstT ? uint32_t(o.bits()) : uint32_t(o.ival))); };
    const int64_t n = value(code[k - 1].a[2]) - value(code[k - 1].a[1]), stride = value(in.a[2]);
    const Operand& base = in.a[1];
    const uint64_t count = l_.count[int(base.area)];
    if (n < 0 || stride < 0 || uint64_t(n) > count || uint64_t(stride) > count ||
        uint64_t(base.index) + uint64_t(n) * uint64_t(stride) >= count) {
      done_.clear();
      return;
    }
    const uint32_t from = l_.addr(base.area, base.index);
    const uint32_t to = l_.addr(base.area, base.index + uint32_t(n * stride)) + span(in, 1).bytes;
    wrote({from, to - from}, t);
  }
  void instr(const std::vector<Instr>& code, size_t k, uint32_t i) {
    const Instr& in = code[k];
    const uint32_t t = i + 1;  // 0: not written in this scan
    if (pure(in) && held(in)) {  // writes nothing new: the destination keeps the earlier stamp
      f_.flags[i] |= kHeld;
      return;
    }
    writes(code, k, t, i);
    if (pure(in) && on_[i]) done_[span(in, in.nopd() - 1).at] = {&in, t};
  }

  struct Done {
    const Instr* in;
    uint32_t t;
  };
  const Layout& l_;
  const std::vector<char>& on_;
  ScanFacts& f_;
  std::vector<uint32_t> last_;  // per image byte: the stamp (index + 1) of its last writer, 0 none
  std::unordered_map<uint32_t, Done> done_;  // by destination address
};

}  // namespace

ScanFacts scan_facts(const Program& p, const Layout& layout, int slots) {
  ScanFacts f;
  f.first.reserve(p.rungs.size());
  uint32_t n = 0;
  for (const Rung& r : p.rungs) f.first.push_back(n), n += uint32_t(r.code.size());
  f.flags.assign(n, 0);
  std::vector<char> on = powered(p, n);
  dead_stores(p, layout, on, f);
  Propagate prop(layout, on, f);
  for (size_t ri = 0; ri < p.rungs.size(); ri++) prop.rung(p.rungs[ri], f.first[ri]);
  Divisions divs(layout, on, f);
  for (size_t ri = 0; ri < p.rungs.size(); ri++) divs.rung(p.rungs[ri], f.first[ri]);
  const bool typed = std::any_of(p.rungs.begin(), p.rungs.end(), [](const Rung& r) {
    return std::any_of(r.code.begin(), r.code.end(), [](const Instr& in) { return is_typed(in.op); });
  });
  if (typed) {  // (its image-sized table only where it can find something)
    Held held(layout, on, f);
    for (size_t ri = 0; ri < p.rungs.size(); ri++) held.rung(p.rungs[ri], f.first[ri]);
  }
  std::sort(f.early_quotient.begin(), f.early_quotient.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  f.fits.resize(p.rungs.size());
  for (size_t ri = 0; ri < p.rungs.size(); ri++) f.fits[ri] = stack_fits_slots(p.rungs[ri].code, slots);
  // shares_stack(p), asked of the rungs that do not fit only: one that fits
  // reads nothing an earlier rung left
  for (size_t ri = 0; ri < p.rungs.size() && !f.shared; ri++)
    f.shared = !f.fits[ri] && foreign_stack_use(p.rungs[ri].code) >= 0;
  if (f.shared) {  // an entry may be read by a later rung
    f.fits.assign(p.rungs.size(), 0);
    return f;
  }
  std::vector<int> depth;
  for (size_t ri = 0; ri < p.rungs.size(); ri++)
    if (f.fits[ri]) unread_entries(p.rungs[ri].code, f.first[ri], f, depth);
  return f;
}

}  // namespace ldc
