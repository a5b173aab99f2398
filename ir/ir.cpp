// ir/ir.cpp -- areas, layout, the op table, operand spelling, the binary IL codec.
#include "ir/ir.h"
#include "ir/typed.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <mutex>
#include <unordered_map>

namespace ldc {

// ---------------------------------------------------------------- label names

// The label table: chunks of strings that never move, so references into
// them (and ids read without the lock) stay valid while others intern.
// `chunks` is reserved once and never reallocates.
namespace {
constexpr uint32_t kLabelChunkBits = 10, kLabelChunkSize = 1u << kLabelChunkBits, kLabelMaxChunks = 1u << 16;
struct LabelTable {
  std::mutex lock;
  std::unordered_map<std::string_view, uint32_t> ids;
  std::vector<std::unique_ptr<std::string[]>> chunks;
  uint32_t next = 1;  // 0: the empty name
  LabelTable() { chunks.reserve(kLabelMaxChunks); }
};
LabelTable& label_table() {
  static LabelTable* t = new LabelTable;  // never destroyed: labels outlive static destructors
  return *t;
}
}  // namespace

uint32_t LabelText::intern(const std::string& text) {
  LabelTable& t = label_table();
  std::lock_guard<std::mutex> g(t.lock);
  auto it = t.ids.find(text);
  if (it != t.ids.end()) return it->second;
  uint32_t id = t.next;
  if ((id >> kLabelChunkBits) >= kLabelMaxChunks) throw std::length_error("too many distinct IL label names");
  if ((id >> kLabelChunkBits) >= t.chunks.size()) t.chunks.push_back(std::make_unique<std::string[]>(kLabelChunkSize));
  std::string& slot = t.chunks[id >> kLabelChunkBits][id & (kLabelChunkSize - 1)];
  slot = text;
  t.ids.emplace(std::string_view(slot), id);
  t.next++;
  return id;
}

const std::string& LabelText::str() const {
  static const std::string empty;
  if (id_ == 0) return empty;
  return label_table().chunks[id_ >> kLabelChunkBits][id_ & (kLabelChunkSize - 1)];
}

static const char* const kAreaNames[kAreaCount] = {"Sys", "S",  "X",  "Y",  "M",  "K",  "TQ", "CQ",
                                                   "TI",  "WX", "WY", "D",  "F",  "TW", "CW", "E"};

const char* area_name(Area a) { return kAreaNames[int(a)]; }

Layout Layout::standard(uint32_t edge_slots) {
  Layout l;
  auto set = [&](Area a, uint32_t n) { l.count[int(a)] = n; };
  set(Area::Sys, kSysSize);
  set(Area::S, kSysBits);
  set(Area::X, 8192); set(Area::Y, 8192); set(Area::M, 8192); set(Area::K, 8192);
  set(Area::TQ, 256); set(Area::CQ, 256); set(Area::TI, 256);
  set(Area::WX, 1024); set(Area::WY, 1024); set(Area::D, 8192); set(Area::F, 1024);
  set(Area::TW, 256); set(Area::CW, 256);
  set(Area::E, edge_slots);
  uint32_t off = 0;
  for (int i = 0; i < kAreaCount; i++) {
    Area a = Area(i);
    if (area_is_word(a)) off = (off + 3) & ~3u;
    l.offset[i] = off;
    off += l.count[i] * l.elem_size(a);
  }
  l.size = (off + 15) & ~15u;
  return l;
}

// ---------------------------------------------------------------- ops

Op compare_op(Rel r) {
  for (int i = 0; i < kOpCount; i++)
    if (kOps[i].rel == r && r != Rel::None) return Op(i);
  throw std::logic_error("compare_op: no compare for this relation");
}

static char ascii_upper(char c) { return c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c; }

// By hash over the names in upper case (every name in ops.def is): an open
// addressed table of op numbers, its slots more than twice the ops.  A name
// of up to 16 characters is packed into two words, so a probe compares two
// integers and the length, not strings.
namespace {
struct NameKey {
  uint64_t w[2] = {0, 0};
  size_t len = 0;
  bool operator==(const NameKey&) const = default;
};
// The letters of `s` in upper case, packed little-endian; false if longer than 16.
bool pack_upper(std::string_view s, NameKey& k) {
  if (s.size() > 16) return false;
  k.len = s.size();
  for (size_t i = 0; i < s.size(); i++) k.w[i >> 3] |= uint64_t(uint8_t(ascii_upper(s[i]))) << (8 * (i & 7));
  return true;
}
size_t key_hash(const NameKey& k) {
  uint64_t h = (k.w[0] ^ (k.w[1] * 0xC2B2AE3D27D4EB4Full) ^ k.len) * 0x9E3779B97F4A7C15ull;
  return size_t(h >> 40);
}
struct OpNames {
  static constexpr size_t kSlots = 512;
  static_assert(kSlots >= 2 * size_t(kOpCount) && (kSlots & (kSlots - 1)) == 0);
  std::array<NameKey, kOpCount> key;
  std::array<int16_t, kSlots> slot;  // an op number, -1 empty
  OpNames() {
    slot.fill(-1);
    for (int i = 0; i < kOpCount; i++) {
      pack_upper(kOps[i].name, key[size_t(i)]);
      size_t at = key_hash(key[size_t(i)]) & (kSlots - 1);
      while (slot[at] >= 0) at = (at + 1) & (kSlots - 1);
      slot[at] = int16_t(i);
    }
  }
};
}  // namespace

std::optional<Op> op_from_name(std::string_view name) {
  static const OpNames t;
  NameKey k;
  if (!pack_upper(name, k)) return std::nullopt;
  for (size_t at = key_hash(k) & (OpNames::kSlots - 1); t.slot[at] >= 0; at = (at + 1) & (OpNames::kSlots - 1))
    if (t.key[size_t(t.slot[at])] == k) return Op(t.slot[at]);
  return std::nullopt;
}

const char* op_class_name(OpClass c) {
  static const char* const n[] = {"basic", "compare", "move", "arith", "logic", "special", "timer", "counter", "flow", "typed"};
  return n[int(c)];
}

bool Instr::operator==(const Instr& o) const {
  if (op != o.op || ty != o.ty || src != o.src) return false;
  for (int i = 0; i < 3; i++)
    if (!(a[i] == o.a[i])) return false;
  return true;
}

// ---------------------------------------------------------------- spelling

static std::string device_prefix(Area a) {
  switch (a) {
    case Area::TQ: case Area::TW: return "T";
    case Area::CQ: case Area::CW: return "C";
    default: return area_name(a);
  }
}

std::string real_text(float f) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.9g", double(f));
  std::string s = buf;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // keep the REAL type visible
  return s;
}

