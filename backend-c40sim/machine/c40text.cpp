// backend-c40sim/machine/c40text.cpp -- C40 source text -> words (c40text.h).
#include "backend-c40sim/machine/c40text.h"

#include <cstdlib>
#include <stdexcept>

#include "backend-c40sim/machine/sim.h"

namespace ldc::c40gen {
namespace {

using namespace as::c40;

std::string trim(std::string_view s) {
  size_t a = 0, b = s.size();
  while (a < b && (s[a] == ' ' || s[a] == '\t' || s[a] == '\r')) a++;
  while (b > a && (s[b - 1] == ' ' || s[b - 1] == '\t' || s[b - 1] == '\r')) b--;
  return std::string(s.substr(a, b - a));
}

// Replaces %NAME_HI% / %NAME_LO% with the halves of the label's address (0
// while the address is not known yet).
std::string substitute(std::string line, const std::map<std::string, uint32_t>& labels,
                       const std::map<std::string, int64_t>& vars, int lineno, const std::string& name) {
  for (size_t p; (p = line.find('%')) != std::string::npos;) {
    size_t q = line.find('%', p + 1);
    if (q == std::string::npos) throw std::runtime_error(name + ":" + std::to_string(lineno) + ": unpaired %");
    std::string key = line.substr(p + 1, q - p - 1);
    if (auto v = vars.find(key); v != vars.end()) {
      line.replace(p, q - p + 1, std::to_string(v->second));
      continue;
    }
    bool hi = key.size() > 3 && key.compare(key.size() - 3, 3, "_HI") == 0;
    bool lo = key.size() > 3 && key.compare(key.size() - 3, 3, "_LO") == 0;
    if (!hi && !lo) throw std::runtime_error(name + ":" + std::to_string(lineno) + ": unknown %" + key + "%");
    std::string label = key.substr(0, key.size() - 3);
    auto it = labels.find(label);
    uint32_t a = it == labels.end() ? 0 : it->second;
    line.replace(p, q - p + 1, std::to_string(hi ? a >> 16 : a & 0xFFFF));
  }
  return line;
}

AsmText assemble_once(std::string_view text, uint32_t base, const std::string& name,
                      const std::map<std::string, uint32_t>& known, const std::map<std::string, int64_t>& vars) {
  AsmText out;
  as::Block<Instruction> blk;
  std::vector<std::pair<size_t, std::string>> label_items;
  int lineno = 0;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t nl = text.find('\n', pos);
    std::string raw(text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos));
    pos = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    lineno++;
    try {
      size_t semi0 = raw.find(';');  // comments are left alone
      std::string line = substitute(raw.substr(0, semi0), known, vars, lineno, name) +
                         (semi0 == std::string::npos ? "" : raw.substr(semi0));
      size_t semi = line.find(';');
      std::string comment = semi == std::string::npos ? "" : trim(line.substr(semi + 1));
      std::string code = trim(line.substr(0, semi));
      std::string label;
      size_t colon = code.find(':');
      if (colon != std::string::npos) {
        label = trim(code.substr(0, colon));
        code = trim(code.substr(colon + 1));
      }
      if (code.rfind(".float", 0) == 0) {
        if (!label.empty()) {
          label_items.emplace_back(blk.items.size(), label);
          blk.items.push_back(as::Item<Instruction>::label_def(label));
        }
        std::string v = trim(code.substr(6));
        char* end = nullptr;
        double d = std::strtod(v.c_str(), &end);
        if (v.empty() || *end) throw as::AsmError("bad .float '" + v + "'");
        uint32_t w = c40sim::fp::to_single(c40sim::fp::from_double(d).v);
        blk.items.push_back(as::Item<Instruction>::instr(make(Mnemonic::Word, {Operand::i(w)}), comment));
        continue;
      }
      Line l = parse_line(line);
      if (!l.label.empty()) {
        label_items.emplace_back(blk.items.size(), l.label);
        blk.items.push_back(as::Item<Instruction>::label_def(l.label));
      }
      if (l.inst) blk.items.push_back(as::Item<Instruction>::instr(*l.inst, l.comment));
    } catch (const as::AsmError& e) {
      throw std::runtime_error(name + ":" + std::to_string(lineno) + ": " + e.what());
    }
  }
  blk.source_line = 1;
  out.program.blocks.push_back(std::move(blk));
  out.result = as::assemble(target(), out.program, as::Mode::WholeProgram);
  if (!out.result.ok()) throw std::runtime_error(name + ": " + out.result.errors[0].message);
  out.words = words_of(out.result.code);
  for (const auto& [item, l] : label_items) out.labels[l] = base + out.result.items[0][item].offset / 4;
  return out;
}

}  // namespace

AsmText assemble_text(std::string_view text, uint32_t base, const std::string& name,
                      const std::map<std::string, int64_t>& vars) {
  AsmText first = assemble_once(text, base, name, {}, vars);
  return assemble_once(text, base, name, first.labels, vars);
}

}  // namespace ldc::c40gen
