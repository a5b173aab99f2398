// mutant_fuzz -- the structure-aware fuzzer of the image validator
// (docs/fuzzing.md, "Hostile images"; docs/image-format.md, "Threat model").
//
// It takes valid images (every example and random ldgen programs at -O0, -O1
// and -O2) and mutates their code at the instruction level: it swaps in
// encodings drawn from the assembler's own form table with random operands,
// displacements and branch targets, retargets branches, moves displacements
// to the edges of the layout, swaps registers, entries and neighbouring
// instructions.  write_image fixes the CRC, so every mutant is a well-formed
// file.  Each mutant is then either refused by read_image, or it runs three
// scans in the sandbox (ldrun --sandbox): a forked child that seccomp confines
// to one socket, with the memory image between PROT_NONE pages and a canary
// after it.  A fault, a system call, a hang, a write past the image or a
// refusal that does not name the code section is an escape.
//
// Large bodies (issue 24: the check must hold, and stay bounded, on long
// code): one mutant in 500 starts from an image whose body begins with a run
// of 16 KiB to 1 MiB of one-byte nops (every branch of the body relative, so
// the image stays valid), and any mutant may insert a nop run of its own (1
// to 64 Ki nops, often near the rel8 reach and the 64-bit words of the
// check's bitmaps) at an instruction boundary, moving everything after it.
//
//   mutant_fuzz [--count N] [--seed S] [--large] [--save DIR] [--quiet]
//
// --large: every x86-64 mutant starts from a large body.
// Exit status 0 when no mutant escaped, 1 otherwise.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>

#include "assembler/x86_forms.h"
#include "driver/c40_target.h"
#include "driver/driver.h"
#include "driver/x86_target.h"
#include "runtime/runtime.h"
#include "runtime/sandbox.h"
#include "tests/loader/programs.h"

using namespace ldc;
namespace x86 = ldc::as::x86;
using x86::detail::OT;

namespace {

struct Base {
  std::string name;
  Image image;
};

// Where the scan body starts: after the prologue and the -O2 base registers' leas.
size_t body_start(const std::vector<uint8_t>& code) {
  size_t off = 0;
  bool o2 = false;
  for (bool slots : {true, false}) {
    size_t at = 0;
    bool ok = true;
    for (const x86::Instruction& want : x86::scan_prologue(slots)) {
      std::optional<x86::Decoded> d = x86::decode(code, at);
      if (!d || !(d->inst == want)) {
        ok = false;
        break;
      }
      at += d->length;
    }
    if (ok) {
      off = at, o2 = slots;
      break;
    }
  }
  while (o2) {
    std::optional<x86::Decoded> d = x86::decode(code, off);
    if (!d || d->inst.mnemonic != x86::Mnemonic::Lea || d->inst.ops[0].kind != x86::OperandKind::Reg) break;
    bool base = false;
    for (int b = 0; b < x86::kNumBases; b++) base |= d->inst.ops[0].reg == x86::r64(x86::kBaseRegs[b]);
    if (!base) break;
    off += d->length;
  }
  return off;
}

// Valid x86-64 images with long bodies: a few programs at -O0 and -O2, their
// body led by `nops` one-byte nops (16 KiB to 1 MiB).
std::vector<Base> large_bases(const std::vector<Program>& ps) {
  std::vector<Base> out;
  for (size_t i = 0; i < ps.size() && i < 3; i++)
    for (int level : {0, 2})
      for (size_t nops : {size_t(16) << 10, size_t(256) << 10 | 63, size_t(1) << 20}) {
        const Program& p = ps[i];
        Image im = make_x86_image(p, build_x86(p, p.source, as::Mode::Blockwise, level, false));
        im.lines.clear();
        size_t at = body_start(im.code);
        im.code.insert(im.code.begin() + long(at), nops, 0x90);
        std::string name = p.source + " -O" + std::to_string(level) + " +" + std::to_string(nops) + " nops";
        out.push_back({name, read_image(write_image(im), name)});  // throws if the loader refuses it: a bug here
      }
  return out;
}

std::vector<Base> bases(const std::vector<Program>& ps) {
  std::vector<Base> out;
  for (const Program& p : ps)
    for (int level : {0, 1, 2})
      for (bool c40 : {false, true}) {
        Image im = c40 ? make_c40_image(p, build_c40(p, p.source, level))
                       : make_x86_image(p, build_x86(p, p.source, as::Mode::Blockwise, level, false));
        im.lines.clear();  // so that only the code check decides
        std::string name = p.source + (c40 ? " c40" : "") + " -O" + std::to_string(level);
        out.push_back({name, read_image(write_image(im), name)});
      }
  return out;
}

// C40 mutants: words are swapped for real encodings taken from every C40
// image (the assembler's output), their operand fields (the low 16 bits: a
// direct address, a displacement or an immediate) set at random or to the
// edges of the memory image, neighbours swapped, bits flipped, the entry moved.
class C40Mutator {
 public:
  C40Mutator(uint64_t seed, const std::vector<uint32_t>& pool) : rng_(seed), pool_(pool) {}
  std::string mutate(std::vector<uint8_t>& code, uint32_t& entry) {
    size_t words = code.size() / 4;
    if (!words) return "";
    std::string what;
    for (int i = 0, n = 1 + int(rng_() % 3); i < n; i++) {
      size_t w = rng_() % words;
      uint32_t v = get(code, w);
      switch (rng_() % 6) {
        case 0: case 1: v = pool_[rng_() % pool_.size()], what += "word@"; break;
        case 2: v = (v & 0xffff0000u) | edge16(), what += "field@"; break;
        case 3: v ^= 1u << (rng_() % 32), what += "flip@"; break;
        case 4:
          if (w + 1 < words) {
            uint32_t next = get(code, w + 1);
            put(code, w + 1, v), v = next;
          }
          what += "swap@";
          break;
        default: entry = uint32_t(rng_() % (code.size() + 8)) & ~3u, what += "entry@"; break;
      }
      put(code, w, v);
      what += std::to_string(w) + " ";
    }
    return what;
  }

