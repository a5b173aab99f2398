// driver/c40_run.cpp -- ldrun on the C40 engines (c40_driver.h).
#include <cstdio>

#include "driver/c40_driver.h"
#include "driver/ldrun_io.h"

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
    img = engine == "c40sim" ? make_c40_image(c.il, build_c40(c.il, input)) : il_image(c.il);
  }
  std::unique_ptr<C40Engine> eng = engine == "c40sim" ? make_c40sim_engine(img.code, img.entry, img.layout)
                                                      : make_c40interp_engine(img.il, img.layout);
  for (Probe& p : parse_watch(watch, img.aliases)) opt.watch.push_back(p);
  Trace trace;
  if (!trace_file.empty()) trace = load_trace(trace_file, img.aliases);
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
