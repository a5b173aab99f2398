// tests/loader/c40_mutants.h -- the C40 half of the structure-aware image
// fuzzer (mutant_fuzz.cpp; docs/fuzzing.md, "Hostile images"): how C40 code
// is mutated, the large bodies it also starts from, and the oracle that
// decides whether an accepted mutant escaped.
//
// An escape of an accepted C40 mutant, run three scans on the board that
// records every instruction it executes:
//   * it runs (or tries to fetch) a word outside its code and the math ROM;
//   * it stores into its code, or a code word differs after the run;
//   * a word of the memory image changes in a scan although no executed
//     direct store (STI/STF @) of the checked code addressed it -- an output
//     (or any other device) written by something the check did not see.
// A scan that stops for another reason (the cycle budget, the stack region
// run out, an access outside every region) is contained, not an escape.
#pragma once

#include <cctype>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "assembler/c40.h"
#include "backend-c40sim/machine/c40layout.h"
#include "backend-c40sim/machine/c40machine.h"
#include "loader/loader.h"

namespace ldc::test {

inline uint32_t c40_get(const std::vector<uint8_t>& c, size_t w) {
  return uint32_t(c[4 * w]) | uint32_t(c[4 * w + 1]) << 8 | uint32_t(c[4 * w + 2]) << 16 | uint32_t(c[4 * w + 3]) << 24;
}
inline void c40_put(std::vector<uint8_t>& c, size_t w, uint32_t v) {
  for (int k = 0; k < 4; k++) c[4 * w + k] = uint8_t(v >> (8 * k));
}
inline std::string c40_hexw(uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "0x%llx", (unsigned long long)v);
  return b;
}

// C40 mutants: words are swapped for real encodings taken from every C40
// image (the assembler's output), their operand fields (the low 16 bits: a
// direct address, a displacement or an immediate) set at random or to the
// edges of the memory image, neighbours swapped, bits flipped, the entry
// moved; and stack shapes written over the code: PUSH/POP/PUSHF/POPF of any
// register (SP too), RETS of every condition, CALLs into the code, the ROM
// and past it, writes and reads of SP, and sequences that try to reach the
// memory image (an address pushed and returned to, a register branch or
// call, the return address popped and replaced, a code word returned to),
// to store into the code (LDPK of its page, a routine that changes DP), or to
// unbalance the stack on one path, and balanced routines the check accepts.
class C40Mutator {
 public:
  C40Mutator(uint64_t seed, const std::vector<uint32_t>& pool, const Layout& layout)
      : rng_(seed), pool_(pool), w_(c40map::C40Layout::of(layout)) {}

  std::string mutate(std::vector<uint8_t>& code, uint32_t& entry) {
    size_t words = code.size() / 4;
    if (!words) return "";
    std::string what;
    for (int i = 0, n = 1 + int(rng_() % 3); i < n; i++) {
      size_t w = rng_() % words;
      uint32_t v = c40_get(code, w);
      switch (rng_() % 8) {
        case 0: case 1: v = pool_[rng_() % pool_.size()], what += "word@"; break;
        case 2: v = (v & 0xffff0000u) | edge16(), what += "field@"; break;
        case 3: v ^= 1u << (rng_() % 32), what += "flip@"; break;
        case 4:
          if (w + 1 < words) {
            uint32_t next = c40_get(code, w + 1);
            c40_put(code, w + 1, v), v = next;
          }
          what += "swap@";
          break;
        case 5: entry = uint32_t(rng_() % (code.size() + 8)) & ~3u, what += "entry@"; break;
        default: what += stack_shape(code, w) + "@"; v = c40_get(code, w); break;
      }
      c40_put(code, w, v);
      what += std::to_string(w) + " ";
    }
    return what;
  }

 private:
  uint64_t pick(uint64_t n) { return n ? rng_() % n : 0; }
  uint16_t edge16() {
    switch (rng_() % 4) {
      case 0: return uint16_t(0xffff - rng_() % 4);
      case 1: return uint16_t(rng_() % 8);
      default: return uint16_t(rng_());
    }
  }
  std::string reg() {
    static const char* const r[] = {"R0", "R1", "R2", "R5", "R10", "R11", "AR0", "AR7", "DP", "SP", "IR0", "ST"};
    return r[pick(sizeof r / sizeof r[0])];
  }
  std::string freg() { return "R" + std::to_string(pick(12)); }
  std::string cond() {
    static const char* const c[] = {"U", "NZ", "Z", "LT", "GE", "HI", "NV"};
    return c[pick(sizeof c / sizeof c[0])];
  }
  // A word address: mostly near w (a routine's return), else anywhere in
  // the code, a ROM entry or beside one, past the code, in the memory image.
  int64_t target(size_t w, size_t words) {
    switch (pick(8)) {
      case 0: case 1: return int64_t(w) + int64_t(pick(9)) - 3;
      case 2: case 3: return int64_t(pick(words));
      case 4: return int64_t(c40map::kRomBase + c40map::kRomStride * pick(c40map::kRomFnCount) + pick(3));
      case 5: return int64_t(words + pick(4));
      case 6: return int64_t(c40map::kDataBase + pick(w_.words));
      default: return -int64_t(pick(4)) - 1;
    }
  }
  // "LDHI hi, Rr" + "OR lo, Rr": a data word's address (mostly), or a code word's.
  std::vector<std::string> address_in(const std::string& r, size_t words) {
    uint64_t a = pick(4) ? c40map::kDataBase + pick(w_.words) : pick(words);
    return {"LDHI " + std::to_string((a >> 16) & 0xFFFF) + ", " + r, "OR " + std::to_string(a & 0xFFFF) + ", " + r};
  }

