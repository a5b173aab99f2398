// The effects column of the x86-64 form table (x86.h, Effects): what each
// form reads and writes, which the loader's code check takes every written
// register from.  The CPU is the oracle: every form, with random registers,
// memory operands pointing into a scratch buffer and random flags, runs
// natively between a harness that loads every general register but rsp (and
// xmm0-15, and the flags) from a block and stores them back with the flags.
//   * writes: a register, the memory operand or the flags that changed must
//     be written by the row (explicit W/RW operand, implicit write, flags out);
//   * reads: changing a register the row does not read (nor uses as an
//     address), the memory it does not read, or the flags when it does not
//     read them, changes nothing else the instruction leaves.
// Also the zero-extension the -O2 counter routines rely on (cmovae r8d).
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

#include "assembler/x86_forms.h"
#include "test_util.h"

using namespace ldc::as;
namespace X = ldc::as::x86;
using X::detail::OT;

namespace {

// What the harness loads and stores (offsets are the harness's).
struct Block {
  uint64_t regs[16];      // 0x00: rax .. r15 in RegNum order (rsp's slot unused)
  uint32_t flag_a, flag_b;  // 0x80: the flags before are those of `cmp flag_a, flag_b`
  uint32_t xmm[16];       // 0x88: the low dword of xmm0..15 (the rest zero)
  uint64_t flags_out;     // 0xc8: the flags after
  uint8_t pad[0x30];
  uint8_t scratch[64];    // 0x100: memory operands address scratch+32
};
static_assert(offsetof(Block, flag_a) == 0x80 && offsetof(Block, xmm) == 0x88 && offsetof(Block, flags_out) == 0xc8 &&
              offsetof(Block, scratch) == 0x100);
constexpr uint64_t kArithFlags = 0x8d5;  // CF PF AF ZF SF OF

std::string h(unsigned v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%x", v);
  return b;
}

// Code mapped read+execute: `void f(Block*)`, the instruction between the
// harness's loads and stores.
class Harness {
 public:
  explicit Harness(const std::vector<uint8_t>& under_test) {
    std::vector<uint8_t> code;
    auto put = [&](const std::string& text) {
      std::vector<uint8_t> b = X::encode_at(X::parse(text), code.size());
      code.insert(code.end(), b.begin(), b.end());
    };
    auto raw = [&](std::initializer_list<uint8_t> b) { code.insert(code.end(), b); };
    for (const char* r : {"rbx", "rbp", "r12", "r13", "r14", "r15", "rdi"}) put(std::string("push ") + r);  // rdi: the block
    put("mov eax, dword ptr [rdi+0x80]");
    put("cmp eax, dword ptr [rdi+0x84]");  // the flags; the loads below leave them
    for (unsigned x = 0; x < 16; x++) put("movd xmm" + std::to_string(x) + ", dword ptr [rdi+" + h(0x88 + 4 * x) + "]");
    for (unsigned r = 0; r < 16; r++)
      if (r != X::SP && r != X::DI) put("mov " + std::string(X::reg_name(X::r64(r))) + ", qword ptr [rdi+" + h(8 * r) + "]");
    put("mov rdi, qword ptr [rdi+0x38]");
    code.insert(code.end(), under_test.begin(), under_test.end());
    put("push rax");
    raw({0x9c});  // pushfq
    put("mov rax, qword ptr [rsp+0x10]");  // the block
    for (unsigned r = 1; r < 16; r++)
      if (r != X::SP) put("mov qword ptr [rax+" + h(8 * r) + "], " + std::string(X::reg_name(X::r64(r))));
    put("pop rcx");
    put("mov qword ptr [rax+0xc8], rcx");
    put("pop rcx");
    put("mov qword ptr [rax], rcx");
    for (const char* r : {"rdi", "r15", "r14", "r13", "r12", "rbp", "rbx"}) put(std::string("pop ") + r);
    put("ret");
    size_ = (code.size() + 4095) / 4096 * 4096;
    void* p = mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::runtime_error("mmap");
    std::memcpy(p, code.data(), code.size());
    if (mprotect(p, size_, PROT_READ | PROT_EXEC) != 0) throw std::runtime_error("mprotect");
    base_ = p;
  }
  ~Harness() { munmap(base_, size_); }
  Block run(Block b) const {
    reinterpret_cast<void (*)(Block*)>(base_)(&b);
    b.flags_out &= kArithFlags;
    return b;
  }