 private:
  uint16_t edge16() {
    switch (rng_() % 4) {
      case 0: return uint16_t(0xffff - rng_() % 4);
      case 1: return uint16_t(rng_() % 8);
      default: return uint16_t(rng_());
    }
  }
  static uint32_t get(const std::vector<uint8_t>& c, size_t w) {
    return uint32_t(c[4 * w]) | uint32_t(c[4 * w + 1]) << 8 | uint32_t(c[4 * w + 2]) << 16 | uint32_t(c[4 * w + 3]) << 24;
  }
  static void put(std::vector<uint8_t>& c, size_t w, uint32_t v) {
    for (int k = 0; k < 4; k++) c[4 * w + k] = uint8_t(v >> (8 * k));
  }
  std::mt19937_64 rng_;
  const std::vector<uint32_t>& pool_;
};

class Mutator {
 public:
  Mutator(uint64_t seed, uint32_t image_size) : rng_(seed), size_(image_size) {}

  // One to three mutations of `code` (and perhaps `entry`); returns what was done.
  std::string mutate(std::vector<uint8_t>& code, uint32_t& entry) {
    std::string what;
    int n = 1 + int(rng_() % 3);
    for (int i = 0; i < n; i++) {
      if (!what.empty()) what += " + ";
      what += one(code, entry);
    }
    return what;
  }

 private:
  uint64_t pick(uint64_t n) { return n ? rng_() % n : 0; }
  bool chance(unsigned percent) { return pick(100) < percent; }

  std::string one(std::vector<uint8_t>& code, uint32_t& entry) {
    x86::Disassembly d = x86::disassemble(code);
    if (d.insts.empty()) return flip(code);
    insts_ = &d.insts;
    // the -O2 frame's base registers: their K from the last leas (the
    // prologue's, or the body's, which points them region by region) before
    // the instruction picked
    for (int64_t& k : k_) k = 0;
    size_t vi = pick(d.insts.size());
    for (size_t i = 0; i < vi; i++) {
      const x86::Instruction& in = d.insts[i].inst;
      if (in.mnemonic == x86::Mnemonic::Lea && in.ops[0].kind == x86::OperandKind::Reg && in.ops[1].kind == x86::OperandKind::Mem &&
          in.ops[1].mem.base == x86::r64(x86::BX))
        for (int b = 0; b < x86::kNumBases; b++)
          if (in.ops[0].reg == x86::r64(x86::kBaseRegs[b])) k_[b] = in.ops[1].mem.disp;
    }
    const x86::Decoded& v = d.insts[vi];
    unsigned r = unsigned(pick(100));
    if (r < 40) return replace(code, v);
    if (r < 55) return retarget(code, d.insts);
    if (r < 70) return displace(code, d.insts);
    if (r < 80) return reregister(code, v);
    if (r < 83) return reenter(entry);
    if (r < 88) return swap(code, d.insts);
    if (r < 92) return erase(code, v);
    if (r < 96) return nop_run(code, v);
    return flip(code);
  }

