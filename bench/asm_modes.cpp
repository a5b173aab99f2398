// asm_modes -- paper 003's Fig. 7 claim, measured: the blockwise two-pass
// assembler (global labels first, then each rung block with its own local
// table) against one whole-program two-pass, on the same program.
//   asm_modes PROG.ld            or   asm_modes --rungs 100000 [--seed 1]
// Prints one CSV line per mode: peak label-table entries, passes, time.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/ldgen.h"
#include "driver/driver.h"
#include "driver/x86_target.h"
#include "frontend/frontend.h"

using namespace ldc;

int main(int argc, char** argv) {
  std::string file;
  int rungs = 0;
  uint64_t seed = 1;
  for (int i = 1; i < argc; i++) {
    std::string a = argv[i];
    if (a == "--rungs" && i + 1 < argc) rungs = std::atoi(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = std::strtoull(argv[++i], nullptr, 10);
    else if (a[0] != '-') file = a;
    else { std::fprintf(stderr, "usage: asm_modes PROG.ld | --rungs N [--seed S]\n"); return 1; }
  }
  try {
    Program p;
    if (!file.empty()) p = compile_source(file).il;
    else {
      GenOptions o;
      o.rungs = rungs > 0 ? rungs : 1000;
      o.classes &= ~uint32_t(kGenEnd);
      p = lower_to_il(parse_ld(generate_ld(seed, o), "generated.ld"));
      file = "ldgen --seed " + std::to_string(seed) + " --rungs " + std::to_string(o.rungs);
    }
    size_t il = 0;
    for (auto& r : p.rungs) il += r.code.size();
    X86Code gen = generate_x86(p, p.layout());
    size_t items = 0;
    for (auto& b : gen.program.blocks) items += b.items.size();
    std::printf("program,rungs,il_instructions,asm_items,mode,code_bytes,peak_label_entries,passes,assemble_ms\n");
    std::vector<uint8_t> first;
    for (as::Mode mode : {as::Mode::Blockwise, as::Mode::WholeProgram}) {
      auto t0 = std::chrono::steady_clock::now();
      as::Result r = as::assemble(as::x86::target(), gen.program, mode);
      double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (!r.ok()) { std::fprintf(stderr, "assembly failed: %s\n", r.errors[0].message.c_str()); return 1; }
      if (first.empty()) first = r.code;
      else if (first != r.code) { std::fprintf(stderr, "the two modes gave different code\n"); return 1; }
      std::printf("\"%s\",%zu,%zu,%zu,%s,%zu,%zu,%zu,%.1f\n", file.c_str(), p.rungs.size(), il, items,
                  mode == as::Mode::Blockwise ? "blockwise" : "whole-program", r.code.size(), r.stats.peak_label_entries,
                  r.stats.relax_passes, ms);
    }
  } catch (std::exception& e) {
    std::fprintf(stderr, "asm_modes: %s\n", e.what());
    return 1;
  }
  return 0;
}