std::string operand_text(const Operand& o) {
  switch (o.kind) {
    case OpdKind::None: return "";
    case OpdKind::Bit: case OpdKind::Int: case OpdKind::Real:
      return device_prefix(o.area) + std::to_string(o.index);
    case OpdKind::ConstInt: return std::to_string(o.ival);
    case OpdKind::ConstReal: return real_text(o.fval);
    case OpdKind::Edge: return "E" + std::to_string(o.index);
    case OpdKind::Timer: return "T" + std::to_string(o.index);
    case OpdKind::Counter: return "C" + std::to_string(o.index);
    case OpdKind::Label: return o.label;
    case OpdKind::ConstT: return "0x" + [&] { char b[24]; std::snprintf(b, sizeof b, "%llx", (unsigned long long)o.bits()); return std::string(b); }();
  }
  return "?";
}

std::string operand_text(const Instr& in, int i) {
  const Operand& o = in.a[i];
  if (o.kind == OpdKind::ConstT) return typed_const_text(operand_type(in, i), o.bits());
  return operand_text(o);
}

std::string instr_text(const Instr& in) {
  std::string s = op_spelling(in);
  for (int i = 0; i < in.nopd(); i++) s += " " + operand_text(in, i);
  return s;
}

// ---------------------------------------------------------------- runtime helpers