  // Inserts a run of one-byte nops at v's offset, moving the code after it:
  // branches across it now land elsewhere.  Lengths near the rel8 reach and
  // the bitmaps' 64-bit words, or up to 64 Ki.
  std::string nop_run(std::vector<uint8_t>& code, const x86::Decoded& v) {
    size_t n;
    switch (pick(4)) {
      case 0: n = 120 + pick(16); break;
      case 1: n = 60 + pick(8) + 64 * pick(4); break;
      case 2: n = 1 + pick(8); break;
      default: n = 1 + pick(size_t(64) << 10);
    }
    code.insert(code.begin() + v.offset, n, 0x90);
    return "nops" + std::to_string(n) + "@" + std::to_string(v.offset);
  }

  // A branch target: mostly an instruction boundary (forward or back), else any offset.
  int64_t target(size_t code_size) {
    const auto& in = *insts_;
    if (chance(80) && !in.empty()) return in[pick(in.size())].offset;
    if (chance(50)) return int64_t(pick(code_size + 16)) - 8;
    return int64_t(int32_t(rng_()));
  }

  int32_t disp(uint32_t width) {
    const int32_t s = int32_t(size_);
    switch (pick(8)) {
      case 0: return s - int32_t(width);                    // the last element
      case 1: return s - int32_t(width) + 1 + int32_t(pick(width));  // straddles the end
      case 2: return -1 - int32_t(pick(8));                 // just below
      case 3: return kCallTableDisp + int32_t(pick(72));    // the call table page
      case 4: return int32_t(rng_());                       // anything
      default: return int32_t(pick(size_ + 64)) - 32;       // near the layout
    }
  }

  // A displacement for a memory operand based on `base`: one of disp()'s
  // image offsets seen through the base register's K (the -O2 frame's rdi, r15).
  int32_t disp_for(const x86::Reg& base, uint32_t width) {
    int64_t d = disp(width);
    for (int b = 0; b < x86::kNumBases; b++)
      if (base == x86::r64(x86::kBaseRegs[b])) d -= k_[b];
    if (chance(30)) d = int8_t(rng_());  // the disp8 the compiler uses with them
    return int32_t(d);
  }

  x86::Reg reg(x86::RegClass c) {
    uint8_t n = uint8_t(pick(16));
    if (chance(25)) n = chance(50) ? x86::BX : x86::SP;  // the fixed registers, often
    else if (chance(20)) n = x86::kBaseRegs[pick(x86::kNumBases)];    // and the base registers
    return {c, n};
  }

  x86::Mem mem(x86::Size size) {
    x86::Mem m;
    m.size = size;
    m.base = x86::r64(x86::BX);
    if (chance(25)) m.base = x86::r64(x86::kBaseRegs[pick(x86::kNumBases)]);  // the -O2 frame's base registers
    else if (chance(12)) {
      switch (pick(4)) {
        case 0: m.base = x86::rip(); break;
        case 1: m.base = {}; break;
        default: m.base = x86::r64(unsigned(pick(16)));
      }
    }
    if (chance(5)) {
      m.index = x86::r64(unsigned(pick(16)));
      if (m.index.num == x86::SP) m.index = {};
      m.scale = uint8_t(1u << pick(4));
    }
    m.disp = disp_for(m.base, size == x86::Size::Byte ? 1 : size == x86::Size::Qword ? 8 : 4);
    return m;
  }

  std::optional<x86::Operand> operand(OT t, size_t code_size) {
    using O = x86::Operand;
    using C = x86::RegClass;
    switch (t) {
      case OT::R8: return O::r(reg(C::Gp8));
      case OT::R32: return O::r(reg(C::Gp32));
      case OT::R64: return O::r(reg(C::Gp64));
      case OT::X: return O::r(x86::xmm(unsigned(pick(16))));
      case OT::M8: return O::m(mem(x86::Size::Byte));
      case OT::M32: case OT::XM32: return t == OT::XM32 && chance(50) ? O::r(x86::xmm(unsigned(pick(16)))) : O::m(mem(x86::Size::Dword));
      case OT::M64: return O::m(mem(x86::Size::Qword));
      case OT::MA: return O::m(mem(x86::Size::None));
      case OT::RM8: return chance(50) ? O::r(reg(C::Gp8)) : O::m(mem(x86::Size::Byte));
      case OT::RM32: return chance(50) ? O::r(reg(C::Gp32)) : O::m(mem(x86::Size::Dword));
      case OT::RM64: return chance(50) ? O::r(reg(C::Gp64)) : O::m(mem(x86::Size::Qword));
      case OT::Al: return O::r(x86::r8(x86::AX));
      case OT::Eax: return O::r(x86::r32(x86::AX));
      case OT::Rax: return O::r(x86::r64(x86::AX));
      case OT::Cl: return O::r(x86::r8(x86::CX));
      case OT::One: return O::i(1);
      case OT::I8: return O::i(int8_t(rng_()));
      case OT::IB: return O::i(uint8_t(rng_()));
      case OT::I32: return O::i(chance(20) ? -1 : int32_t(rng_()));
      case OT::Rel8: case OT::Rel32: return O::a(target(code_size));
      case OT::None: break;
    }
    return std::nullopt;
  }

