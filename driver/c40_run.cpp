// driver/c40_run.cpp -- ldrun on the C40 engines (c40_driver.h).
#include <cstdio>

#include "driver/c40_driver.h"

namespace ldc {
namespace {

// Keeps the cost of every scan of the engine it wraps.
class Recorder : public Engine {
 public:
  explicit Recorder(C40Engine& e) : e_(e) {}
  void scan(uint8_t* mem) override {
    e_.scan(mem);
    costs.push_back(e_.last_scan());
  }
  std::vector<C40ScanCost> costs;

 private:
  C40Engine& e_;
};

}  // namespace

int run_c40(const std::string& input, const std::string& engine, const std::string& trace_file,
            const std::string& watch, RunOptions opt, bool cycles) {
  Image img;
  if (is_image_file(input)) {
    img = load_image_file(input);
    if (engine == "native")
      throw UserError("ldrun: error: " + input + " is a C40 image; use --engine=c40sim (or c40interp, interp)");
    if (engine == "c40sim" && img.target != ImageTarget::C40)
      throw UserError("ldrun: error: " + input + " is not a C40 image; compile it with ldc --target=c40, or use --engine=c40interp");
  } else {
    Compiled c = compile_source(input);
    if (engine == "c40sim") img = make_c40_image(c.il, build_c40(c.il, input));
    else {
      img.layout = c.il.layout();
      img.il = encode_il(c.il).code;
      img.aliases = c.il.aliases;
      if (std::string why = validate_il(img.il, img.layout); !why.empty()) throw UserError("ldrun: error: IL " + why);
    }
  }
  std::unique_ptr<C40Engine> eng = engine == "c40sim" ? make_c40sim_engine(img.code, img.entry, img.layout)
                                                      : make_c40interp_engine(img.il, img.layout);
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
  Recorder rec(*eng);
  std::string out;
  run_trace(rec, img.layout, trace_file.empty() ? nullptr : &trace, trace_file, opt, out);
  if (cycles) {  // two more columns: the scan's cycles and microseconds
    std::string with;
    size_t pos = 0, row = 0;
    while (pos < out.size()) {
      size_t nl = out.find('\n', pos);
      std::string line = out.substr(pos, nl - pos);
      pos = nl + 1;
      if (row == 0) line += ",cycles,us";
      else if (row - 1 < rec.costs.size()) {
        char buf[64];
        std::snprintf(buf, sizeof buf, ",%llu,%.2f", (unsigned long long)rec.costs[row - 1].cycles, rec.costs[row - 1].us());
        line += buf;
      }
      with += line + "\n";
      row++;
    }
    out = with;
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}

}  // namespace ldc
