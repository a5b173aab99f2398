// Fuzz the project file reader (driver/project.h parse_project), without and
// with error recovery (tests/fuzz/fuzz_recovery.h).  It reads a path, so the
// input goes to a per-process temporary file first.
#include <unistd.h>

#include <cstdio>
#include <string>

#include "driver/driver.h"
#include "driver/project.h"
#include "tests/fuzz/fuzz_common.h"
#include "tests/fuzz/fuzz_recovery.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = [] {
    const char* tmp = getenv("TMPDIR");
    return std::string(tmp && *tmp ? tmp : "/tmp") + "/ldc_fuzz_project_" + std::to_string(getpid()) + ".ldp";
  }();
  FILE* f = fopen(path.c_str(), "wb");
  if (!f) return 0;
  if (size) fwrite(data, 1, size, f);
  fclose(f);
  bool first_error = false;
  try {
    ldc::Project p = ldc::parse_project(path);
    std::vector<std::string> files;
    for (const auto& t : p.tasks) files.push_back(t.file);
    try {
      (void)ldc::print_project(p, files);
    } catch (const ldc::UserError&) {  // a retentive file no project line can name
    }
  } catch (const ldc::UserError&) {
    first_error = true;
  }
  ldc::Diagnostics d(ldc_fuzz::recovery_options());
  bool refused = false;
  try {
    (void)ldc::parse_project(path, d);
  } catch (const ldc::UserError& e) {
    refused = true;
    if (d.text().rfind(e.what(), 0) != 0) std::abort();  // the error is what was reported
  }
  ldc_fuzz::check_recovery(first_error, refused, d);
  return 0;
}
