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

namespace {
DiagOptions g_warnings;

// Warning `name` at a place in `file` (its line quoted, a caret), on stderr,
// or a UserError under -Werror.
void ldrun_warning(const char* name, const std::string& file, std::string_view text, int line, int col, const std::string& msg) {
  Diagnostics d(g_warnings);
  d.source(file, text);
  if (!d.warning(name, file, line, col, msg)) return;
  std::string t = d.text();
  if (d.errors()) throw UserError(t.substr(0, t.size() - 1));
  std::fputs(t.c_str(), stderr);
}
}  // namespace

void set_ldrun_warnings(const DiagOptions& o) { g_warnings = o; }

void ldrun_option_warning(const char* name, const std::string& msg) {
  if (!g_warnings.enabled(name)) return;
  if (g_warnings.is_error(name)) throw UserError("ldrun: error: " + msg + " [-Werror=" + name + "]");
  std::fprintf(stderr, "ldrun: warning: %s [-W%s]\n", msg.c_str(), name);
}

Trace load_trace(const std::string& path, const std::vector<Alias>& aliases) {
  std::string text = read_file(path);
  Trace t;
  try {
    t = read_trace(text, path, aliases);
  } catch (UserError&) { throw; } catch (std::exception& ex) { throw UserError(ex.what()); }
  for (size_t i = 0; i < t.columns.size() && i < t.column_col.size(); i++) {
    const Probe& p = t.columns[i];
    if (p.area != Area::Y && p.area != Area::WY) continue;
    std::string dev = std::string(p.area == Area::Y ? "Y" : "WY") + std::to_string(p.index);
    ldrun_warning("trace-output", path, text, t.header_line, t.column_col[i],
                  "column '" + p.name + "' writes the output " + dev +
                      " before every scan; outputs are the program's: its coils write them too, and the last write of a scan is what the outputs show");
  }
  return t;
}

}  // namespace ldc
