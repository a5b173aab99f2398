// ldrun -- run a program scan by scan over an input trace and print watched devices.
#include <cstdio>
#include <string>

#include "backend-c/backend_c.h"
#include "driver/driver.h"
#include "runtime/runtime.h"

using namespace ldc;

static const char kUsage[] =
    "usage: ldrun FILE [--engine=native|interp|c] [--trace in.csv] [--watch Y0,D3,...] [--scans N] [--period 10ms]\n";

int main(int argc, char** argv) {
  std::string input, engine = "native", trace_file, watch, tmpdir, so_path;
  struct Cleanup {
    std::string& dir;
    ~Cleanup() { if (!dir.empty()) remove_tree(dir); }
  } cleanup{tmpdir};
  RunOptions opt;
  try {
    for (int i = 1; i < argc; i++) {
      std::string a = argv[i];
      auto value = [&](const std::string& name) -> std::string {
        if (a.rfind(name + "=", 0) == 0) return a.substr(name.size() + 1);
        if (a == name && i + 1 < argc) return argv[++i];
        throw UserError("ldrun: error: " + name + " needs a value");
      };
      if (a.rfind("--engine", 0) == 0) engine = value("--engine");
      else if (a.rfind("--trace", 0) == 0) trace_file = value("--trace");
      else if (a.rfind("--watch", 0) == 0) watch = value("--watch");
      else if (a.rfind("--scans", 0) == 0) {
        std::string v = value("--scans");
        auto n = parse_period(v);
        if (!n || v.find_first_not_of("0123456789") != std::string::npos) throw UserError("ldrun: error: bad --scans '" + v + "'");
        opt.scans = *n;
      } else if (a.rfind("--period", 0) == 0) {
        std::string v = value("--period");
        auto p = parse_period(v);
        if (!p) throw UserError("ldrun: error: bad --period '" + v + "' (e.g. 10ms, 1s)");
        opt.period_ms = *p;
      } else if (a == "-h" || a == "--help") { std::fputs(kUsage, stdout); return 0; }
      else if (!a.empty() && a[0] == '-') throw UserError("ldrun: error: unknown option '" + a + "'\n" + kUsage);
      else if (input.empty()) input = a;
      else throw UserError("ldrun: error: more than one program");
    }
    if (input.empty()) throw UserError(std::string("ldrun: error: no program\n") + kUsage);
    if (engine != "interp" && engine != "native" && engine != "c")
      throw UserError("ldrun: error: unknown engine '" + engine + "' (native, interp or c)");
    // The program: an image (checked in full before anything runs), or a
    // source file compiled in memory.
    Image img;
    if (is_image_file(input)) {
      img = load_image_file(input);
      if (engine == "c") throw UserError("ldrun: error: --engine=c needs the program's source (.ld or .il), not an image");
      if (img.target != ImageTarget::X86_64 && engine == "native")
        throw UserError("ldrun: error: " + input + " is not an x86-64 image; use --engine=interp");
    } else if (engine == "c") {
      Compiled c = compile_source(input);
      img.layout = c.il.layout();
      img.aliases = c.il.aliases;
      tmpdir = make_temp_dir();
      so_path = build_c_shared_object(c.il, tmpdir);
    } else {
      Compiled c = compile_source(input);
      if (engine == "native") img = make_x86_image(c.il, build_x86(c.il, input, as::Mode::Blockwise, 0, /*notes=*/false));
      else {
        img.layout = c.il.layout();
        img.il = encode_il(c.il).code;
        img.aliases = c.il.aliases;
        if (std::string why = validate_il(img.il, img.layout); !why.empty()) throw UserError("ldrun: error: IL " + why);
      }
    }
    const Layout& layout = img.layout;
    std::unique_ptr<Engine> eng = engine == "interp" ? make_interp_engine(img.il, layout)
                                  : engine == "c"    ? make_shared_object_engine(so_path, kCScanSymbol)
                                                     : make_native_engine(img.code, img.entry);
    size_t s = 0;
    while (!watch.empty() && s <= watch.size()) {
      size_t e = watch.find(',', s);
      std::string name = watch.substr(s, e == std::string::npos ? std::string::npos : e - s);
      try {
        opt.watch.push_back(resolve_probe(name, img.aliases));
      } catch (std::exception& ex) { throw UserError("ldrun: error: --watch: " + std::string(ex.what())); }
      if (e == std::string::npos) break;
      s = e + 1;
    }
    Trace trace;
    if (!trace_file.empty()) {
      try {
        trace = read_trace(read_file(trace_file), trace_file, img.aliases);
      } catch (UserError&) { throw; } catch (std::exception& ex) { throw UserError(ex.what()); }
    }
    std::string out;
    run_trace(*eng, layout, trace_file.empty() ? nullptr : &trace, trace_file, opt, out);
    std::fwrite(out.data(), 1, out.size(), stdout);
  } catch (UserError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  } catch (std::exception& e) {
    std::fprintf(stderr, "ldrun: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
