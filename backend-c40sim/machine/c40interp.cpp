// backend-c40sim/machine/c40interp.cpp -- the C40-hosted interpreter and its word IL.
#include "backend-c40sim/machine/c40interp.h"

#include <map>
#include <stdexcept>

#include "backend-c40sim/machine/c40layout.h"
#include "backend-c40sim/machine/interp_c40s.h"  // kInterpSource, generated from interp.c40s
#include "backend-c40sim/machine/mathrom.h"

namespace ldc::c40gen {

const InterpProgram& interp_program() {
  static const InterpProgram prog = [] {
    InterpProgram p;
    p.source = kInterpSource;
    C40Layout w = C40Layout::of(Layout::standard(0));  // area bases do not depend on the edge count
    std::map<std::string, int64_t> vars = {
        {"DATA_PAGE", kDataPage},
        {"IL_HI", kIlBase >> 16},
        {"IL_LO", kIlBase & 0xFFFF},
        {"TAG_F", 0x10 + int(Area::F)},
        {"TAG_E", 0x10 + int(Area::E)},
        {"TAG_TQ", 0x10 + int(Area::TQ)},
        {"TAG_TI", 0x10 + int(Area::TI)},
        {"TAG_CQ", 0x10 + int(Area::CQ)},
        {"S0", w.addr(Area::S, kBitError) & 0xFFFF},
        {"DT", (kDataBase + kSysDtWord) & 0xFFFF},
    };
    for (int k = 0; k < kRomFnCount; k++) {
      std::string n = rom_name(RomFn(k));
      for (char& c : n) c = char(std::toupper(static_cast<unsigned char>(c)));
      vars["ROM_" + n] = rom_entry(RomFn(k));
    }
    for (int a = 0; a < kAreaCount; a++) vars["AREA" + std::to_string(a)] = w.addr(Area(a), 0);
    p.text = assemble_text(p.source, kCodeBase, "interp.c40s", vars);
    p.words = p.text.words;
    p.entry = p.text.labels.at("interp");
    // the dispatch table, checked against ops.def: one routine per untyped
    // mnemonic (word_il refuses the typed ones, class Typed, and LOOP at load)
    uint32_t table = p.text.labels.at("dispatch");
    for (int op = 0; op < kOpCount; op++) {
      if (op_info(Op(op)).klass == OpClass::Typed || Op(op) == Op::LOOP) {
        if (p.text.labels.count(std::string("op_") + op_info(Op(op)).name))
          throw std::logic_error(std::string("interp.c40s: a routine for the typed ") + op_info(Op(op)).name +
                                 " that word_il refuses");
        continue;
      }
      std::string name = std::string("op_") + op_info(Op(op)).name;
      auto it = p.text.labels.find(name);
      if (it == p.text.labels.end()) throw std::logic_error("interp.c40s: no routine " + name);
      if (p.words.at(table - kCodeBase + op) != it->second)
        throw std::logic_error("interp.c40s: dispatch entry " + std::to_string(op) + " is not " + name);
    }
    return p;
  }();
  return prog;
}

// The C40-hosted interpreter has no routines for the typed instructions
// (class Typed, issue 25): a program with one is refused by name when loaded
// (native C40 code runs the typed instructions that fit a 32-bit word).
static void refuse_typed(std::span<const uint8_t> il, uint32_t off) {
  const OpInfo& oi = op_info(Op(il[off]));
  if (Op(il[off]) == Op::LOOP)
    throw std::runtime_error("the C40-hosted interpreter (--engine=c40interp) cannot run LOOP (IL offset " + std::to_string(off) +
                             "): its word IL has no backward jump; use another engine");
  if (oi.klass != OpClass::Typed) return;
  Instr in;
  in.op = Op(il[off]);
  in.ty = Ty(il[off + 1]);
  if (oi.typed == 2) in.src = Ty(il[off + 2]);
  throw std::runtime_error("the C40-hosted interpreter (--engine=c40interp) cannot run " + op_spelling(in) +
                           " (IL offset " + std::to_string(off) +
                           "): it has no typed instructions; use --engine=c40sim (native C40 code) or another engine");
}

std::vector<uint32_t> word_il(std::span<const uint8_t> il, const Layout&, std::vector<uint32_t>* starts) {
  auto rd32 = [&](uint32_t p) {
    return uint32_t(il[p]) | uint32_t(il[p + 1]) << 8 | uint32_t(il[p + 2]) << 16 | uint32_t(il[p + 3]) << 24;
  };
  // pass 1: the word offset of every instruction (and of the end)
  std::map<uint32_t, uint32_t> word_at;
  uint32_t off = 0, words = 0;
  while (off < il.size()) {
    refuse_typed(il, off);
    word_at[off] = words;
    if (starts) starts->push_back(words);
    const char* sig = op_info(Op(il[off])).operands;
    off++, words++;
    for (int i = 0; sig[i]; i++) {
      uint8_t tag = il[off];
      if (tag == 1 || tag == 2) off += 5, words += 2;
      else if (tag == 3 || tag == 4) off += 5, words += 1;
      else off += 3, words += 1;
    }
  }
  word_at[off] = words;
  // pass 2
  std::vector<uint32_t> out;
  out.reserve(words + 1);
  out.push_back(words);
  off = 0;
  while (off < il.size()) {
    const char* sig = op_info(Op(il[off])).operands;
    out.push_back(il[off]);
    off++;
    for (int i = 0; sig[i]; i++) {
      uint32_t tag = il[off];
      if (tag == 1 || tag == 2) {
        out.push_back(tag << 24);
        out.push_back(rd32(off + 1));
        off += 5;
      } else if (tag == 3) {
        out.push_back(tag << 24 | (rd32(off + 1) & 0xFFFFFF));
        off += 5;
      } else if (tag == 4) {
        out.push_back(tag << 24 | word_at.at(rd32(off + 1)));
        off += 5;
      } else {
        out.push_back(tag << 24 | (uint32_t(il[off + 1]) | uint32_t(il[off + 2]) << 8));
        off += 3;
      }
    }
  }
  return out;
}

}  // namespace ldc::c40gen
