// runtime/scan_fault.cpp -- a fault that ends a scan (docs/il.md, "Index
// faults"): the record every engine writes in the Sys area, and its message.
#include <cstring>

#include "loader/loader.h"
#include "runtime/runtime.h"

namespace ldc {

std::optional<ScanFault> read_scan_fault(const uint8_t* mem) {
  ScanFault f;
  std::memcpy(&f.kind, mem + kSysFault, 4);
  if (f.kind == kFaultNone) return std::nullopt;
  std::memcpy(&f.il_offset, mem + kSysFaultAt, 4);
  std::memcpy(&f.value, mem + kSysFaultValue, 8);
  return f;
}

// "index 11 outside 1..10 at prog.st:12 (rung 3 "POU main")": the bounds from
// the IDX instruction, the line and rung from the image's line map.
std::string describe_scan_fault(const ScanFault& f, const Image* img) {
  if (f.kind != kFaultIndex && f.kind != kFaultLoop)
    return "fault " + std::to_string(f.kind) + " at IL offset " + std::to_string(f.il_offset);
  std::string s = f.kind == kFaultLoop ? "the loop budget (" + std::to_string(f.value) + " back edges in a scan) spent"
                                       : "index " + std::to_string(f.value);
  const LineEntry* at = nullptr;
  if (img) {
    for (const LineEntry& e : img->lines)
      if (e.il_offset == f.il_offset) { at = &e; break; }
    if (f.kind == kFaultIndex && f.il_offset < img->il.size() && img->il[f.il_offset] == uint8_t(Op::TIDX)) {
      Instr in;
      decode_instr(img->il, f.il_offset, in);
      s += " outside " + std::to_string(in.a[1].ival) + ".." + std::to_string(in.a[2].ival);
    }
  }
  if (!at) return s + (f.kind == kFaultLoop ? "" : " out of range") + " at IL offset " + std::to_string(f.il_offset);
  s += " at " + img->source + ":" + std::to_string(at->line);
  std::string title = at->rung < img->rung_titles.size() ? img->rung_titles[at->rung] : "";
  s += " (rung " + std::to_string(at->rung + 1) + (title.empty() ? "" : " \"" + title + "\"") + ")";
  return s;
}

}  // namespace ldc
