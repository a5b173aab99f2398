// x86-64 target: names, one-line parser, printer, GNU as source, listings.
#include <array>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <set>

#include "assembler/x86_forms.h"

namespace ldc::as::x86 {
namespace {

constexpr std::string_view kGp64[] = {"rax", "rcx", "rdx", "rbx", "rsp", "rbp", "rsi", "rdi",
                                      "r8",  "r9",  "r10", "r11", "r12", "r13", "r14", "r15"};
constexpr std::string_view kGp32[] = {"eax", "ecx", "edx", "ebx", "esp", "ebp", "esi", "edi",
                                      "r8d", "r9d", "r10d", "r11d", "r12d", "r13d", "r14d", "r15d"};
constexpr std::string_view kGp8[] = {"al",  "cl",  "dl",   "bl",   "spl",  "bpl",  "sil",  "dil",
                                     "r8b", "r9b", "r10b", "r11b", "r12b", "r13b", "r14b", "r15b"};
constexpr std::string_view kXmm[] = {"xmm0", "xmm1", "xmm2",  "xmm3",  "xmm4",  "xmm5",
                                     "xmm6", "xmm7", "xmm8",  "xmm9",  "xmm10", "xmm11",
                                     "xmm12", "xmm13", "xmm14", "xmm15"};

constexpr std::string_view kMnemonics[] = {
    "mov",   "movzx", "movsx", "lea",  "add",  "or",   "and",      "sub",       "xor",
    "cmp",   "test",  "shl",   "shr",  "sar",  "not",  "neg",      "imul",      "cdq",
    "idiv",  "set",   "cmov",  "j",    "jmp",  "call", "ret",      "push",      "pop",
    "nop",   "movss", "movd",  "cvtsi2ss", "cvttss2si", "addss", "subss", "mulss", "divss",
    "sqrtss", "minss", "maxss", "ucomiss", "andps", "xorps",
    "movsd", "addsd", "subsd", "mulsd", "divsd", "sqrtsd", "minsd", "maxsd", "ucomisd",
    "cvtss2sd", "cvtsd2ss", "cvtsi2sd", "cvttsd2si", "cvtsd2si", "movq",
    "cwde", "cdqe", "cqo", "div", "rol", "ror", "movsxd"};
static_assert(std::size(kMnemonics) == size_t(Mnemonic::Count_));

constexpr std::string_view kConds[] = {"o", "no", "b", "ae", "e", "ne", "be", "a",
                                       "s", "ns", "p", "np", "l", "ge", "le", "g"};
struct Alias {
  std::string_view name;
  Cond cond;
};
constexpr Alias kCondAliases[] = {
    {"c", Cond::B},   {"nae", Cond::B}, {"nb", Cond::AE}, {"nc", Cond::AE}, {"z", Cond::E},
    {"nz", Cond::NE}, {"na", Cond::BE}, {"nbe", Cond::A}, {"pe", Cond::P},  {"po", Cond::NP},
    {"nge", Cond::L}, {"nl", Cond::GE}, {"ng", Cond::LE}, {"nle", Cond::G}};

bool is_cc(Mnemonic m) { return m == Mnemonic::Setcc || m == Mnemonic::Cmovcc || m == Mnemonic::Jcc; }
bool is_branch(Mnemonic m) { return m == Mnemonic::Jcc || m == Mnemonic::Jmp || m == Mnemonic::Call; }

std::string lower(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = char(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

std::optional<Cond> cond_by_name(std::string_view s) {
  for (unsigned i = 0; i < 16; ++i)
    if (kConds[i] == s) return Cond(i);
  for (const Alias& a : kCondAliases)
    if (a.name == s) return a.cond;
  return std::nullopt;
}

std::optional<std::pair<Mnemonic, Cond>> mnemonic_by_name(std::string_view s) {
  if (s == "movabs") return std::pair{Mnemonic::Mov, Cond::O};  // objdump's spelling of mov r64, imm64
  for (unsigned i = 0; i < std::size(kMnemonics); ++i) {
    Mnemonic m = Mnemonic(i);
    if (!is_cc(m) && kMnemonics[i] == s) return std::pair{m, Cond::O};
  }
  for (Mnemonic m : {Mnemonic::Setcc, Mnemonic::Cmovcc, Mnemonic::Jcc}) {
    std::string_view pre = kMnemonics[size_t(m)];
    if (s.size() > pre.size() && s.substr(0, pre.size()) == pre)
      if (auto c = cond_by_name(s.substr(pre.size()))) return std::pair{m, *c};
  }
  return std::nullopt;
}

std::optional<Reg> reg_by_name(std::string_view s) {
  for (unsigned i = 0; i < 16; ++i) {
    if (kGp64[i] == s) return r64(i);
    if (kGp32[i] == s) return r32(i);
    if (kGp8[i] == s) return r8(i);
    if (kXmm[i] == s) return xmm(i);
  }
  if (s == "rip") return rip();
  return std::nullopt;
}

std::optional<Size> size_by_name(std::string_view s) {
  if (s == "byte") return Size::Byte;
  if (s == "dword") return Size::Dword;
  if (s == "qword") return Size::Qword;
  if (s == "word") return Size::Word;
  return std::nullopt;
}

bool is_reserved(std::string_view lowered) {
  return reg_by_name(lowered) || size_by_name(lowered) || lowered == "ptr" || lowered == "word" ||
         lowered == "xmmword" || lowered == "offset" || lowered == "short" || lowered == "near" ||
         lowered == "ah" || lowered == "bh" || lowered == "ch" || lowered == "dh";
}

std::string hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string signed_hex(int64_t v) {
  return v < 0 ? "-" + hex(0 - uint64_t(v)) : hex(uint64_t(v));
}

class Parser {
 public:
  explicit Parser(std::string_view s) : s_(s) {}

  Instruction instruction() {
    Instruction in;
    ws();
    if (eat('{')) {
      if (lower(ident()) != "disp32") fail("only the {disp32} pseudo-prefix is supported");
      expect('}');
      in.long_branch = true;
      ws();
    }
    std::string name = lower(ident());
    if (name.empty()) fail("expected a mnemonic");
    auto mn = mnemonic_by_name(name);
    if (!mn) fail("unknown mnemonic '" + name + "'");
    in.mnemonic = mn->first;
    in.cond = mn->second;
    if (in.long_branch && in.mnemonic != Mnemonic::Jmp && in.mnemonic != Mnemonic::Jcc)
      fail("{disp32} is only supported on jmp and jcc");
    ws();
    if (!at_end()) {
      for (;;) {
        if (in.num_operands == 3) fail("too many operands");
        in.ops[in.num_operands++] = operand(is_branch(in.mnemonic));
        ws();
        if (!eat(',')) break;
      }
    }
    ws();
    if (!at_end()) fail("unexpected '" + std::string(s_.substr(i_)) + "'");
    return in;
  }

 private:
  [[noreturn]] void fail(const std::string& msg) {
    throw AsmError(msg + " in '" + std::string(s_) + "'");
  }
  void ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool at_end() const { return i_ >= s_.size(); }
  bool eat(char c) {
    ws();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!eat(c)) fail(std::string("expected '") + c + "'");
  }
  static bool ident_start(char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '$' || c == '@';
  }
  static bool ident_char(char c) {
    return ident_start(c) || std::isdigit(static_cast<unsigned char>(c));
  }
  bool peek_ident() {
    ws();
    return i_ < s_.size() && ident_start(s_[i_]);
  }
  bool peek_number() {
    ws();
    return i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]));
  }
  std::string_view ident() {
    ws();
    size_t b = i_;
    if (i_ < s_.size() && ident_start(s_[i_]))
      while (i_ < s_.size() && ident_char(s_[i_])) ++i_;
    return s_.substr(b, i_ - b);
  }
  uint64_t number() {
    ws();
    uint64_t v = 0;
    unsigned base = 10;
    if (i_ + 1 < s_.size() && s_[i_] == '0' && (s_[i_ + 1] == 'x' || s_[i_ + 1] == 'X')) {
      base = 16;
      i_ += 2;
    }
    size_t b = i_;
    for (; i_ < s_.size(); ++i_) {
      int c = std::tolower(static_cast<unsigned char>(s_[i_]));
      unsigned d;
      if (c >= '0' && c <= '9') d = unsigned(c - '0');
      else if (base == 16 && c >= 'a' && c <= 'f') d = unsigned(c - 'a' + 10);
      else break;
      if (v > (UINT64_MAX - d) / base) fail("number too large");
      v = v * base + d;
    }
    if (i_ == b) fail("expected a number");
    if (i_ < s_.size() && ident_char(s_[i_])) fail("malformed number");
    return v;
  }
  int64_t signed_number() {
    bool neg = eat('-');
    if (!neg) eat('+');
    uint64_t v = number();
    if (neg) {
      if (v > uint64_t(INT64_MAX) + 1) fail("number too large");
      return int64_t(0 - v);
    }
    return int64_t(v);
  }