  std::vector<std::string> shape(size_t w, size_t words) {
    auto at = [&](int64_t d) { return std::to_string(int64_t(w) + d); };
    auto t = [&] { return std::to_string(target(w, words)); };
    switch (pick(20)) {
      case 0: return {"PUSH " + reg()};
      case 1: return {"POP " + reg()};
      case 2: return {"PUSHF " + freg()};
      case 3: return {"POPF " + freg()};
      case 4: return {"RETS" + cond()};
      case 5: return {"CALL " + t()};
      case 6: {  // SP written or read
        static const char* const s[] = {"LDI R0, SP", "LDI 0, SP", "ADDI 1, SP", "SUBI 1, SP", "LDA R1, SP",
                                        "POP SP",     "PUSH SP",   "LDI SP, R0", "LDHI 020h, SP", "NOT SP, SP"};
        return {s[pick(sizeof s / sizeof s[0])]};
      }
      case 7: {  // an address pushed and returned to
        auto v = address_in("R0", words);
        v.push_back(pick(2) ? "PUSH R0" : "PUSHF R0");
        v.push_back("RETS" + cond());
        return v;
      }
      case 8: {  // a register branch or call to it
        auto v = address_in("R0", words);
        static const char* const b[] = {"BU R0", "CALLU R0", "BUD R0", "BNZ R0", "CALLNZ R0"};
        v.push_back(b[pick(sizeof b / sizeof b[0])]);
        return v;
      }
      case 9: {  // the return address replaced
        auto v = address_in("R0", words);
        v.insert(v.end(), {"POP R1", "PUSH R0", "RETSU"});
        return v;
      }
      case 10: return {"POP R1", "RETS" + cond()};
      case 11: return {"LDI " + std::to_string(pick(words)) + ", R0", "PUSH R0", "RETSU"};  // a code word as return address
      case 12: return {"LDPK " + std::to_string(pick(3) ? 0 : pick(0x100)), "STI R0, @" + std::to_string(pick(words))};
      case 13: return {"CALL " + at(3), "STI R0, @" + std::to_string(pick(words)), "RETSU", "LDPK 0", "RETSU"};  // DP changed by a routine
      case 14: return {"BZ " + at(2), "PUSH R0", "RETSU"};  // a push on one path
      case 15: return {"CALL " + at(2), "RETSU", "PUSH R0", "RETSU"};  // a routine returning through a pushed word
      case 16: return {"BUD " + at(pick(6)), "NOP", "NOP", "NOP", "B" + cond() + " " + at(int64_t(pick(5)) - 1)};  // into delay slots
      case 17: return {"CALL " + at(2), "RETS" + cond(), "PUSHF R0", "POP R2", "PUSH R2", "POPF R0", "RETSU"};  // balanced
      case 18: return {"CALL " + std::to_string(c40map::kRomBase + c40map::kRomStride * pick(c40map::kRomFnCount)), "PUSH R0",
                       "POP R0"};
      default: return {"PUSH R0", "CALL " + at(3), "POP R0", "RETSU", "RETS" + cond()};  // a call with a word pushed
    }
  }

  // Writes a stack shape over the code at word w (as far as the code goes).
  std::string stack_shape(std::vector<uint8_t>& code, size_t w) {
    size_t words = code.size() / 4;
    std::vector<std::string> s = shape(w, words);
    std::string name = "stack{" + s[0] + (s.size() > 1 ? ";.." : "") + "}";
    for (size_t k = 0; k < s.size() && w + k < words; k++) {
      try {
        c40_put(code, w + k, as::c40::encode_at(as::c40::parse(s[k]), int64_t(w + k)));
      } catch (const std::exception&) {  // a target out of reach: the word stays
      }
    }
    return name;
  }

  std::mt19937_64 rng_;
  const std::vector<uint32_t>& pool_;
  c40map::C40Layout w_;
};