 private:
  void* base_ = nullptr;
  size_t size_ = 0;
};

// A random instance of a form: no operand names rsp (the harness's stack),
// memory operands have a base (not rsp, not rip) and perhaps an index.
struct Instance {
  X::Instruction in;
  std::vector<uint8_t> bytes;
};
std::optional<Instance> instance(const X::detail::Form& f, std::mt19937_64& rng) {
  auto gp = [&] {
    unsigned n;
    do n = unsigned(rng() % 16); while (n == X::SP);
    return n;
  };
  auto mem = [&](X::Size size) {
    X::Mem m;
    m.size = size;
    m.base = X::r64(gp());
    m.disp = int32_t(rng() % 64) - 32;
    if (rng() % 4 == 0) {
      m.index = X::r64(gp());
      m.scale = uint8_t(1u << (rng() % 4));
      if (m.index == m.base) m.index = {}, m.scale = 1;
    }
    return X::Operand::m(m);
  };
  X::Instruction in;
  in.mnemonic = f.mn;
  in.cond = X::Cond(rng() % 16);
  in.num_operands = uint8_t(X::detail::num_ops(f));
  for (unsigned k = 0; k < in.num_operands; k++) {
    using O = X::Operand;
    switch (f.ops[k]) {
      case OT::R8: in.ops[k] = O::r(X::r8(gp())); break;
      case OT::R32: in.ops[k] = O::r(X::r32(gp())); break;
      case OT::R64: in.ops[k] = O::r(X::r64(gp())); break;
      case OT::X: in.ops[k] = O::r(X::xmm(unsigned(rng() % 16))); break;
      case OT::M8: in.ops[k] = mem(X::Size::Byte); break;
      case OT::M16: in.ops[k] = mem(X::Size::Word); break;
      case OT::M32: in.ops[k] = mem(X::Size::Dword); break;
      case OT::M64: in.ops[k] = mem(X::Size::Qword); break;
      case OT::MA: in.ops[k] = mem(X::Size::None); break;
      case OT::RM8: in.ops[k] = rng() % 2 ? O::r(X::r8(gp())) : mem(X::Size::Byte); break;
      case OT::RM32: in.ops[k] = rng() % 2 ? O::r(X::r32(gp())) : mem(X::Size::Dword); break;
      case OT::RM64: in.ops[k] = rng() % 2 ? O::r(X::r64(gp())) : mem(X::Size::Qword); break;
      case OT::XM32: in.ops[k] = rng() % 2 ? O::r(X::xmm(unsigned(rng() % 16))) : mem(X::Size::Dword); break;
      case OT::XM64: in.ops[k] = rng() % 2 ? O::r(X::xmm(unsigned(rng() % 16))) : mem(X::Size::Qword); break;
      case OT::Al: in.ops[k] = O::r(X::r8(X::AX)); break;
      case OT::Eax: in.ops[k] = O::r(X::r32(X::AX)); break;
      case OT::Rax: in.ops[k] = O::r(X::r64(X::AX)); break;
      case OT::Cl: in.ops[k] = O::r(X::r8(X::CX)); break;
      case OT::One: in.ops[k] = O::i(1); break;
      case OT::I8: in.ops[k] = O::i(int8_t(rng())); break;
      case OT::IB: in.ops[k] = O::i(uint8_t(rng())); break;
      case OT::I32: in.ops[k] = O::i(int32_t(rng())); break;
      case OT::I64: in.ops[k] = O::i(int64_t(rng())); break;
      default: return std::nullopt;  // branch targets: not run here
    }
  }
  try {
    return Instance{in, X::encode_at(in, 0)};
  } catch (const AsmError&) {
    return std::nullopt;
  }
}

const X::Mem* mem_operand(const X::Instruction& in, size_t* at = nullptr) {
  for (unsigned k = 0; k < in.num_operands; k++)
    if (in.ops[k].kind == X::OperandKind::Mem) {
      if (at) *at = k;
      return &in.ops[k].mem;
    }
  return nullptr;
}

// The block an instance runs on: random registers, flags and xmm, the memory
// operand's base set so that it addresses scratch+32, an idiv's operands set
// so that it cannot fault.  `block` is where the block will live (the address
// matters).  False if the instance cannot be made safe.
bool prepare(const Instance& x, Block& b, std::mt19937_64& rng) {
  for (uint64_t& r : b.regs) r = rng();
  b.flag_a = uint32_t(rng()), b.flag_b = uint32_t(rng() % 3 == 0 ? b.flag_a : rng());
  for (uint32_t& v : b.xmm) v = uint32_t(rng());
  for (uint8_t& v : b.scratch) v = uint8_t(rng());
  if (x.in.mnemonic == X::Mnemonic::Idiv || x.in.mnemonic == X::Mnemonic::Div) {  // edx:eax / divisor: edx 0, eax positive, the divisor 7
    const X::Operand& d = x.in.ops[0];
    if (d.kind == X::OperandKind::Reg && d.reg.num == X::DX) return false;
    if (d.kind == X::OperandKind::Mem && (d.mem.base == X::r64(X::DX) || d.mem.index == X::r64(X::DX))) return false;  // aim() sets it
    b.regs[X::DX] = 0;
    b.regs[X::AX] = rng() & 0x7fffffff;
    if (d.kind == X::OperandKind::Reg) b.regs[d.reg.num] = 7;
    else std::memcpy(b.scratch + 32, "\x07\0\0\0\0\0\0\0", 8);
  }
  return true;
}
// Points the memory operand (if any) at the scratch of the block at `where`.
void aim(const X::Instruction& in, Block& b, const Block* where) {
  const X::Mem* m = mem_operand(in);
  if (!m) return;
  uint64_t target = reinterpret_cast<uint64_t>(where->scratch + 32);
  uint64_t idx = m->index.valid() ? b.regs[m->index.num] * m->scale : 0;
  b.regs[m->base.num] = target - uint64_t(int64_t(m->disp)) - idx;
}

// The registers the row says the instance writes / reads (bit RegNum), by
// its operands and implicit uses; memory bases and indexes count as read.
uint16_t written(const X::Instruction& in, const X::Effects& e) {
  uint16_t w = e.writes;
  for (unsigned k = 0; k < in.num_operands; k++)
    if (in.ops[k].kind == X::OperandKind::Reg && in.ops[k].reg.cls != X::RegClass::Xmm && X::writes_operand(e.ops[k]))
      w |= uint16_t(1u << in.ops[k].reg.num);
  return w;
}
uint16_t read(const X::Instruction& in, const X::Effects& e) {
  uint16_t r = e.reads;
  for (unsigned k = 0; k < in.num_operands; k++) {
    const X::Operand& o = in.ops[k];
    if (o.kind == X::OperandKind::Reg && o.reg.cls != X::RegClass::Xmm && X::reads_operand(e.ops[k])) r |= uint16_t(1u << o.reg.num);
    if (o.kind == X::OperandKind::Mem) {
      if (o.mem.base.valid()) r |= uint16_t(1u << o.mem.base.num);
      if (o.mem.index.valid()) r |= uint16_t(1u << o.mem.index.num);
    }
  }
  return r;
}

// {r} unless the instance writes all of r: r itself, changed, keeps the
// change when nothing writes it, and keeps bits 63..8 when a byte write does
// (its result depends on r though the row need not say R).  A 32- or 64-bit
// write replaces all of r: its result may not depend on r unless the row reads
// it (a cmov that did not move keeps r's low half).
uint16_t unless_written_whole(const X::Instruction& in, const X::Effects& e, unsigned r) {
  if (e.writes >> r & 1) return 0;  // implicit writes are 32-bit
  for (unsigned k = 0; k < in.num_operands; k++)
    if (in.ops[k].kind == X::OperandKind::Reg && in.ops[k].reg.cls != X::RegClass::Gp8 &&
        in.ops[k].reg.cls != X::RegClass::Xmm && in.ops[k].reg.num == r && X::writes_operand(e.ops[k]))
      return 0;
  return uint16_t(1u << r);
}

// What an instance leaves, but for the registers in `skip`.
bool same_results(const Block& a, const Block& b, uint16_t skip, bool memory) {
  for (unsigned r = 0; r < 16; r++)
    if (r != X::SP && !(skip >> r & 1) && a.regs[r] != b.regs[r]) return false;
  if (memory && std::memcmp(a.scratch, b.scratch, sizeof a.scratch) != 0) return false;
  return a.flags_out == b.flags_out;
}

TEST(X86Effects, EveryFormsRowAgreesWithTheCpu) {
  std::mt19937_64 rng(20261128);
  Block* home = new Block;  // where every run's block lives, so that aim() holds
  size_t runs = 0, forms_run = 0;
  for (const X::detail::Form& f : X::detail::forms()) {
    using M = X::Mnemonic;
    if (f.mn == M::Jcc || f.mn == M::Jmp || f.mn == M::Call || f.mn == M::Ret || f.mn == M::Push || f.mn == M::Pop) continue;
    bool ran = false;
    for (int tries = 0, done = 0; tries < 200 && done < 12; tries++) {
      std::optional<Instance> x = instance(f, rng);
      if (!x) continue;
      Block b{};
      if (!prepare(*x, b, rng)) continue;
      aim(x->in, b, home);
      const X::Effects e = X::effects(x->in);
      X::Decoded d = *X::decode(x->bytes, 0);
      ASSERT_EQ(d.effects, e) << X::print(x->in) << ": the decoder's form and the encoder's differ";
      const std::string what = X::print(x->in);
      Harness hn(x->bytes);
      *home = b;
      const Block after = hn.run(*home);
      runs++, done++, ran = true;
      // writes
      const uint16_t w = written(x->in, e);
      for (unsigned r = 0; r < 16; r++) {
        if (r != X::SP && after.regs[r] != b.regs[r]) {
          EXPECT_TRUE(w >> r & 1) << what << " changed " << X::reg_name(X::r64(r)) << ", which its row does not write";
        }
      }
      size_t mk = 0;
      const X::Mem* m = mem_operand(x->in, &mk);
      if (std::memcmp(after.scratch, b.scratch, sizeof b.scratch) != 0) {
        EXPECT_TRUE(m && X::writes_operand(e.ops[mk])) << what << " changed memory its row does not write";
      }
      // reads: each register it does not read, changed, changes nothing but itself
      const uint16_t rd = read(x->in, e);
      for (unsigned r = 0; r < 16; r++) {
        if (r == X::SP || (rd >> r & 1)) continue;
        Block p = b;
        p.regs[r] ^= rng() | 1;
        *home = p;
        const Block q = hn.run(*home);
        runs++;
        EXPECT_TRUE(same_results(after, q, unless_written_whole(x->in, e, r), true))
            << what << ": its results depend on " << X::reg_name(X::r64(r)) << ", which its row does not read";
      }
      if (m && !X::reads_operand(e.ops[mk])) {  // memory it does not read
        Block p = b;
        for (uint8_t& v : p.scratch) v = uint8_t(~v);
        *home = p;
        const Block q = hn.run(*home);
        runs++;
        EXPECT_TRUE(same_results(after, q, 0, false)) << what << ": its results depend on memory its row does not read";
      }
      if (!e.reads_flags) {  // the flags, when it does not read them: flip the comparison
        Block p = b;
        p.flag_b = p.flag_a == p.flag_b ? p.flag_a + 1 : p.flag_a;
        *home = p;
        Block q = hn.run(*home);
        runs++;
        // the flags it leaves are not compared: those it leaves undefined (AF
        // after a logic instruction, all after a shift by 0) may keep their value
        q.flags_out = after.flags_out;
        EXPECT_TRUE(same_results(after, q, 0, true)) << what << ": its results depend on the flags, which its row does not read";
      }
      // flags it changed: written (the flags before: the harness with a nop in its place)
      static const Harness nop({0x90});
      *home = b;
      const Block before_flags = nop.run(*home);
      if (before_flags.flags_out != after.flags_out) {
        EXPECT_TRUE(e.writes_flags) << what << " changed the flags, which its row does not write";
      }
    }
    if (ran) forms_run++;
    else ADD_FAILURE() << "no runnable instance of a form of " << X::mnemonic_name(f.mn);
  }
  delete home;
  std::printf("%zu forms run, %zu runs\n", forms_run, runs);
}

// A 32-bit cmov writes its destination whatever the condition: when it is
// false the register keeps its low 32 bits and bits 63..32 become 0 (Intel
// SDM, "CMOVcc": "In 64-bit mode, ... the upper 32 bits of the destination are
// cleared even if the condition is false").  The row says RW for that reason.
TEST(X86Effects, CmovZeroExtendsWhenTheConditionIsFalse) {
  Block* home = new Block{};
  Harness h(X::encode_at(X::parse("cmovae r8d, r9d"), 0));
  home->flag_a = 1, home->flag_b = 2;  // cmp 1, 2: below, so `ae` is false
  home->regs[X::R8] = 0xdeadbeef00000005ull;
  home->regs[X::R9] = 0;
  Block after = h.run(*home);
  EXPECT_EQ(after.regs[X::R8], 5u) << "the upper half of r8 survived a 32-bit cmov whose condition was false";
  EXPECT_EQ(X::effects(X::parse("cmovae r8d, r9d")).ops[0], X::Use::RW);
  delete home;
}

// The -O2 counter routines (as::x86::scan_routine, Ctu and Ctd) take the
// number of an edge slot in r8d from their caller and index the edge area
// with all of r8: `xor r9d, r9d; cmp r8d, e_count; cmovae r8d, r9d; ...
// byte ptr [rbp+r8*1+E]`.  The caller is the checked code, which may leave
// anything in r8's upper half; the loader's check accepts the routine because
// [E + r8] then stays inside the edge area, and that holds only because the
// 32-bit cmovae clears r8's upper half even when the slot is in range (the
// condition false).  Here the routine's own instructions, up to that cmovae,
// run with r8's upper half dirty: a 64-bit cmov (or a 16-bit one, or none)
// leaves an index far outside the image, and this test fails.
TEST(X86Effects, CounterRoutineBoundsTheEdgeSlotInAll64BitsOfR8) {
  const int32_t e_count = 6;
  X::RoutineAreas areas;
  areas.tw = 0x100, areas.tq = 0x600, areas.ti = 0x700, areas.cw = 0x800, areas.cq = 0xc00, areas.dt = 0;
  areas.e = 0xd00, areas.e_count = e_count;
  for (X::Routine r : {X::Routine::Ctu, X::Routine::Ctd}) {
    std::vector<X::Instruction> body = X::scan_routine(r, areas);
    // its instructions up to the first that reads memory through r8: the slot's bounding
    std::vector<uint8_t> prefix;
    bool indexed = false;
    for (const X::Instruction& in : body) {
      const X::Mem* m = mem_operand(in);
      if (m && (m->index == X::r64(X::R8) || m->base == X::r64(X::R8))) {
        indexed = true;
        break;
      }
      std::vector<uint8_t> b = X::encode_at(in, prefix.size());
      prefix.insert(prefix.end(), b.begin(), b.end());
    }
    ASSERT_TRUE(indexed) << X::routine_name(r) << " no longer indexes the edge area with r8: revisit this test";
    Harness h(prefix);
    Block* home = new Block{};
    for (uint64_t slot : {uint64_t(0), uint64_t(3), uint64_t(e_count - 1), uint64_t(e_count), uint64_t(0xffffffff)})
      for (uint64_t upper : {uint64_t(0), uint64_t(0xdeadbeef), uint64_t(0xffffffff)}) {
        *home = Block{};
        home->regs[X::R8] = upper << 32 | slot;
        Block after = h.run(*home);
        uint64_t want = slot < uint64_t(e_count) ? slot : 0;  // a slot outside the layout counts as slot 0
        EXPECT_EQ(after.regs[X::R8], want) << X::routine_name(r) << " with r8 = " << std::hex << home->regs[X::R8];
      }
    delete home;
  }
}

}  // namespace