  // Bytes of a random instruction from the form table, placed at `at`.
  std::vector<uint8_t> random_instruction(uint64_t at, size_t code_size) {
    auto forms = x86::detail::forms();
    for (int tries = 0; tries < 64; tries++) {
      const x86::detail::Form& f = forms[pick(forms.size())];
      x86::Instruction in;
      in.mnemonic = f.mn;
      in.cond = x86::Cond(pick(16));
      unsigned n = x86::detail::num_ops(f);
      bool ok = true;
      for (unsigned k = 0; k < n && ok; k++) {
        std::optional<x86::Operand> o = operand(f.ops[k], code_size);
        if (!o) ok = false;
        else in.ops[k] = *o;
      }
      if (!ok) continue;
      in.num_operands = uint8_t(n);
      in.long_branch = f.ops[0] == OT::Rel32 && chance(50);
      try {
        return x86::encode_at(in, at);
      } catch (const std::exception&) {
      }
    }
    return {0x90};
  }

  // Writes `b` at v.offset; pads with nops to the next instruction boundary
  // so the code after it keeps its layout.
  std::string place(std::vector<uint8_t>& code, const x86::Decoded& v, const std::vector<uint8_t>& b) {
    size_t end = v.offset + v.length;
    for (const x86::Decoded& d : *insts_)
      if (d.offset < v.offset + b.size()) end = std::max<size_t>(end, d.offset + d.length);
    end = std::min(end, code.size());
    for (size_t k = v.offset; k < end; k++) code[k] = k - v.offset < b.size() ? b[k - v.offset] : 0x90;
    return "";
  }

  std::string replace(std::vector<uint8_t>& code, const x86::Decoded& v) {
    place(code, v, random_instruction(v.offset, code.size()));
    return "replace@" + std::to_string(v.offset);
  }

  const x86::Decoded* find(const std::vector<x86::Decoded>& in, bool (*want)(const x86::Instruction&)) {
    for (int tries = 0; tries < 16; tries++) {
      const x86::Decoded& d = in[pick(in.size())];
      if (want(d.inst)) return &d;
    }
    return nullptr;
  }

  std::string retarget(std::vector<uint8_t>& code, const std::vector<x86::Decoded>& in) {
    const x86::Decoded* b = find(in, [](const x86::Instruction& i) {
      return (i.mnemonic == x86::Mnemonic::Jmp || i.mnemonic == x86::Mnemonic::Jcc || i.mnemonic == x86::Mnemonic::Call) &&
             i.num_operands && i.ops[0].kind == x86::OperandKind::Address;  // calls: to the shared routines
    });
    if (!b) return replace(code, in[pick(in.size())]);
    x86::Instruction i = b->inst;
    i.ops[0].imm = target(code.size());
    std::vector<uint8_t> bytes;
    try {
      bytes = x86::encode_at(i, b->offset);
    } catch (const std::exception&) {
      return "retarget-unencodable";
    }
    place(code, *b, bytes);
    return "retarget@" + std::to_string(b->offset);
  }