int32_t real_to_int(float f) {
  if (std::isnan(f)) return 0;
  if (f >= 2147483648.0f) return std::numeric_limits<int32_t>::max();
  if (f < -2147483648.0f) return std::numeric_limits<int32_t>::min();
  return static_cast<int32_t>(f);
}
float int_to_real(int32_t i) { return static_cast<float>(i); }

int32_t Memory::get_int(Area a, uint32_t i) const {
  int32_t v;
  std::memcpy(&v, &bytes[layout.addr(a, i)], 4);
  return v;
}
float Memory::get_real(uint32_t i) const {
  float v;
  std::memcpy(&v, &bytes[layout.addr(Area::F, i)], 4);
  return v;
}
void Memory::set_int(Area a, uint32_t i, int32_t v) { std::memcpy(&bytes[layout.addr(a, i)], &v, 4); }
void Memory::set_real(uint32_t i, float v) { std::memcpy(&bytes[layout.addr(Area::F, i)], &v, 4); }

// ---------------------------------------------------------------- binary IL
//
// tag 0x01 + i32   INT constant          tag 0x02 + f32   REAL constant
// tag 0x03 + u32   edge slot             tag 0x04 + u32   label (byte offset)
// tag 0x10+area + u16   device (bit, word, timer, counter)

enum : uint8_t { kTagInt = 1, kTagReal = 2, kTagEdge = 3, kTagLabel = 4, kTagTyped = 5, kTagArea = 0x10 };

// The binary IL is written through a pointer into room made ahead: a byte
// appended with push_back may alias the vector's own end pointer (uint8_t
// stores alias anything), so each push_back reloaded and stored it.
static uint8_t* put16(uint8_t* p, uint32_t x) {
  p[0] = uint8_t(x), p[1] = uint8_t(x >> 8);
  return p + 2;
}
static uint8_t* put32(uint8_t* p, uint32_t x) {
  for (int i = 0; i < 4; i++) p[i] = uint8_t(x >> (8 * i));
  return p + 4;
}
static uint32_t get16(const uint8_t* p) { return p[0] | (p[1] << 8); }
static uint32_t get32(const uint8_t* p) { return p[0] | (p[1] << 8) | (p[2] << 16) | (uint32_t(p[3]) << 24); }

// Writes o's bytes at p (a tag and a u16 or a u32); a label's offset is left
// 0 and listed in `fix` (`at`: the offset of p in the code).
static uint8_t* encode_operand(uint8_t* p, size_t at, const Operand& o, std::vector<std::pair<size_t, std::string>>& fix) {
  switch (o.kind) {
    case OpdKind::None: return p;
    case OpdKind::Bit: case OpdKind::Int: case OpdKind::Real: *p = uint8_t(kTagArea + int(o.area)); return put16(p + 1, o.index);
    case OpdKind::Timer: *p = uint8_t(kTagArea + int(Area::TW)); return put16(p + 1, o.index);
    case OpdKind::Counter: *p = uint8_t(kTagArea + int(Area::CW)); return put16(p + 1, o.index);
    case OpdKind::ConstInt: *p = kTagInt; return put32(p + 1, uint32_t(o.ival));
    case OpdKind::ConstReal: {
      uint32_t u;
      std::memcpy(&u, &o.fval, 4);
      *p = kTagReal;
      return put32(p + 1, u);
    }
    case OpdKind::Edge: *p = kTagEdge; return put32(p + 1, o.index);
    case OpdKind::Label: *p = kTagLabel; fix.emplace_back(at + 1, o.label); return put32(p + 1, 0);
    case OpdKind::ConstT: *p = kTagTyped; p = put32(p + 1, uint32_t(o.ival)); return put32(p, o.index);
  }
  return p;
}