namespace {

// ------------------------------------------------- the table in the docs

std::string ot_name(OT t) {
  switch (t) {
    case OT::R8: return "r8";
    case OT::R32: return "r32";
    case OT::R64: return "r64";
    case OT::X: return "xmm";
    case OT::M8: return "m8";
    case OT::M16: return "m16";
    case OT::M32: return "m32";
    case OT::M64: return "m64";
    case OT::MA: return "m";
    case OT::RM8: return "r/m8";
    case OT::RM32: return "r/m32";
    case OT::RM64: return "r/m64";
    case OT::XM32: return "xmm/m32";
    case OT::XM64: return "xmm/m64";
    case OT::Al: return "al";
    case OT::Eax: return "eax";
    case OT::Rax: return "rax";
    case OT::Cl: return "cl";
    case OT::One: return "1";
    case OT::I8: case OT::IB: return "imm8";
    case OT::I32: return "imm32";
    case OT::I64: return "imm64";
    case OT::Rel8: return "rel8";
    case OT::Rel32: return "rel32";
    case OT::None: break;
  }
  return "";
}

std::string form_name(const X::detail::Form& f) {
  using M = X::Mnemonic;
  std::string s = f.mn == M::Setcc ? "setcc" : f.mn == M::Cmovcc ? "cmovcc" : f.mn == M::Jcc ? "jcc" : std::string(X::mnemonic_name(f.mn));
  for (unsigned k = 0; k < X::detail::num_ops(f); k++) s += (k ? ", " : " ") + ot_name(f.ops[k]);
  return s;
}

std::string regs(uint16_t bits) {
  std::string s;
  for (unsigned r = 0; r < 16; r++)
    if (bits >> r & 1) s += (s.empty() ? "" : " ") + std::string(X::reg_name(X::r32(r)));
  return s;
}

// "reads" and "writes" of a row in words: operands by number (a memory
// operand's number means the memory), implicit registers, flags, the stack.
std::pair<std::string, std::string> in_words(const X::detail::Form& f) {
  const X::Effects& e = f.effects;
  std::string r, w;
  auto add = [](std::string& s, const std::string& x) { s += (s.empty() ? "" : ", ") + x; };
  for (unsigned k = 0; k < 3; k++) {
    if (X::reads_operand(e.ops[k])) add(r, "op" + std::to_string(k + 1));
    if (e.ops[k] == X::Use::Addr && f.ops[k] == OT::MA) add(r, "op" + std::to_string(k + 1) + "'s registers (no memory)");
    if (X::writes_operand(e.ops[k])) add(w, "op" + std::to_string(k + 1));
  }
  if (e.reads) add(r, regs(e.reads));
  if (e.writes) add(w, regs(e.writes));
  if (e.reads_flags) add(r, "flags");
  if (e.writes_flags) add(w, "flags");
  switch (e.stack) {
    case X::StackUse::Push: add(r, "rsp"), add(w, "rsp, [rsp]"); break;
    case X::StackUse::Pop: add(r, "rsp, [rsp]"), add(w, "rsp"); break;
    case X::StackUse::Call: add(r, "rsp"), add(w, "rsp, [rsp], what the callee writes"); break;
    case X::StackUse::Ret: add(r, "rsp, [rsp]"), add(w, "rsp"); break;
    case X::StackUse::None: break;
  }
  return {r.empty() ? "–" : r, w.empty() ? "–" : w};
}

// The form table's effects column as docs/assembler.md shows it: one line per
// run of forms of one mnemonic with the same row.
std::string effects_table() {
  std::string out = "| forms | reads | writes |\n|---|---|---|\n";
  auto forms = X::detail::forms();
  for (size_t i = 0; i < forms.size();) {
    size_t j = i + 1;
    while (j < forms.size() && forms[j].mn == forms[i].mn && forms[j].effects == forms[i].effects) j++;
    std::string name = j - i == 1 ? "`" + form_name(forms[i]) + "`"
                                  : "`" + form_name(forms[i]).substr(0, form_name(forms[i]).find(' ')) + "`, " +
                                        std::to_string(j - i) + " forms";
    auto [r, w] = in_words(forms[i]);
    out += "| " + name + " | " + r + " | " + w + " |\n";
    i = j;
  }
  return out;
}

// docs/assembler.md shows the effects column between two markers; it must be
// the table's (LDC_UPDATE=1 rewrites it).
TEST(X86Effects, TheDocsShowTheFormTablesColumn) {
  std::ifstream f(LDC_ASSEMBLER_DOC);
  ASSERT_TRUE(f) << LDC_ASSEMBLER_DOC;
  std::stringstream ss;
  ss << f.rdbuf();
  std::string doc = ss.str();
  const std::string open = "<!-- effects-table-begin -->\n", close = "<!-- effects-table-end -->";
  size_t b = doc.find(open), e = doc.find(close);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  b += open.size();
  const std::string want = effects_table();
  if (const char* upd = std::getenv("LDC_UPDATE"); upd && std::string(upd) == "1") {
    std::ofstream(LDC_ASSEMBLER_DOC) << doc.substr(0, b) + want + doc.substr(e);
    return;
  }
  EXPECT_EQ(doc.substr(b, e - b), want) << "docs/assembler.md's effects table is not the form table's (LDC_UPDATE=1 rewrites it)";
}

}  // namespace