  Operand operand(bool branch) {
    size_t save = i_;
    if (peek_ident()) {
      std::string_view word = ident();
      std::string w = lower(word);
      if (auto sz = size_by_name(w)) {
        if (lower(ident()) != "ptr") fail("expected 'ptr' after '" + w + "'");
        Mem m = memory();
        m.size = *sz;
        return Operand::m(m);
      }
      if (w == "ds") {
        i_ = save;
        return Operand::m(memory());
      }
      if (w == "ah" || w == "bh" || w == "ch" || w == "dh")
        fail("register '" + w + "' is not supported");
      if (auto r = reg_by_name(w)) {
        if (r->cls == RegClass::Rip) fail("rip is only allowed as a memory base");
        return Operand::r(*r);
      }
      if (w == "xmmword") fail("operand size '" + w + "' is not supported");
      if (!branch) fail("unexpected '" + std::string(word) + "'");
      if (is_reserved(w)) fail("'" + std::string(word) + "' cannot be a label");
      return Operand::l(std::string(word));
    }
    ws();
    if (i_ < s_.size() && s_[i_] == '[') return Operand::m(memory());
    if (i_ < s_.size() && (s_[i_] == '-' || s_[i_] == '+' || peek_number())) {
      int64_t v = signed_number();
      return branch ? Operand::a(v) : Operand::i(v);
    }
    fail("expected an operand");
  }

