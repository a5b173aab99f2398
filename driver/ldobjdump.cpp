// ldobjdump -- an objdump-style listing of an ldc image: address, bytes and
// instruction, with each rung's source line and IL interleaved.  A source
// (what ldc and ldrun read) is compiled in memory first, as ldrun does.
#include <cstdio>
#include <string>

#include "driver/driver.h"
#include "driver/targets.h"
#include "driver/version.h"

using namespace ldc;

namespace {

std::string usage() {
  std::string targets;
  for (const Target& t : ldc::targets()) targets += (targets.empty() ? "" : "|") + std::string(t.name);
  return "usage: ldobjdump IMAGE.bin|IMAGE.hex\n"
         "       ldobjdump SOURCE [--target=" + targets + "] [-O0|-O1|-O2] [--task NAME]\n"
         "       SOURCE: what ldc reads (.ld, .il, .st, .xml, .rtsp, .sfc), compiled in memory (x86-64 at -O0 unless told)\n";
}

struct Args {
  std::string file, target, task;
  int opt = -1;  // -O<n>; -1: none given
};

// The image to list: the file itself, or the source compiled as `ldc FILE -o F.bin` would.
Image image_of(const Args& a, std::string& what) {
  if (is_image_file(a.file)) {
    if (!a.target.empty() || a.opt >= 0 || !a.task.empty())
      throw UserError("ldobjdump: error: " + a.file + " is an image, already compiled: --target, -O and --task are for a source");
    Image img = load_image_file(a.file);
    what = "image of " + img.source;
    return img;
  }
  const Target* t = a.target.empty() ? &host_target() : find_target(a.target);
  if (!t) throw UserError("ldobjdump: error: unknown target '" + a.target + "' (" + target_names() + ")");
  Compiled c = compile_source(a.file, false, a.task);
  int opt = a.opt < 0 ? 0 : a.opt;
  what = "compiled in memory from " + a.file + " at -O" + std::to_string(opt);
  return target_image(*t, c.il, a.file, opt);
}

// The change-driven region table (ldc --change-driven): which rungs each
// region holds and where its scan function lies in the region code.
std::string region_table_text(const RegionTable& t) {
  std::string s = "\nchange-driven scan (docs/change-driven.md): " + std::to_string(t.first.size()) + " regions of up to " +
                  std::to_string(t.max_rungs) + " rungs, region code " + std::to_string(t.code.size()) + " bytes\n";
  for (size_t i = 0; i < t.first.size(); i++) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "  region %zu: rungs %u..%s  code %08x +%u\n", i, t.first[i],
                  i + 1 < t.first.size() ? std::to_string(t.first[i + 1] - 1).c_str() : "end", t.start[i], t.size[i]);
    s += buf;
  }
  return s;
}

int ldobjdump_main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; i++) {
    std::string s = argv[i];
    if (s == "--version") return print_version("ldobjdump");
    if (s == "-h" || s == "--help") { std::fputs(usage().c_str(), stdout); return 0; }
    if (s.rfind("--target=", 0) == 0) a.target = s.substr(9);
    else if (s == "--task" && i + 1 < argc) a.task = argv[++i];
    else if (s.rfind("--task=", 0) == 0) a.task = s.substr(7);
    else if (s == "-O0" || s == "-O1" || s == "-O2") a.opt = s[2] - '0';
    else if (!s.empty() && s[0] == '-') throw UserError("ldobjdump: error: unknown option '" + s + "'\n" + usage());
    else if (a.file.empty()) a.file = s;
    else throw UserError("ldobjdump: error: more than one file\n" + usage());
  }
  if (a.file.empty()) throw UserError("ldobjdump: error: no file\n" + usage());
  std::string what;
  Image img = image_of(a, what);
  const Target& t = target_of(img.target);
  std::string out = "\n" + a.file + ":     file format ldc-" + std::string(t.assembler().name) + " (" + what + ")\n\n" +
                    t.disassemble(img);
  if (img.regions) out += region_table_text(*img.regions);
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("ldobjdump", [&] { return ldobjdump_main(argc, argv); });
}
