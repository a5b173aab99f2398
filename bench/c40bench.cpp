// bench/c40bench.cpp -- ldbench_c40: paper 003's measurements on the simulated
// TMS320C40-40 (docs/c40.md, "Measurements"): cycles per mnemonic class for
// native C40 code and the C40-hosted interpreter (Fig. 8), the memory use of
// both as functions of N_exe (eqs. 3 and 4), and scan times against N_exe
// (Fig. 10, P_basic = 0.689).
//
// Every cycle the simulator counts is attributed to the IL instruction it
// belongs to: native code by the code range of each instruction (the image's
// line map; a routine or the math ROM called from it counts for it), the
// interpreter from one fetch of a mnemonic to the next (the dispatch loop, the
// routine and its operand decoding count for it).  The prologue and the return
// are scan overhead.  The programs are bench/synth.h's: one class at a time,
// and mixes with exactly N_exe instructions; the same random inputs go to both
// engines before every scan.
//
//   ldbench_c40 [--quick] [--scans N] [--per-mnemonic]
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "backend-c40sim/machine/c40interp.h"
#include "backend-c40sim/machine/c40machine.h"
#include "bench/synth.h"
#include "driver/c40_target.h"

namespace {

using namespace ldc;
using namespace ldc::c40gen;
using synth::SynthDevices;

struct Cost {
  std::vector<uint64_t> native, interp;  // cycles per IL instruction, summed over the scans
  uint64_t native_total = 0, interp_total = 0, native_overhead = 0, interp_overhead = 0;
  int scans = 0;
};

// Random inputs of the synthetic programs (synth.h's SynthDevices).
void write_inputs(Memory& m, std::mt19937& rng, int scan) {
  std::uniform_real_distribution<float> pos(0.1f, 8.0f), any(-8.0f, 8.0f);
  for (int i = 0; i < SynthDevices::kInX; i++) m.set_bit(Area::X, uint32_t(i), rng() & 1);
  for (int i = 0; i < SynthDevices::kInWX; i++) m.set_int(Area::WX, uint32_t(i), int32_t(rng() % 2001) - 1000);
  for (int i = 0; i < SynthDevices::kInFPos; i++) m.set_real(uint32_t(i), pos(rng));
  for (int i = SynthDevices::kInFPos; i < SynthDevices::kInF; i++) m.set_real(uint32_t(i), any(rng));
  int32_t dt = 10;
  std::memcpy(m.data() + kSysDt, &dt, 4);
  m.set_bit(Area::S, kBitFirstScan, scan == 0);
}

Cost measure(const Program& p, int scans, uint64_t seed) {
  const Layout L = p.layout();
  Cost c;
  c.scans = scans;
  size_t n_il = 0;
  for (const Rung& r : p.rungs) n_il += r.code.size();
  c.native.assign(n_il, 0);
  c.interp.assign(n_il, 0);

  // native: the owner of every code word
  C40Build b = build_c40(p, "bench");
  Image img = make_c40_image(p, b);
  std::vector<uint32_t> code = as::c40::words_of(img.code);
  const int32_t kOverhead = -1, kRoutine = -2;
  std::vector<int32_t> owner(code.size(), kRoutine);
  uint32_t epilogue = b.asm_result.block_offsets.back() / 4;  // scan_exit: RETSU, then __divi, __divf
  for (uint32_t a = 0; a < code.size(); a++) owner[a] = a < epilogue ? kOverhead : kRoutine;
  for (size_t k = 0; k < img.lines.size(); k++) {
    uint32_t from = img.lines[k].code_offset / 4, to = k + 1 < img.lines.size() ? img.lines[k + 1].code_offset / 4 : epilogue;
    for (uint32_t a = from; a < to; a++) owner[a] = int32_t(k);
  }
  owner[epilogue] = kOverhead;
  C40Machine mn(L, code, 0);
  int32_t cur = kOverhead;
  mn.observer = [&](const c40sim::TraceEntry& t) {
    if (t.pc < code.size() && owner[t.pc] != kRoutine) cur = owner[t.pc];
    if (cur >= 0) c.native[size_t(cur)] += t.cycles;
    else c.native_overhead += t.cycles;
  };

  // the C40-hosted interpreter: a fetch at `loop` starts the next instruction
  const InterpProgram& ip = interp_program();
  BinaryIl bin = encode_il(p);
  std::vector<uint32_t> starts;
  std::vector<uint32_t> wil = word_il(bin.code, L, &starts);
  std::map<uint32_t, int32_t> index;  // word address of an opcode -> IL instruction
  for (size_t k = 0; k < starts.size(); k++) index[kIlBase + 1 + starts[k]] = int32_t(k);
  uint32_t loop = ip.text.labels.at("loop"), done = ip.text.labels.at("done");
  C40Machine mi(L, ip.words, ip.entry, wil);
  int32_t icur = kOverhead;
  mi.observer = [&](const c40sim::TraceEntry& t) {
    if (t.pc == loop) icur = index.at(mi.sim().reg(as::c40::Reg::AR7) - 1);
    else if (t.pc == done) icur = kOverhead;
    if (icur >= 0) c.interp[size_t(icur)] += t.cycles;
    else c.interp_overhead += t.cycles;
  };

  Memory a(L), m(L);
  std::mt19937 rng_a{uint32_t(seed)}, rng_m{uint32_t(seed)};
  for (int s = 0; s < scans; s++) {
    write_inputs(a, rng_a, s);
    write_inputs(m, rng_m, s);
    cur = icur = kOverhead;
    c.native_total += mn.scan(a.data()).cycles;
    c.interp_total += mi.scan(m.data()).cycles;
    uint32_t done_scans = uint32_t(s + 1);
    std::memcpy(a.data() + kSysScan, &done_scans, 4);
    std::memcpy(m.data() + kSysScan, &done_scans, 4);
  }
  if (a.bytes != m.bytes) std::fprintf(stderr, "warning: the two engines' images differ\n");
  return c;
}

std::vector<const Instr*> instrs(const Program& p) {
  std::vector<const Instr*> v;
  for (const Rung& r : p.rungs)
    for (const Instr& in : r.code) v.push_back(&in);
  return v;
}

struct Avg {
  double native = 0, interp = 0;
  long n = 0;
};

void add(std::map<std::string, Avg>& per_op, const Program& p, const Cost& c) {
  auto v = instrs(p);
  for (size_t k = 0; k < v.size(); k++) {
    Avg& a = per_op[op_info(v[k]->op).name];
    a.native += double(c.native[k]) / c.scans;
    a.interp += double(c.interp[k]) / c.scans;
    a.n++;
  }
}

double us(double cycles) { return cycles * kNsPerCycle / 1000.0; }

// least squares y = a x + b
void fit(const std::vector<double>& x, const std::vector<double>& y, double& a, double& b) {
  double n = double(x.size()), sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < x.size(); i++) sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
  a = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  b = (sy - a * sx) / n;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, per_mnemonic = false;
  int scans = 20;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    if (a == "--quick") quick = true, scans = 3;
    else if (a == "--per-mnemonic") per_mnemonic = true;
    else if (a == "--scans" && i + 1 < argc) scans = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: ldbench_c40 [--quick] [--scans N] [--per-mnemonic]\n");
      return 2;
    }
  }
  const int n = quick ? 60 : 300;
  std::printf("# ldbench_c40: simulated TMS320C40-40 (50 ns/cycle), code in zero-wait SRAM, memory image in SRAM with "
              "1 wait state\n\n");

  // ---- Fig. 8: cycles per instruction class
  std::printf("## Cycles per instruction, by class (paper 003, Fig. 8)\n\n");
  std::printf("%d instructions of each class (bench/synth.h synth_class_il), %d scans, random inputs; averages per "
              "executed instruction.\n\n", n, scans);
  std::printf("| class | native C40 cycles (us) | C40-hosted interpreter cycles (us) | interpreter / native | "
              "skipped (no power): native / interpreter |\n|---|---|---|---|---|\n");
  const OpClass classes[] = {OpClass::Basic, OpClass::Compare, OpClass::Move, OpClass::Arith,
                             OpClass::Logic, OpClass::Special, OpClass::Timer, OpClass::Counter};
  std::map<std::string, Avg> per_op;
  bool ok = true;
  for (OpClass k : classes) {
    Avg on, off;
    for (int powered = 1; powered >= 0; powered--) {
      if (!powered && (k == OpClass::Basic || k == OpClass::Compare)) continue;
      Program p = parse_il_text(synth::synth_class_il(k, n, 17, powered), "class.il");
      Cost c = measure(p, scans, 99);
      if (powered) add(per_op, p, c);
      Avg& a = powered ? on : off;
      auto v = instrs(p);
      for (size_t i = 0; i < v.size(); i++) {
        if (op_info(v[i]->op).klass != k) continue;
        a.native += double(c.native[i]) / c.scans;
        a.interp += double(c.interp[i]) / c.scans;
        a.n++;
      }
    }
    double nat = on.native / on.n, itp = on.interp / on.n;
    ok &= itp > nat;
    std::string skipped = off.n ? std::to_string(int(std::lround(off.native / off.n))) + " / " +
                                      std::to_string(int(std::lround(off.interp / off.n)))
                                : "–";
    std::printf("| %s | %.1f (%.2f) | %.1f (%.2f) | %.1f | %s |\n", op_class_name(k), nat, us(nat), itp, us(itp),
                itp / nat, skipped.c_str());
  }
  if (per_mnemonic) {
    std::printf("\n| mnemonic | native cycles | interpreter cycles | ratio |\n|---|---|---|---|\n");
    for (int o = 0; o < kOpCount; o++) {
      auto it = per_op.find(op_info(Op(o)).name);
      if (it == per_op.end()) continue;
      const Avg& a = it->second;
      std::printf("| %s | %.1f | %.1f | %.1f |\n", it->first.c_str(), a.native / a.n, a.interp / a.n,
                  a.interp / a.native);
    }
  }

  // ---- memory: eqs. (3) and (4), and scan times (Fig. 10)
  std::printf("\n## Memory and scan time against N_exe (P_basic = %.3f, bench/synth.h synth_il)\n\n", synth::kTypicalPBasic);
  std::printf("Words are 32-bit C40 words.  Native M: the code section (templates, prologue, return, __divi, __divf).  "
              "Interpreter M': the word IL (with its length word) plus the interpreter program (%zu words for "
              "N_PLC = %d mnemonics); the math ROM (%u words) serves both and is counted in neither.\n\n",
              interp_program().words.size(), kOpCount, kRomWords);
  std::printf("| N_exe | native code words | word IL words | interpreter + IL words | native scan cycles (us) | "
              "interpreter scan cycles (us) | ratio |\n|---|---|---|---|---|---|---|\n");
  std::vector<double> xs, code_words, il_words;
  int step = quick ? 1500 : 300;
  for (int ne = step; ne <= 3000; ne += step) {
    synth::SynthOptions so;
    so.n_exe = ne;
    so.seed = uint64_t(ne);
    Program p = parse_il_text(synth::synth_il(so), "mix.il");
    C40Build b = build_c40(p, "mix");
    size_t cw = b.asm_result.code.size() / 4;
    size_t iw = word_il(encode_il(p).code, p.layout()).size();
    Cost c = measure(p, quick ? 2 : 5, uint64_t(ne));
    double nat = double(c.native_total) / c.scans, itp = double(c.interp_total) / c.scans;
    std::printf("| %d | %zu | %zu | %zu | %.0f (%.1f) | %.0f (%.1f) | %.1f |\n", ne, cw, iw,
                iw + interp_program().words.size(), nat, us(nat), itp, us(itp), itp / nat);
    xs.push_back(ne);
    code_words.push_back(double(cw));
    il_words.push_back(double(iw));
  }
  double a, b, a2, b2;
  fit(xs, code_words, a, b);
  fit(xs, il_words, a2, b2);
  double w = double(interp_program().words.size());
  std::printf("\nFits (least squares over the rows above):\n\n");
  std::printf("* native:      M  = %.3f N_exe %+.1f words   (paper 003: M  = 9.790 N_exe)\n", a, b);
  std::printf("* interpreter: M' = %.3f N_exe %+.1f words   (paper 003: M' = 2.114 N_exe + 18.973 N_PLC + 183 = "
              "2.114 N_exe + %.0f at N_PLC = %d)\n", a2, b2 + w, 18.973 * kOpCount + 183, kOpCount);
  std::printf("  the interpreter program alone: %.0f words = %.1f words per supported mnemonic\n", w, w / kOpCount);
  return ok ? 0 : 1;
}