  // [ base + index*scale + disp ], or objdump's ds:disp.
  Mem memory() {
    Mem m;
    int64_t disp = 0;
    size_t save = i_;
    if (peek_ident() && lower(ident()) == "ds") {
      expect(':');
      disp = signed_number();
      if (disp < INT32_MIN || disp > INT32_MAX) fail("displacement out of range");
      m.disp = int32_t(disp);
      return m;
    }
    i_ = save;
    expect('[');
    bool first = true;
    for (;;) {
      int sign = 1;
      if (eat('-')) sign = -1;
      else if (!eat('+') && !first) fail("expected '+', '-' or ']'");
      first = false;
      if (peek_number()) {
        uint64_t n = number();
        if (eat('*')) {
          if (sign < 0) fail("negative scale");
          set_index(m, reg(), n);
        } else {
          if (n > (uint64_t(1) << 40)) fail("displacement out of range");
          disp += sign * int64_t(n);
          if (disp > (int64_t(1) << 40) || disp < -(int64_t(1) << 40))
            fail("displacement out of range");
        }
      } else {
        if (sign < 0) fail("cannot subtract a register");
        Reg r = reg();
        if (eat('*')) {
          set_index(m, r, number());
        } else if (!m.base.valid() && !m.index.valid()) {
          m.base = r;
        } else if (!m.index.valid()) {
          set_index(m, r, 1);
        } else {
          fail("too many registers in address");
        }
      }
      if (eat(']')) break;
    }
    if (disp < INT32_MIN || disp > INT32_MAX) fail("displacement out of range");
    m.disp = int32_t(disp);
    return m;
  }

  Reg reg() {
    std::string w = lower(ident());
    auto r = reg_by_name(w);
    if (!r) fail(w.empty() ? "expected a register or number" : "'" + w + "' is not a register");
    if (r->cls != RegClass::Gp64 && r->cls != RegClass::Rip)
      fail("address registers must be 64-bit");
    return *r;
  }

  void set_index(Mem& m, Reg r, uint64_t scale) {
    if (m.index.valid()) fail("two index registers");
    if (r.cls == RegClass::Rip) fail("rip cannot be an index");
    if (r.num == SP) fail("rsp cannot be an index register");
    if (scale != 1 && scale != 2 && scale != 4 && scale != 8) fail("scale must be 1, 2, 4 or 8");
    m.index = r;
    m.scale = uint8_t(scale);
  }

  std::string_view s_;
  size_t i_ = 0;
};