BinaryIl encode_il(const Program& p) {
  constexpr size_t kMaxInstrBytes = 3 + 3 * 9;  // an opcode, two type bytes and three operands of up to 9 bytes
  BinaryIl b;
  std::vector<std::pair<size_t, std::string>> fix;
  std::vector<std::pair<std::string, uint32_t>> labels;
  size_t n = 0;
  for (const Rung& r : p.rungs) n += r.code.size();
  b.instr_offset.reserve(n);
  b.rung_offset.reserve(p.rungs.size());
  b.code.resize(8 * n + kMaxInstrBytes);  // about 8 bytes an instruction; grown below if short, cut at the end
  size_t used = 0;
  for (const Rung& r : p.rungs) {
    for (const auto& l : r.labels) labels.emplace_back(l, uint32_t(used));
    b.rung_offset.push_back(uint32_t(used));
    for (const Instr& in : r.code) {
      if (b.code.size() - used < kMaxInstrBytes) b.code.resize(2 * b.code.size());
      b.instr_offset.push_back(uint32_t(used));
      uint8_t* const start = b.code.data();
      uint8_t* at = start + used;
      *at++ = uint8_t(in.op);
      if (op_info(in.op).typed) *at++ = uint8_t(in.ty);
      if (op_info(in.op).typed == 2) *at++ = uint8_t(in.src);
      for (int i = 0; i < in.nopd(); i++) at = encode_operand(at, size_t(at - start), in.a[i], fix);
      used = size_t(at - start);
    }
  }
  b.code.resize(used);
  for (const auto& l : p.end_labels) labels.emplace_back(l, uint32_t(b.code.size()));
  for (auto& [pos, name] : fix) {
    uint32_t target = 0;
    bool found = false;
    for (auto& [n, off] : labels)
      if (n == name) { target = off; found = true; break; }
    if (!found) throw std::runtime_error("IL refers to undefined label '" + name + "'");
    for (int i = 0; i < 4; i++) b.code[pos + i] = uint8_t(target >> (8 * i));
  }
  return b;
}

// One operand: checks the tag against the signature letter and the index
// against the layout.  Returns "" or the reason.
static std::string check_operand(char sig, const uint8_t* p, size_t avail, const Layout& L, size_t& len,
                                 uint32_t& label_target) {
  if (avail < 1) return "truncated operand";
  uint8_t tag = p[0];
  auto need = [&](size_t n) { return avail >= 1 + n; };
  if (tag == kTagInt || tag == kTagReal) {
    if (!need(4)) return "truncated constant";
    len = 5;
    if (sig != 'v' && sig != 'i') return "constant where a device is required";
    if (tag == kTagReal && sig == 'i') return "REAL constant where INT32 is required";
    return "";
  }
  if (tag == kTagEdge || tag == kTagLabel) {
    if (!need(4)) return "truncated operand";
    len = 5;
    uint32_t v = get32(p + 1);
    if (tag == kTagEdge) {
      if (sig != 'e') return "edge slot operand out of place";
      if (v >= L.count[int(Area::E)]) return "edge slot " + std::to_string(v) + " outside the edge area";
    } else {
      if (sig != 'l') return "label operand out of place";
      label_target = v;
    }
    return "";
  }
  if (tag < kTagArea || tag >= kTagArea + kAreaCount) return "bad operand tag " + std::to_string(tag);
  if (!need(2)) return "truncated device operand";
  len = 3;
  Area a = Area(tag - kTagArea);
  uint32_t idx = get16(p + 1);
  if (idx >= L.count[int(a)]) return std::string("device index ") + std::to_string(idx) + " outside area " + area_name(a);
  bool ok = operand_area_ok(sig, a, idx);
  if (!ok) return std::string("operand area ") + area_name(a) + " not allowed here";
  return "";
}

// A typed operand (s x r a k) of type t.  Returns "" or the reason; a device
// operand's area and index, a constant's value.
struct TypedOpd {
  Area area = Area::Sys;
  uint32_t index = 0;
  int64_t value = 0;
};
static std::string check_typed_operand(char sig, Ty t, const uint8_t* p, size_t avail, const Layout& L, size_t& len,
                                       TypedOpd& o) {
  if (avail < 1) return "truncated operand";
  uint8_t tag = p[0];
  if (sig == 'k') {
    if (tag != kTagInt || avail < 5) return "an INT32 constant is required";
    len = 5;
    o.value = int32_t(get32(p + 1));
    return "";
  }
  if (tag == kTagTyped) {
    if (avail < 9) return "truncated constant";
    len = 9;
    if (sig != 's' && sig != 'x') return "constant where a device is required";
    if (t == Ty::STRING) return "a STRING operand is a device (33 cells); a literal is moved into one (docs/il.md, \"Strings\")";
    uint64_t v = get32(p + 1) | (uint64_t(get32(p + 5)) << 32);
    if (typed::norm(t, v) != v) return std::string("constant not a canonical ") + ty_info(t).name;
    return "";
  }
  if (tag < kTagArea || tag >= kTagArea + kAreaCount || avail < 3) return "bad typed operand";
  len = 3;
  o.area = Area(tag - kTagArea);
  o.index = get16(p + 1);
  if (!typed_area_ok(sig, t, o.area, o.index, L))
    return std::string(area_name(o.area)) + std::to_string(o.index) + " cannot hold this " + ty_info(t).name + " operand";
  return "";
}