  std::string displace(std::vector<uint8_t>& code, const std::vector<x86::Decoded>& in) {
    const x86::Decoded* m = find(in, [](const x86::Instruction& i) {
      for (unsigned k = 0; k < i.num_operands; k++)
        if (i.ops[k].kind == x86::OperandKind::Mem) return true;
      return false;
    });
    if (!m) return replace(code, in[pick(in.size())]);
    x86::Instruction i = m->inst;
    for (unsigned k = 0; k < i.num_operands; k++)
      if (i.ops[k].kind == x86::OperandKind::Mem) {
        x86::Size s = i.ops[k].mem.size;
        i.ops[k].mem.disp = disp_for(i.ops[k].mem.base, s == x86::Size::Byte ? 1 : s == x86::Size::Qword ? 8 : 4);
        if (chance(10)) i.ops[k].mem = mem(s);
      }
    try {
      place(code, *m, x86::encode_at(i, m->offset));
    } catch (const std::exception&) {
      return "displace-unencodable";
    }
    return "displace@" + std::to_string(m->offset);
  }

  std::string reregister(std::vector<uint8_t>& code, const x86::Decoded& v) {
    x86::Instruction i = v.inst;
    for (unsigned k = 0; k < i.num_operands; k++)
      if (i.ops[k].kind == x86::OperandKind::Reg && i.ops[k].reg.cls != x86::RegClass::Rip && chance(70))
        i.ops[k].reg = reg(i.ops[k].reg.cls);
    try {
      place(code, v, x86::encode_at(i, v.offset));
    } catch (const std::exception&) {
      return "reregister-unencodable";
    }
    return "reregister@" + std::to_string(v.offset);
  }

  std::string reenter(uint32_t& entry) {
    entry = uint32_t(target(0));
    return "entry=" + std::to_string(entry);
  }

  std::string swap(std::vector<uint8_t>& code, const std::vector<x86::Decoded>& in) {
    if (in.size() < 2) return flip(code);
    size_t k = pick(in.size() - 1);
    const x86::Decoded &a = in[k], &b = in[k + 1];
    std::vector<uint8_t> t(code.begin() + b.offset, code.begin() + b.offset + b.length);
    t.insert(t.end(), code.begin() + a.offset, code.begin() + a.offset + a.length);
    std::copy(t.begin(), t.end(), code.begin() + a.offset);
    return "swap@" + std::to_string(a.offset);
  }

  std::string erase(std::vector<uint8_t>& code, const x86::Decoded& v) {
    std::fill(code.begin() + v.offset, code.begin() + v.offset + v.length, 0x90);
    return "erase@" + std::to_string(v.offset);
  }

  std::string flip(std::vector<uint8_t>& code) {
    size_t at = pick(code.size());
    code[at] ^= uint8_t(1u << pick(8));
    return "flip@" + std::to_string(at);
  }

  std::mt19937_64 rng_;
  uint32_t size_;
  int64_t k_[x86::kNumBases] = {};
  const std::vector<x86::Decoded>* insts_ = nullptr;
};

// Three scans of an accepted C40 mutant on the simulator, which bounds-checks
// every access and stops a scan at its cycle budget: either ends the scan or
// stops with a message (counted in `stopped`); anything else is a crash.
void run_simulated(const Image& im, std::mt19937_64& rng, uint64_t& stopped) {
  Memory m(im.layout);
  try {
    auto e = make_c40sim_engine(im.code, im.entry, im.layout);
    for (int scan = 0; scan < 3; scan++) {
      for (uint32_t i = 0; i < 32; i++) m.data()[im.layout.addr(Area::X, i)] = rng() & 1;
      e->scan(m.data());
    }
  } catch (const std::exception&) {
    stopped++;
  }
}

// Three scans of an accepted mutant in the sandbox; "" if they ran and ended.
std::string run_confined(const Image& im, std::mt19937_64& rng) {
  Memory m(im.layout);
  std::unique_ptr<Engine> e;
  try {
    e = make_sandboxed_engine(make_native_engine(map_checked_code(im.code, im.entry, im.layout)), im.layout, 5000);
    for (int scan = 0; scan < 3; scan++) {
      for (uint32_t i = 0; i < 32; i++) m.data()[im.layout.addr(Area::X, i)] = rng() & 1;
      int32_t dt = int32_t(rng() % 100);
      std::memcpy(m.data() + kSysDt, &dt, 4);
      e->scan(m.data());
    }
  } catch (const std::exception& x) {
    return x.what();
  }
  return "";
}

// "the reason" of a refusal, for the tally: the text after the instruction.
std::string reason_class(const std::string& why) {
  std::string r = why;
  if (size_t at = r.find("at code offset "); at != std::string::npos) r = r.substr(r.find(": ", at) + 2);
  if (!r.empty() && r[0] == '\'') r = r.substr(r.find("': ") == std::string::npos ? 0 : r.find("': ") + 3);
  for (const char* cut : {" (", " 0x", " [", " -", " '", ","})
    if (size_t c = r.find(cut); c != std::string::npos && c > 8) r = r.substr(0, c);
  return r.substr(0, 60);
}

}  // namespace