std::string mem_text(const Mem& m) {
  std::string s;
  switch (m.size) {
    case Size::Byte: s = "byte ptr "; break;
    case Size::Dword: s = "dword ptr "; break;
    case Size::Qword: s = "qword ptr "; break;
    case Size::Word: s = "word ptr "; break;
    case Size::None: break;
  }
  s += '[';
  if (m.base.valid()) s += reg_name(m.base);
  if (m.index.valid()) {
    if (m.base.valid()) s += '+';
    s += reg_name(m.index);
    if (m.scale != 1 || !m.base.valid()) s += "*" + std::to_string(m.scale);
  }
  if (!m.base.valid() && !m.index.valid()) s += signed_hex(m.disp);
  else if (m.disp > 0) s += "+" + hex(uint64_t(m.disp));
  else if (m.disp < 0) s += signed_hex(m.disp);
  s += ']';
  return s;
}

}  // namespace

std::string_view reg_name(Reg r) {
  unsigned n = r.num & 15;
  switch (r.cls) {
    case RegClass::Gp8: return kGp8[n];
    case RegClass::Gp32: return kGp32[n];
    case RegClass::Gp64: return kGp64[n];
    case RegClass::Xmm: return kXmm[n];
    case RegClass::Rip: return "rip";
    case RegClass::None: break;
  }
  return "?";
}

std::string_view mnemonic_name(Mnemonic m, Cond c) {
  static const std::array<std::array<std::string, 16>, 3> cc_names = [] {
    std::array<std::array<std::string, 16>, 3> t;
    for (unsigned i = 0; i < 16; ++i) {
      t[0][i] = "set" + std::string(kConds[i]);
      t[1][i] = "cmov" + std::string(kConds[i]);
      t[2][i] = "j" + std::string(kConds[i]);
    }
    return t;
  }();
  unsigned ci = unsigned(c) & 15;
  if (m == Mnemonic::Setcc) return cc_names[0][ci];
  if (m == Mnemonic::Cmovcc) return cc_names[1][ci];
  if (m == Mnemonic::Jcc) return cc_names[2][ci];
  if (size_t(m) < std::size(kMnemonics)) return kMnemonics[size_t(m)];
  return "?";
}

Instruction parse(std::string_view line) {
  size_t hash = line.find('#');
  if (hash != std::string_view::npos) line = line.substr(0, hash);
  return Parser(line).instruction();
}

std::string print(const Instruction& in, bool force_long, std::string_view address_base) {
  std::string s;
  bool target = in.num_operands > 0 && (in.ops[0].kind == OperandKind::Label ||
                                       in.ops[0].kind == OperandKind::Address);
  if ((in.long_branch || force_long) && target &&
      (in.mnemonic == Mnemonic::Jmp || in.mnemonic == Mnemonic::Jcc))
    s = "{disp32} ";
  s += mnemonic_name(in.mnemonic, in.cond);
  for (unsigned i = 0; i < in.num_operands && i < 3; ++i) {
    s += i ? ", " : " ";
    const Operand& o = in.ops[i];
    switch (o.kind) {
      case OperandKind::Reg: s += reg_name(o.reg); break;
      case OperandKind::Mem: s += mem_text(o.mem); break;
      case OperandKind::Imm: s += signed_hex(o.imm); break;
      case OperandKind::Label: s += o.label; break;
      case OperandKind::Address:
        if (!address_base.empty()) {
          s += address_base;
          s += o.imm < 0 ? "" : "+";
        }
        s += signed_hex(o.imm);
        break;
      case OperandKind::None: s += "?"; break;
    }
  }
  return s;
}

std::string to_gnu_as(const X86Program& p) {
  return gnu_as_text(p, ".intel_syntax noprefix\n.text\n.Lcode:\n", "#", [](const Instruction& in, bool outside) {
    bool address = false;  // an absolute code address: reached with the long form too
    for (unsigned i = 0; i < in.num_operands && i < 3; ++i) address = address || in.ops[i].kind == OperandKind::Address;
    return print(in, outside || address, ".Lcode");
  });
}

std::string listing(const X86Program& p, const Result& r) {
  auto item_head = [&](const ItemLayout& lay) {
    std::string bytes;
    for (uint32_t k = 0; k < lay.size && lay.offset + k < r.code.size(); ++k) bytes += listing_field("%02x", r.code[lay.offset + k]);
    bytes.resize(std::max<size_t>(bytes.size(), 20), ' ');
    return listing_field("%08x  ", lay.offset) + bytes + "  ";
  };
  return listing_text(
      p, r, "#", [&](uint32_t off) { return listing_field("%08x", off) + "  "; }, item_head,
      [](const Instruction& in, const ItemLayout& lay) { return print(in, lay.long_form); });
}