// Large bodies (issue 24, item 10): the code check and the board on code far
// larger than the examples'.  `executed`: LDPK, then `words` of loads and
// stores of the memory image that every scan runs, then RETSU.  Otherwise
// `code` (an image ldc made) followed by `words` NOPs and a RETSU that no path
// reaches until a mutant makes one.
inline Image c40_large_body(const Image& base, uint32_t words, bool executed) {
  Image im = base;
  im.lines.clear();
  auto word = [](const std::string& t) { return as::c40::encode_at(as::c40::parse(t), 0); };
  std::vector<uint8_t> code;
  auto add = [&](uint32_t v) {
    code.resize(code.size() + 4);
    c40_put(code, code.size() / 4 - 1, v);
  };
  if (executed) {
    const c40map::C40Layout w = c40map::C40Layout::of(im.layout);
    add(word("LDPK 080h"));
    for (uint32_t k = 0; code.size() / 4 + 3 < words; k++) {
      uint32_t x = w.addr(Area::X, k % 64) & 0xFFFF, m = w.addr(Area::M, k % 256) & 0xFFFF;
      add(word("LDI @" + std::to_string(x) + ", R0"));
      add(word("OR @" + std::to_string(x + 1) + ", R0"));
      add(word("STI R0, @" + std::to_string(m)));
    }
  } else {
    code = base.code;
    const uint32_t nop = word("NOP");
    while (code.size() / 4 < words) add(nop);
  }
  add(word("RETSU"));
  im.code = std::move(code);
  return im;
}

// A stop message with its numbers taken out, for the tally.
inline std::string stop_class(const std::string& why) {
  std::string r;
  for (size_t i = 0; i < why.size(); i++) {
    if (why.compare(i, 2, "0x") == 0) {
      r += "X";
      for (i += 2; i < why.size() && std::isxdigit(static_cast<unsigned char>(why[i])); i++) {}
      i--;
    } else if (std::isdigit(static_cast<unsigned char>(why[i]))) {
      if (r.empty() || r.back() != 'N') r += "N";
    } else {
      r += why[i];
    }
  }
  return r.substr(0, 90);
}

// Three scans of an accepted C40 mutant on the board, judged as the header
// says.  Returns the escape ("" if none); a scan the board stopped
// (contained) is counted in `stops` by stop_class.
inline std::string run_c40_judged(const Image& im, std::mt19937_64& rng, std::map<std::string, uint64_t>& stops) {
  using namespace as::c40;
  const uint32_t n = uint32_t(im.code.size() / 4);
  const std::vector<uint32_t> code = words_of(im.code);
  c40gen::C40Machine m(im.layout, code, im.entry / 4);
  const c40map::C40Layout& w = m.words();
  std::vector<uint8_t> stored(w.words);
  std::string escape;
  m.observer = [&](const c40sim::TraceEntry& t) {
    const bool in_rom = t.pc >= c40map::kRomBase && t.pc - c40map::kRomBase < c40map::kRomWords;
    if (t.pc >= n && !in_rom && escape.empty()) escape = "ran the word at " + c40_hexw(t.pc) + ", outside the code";
    const Instruction& in = *t.inst;
    if ((in.mnemonic == Mnemonic::Sti || in.mnemonic == Mnemonic::Stf) && in.ops[1].kind == OperandKind::Direct) {
      uint32_t a = (m.sim().reg(Reg::DP) & 0xFFFF) << 16 | uint32_t(in.ops[1].imm);
      if (a - c40map::kDataBase < w.words) stored[a - c40map::kDataBase] = 1;
    }
  };
  Memory mem(im.layout);
  std::vector<uint32_t> before(w.words);
  for (int scan = 0; scan < 3 && escape.empty(); scan++) {
    for (uint32_t i = 0; i < 32; i++) mem.data()[im.layout.addr(Area::X, i)] = rng() & 1;
    int32_t dt = int32_t(rng() % 100);
    std::memcpy(mem.data() + kSysDt, &dt, 4);
    c40gen::bytes_to_words(im.layout, w, mem.data(), before.data());  // what the scan starts from
    std::fill(stored.begin(), stored.end(), 0);
    std::string fault;
    try {
      m.scan(mem.data());
    } catch (const std::exception& e) {
      fault = e.what();
    }
    for (uint32_t i = 0; i < w.words && escape.empty(); i++)
      if (m.sim().read(c40map::kDataBase + i) != before[i] && !stored[i])
        escape = "memory image word " + c40_hexw(c40map::kDataBase + i) + " changed with no store of the checked code to it";
    if (escape.empty() && (fault.find("fetch of") != std::string::npos || fault.find("read-only region") != std::string::npos))
      escape = fault;
    if (!fault.empty()) {
      stops[stop_class(fault)]++;
      break;
    }
  }
  for (uint32_t i = 0; i < n && escape.empty(); i++)
    if (m.sim().read(c40map::kCodeBase + i) != code[i]) escape = "code word " + c40_hexw(i) + " changed";
  return escape;
}

}  // namespace ldc::test