// A typed instruction (its op byte read, p after it): its type bytes and
// operands.  An LDX / STX must come right after an IDX (`idx_span`: that IDX's
// hi - lo, or -1 if the instruction before was none), and its base plus the
// span times its stride must stay inside the base's area.
// Likewise a MID / DELETE / INSERT / REPLACE must come right after an ARGS
// (`args`: the instruction before was one).
static bool reads_args(Op op) { return op == Op::TMID || op == Op::TDELETE || op == Op::TINSERT || op == Op::TREPLACE; }
static std::string check_typed(Op op, std::span<const uint8_t> code, size_t& p, const Layout& L, int64_t& idx_span,
                               bool& args) {
  const OpInfo& oi = op_info(op);
  if (code.size() - p < size_t(oi.typed)) return "truncated type";
  Ty t = Ty(code[p]), u = oi.typed == 2 ? Ty(code[p + 1]) : Ty::None;
  if (int(t) >= kTyCount || (oi.typed == 2 && int(u) >= kTyCount) || !op_takes(op, t, u))
    return std::string(oi.name + 1) + " does not take type " + (int(t) < kTyCount ? ty_info(t).name : "?") +
           (oi.typed == 2 ? std::string(".") + (int(u) < kTyCount ? ty_info(u).name : "?") : "");
  p += size_t(oi.typed);
  TypedOpd o[3];
  for (int i = 0; oi.operands[i]; i++) {
    size_t len = 0;
    char sig = oi.operands[i];
    std::string e = check_typed_operand(sig, sig == 'x' ? u : t, code.data() + p, code.size() - p, L, len, o[i]);
    if (!e.empty()) return "operand " + std::to_string(i + 1) + ": " + e;
    p += len;
  }
  const int64_t span = idx_span;
  idx_span = -1;
  const bool had_args = args;
  args = op == Op::TARGS;
  if (reads_args(op) && !had_args) return std::string(oi.name + 1) + " not right after an ARGS";
  if (op == Op::TIDX) {
    if (o[1].value > o[2].value) return "IDX bounds " + std::to_string(o[1].value) + ".." + std::to_string(o[2].value) + " are empty";
    idx_span = o[2].value - o[1].value;
  } else if (op == Op::TLDX || op == Op::TSTX) {
    if (span < 0) return std::string(oi.name + 1) + " not right after an IDX";
    const TypedOpd& base = o[op == Op::TLDX ? 0 : 1];
    int64_t stride = o[op == Op::TLDX ? 1 : 2].value;
    if (stride < 0) return "negative stride";
    int64_t last = int64_t(base.index) + span * stride + std::max(ty_info(t).cells, 1) - 1;
    if (last >= int64_t(L.count[int(base.area)]))
      return std::string("the array at ") + area_name(base.area) + std::to_string(base.index) + " extends past its area";
  }
  return "";
}

