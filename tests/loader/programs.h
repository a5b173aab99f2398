// tests/loader/programs.h -- the programs whose images the validator tests
// and the mutant fuzzer start from: every example, then `random` ldgen
// programs of `rungs` rungs (seeds 1, 2, ...).
#pragma once

#include <dirent.h>

#include <string>
#include <vector>

#include "bench/ldgen.h"
#include "driver/driver.h"
#include "driver/x86_target.h"
#include "frontend/frontend.h"

namespace ldc::test {

inline std::vector<Program> examples_and_random_programs(uint64_t random, int rungs) {
  std::vector<Program> out;
  std::string dir = std::string(LDC_SOURCE_DIR) + "/examples";
  if (DIR* h = opendir(dir.c_str())) {
    while (dirent* e = readdir(h)) {
      std::string n = e->d_name;
      if (n.size() > 3 && n.substr(n.size() - 3) == ".ld") out.push_back(compile_source(dir + "/" + n).il);
    }
    closedir(h);
  }
  for (uint64_t seed = 1; seed <= random; seed++) {
    GenOptions o;
    o.rungs = rungs;
    out.push_back(lower_to_il(parse_ld(generate_ld(seed, o), "gen" + std::to_string(seed) + ".ld")));
  }
  return out;
}

}  // namespace ldc::test
