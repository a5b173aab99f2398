// driver/ldrun_io.cpp -- see ldrun_io.h.
#include "driver/ldrun_io.h"

#include "driver/driver.h"

namespace ldc {

Image il_image(const Program& p) {
  Image img;
  img.source = p.source;
  img.layout = p.layout();
  BinaryIl b = encode_il(p);
  img.il = std::move(b.code);
  size_t k = 0;  // the line map without code: where a scan fault's IL offset was written (describe_scan_fault)
  for (uint32_t r = 0; r < p.rungs.size(); r++) {
    img.rung_titles.push_back(p.rungs[r].title);
    for (const Instr& in : p.rungs[r].code)
      img.lines.push_back({0, b.instr_offset[k++], in.loc.line ? in.loc.line : p.rungs[r].line, r});
  }
  img.aliases = p.aliases;
  img.vars = p.vars;
  img.retentive = retentive_ranges(p);
  if (std::string why = validate_il(img.il, img.layout); !why.empty()) throw UserError("ldrun: error: IL " + why);
  return img;
}

std::vector<Probe> parse_watch(const std::string& watch, const std::vector<Alias>& aliases) {
  std::vector<Probe> probes;
  if (watch.empty()) return probes;
  for (const std::string& name : split_names(watch)) {  // a[1,2] is one name
    try {
      probes.push_back(resolve_probe(name, aliases));
    } catch (std::exception& ex) { throw UserError("ldrun: error: --watch: " + std::string(ex.what())); }
  }
  return probes;
}

Trace load_trace(const std::string& path, const std::vector<Alias>& aliases) {
  try {
    return read_trace(read_file(path), path, aliases);
  } catch (UserError&) { throw; } catch (std::exception& ex) { throw UserError(ex.what()); }
}

}  // namespace ldc
