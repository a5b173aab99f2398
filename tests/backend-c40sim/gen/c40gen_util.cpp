// tests/backend-c40sim/gen/c40gen_util.cpp -- engines and checks shared by the C40 tests.
#include "tests/backend-c40sim/gen/c40gen_util.h"

#include <stdexcept>

#include "backend-c40sim/gen/c40gen.h"

namespace ldc::c40gen::test {
namespace {

class ModelEngine : public Engine {
 public:
  ModelEngine(const Program& p, C40Model::Mode mode, CheckReport* out)
      : bin_(encode_il(p)), model_(bin_.code, p.layout(), mode), out_(out) {}
  void scan(ImageBytes& mem_bytes) override {
    uint8_t* mem = mem_bytes.data();
    model_.scan(mem);
    if (out_) *out_ = model_.report();
  }

 private:
  BinaryIl bin_;
  C40Model model_;
  CheckReport* out_;
};

}  // namespace

std::unique_ptr<Engine> make_native(const Program& p, int opt_level) {
  C40Code c = generate_c40(p, p.layout(), opt_level);
  as::Result r = as::assemble(as::c40::target(), c.program);
  if (!r.ok()) throw std::runtime_error("C40 assembly: " + r.errors[0].message);
  return make_c40sim_engine(r.code, 0, p.layout());
}

diff::EngineFactory native_at(int opt_level) {
  return [opt_level](const Program& p) { return make_native(p, opt_level); };
}

std::unique_ptr<Engine> make_interp(const Program& p) {
  BinaryIl bin = encode_il(p);
  return make_c40interp_engine(bin.code, p.layout());
}

std::unique_ptr<Engine> make_model(const Program& p) {
  return std::make_unique<ModelEngine>(p, C40Model::Mode::C40, nullptr);
}

diff::EngineFactory make_check(CheckReport* report) {
  return [report](const Program& p) -> std::unique_ptr<Engine> {
    return std::make_unique<ModelEngine>(p, C40Model::Mode::Check, report);
  };
}

bool Verdict::ok() const {
  return !native.failed() && !native_o1.failed() && !native_o2.failed() && !interp.failed() && !check.failed() &&
         report.violations == 0 && native.kind != diff::Outcome::Kind::FrontEndError;
}

static std::string outcome_text(const char* what, const diff::Outcome& o) {
  using K = diff::Outcome::Kind;
  if (o.kind == K::Same) return "";
  std::string s = std::string(what) + ": ";
  if (o.kind == K::Differ)
    s += "scan " + std::to_string(o.scan) + ": " + o.place.name + " is " + o.test_value + ", expected " + o.ref_value;
  else
    s += o.message;
  for (const std::string& a : o.also) s += "; also " + a;
  return s + "\n";
}

std::string Verdict::text() const {
  std::string s = outcome_text("native vs C40 model", native) + outcome_text("native -O1 vs C40 model", native_o1) +
                  outcome_text("native -O2 vs C40 model", native_o2) + outcome_text("c40interp vs C40 model", interp) +
                  outcome_text("C40 model (check) vs reference", check);
  for (const std::string& v : report.first_violations) s += "precision: " + v + "\n";
  return s;
}

diff::Outcome Verdict::first_failure() const {
  for (const diff::Outcome* o : {&native, &native_o1, &native_o2, &interp, &check})
    if (o->failed() || o->kind == diff::Outcome::Kind::FrontEndError) return *o;
  diff::Outcome o;
  if (report.violations) {
    o.kind = diff::Outcome::Kind::Differ;
    o.message = report.first_violations.empty() ? "precision" : report.first_violations[0];
    o.place.name = "a REAL result outside the bound";
  }
  return o;
}

Verdict check_c40(const std::string& ld, const std::string& csv, const diff::EngineFactory& native) {
  Verdict v;
  v.native = diff::compare_run(ld, csv, make_model, native ? native : native_at(0));
  v.scans = v.native.scans;
  if (!native) {
    v.native_o1 = diff::compare_run(ld, csv, make_model, native_at(1));
    v.native_o2 = diff::compare_run(ld, csv, make_model, native_at(2));
  }
  v.interp = diff::compare_run(ld, csv, make_model, make_interp);
  v.check = diff::compare_run(ld, csv, diff::make_interp, make_check(&v.report));
  return v;
}

}  // namespace ldc::c40gen::test