// Two passes over the code, holding a bit per byte of it (where the
// instructions start), not a record per instruction: the loader runs this on
// untrusted images (docs/image-format.md, "What the loader allocates").  The
// first checks every operand and marks the starts, the second every jump's
// target against them.
std::string validate_il(std::span<const uint8_t> code, const Layout& layout) {
  std::vector<bool> starts(code.size()), indexed(code.size());  // instruction starts; LDX / STX
  // Walks the instructions, calling jump(offset, target) for each jump
  // operand; an operand's error ends the walk.
  auto walk = [&](auto&& jump) -> std::string {
    size_t off = 0;
    int64_t idx_span = -1;
    bool args = false;
    while (off < code.size()) {
      uint8_t opb = code[off];
      if (opb >= kOpCount) return "offset " + std::to_string(off) + ": unknown opcode " + std::to_string(opb);
      const OpInfo& oi = op_info(Op(opb));
      size_t p = off + 1;
      if (oi.typed) {
        if (std::string e = check_typed(Op(opb), code, p, layout, idx_span, args); !e.empty())
          return "offset " + std::to_string(off) + ": " + op_info(Op(opb)).name + ": " + e;
        indexed[off] = Op(opb) == Op::TLDX || Op(opb) == Op::TSTX || reads_args(Op(opb));
        starts[off] = true;
        off = p;
        continue;
      }
      idx_span = -1;
      args = false;
      for (const char* s = oi.operands; *s; s++) {
        size_t len = 0;
        uint32_t target = UINT32_MAX;
        std::string e = check_operand(*s, code.data() + p, code.size() - p, layout, len, target);
        if (!e.empty()) return "offset " + std::to_string(p) + ": " + oi.name + ": " + e;
        if (target != UINT32_MAX)
          if (std::string why = jump(uint32_t(off), target, Op(opb) == Op::LOOP); !why.empty()) return why;
        p += len;
      }
      starts[off] = true;
      off = p;
    }
    return "";
  };
  if (std::string why = walk([](uint32_t, uint32_t, bool) { return std::string(); }); !why.empty()) return why;
  return walk([&](uint32_t from, uint32_t to, bool loop) -> std::string {
    bool at_boundary = to == code.size() || (to < code.size() && starts[to]);
    if (!at_boundary) return "offset " + std::to_string(from) + ": jump target " + std::to_string(to) + " is not an instruction boundary";
    if (to < code.size() && indexed[to]) return "offset " + std::to_string(from) + ": jump to an LDX / STX past its IDX, or a string function past its ARGS";
    if (loop && to >= from) return "offset " + std::to_string(from) + ": LOOP to a label that does not come before it";
    if (!loop && to <= from) return "offset " + std::to_string(from) + ": backward jump (only a LOOP goes back)";
    return "";
  });
}

void write_scan_fault(uint8_t* mem, uint32_t kind, uint32_t il_offset, uint64_t value) {
  std::memcpy(mem + kSysFault, &kind, 4);
  std::memcpy(mem + kSysFaultAt, &il_offset, 4);
  std::memcpy(mem + kSysFaultValue, &value, 8);
}

bool has_loop(const Program& p) {
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code)
      if (in.op == Op::LOOP) return true;
  return false;
}

void append_rungs(Program& p, Program& q) {
  for (Rung& r : q.rungs) {
    for (Instr& in : r.code)
      for (Operand& o : in.a)
        if (o.kind == OpdKind::Edge) o.index += p.edge_slots;
    p.rungs.push_back(std::move(r));
  }
  q.rungs.clear();
  p.edge_slots += q.edge_slots;
}

