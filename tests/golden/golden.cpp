// Golden tests in the style of LLVM lit / cproc: foo.ld beside foo.tree and
// foo.il (what ldc --emit=tree / --emit=il print) or foo.err (the exact error);
// an IEC IL source foo.il has its ldc IL in foo.out.il and no tree.
// a chart foo.sfc beside foo.il and foo.c (ldc --emit=c, docs/sfc.md).
// With LDC_UPDATE=1 in the environment it rewrites the expected files instead,
// to be reviewed as a diff (the one update switch of every golden test, docs/testing.md).
// `golden --roundtrip FILE...` only compiles and checks the round trip.
// Every IL is also printed, read back and compared (the IL text round trip).
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "driver/driver.h"

using namespace ldc;

static bool exists(const std::string& p) { return access(p.c_str(), F_OK) == 0; }

static std::string slurp(const std::string& p) {
  try { return read_file(p); } catch (...) { return ""; }
}

static int check(const std::string& name, const std::string& want_file, const std::string& got, bool update) {
  if (update) {
    write_file_atomic(want_file, got);
    return 0;
  }
  std::string want = slurp(want_file);
  if (want == got) return 0;
  std::fprintf(stderr, "%s: output differs from %s\n--- expected\n%s--- actual\n%s", name.c_str(), want_file.c_str(),
               want.c_str(), got.c_str());
  return 1;
}

int main(int argc, char** argv) {
  const char* env = std::getenv("LDC_UPDATE");
  bool update = env && std::string(env) == "1", roundtrip_only = false;
  int failures = 0, cases = 0;
  for (int i = 1; i < argc; i++) {
    std::string path = argv[i];
    if (path == "--roundtrip") { roundtrip_only = true; continue; }  // no expected files
    size_t slash = path.rfind('/');
    std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
    std::string file = slash == std::string::npos ? path : path.substr(slash + 1);
    std::string stem = file.substr(0, file.rfind('.'));
    std::string cwd(4096, '\0');
    if (!getcwd(cwd.data(), cwd.size()) || chdir(dir.c_str()) != 0) { std::fprintf(stderr, "cannot enter %s\n", dir.c_str()); return 1; }
    cases++;
    try {
      Compiled c = compile_source(file, false, "", true);  // with the tree, for NAME.tree
      if (exists(stem + ".err") && !update) {
        std::fprintf(stderr, "%s: expected an error (%s.err) but it compiled\n", file.c_str(), stem.c_str());
        failures++;
      } else {
        std::string il = print_il_text(c.il);
        if (!roundtrip_only) {
          // an IL source (IEC IL) has no tree, and its expected IL is NAME.out.il
          bool il_source = file.size() > 3 && file.compare(file.size() - 3, 3, ".il") == 0;
          if (c.from_ld) failures += check(file, stem + ".tree", print_tree(c.tree), update);
          if (c.chart) failures += check(file, stem + ".c", c_source(c), update);
          failures += check(file, stem + (il_source ? ".out.il" : ".il"), il, update);
        }
        Program back = parse_il_text(il, file);
        bool same = print_il_text(back) == il && back.rungs.size() == c.il.rungs.size();
        for (size_t r = 0; same && r < back.rungs.size(); r++)
          same = back.rungs[r].code == c.il.rungs[r].code && back.rungs[r].labels == c.il.rungs[r].labels;
        if (!same) { std::fprintf(stderr, "%s: IL text does not read back to the same program\n", file.c_str()); failures++; }
      }
    } catch (UserError& e) {
      std::string got = std::string(e.what()) + "\n";
      if (!exists(stem + ".err") && !update) {
        std::fprintf(stderr, "%s: unexpected error\n%s", file.c_str(), got.c_str());
        failures++;
      } else {
        failures += check(file, stem + ".err", got, update);
      }
    }
    if (chdir(cwd.c_str()) != 0) return 1;
  }
  std::printf("%d cases, %d failures\n", cases, failures);
  return failures ? 1 : 0;
}