namespace {

// The prologue of a frame that saves r12-r15 too (the -O2 frames), the image
// in `image` (`bias` bytes into it) and the bit stack `stack` cleared.
std::vector<Instruction> slots_prologue(std::string_view image, std::string_view stack, int32_t bias = 0) {
  std::vector<Instruction> v;
  for (const char* t : {"push rbx", "push rbp", "push r12", "push r13", "push r14", "push r15", "push rax"})
    v.push_back(parse(t));
  v.push_back(parse(bias ? "lea " + std::string(image) + ", [rdi+" + std::to_string(bias) + "]"
                         : "mov " + std::string(image) + ", rdi"));
  v.push_back(parse("xor " + std::string(stack) + ", " + std::string(stack)));
  return v;
}

}  // namespace

std::span<const Instruction> scan_prologue(bool with_slots) {
  static const std::vector<Instruction> o0 = [] {
    std::vector<Instruction> v;
    for (const char* t : {"push rbx", "push rbp", "push rax", "mov rbx, rdi", "xor ebp, ebp"}) v.push_back(parse(t));
    return v;
  }();
  static const std::vector<Instruction> o2 = slots_prologue("rbp", "ebx", kImageBias);
  return with_slots ? o2 : o0;
}

std::span<const Instruction> scan_prologue_unbiased() {
  static const std::vector<Instruction> v = slots_prologue("rbp", "ebx");
  return v;
}

std::span<const Instruction> scan_prologue_rbx_slots() {
  static const std::vector<Instruction> v = slots_prologue("rbx", "ebp");
  return v;
}

std::span<const Instruction> scan_epilogue(bool with_slots) {
  static const std::vector<Instruction> o0 = [] {
    std::vector<Instruction> v;
    for (const char* t : {"pop rax", "pop rbp", "pop rbx", "ret"}) v.push_back(parse(t));
    return v;
  }();
  static const std::vector<Instruction> o2 = [] {
    std::vector<Instruction> v;
    for (const char* t : {"pop rax", "pop r15", "pop r14", "pop r13", "pop r12", "pop rbp", "pop rbx", "ret"})
      v.push_back(parse(t));
    return v;
  }();
  return with_slots ? o2 : o0;
}

Instruction base_lea(RegNum reg, int32_t k, RegNum image) {
  Mem m;
  m.base = r64(image);
  m.disp = k;
  m.size = Size::None;
  return make(Mnemonic::Lea, {Operand::r(r64(reg)), Operand::m(m)});
}

std::span<const Instruction> safe_divisor() {
  using M = Mnemonic;
  Mem rcx1;
  rcx1.base = r64(CX);
  rcx1.disp = 1;
  rcx1.size = Size::None;
  static const std::array<Instruction, 4> seq = {
      make(M::Lea, {Operand::r(r32(DX)), Operand::m(rcx1)}),
      make(M::Cmp, {Operand::r(r32(DX)), Operand::i(1)}),
      make(M::Mov, {Operand::r(r32(DX)), Operand::i(1)}),
      make_cc(M::Cmovcc, Cond::BE, {Operand::r(r32(CX)), Operand::r(r32(DX))})};
  return seq;
}

std::string_view routine_name(Routine r) {
  static const char* const names[] = {"rt_ton", "rt_tof", "rt_tp", "rt_ctu", "rt_ctd"};
  return names[int(r)];
}