uint32_t decode_instr(std::span<const uint8_t> code, uint32_t off, Instr& out) {
  out = Instr{};
  out.op = Op(code[off]);
  uint32_t p = off + 1;
  const OpInfo& oi = op_info(out.op);
  if (oi.typed) out.ty = Ty(code[p++]);
  if (oi.typed == 2) out.src = Ty(code[p++]);
  const char* sig = oi.operands;
  for (int i = 0; sig[i]; i++) {
    Operand& o = out.a[i];
    uint8_t tag = code[p];
    if (tag == kTagTyped) { o = Operand::typed_const(get32(&code[p + 1]) | (uint64_t(get32(&code[p + 5])) << 32)); p += 9; continue; }
    if (tag == kTagInt) { o.kind = OpdKind::ConstInt; o.ival = int32_t(get32(&code[p + 1])); p += 5; continue; }
    if (tag == kTagReal) {
      uint32_t u = get32(&code[p + 1]);
      o.kind = OpdKind::ConstReal; std::memcpy(&o.fval, &u, 4); p += 5; continue;
    }
    if (tag == kTagEdge) { o.kind = OpdKind::Edge; o.index = get32(&code[p + 1]); p += 5; continue; }
    if (tag == kTagLabel) {
      o.kind = OpdKind::Label; o.index = get32(&code[p + 1]);
      o.label = "@" + std::to_string(o.index); p += 5; continue;
    }
    Area a = Area(tag - kTagArea);
    o.area = a;
    o.index = get16(&code[p + 1]);
    p += 3;
    if (sig[i] == 't') o.kind = OpdKind::Timer;
    else if (sig[i] == 'c') o.kind = OpdKind::Counter;
    else if (area_is_bit(a)) o.kind = OpdKind::Bit;
    else o.kind = area_is_real(a) ? OpdKind::Real : OpdKind::Int;
    if (o.kind == OpdKind::Timer || o.kind == OpdKind::Counter) o.area = Area::Sys;
  }
  return p;
}

}  // namespace ldc