int main(int argc, char** argv) {
  uint64_t count = 20000, seed = 1;
  std::string save;
  bool quiet = false, all_large = false;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    if (a == "--count" && i + 1 < argc) count = std::stoull(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = std::stoull(argv[++i]);
    else if (a == "--save" && i + 1 < argc) save = argv[++i];
    else if (a == "--quiet") quiet = true;
    else if (a == "--large") all_large = true;
    else {
      std::fprintf(stderr, "usage: mutant_fuzz [--count N] [--seed S] [--large] [--save DIR] [--quiet]\n");
      return 2;
    }
  }
  auto t0 = std::chrono::steady_clock::now();
  std::vector<Program> programs = test::examples_and_random_programs(12, 25);
  std::vector<Base> bs = bases(programs);
  const std::vector<Base> large = large_bases(programs);
  std::vector<uint32_t> pool;  // every word of every C40 image
  for (const Base& b : bs)
    if (b.image.target == ImageTarget::C40)
      for (size_t k = 0; k + 4 <= b.image.code.size(); k += 4)
        pool.push_back(uint32_t(b.image.code[k]) | uint32_t(b.image.code[k + 1]) << 8 |
                       uint32_t(b.image.code[k + 2]) << 16 | uint32_t(b.image.code[k + 3]) << 24);
  std::mt19937_64 rng(seed);
  uint64_t refused = 0, accepted = 0, escapes = 0, c40_accepted = 0, c40_stopped = 0, large_count = 0, large_accepted = 0;
  std::map<std::string, uint64_t> reasons;
  for (uint64_t n = 0; n < count; n++) {
    const bool from_large = all_large || rng() % 500 == 0;
    const Base& b = from_large ? large[rng() % large.size()] : bs[rng() % bs.size()];
    large_count += from_large;
    Image im = b.image;
    const bool c40 = im.target == ImageTarget::C40;
    std::string what = c40 ? C40Mutator(rng(), pool).mutate(im.code, im.entry)
                           : Mutator(rng(), im.layout.size).mutate(im.code, im.entry);
    std::vector<uint8_t> bytes = write_image(im);  // a well-formed file: the CRC fixed
    std::string escape;
    try {
      Image back = read_image(bytes, "mutant.bin");
      accepted++;
      large_accepted += from_large;
      if (c40) c40_accepted++, run_simulated(back, rng, c40_stopped);
      else escape = run_confined(back, rng);
    } catch (const ImageError& e) {
      refused++;
      std::string why = e.what();
      if (why.rfind("mutant.bin: section 'code'", 0) != 0 && why.rfind("mutant.bin: section 'entry'", 0) != 0)
        escape = "refused without naming the code: " + why;
      else
        reasons[reason_class(why)]++;
    }
    if (!escape.empty()) {
      escapes++;
      std::printf("ESCAPE %llu: %s [%s]: %s\n", (unsigned long long)n, b.name.c_str(), what.c_str(), escape.c_str());
      if (!save.empty()) {
        std::ofstream(save + "/escape-" + std::to_string(n) + ".bin", std::ios::binary)
            .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
      }
    }
  }
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!quiet) {
    std::printf("reasons of refusal (top):\n");
    std::vector<std::pair<uint64_t, std::string>> top;
    for (auto& [r, k] : reasons) top.push_back({k, r});
    std::sort(top.rbegin(), top.rend());
    for (size_t i = 0; i < top.size() && i < 15; i++) std::printf("  %9llu  %s\n", (unsigned long long)top[i].first, top[i].second.c_str());
  }
  std::printf("%llu mutants of %zu images (seed %llu): %llu refused, %llu accepted and ran (x86-64: %llu in the sandbox;"
              " C40: %llu on the simulator, %llu of them stopped by it; from %zu large x86-64 bodies: %llu mutants,"
              " %llu accepted), %llu escapes, %.1f s\n",
              (unsigned long long)count, bs.size() + large.size(), (unsigned long long)seed, (unsigned long long)refused,
              (unsigned long long)accepted, (unsigned long long)(accepted - c40_accepted), (unsigned long long)c40_accepted,
              (unsigned long long)c40_stopped, large.size(), (unsigned long long)large_count,
              (unsigned long long)large_accepted, (unsigned long long)escapes, secs);
  return escapes ? 1 : 0;
}