std::vector<Instruction> scan_routine(Routine r, const RoutineAreas& a, RegNum image, int32_t bias) {
  std::vector<std::string> t;
  const std::string img(reg_name(r64(image)));
  auto plus = [&](int32_t disp) { return (disp < bias ? "-" : "+") + std::to_string(std::abs(int64_t(disp) - bias)); };
  auto at = [&](const char* index, int32_t disp) { return "[" + img + "+" + index + plus(disp) + "]"; };
  const std::string tw = "dword ptr " + at("rdx*4", a.tw), tq = "byte ptr " + at("rdx*1", a.tq),
                    ti = "byte ptr " + at("rdx*1", a.ti), cw = "dword ptr " + at("rdx*4", a.cw),
                    cq = "byte ptr " + at("rdx*1", a.cq);
  t.push_back("movzx edx, dl");  // the mask: 0..255 whatever the caller passed
  if ((r == Routine::Ctu || r == Routine::Ctd) && image == image_reg(true)) {
    // esi = the input, r8d = the edge slot: one of the image's (else slot 0,
    // which only breaks the program's own rule); esi becomes the rising edge.
    // (The older -O2 frame's counters take the edge itself in esi.)
    const std::string e = "byte ptr " + at("r8*1", a.e);
    for (const std::string& x : {std::string("xor r9d, r9d"), "cmp r8d, " + std::to_string(a.e_count),
                                  std::string("cmovae r8d, r9d"), "movzx eax, " + e, "mov " + e + ", sil",
                                  std::string("not eax"), std::string("and esi, eax")})
      t.push_back(x);
  }
  if (r == Routine::Ctu || r == Routine::Ctd) {
    // CV' = CV +- edge unless that overflows; Q' = CV' >= PV (CTU) or CV' <= 0 (CTD)
    t.push_back("mov eax, " + cw);
    t.push_back(std::string(r == Routine::Ctu ? "add" : "sub") + " eax, esi");
    t.push_back("cmovo eax, " + cw);
    t.push_back("mov " + cw + ", eax");
    t.push_back("xor r8d, r8d");
    if (r == Routine::Ctu) { t.push_back("cmp eax, ecx"); t.push_back("setge r8b"); }
    else { t.push_back("test eax, eax"); t.push_back("setle r8b"); }
    t.push_back("mov " + cq + ", r8b");
  } else {
    // r8d = advance(ET, dt, PT) (see the backend's advance_edx); the caller
    // passes PT >= 0 (a negative preset counts as 0: its call site clamps it)
    for (const std::string& x : std::initializer_list<std::string>{"mov eax, " + tw, "mov r10d, eax",
                          "add r10d, dword ptr [" + img + plus(a.dt) + "]", std::string("mov r8d, ecx"),
                          std::string("cmovl r8d, r10d"), std::string("cmp r10d, ecx"), std::string("cmovbe r8d, r10d"),
                          std::string("cmp eax, ecx"), std::string("cmovge r8d, ecx"), std::string("xor r10d, r10d"),
                          std::string("xor r9d, r9d")})
      t.push_back(x);
    // eax = ET, r8d = advance, r10d = 0; ET' into r8d, Q' into r9d
    if (r == Routine::Ton) {  // IN: TI ? advance : 0, Q' = ET' >= PT; !IN: 0, 0
      for (const std::string& x : std::initializer_list<std::string>{"cmp " + ti + ", 0", std::string("cmove r8d, r10d"), std::string("test esi, esi"),
                            std::string("cmove r8d, r10d"), std::string("cmp r8d, ecx"), std::string("setge r9b"),
                            std::string("and r9d, esi")})
        t.push_back(x);
    } else if (r == Routine::Tof) {  // Q: advance, ET' < PT; !Q: unchanged; TI: 0, PT > 0; IN: 0, 1
      for (const std::string& x : std::initializer_list<std::string>{std::string("cmp r8d, ecx"), std::string("setl r9b"), "cmp " + tq + ", 0",
                            std::string("cmove r8d, eax"), std::string("cmove r9d, r10d"), std::string("xor r11d, r11d"),
                            std::string("test ecx, ecx"), std::string("setg r11b"), "cmp " + ti + ", 0",
                            std::string("cmovne r8d, r10d"), std::string("cmovne r9d, r11d"), std::string("test esi, esi"),
                            std::string("cmovne r8d, r10d"), std::string("cmovne r9d, esi")})
        t.push_back(x);
    } else {  // TP. !Q: IN && TI unchanged; rising: 0, PT > 0; !IN: 0, 0.  Q: advance, ET' < PT
      for (const std::string& x : std::initializer_list<std::string>{std::string("xor r11d, r11d"), "cmp " + ti + ", 0", std::string("sete r11b"),
                            std::string("and r11d, esi"), std::string("cmovne eax, r10d"), std::string("test esi, esi"),
                            std::string("cmove eax, r10d"), std::string("test ecx, ecx"), std::string("setg r9b"),
                            std::string("and r9d, r11d"), std::string("xor r11d, r11d"), std::string("cmp r8d, ecx"),
                            std::string("setl r11b"), "cmp " + tq + ", 0", std::string("cmove r8d, eax"),
                            std::string("cmovne r9d, r11d")})
        t.push_back(x);
    }
    t.push_back("mov " + tw + ", r8d");
    t.push_back("mov " + tq + ", r9b");
    t.push_back("mov " + ti + ", sil");
  }
  t.push_back("ret");
  std::vector<Instruction> v;
  for (const std::string& x : t) v.push_back(parse(x));
  return v;
}

}  // namespace ldc::as::x86