namespace ldc {

// ---------------------------------------------------------------- device spelling

static const char* const kDevNames[] = {"X", "Y", "M", "K", "S", "T", "C", "WX", "WY", "D", "F"};
static constexpr std::string_view kDevViews[] = {"X", "Y", "M", "K", "S", "T", "C", "WX", "WY", "D", "F"};
static_assert(std::size(kDevViews) == std::size(kDevNames));
const char* dev_name(Dev d) { return kDevNames[int(d)]; }

// isalpha and isdigit of the "C" locale, the one ldc runs in (it never sets
// another), without their table look-ups through the locale
static bool ascii_alpha(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
static bool ascii_digit(char c) { return c >= '0' && c <= '9'; }

// One pass over the name: the prefix packed in upper case as it is read, the
// digits summed as they are checked.
std::optional<DeviceRef> parse_device(std::string_view s) {
  // the names (one or two letters) as keys: their letters in upper case, packed
  static const auto dev_keys = [] {
    std::array<uint32_t, std::size(kDevViews)> k{};
    for (size_t i = 0; i < k.size(); i++)
      for (size_t j = 0; j < kDevViews[i].size(); j++) k[i] |= uint32_t(uint8_t(kDevViews[i][j])) << (8 * j);
    return k;
  }();
  size_t n = 0;
  uint32_t pk = 0;
  for (; n < s.size() && ascii_alpha(s[n]); n++)
    if (n < 2) pk |= uint32_t(uint8_t(ascii_upper(s[n]))) << (8 * n);
  if (n == 0 || n == s.size() || n > 2) return std::nullopt;
  uint32_t v = 0;  // wraps past 9 digits (unsigned, defined), then not used
  for (size_t i = n; i < s.size(); i++) {
    if (!ascii_digit(s[i])) return std::nullopt;
    v = v * 10 + uint32_t(s[i] - '0');
  }
  if (s.size() - n > 9) return DeviceRef{Dev::X, UINT32_MAX};  // surely out of range
  for (size_t i = 0; i < dev_keys.size(); i++)
    if (pk == dev_keys[i]) return DeviceRef{Dev(i), v};
  return std::nullopt;
}

// iec_address = "%" ("I"|"Q"|"M") ("X" a "." b | "W" n | "D" n)
//   %IXa.b = X(8a+b)   %QXa.b = Y(8a+b)   %MXa.b = M(8a+b)
//   %IWn = WXn         %QWn = WYn         %MWn = Dn          %MDn = Fn
std::optional<DeviceRef> parse_iec_address(std::string_view s, std::string& why) {
  std::string u(s);
  for (char& c : u) c = char(std::toupper((unsigned char)c));
  if (u.size() < 4 || u[0] != '%') return std::nullopt;
  char region = u[1], size = u[2];
  std::string rest = u.substr(3);
  auto number = [&](const std::string& t, uint64_t& v) {
    if (t.empty() || t.size() > 9) return false;
    v = 0;
    for (char c : t) {
      if (!std::isdigit((unsigned char)c)) return false;
      v = v * 10 + uint64_t(c - '0');
    }
    return true;
  };
  if (size == 'X') {
    size_t dot = rest.find('.');
    uint64_t a = 0, b = 0;
    if (dot == std::string::npos || !number(rest.substr(0, dot), a) || !number(rest.substr(dot + 1), b)) {
      why = "a bit address is written %" + std::string(1, region) + "Xbyte.bit, e.g. %IX0.3";
      return std::nullopt;
    }
    if (b > 7) {
      why = "bit number " + std::to_string(b) + " in " + std::string(s) + " must be 0..7";
      return std::nullopt;
    }
    uint64_t idx = a * 8 + b;
    Dev d = region == 'I' ? Dev::X : region == 'Q' ? Dev::Y : Dev::M;
    if (region != 'I' && region != 'Q' && region != 'M') return std::nullopt;
    return DeviceRef{d, idx > UINT32_MAX ? UINT32_MAX : uint32_t(idx)};
  }
  uint64_t n;
  if (!number(rest, n)) return std::nullopt;
  uint32_t idx = n > UINT32_MAX ? UINT32_MAX : uint32_t(n);
  if (size == 'W' && region == 'I') return DeviceRef{Dev::WX, idx};
  if (size == 'W' && region == 'Q') return DeviceRef{Dev::WY, idx};
  if (size == 'W' && region == 'M') return DeviceRef{Dev::D, idx};
  if (size == 'D' && region == 'M') return DeviceRef{Dev::F, idx};
  why = "unsupported IEC address " + std::string(s) + " (use %IX %QX %MX %IW %QW %MW %MD)";
  return std::nullopt;
}

bool stack_fits_slots(const std::vector<Instr>& code, int slots) {
  struct Ev { size_t at; int pos; bool write; };
  // at most 3 events an instruction (ANDBLK/ORBLK): on the stack for rungs of
  // up to 32 instructions, else one allocation
  constexpr size_t kOnStack = 96;
  std::array<Ev, kOnStack> small;
  std::vector<Ev> big;
  if (3 * code.size() > kOnStack) big.resize(3 * code.size());
  Ev* const ev = big.empty() ? small.data() : big.data();
  size_t nev = 0;
  int d = 0;
  for (size_t i = 0; i < code.size(); i++) {
    StackUse u = stack_use(code[i].op, d);
    for (int r = 0; r < u.nreads; r++) {
      if (u.reads[r] < 0) return false;  // an entry an earlier rung left
      ev[nev++] = {i, u.reads[r], false};
    }
    if (u.writes) ev[nev++] = {i, u.write, true};
    d += op_info(code[i].op).push - op_info(code[i].op).pop;
    if (d < 0 || d > kMaxStackDepth) return false;
  }
  // for every point between instructions: the positions read again before
  // they are written must lie within one window of `slots`.  Swept from the
  // end: bit p of `reads` says the first event of position p at or after the
  // point reads it (positions are at most kMaxStackDepth).
  static_assert(kMaxStackDepth < 64);
  uint64_t reads = 0;
  size_t j = nev;
  for (size_t at = code.size() + 1; at-- > 0;) {
    for (; j > 0 && ev[j - 1].at >= at; j--) {
      uint64_t bit = uint64_t(1) << ev[j - 1].pos;
      reads = ev[j - 1].write ? reads & ~bit : reads | bit;
    }
    if (reads && (63 - std::countl_zero(reads)) - std::countr_zero(reads) >= slots) return false;
  }
  return true;
}

int foreign_stack_use(const std::vector<Instr>& code) {
  int d = 0;
  for (size_t i = 0; i < code.size(); i++) {
    StackUse u = stack_use(code[i].op, d);
    for (int r = 0; r < u.nreads; r++)
      if (u.reads[r] < 0) return int(i);
    d += op_info(code[i].op).push - op_info(code[i].op).pop;
    if (d < 0) return int(i);
  }
  return -1;
}

bool shares_stack(const Program& p) {
  return std::any_of(p.rungs.begin(), p.rungs.end(), [](const Rung& r) { return foreign_stack_use(r.code) >= 0; });
}

}  // namespace ldc
