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
// refusal that does not name the code section is an escape.  C40 mutants
// (c40_mutants.h: stack shapes among the mutations, large bodies too) run
// three scans on the simulated board instead, which records what they run
// and store; c40_mutants.h defines their escapes.
//
// Large x86-64 bodies (issue 24: the check must hold, and stay bounded, on
// long code): a mutant may start from an image whose body begins with a run
// of 16 KiB to 1 MiB of one-byte nops (every branch of the body relative, so
// the image stays valid), and any mutant may insert a nop run of its own (1
// to 64 Ki nops, often near the rel8 reach and the 64-bit words of the
// check's bitmaps) at an instruction boundary, moving everything after it.
// One mutant in 500 starts from a large body of either target.
//
// Change-driven images (ldc --change-driven, docs/change-driven.md): every
// x86-64 base also comes with a region table (regions of two rungs), and a
// mutant of such a base mutates one region's code instead (its size and the
// starts after it follow the mutation); refused, it must name the 'regions'
// section; accepted, its regions all run (the engine walks them) in the
// sandbox.
//
//   mutant_fuzz [--count N] [--seed S] [--target all|x86|c40] [--large] [--save DIR] [--quiet]
//
// --large: every mutant starts from a large body.
//
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
#include "tests/loader/c40_mutants.h"
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
std::vector<Base> large_x86_bases(const std::vector<Program>& ps) {
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

// The images of one target ("x86", "c40") or both ("all").
std::vector<Base> bases(const std::vector<Program>& ps, const std::string& only) {
  std::vector<Base> out;
  for (const Program& p : ps)
    for (int level : {0, 1, 2})
      for (bool c40 : {false, true}) {
        if (only != "all" && c40 != (only == "c40")) continue;
        Image im = c40 ? make_c40_image(p, build_c40(p, p.source, level))
                       : make_x86_image(p, build_x86(p, p.source, as::Mode::Blockwise, level, false));
        std::string name = p.source + (c40 ? " c40" : "") + " -O" + std::to_string(level);
        if (!c40) {  // the same with a region table (which needs the line map)
          Image rim = im;
          rim.regions = x86_region_table(p, 2, level);
          out.push_back({name + " regions", read_image(write_image(rim), name)});
        }
        im.lines.clear();  // so that only the code check decides
        out.push_back({name, read_image(write_image(im), name)});
      }
  return out;
}

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
    m.disp = disp_for(m.base, size == x86::Size::Byte ? 1 : size == x86::Size::Qword ? 8 : size == x86::Size::Word ? 2 : 4);
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
      case OT::M16: return O::m(mem(x86::Size::Word));
      case OT::XM64: return chance(50) ? O::r(x86::xmm(unsigned(pick(16)))) : O::m(mem(x86::Size::Qword));
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
      case OT::I64: return O::i(int64_t(rng_()));
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

// Mutates one region's code of a change-driven image: the region's bytes
// through the same mutator, its size and the starts after it moved by the
// change of length.
std::string mutate_region(Image& im, Mutator&& mut, std::mt19937_64& rng) {
  RegionTable& t = *im.regions;
  const size_t r = rng() % t.first.size();
  std::vector<uint8_t> bytes(t.code.begin() + t.start[r], t.code.begin() + t.start[r] + t.size[r]);
  uint32_t entry = 0;
  std::string what = "region " + std::to_string(r) + ": " + mut.mutate(bytes, entry);
  const int64_t delta = int64_t(bytes.size()) - int64_t(t.size[r]);
  t.code.erase(t.code.begin() + t.start[r], t.code.begin() + t.start[r] + t.size[r]);
  t.code.insert(t.code.begin() + t.start[r], bytes.begin(), bytes.end());
  t.size[r] = uint32_t(bytes.size());
  for (size_t k = r + 1; k < t.start.size(); k++) t.start[k] = uint32_t(int64_t(t.start[k]) + delta);
  return what;
}

// Three scans of an accepted mutant in the sandbox; "" if they ran and ended.
// A change-driven image's regions all run in the first (its engine walks
// them: no full scan to fall back on).
std::string run_confined(const Image& im, std::mt19937_64& rng) {
  Memory m(im.layout);
  std::unique_ptr<Engine> e;
  try {
    std::unique_ptr<Engine> inner = im.regions ? make_change_driven_engine(im, nullptr)
                                               : make_native_engine(map_checked_code(im.code, im.entry, im.layout));
    e = make_sandboxed_engine(std::move(inner), im.layout, 5000);
    for (int scan = 0; scan < 3; scan++) {
      for (uint32_t i = 0; i < 32; i++) m.data()[im.layout.addr(Area::X, i)] = rng() & 1;
      int32_t dt = int32_t(rng() % 100);
      std::memcpy(m.data() + kSysDt, &dt, 4);
      e->scan(m.bytes);
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
  else if (size_t at = r.find(" (code offset "); at != std::string::npos) {  // C40: the instruction and numbers out
    r = r.substr(r.find("): ", at) + 3);
    if (!r.empty() && r[0] == '\'' && r.find("': ") != std::string::npos) r = r.substr(r.find("': ") + 3);
    return test::stop_class(r).substr(0, 60);
  }
  if (!r.empty() && r[0] == '\'') r = r.substr(r.find("': ") == std::string::npos ? 0 : r.find("': ") + 3);
  for (const char* cut : {" (", " 0x", " [", " -", " '", ","})
    if (size_t c = r.find(cut); c != std::string::npos && c > 8) r = r.substr(0, c);
  return r.substr(0, 60);
}

// The large C40 bodies (c40_mutants.h), from the first C40 base: one that
// every scan runs (70,000 words: past the simulator's 2^16-entry decode
// cache) and one mostly unreached (300,000 words: past the check's 2^18-word
// work-list summary).
std::vector<Base> large_c40_bases(const std::vector<Base>& bs) {
  for (const Base& b : bs)
    if (b.image.target == ImageTarget::C40)
      return {{b.name + " + 70000 executed words", test::c40_large_body(b.image, 70000, true)},
              {b.name + " + 300000 unreached NOPs", test::c40_large_body(b.image, 300000, false)}};
  return {};
}

void print_top(const char* title, const std::map<std::string, uint64_t>& tally) {
  std::printf("%s\n", title);
  std::vector<std::pair<uint64_t, std::string>> top;
  for (auto& [r, k] : tally) top.push_back({k, r});
  std::sort(top.rbegin(), top.rend());
  for (size_t i = 0; i < top.size() && i < 15; i++) std::printf("  %9llu  %s\n", (unsigned long long)top[i].first, top[i].second.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  uint64_t count = 20000, seed = 1;
  std::string save, only = "all";
  bool quiet = false, all_large = false;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    if (a == "--count" && i + 1 < argc) count = std::stoull(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = std::stoull(argv[++i]);
    else if (a == "--save" && i + 1 < argc) save = argv[++i];
    else if (a == "--target" && i + 1 < argc && (only = argv[++i], only == "all" || only == "x86" || only == "c40")) {}
    else if (a == "--quiet") quiet = true;
    else if (a == "--large") all_large = true;
    else {
      std::fprintf(stderr, "usage: mutant_fuzz [--count N] [--seed S] [--target all|x86|c40] [--large] [--save DIR] [--quiet]\n");
      return 2;
    }
  }
  auto t0 = std::chrono::steady_clock::now();
  const std::vector<Program> programs = test::examples_and_random_programs(12, 25);
  std::vector<Base> bs = bases(programs, only);
  std::vector<uint32_t> pool;  // every word of every C40 image
  for (const Base& b : bs)
    if (b.image.target == ImageTarget::C40)
      for (size_t k = 0; k + 4 <= b.image.code.size(); k += 4) pool.push_back(test::c40_get(b.image.code, k / 4));
  std::vector<Base> large = large_c40_bases(bs);
  if (only != "c40")
    for (Base& b : large_x86_bases(programs)) large.push_back(std::move(b));
  std::mt19937_64 rng(seed);
  uint64_t refused = 0, accepted = 0, escapes = 0, c40_accepted = 0, c40_stopped = 0, large_mutants = 0;
  std::map<std::string, uint64_t> reasons, stops;
  for (uint64_t n = 0; n < count; n++) {
    const bool big = !large.empty() && (all_large || rng() % 500 == 0);
    const Base& b = big ? large[rng() % large.size()] : bs[rng() % bs.size()];
    large_mutants += big;
    Image im = b.image;
    const bool c40 = im.target == ImageTarget::C40;
    std::string what = c40          ? test::C40Mutator(rng(), pool, im.layout).mutate(im.code, im.entry)
                       : im.regions ? mutate_region(im, Mutator(rng(), im.layout.size), rng)
                                    : Mutator(rng(), im.layout.size).mutate(im.code, im.entry);
    std::vector<uint8_t> bytes = write_image(im);  // a well-formed file: the CRC fixed
    std::string escape;
    try {
      Image back = read_image(bytes, "mutant.bin");
      accepted++;
      if (c40) c40_accepted++, escape = test::run_c40_judged(back, rng, stops);
      else escape = run_confined(back, rng);
    } catch (const ImageError& e) {
      refused++;
      std::string why = e.what();
      if (why.rfind("mutant.bin: section 'code'", 0) != 0 && why.rfind("mutant.bin: section 'entry'", 0) != 0 &&
          why.rfind("mutant.bin: section 'regions'", 0) != 0)
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
  for (auto& [r, k] : stops) c40_stopped += k;
  if (!quiet) {
    print_top("reasons of refusal (top):", reasons);
    if (!stops.empty()) print_top("C40 scans the simulator stopped (contained), by reason:", stops);
  }
  std::printf("%llu mutants of %zu images (%s, seed %llu; %llu from the large bodies): %llu refused, %llu accepted and ran"
              " (x86-64: %llu in the sandbox; C40: %llu on the simulator, %llu of them stopped by it), %llu escapes, %.1f s\n",
              (unsigned long long)count, bs.size() + large.size(), only.c_str(), (unsigned long long)seed,
              (unsigned long long)large_mutants, (unsigned long long)refused, (unsigned long long)accepted,
              (unsigned long long)(accepted - c40_accepted), (unsigned long long)c40_accepted, (unsigned long long)c40_stopped,
              (unsigned long long)escapes, secs);
  return escapes ? 1 : 0;
}
