// backend-c40sim/machine/mathrom.cpp -- the math ROM: assembly and the host service (mathrom.h).
#include "backend-c40sim/machine/mathrom.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "backend-c40sim/machine/c40text.h"
#include "backend-c40sim/machine/mathrom_c40s.h"  // kMathRomSource, generated from mathrom.c40s

namespace ldc::c40gen {

const char* rom_name(RomFn f) {
  static const char* const names[kRomFnCount] = {"sin", "cos", "tan", "sqrt", "exp", "ln"};
  return names[int(f)];
}

float rom_host(RomFn f, float x) {
  int k = 0;
  while (k < int(RealFn::None) && rom_of(RealFn(k)) != f) k++;
  return apply_real_fn(RealFn(k), x);
}

c40sim::Ext rom_result(RomFn f, c40sim::Ext x) {
  uint32_t in = c40sim::fp::to_ieee(x), out;
  float a, y;
  std::memcpy(&a, &in, 4);
  y = rom_host(f, a);
  std::memcpy(&out, &y, 4);
  return c40sim::fp::from_ieee(out).v;
}

const MathRom& math_rom() {
  static const MathRom rom = [] {
    MathRom r;
    r.source = kMathRomSource;
    r.words.assign(kRomWords, 0);
    std::string_view src = r.source;
    // split at ".routine NAME" lines
    std::vector<std::pair<std::string, std::string>> parts;
    size_t pos = 0;
    int line = 0;
    std::string header;
    while (pos < src.size()) {
      size_t nl = src.find('\n', pos);
      std::string_view l = src.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
      pos = nl == std::string_view::npos ? src.size() : nl + 1;
      line++;
      if (l.rfind(".routine ", 0) == 0) {
        // keep line numbers: the part starts with blank lines up to here
        parts.emplace_back(std::string(l.substr(9)), std::string(size_t(line), '\n'));
      } else if (!parts.empty()) {
        parts.back().second += std::string(l) + "\n";
      }
    }
    bool seen[kRomFnCount] = {};
    for (const auto& [name, text] : parts) {
      int k = 0;
      while (k < kRomFnCount && name != rom_name(RomFn(k))) k++;
      if (k == kRomFnCount) throw std::logic_error("mathrom.c40s: unknown routine " + name);
      uint32_t base = rom_entry(RomFn(k));
      AsmText a = assemble_text(text, base, "mathrom.c40s");
      if (a.words.size() > kRomStride) throw std::logic_error("mathrom.c40s: " + name + " is longer than a ROM slot");
      std::copy(a.words.begin(), a.words.end(), r.words.begin() + (base - kRomBase));
      int rets = 0;
      const auto& items = a.program.blocks[0].items;
      for (size_t i = 0; i < items.size(); i++)
        if (items[i].kind == as::ItemKind::Instruction && items[i].inst.mnemonic == as::c40::Mnemonic::Retsc) {
          rets++;
          r.exit[k] = base + a.result.items[0][i].offset / 4;
        }
      if (rets != 1) throw std::logic_error("mathrom.c40s: " + name + " needs exactly one RETS");
      seen[k] = true;
    }
    for (int k = 0; k < kRomFnCount; k++)
      if (!seen[k]) throw std::logic_error(std::string("mathrom.c40s: no routine ") + rom_name(RomFn(k)));
    return r;
  }();
  return rom;
}

void RomService::install(c40sim::C40Sim& sim) const {
  const MathRom& rom = math_rom();
  sim.load(rom.words, kRomBase);
}

void RomService::on_instruction(c40sim::C40Sim& sim, uint32_t pc) {
  if (pc < kRomBase || pc >= kRomBase + kRomWords) return;
  int k = int((pc - kRomBase) / kRomStride);
  if (k >= kRomFnCount) return;
  if (pc == rom_entry(RomFn(k))) {
    arg_[k] = sim.ext(as::c40::Reg::R0);
    calls_[k]++;
  } else if (pc == math_rom().exit[k] && host_) {
    sim.set_ext(as::c40::Reg::R0, rom_result(RomFn(k), arg_[k]));
  }
}

}  // namespace ldc::c40gen
