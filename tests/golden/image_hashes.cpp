// image_hashes -- every example and every shared corpus program compiled at
// -O0, -O1 and -O2 for every target of the table (driver/targets.h), and the
// CRC-32 and size of each image, against tests/golden/image_hashes.txt.  A
// change of code generation shows here as the list of images it changed; a
// refactor must change none.  Every image must also pass its target's code
// check (the one the loader applies), else its line says "refused by the
// code check".
//
//   image_hashes SRCDIR          (LDC_UPDATE=1: rewrite the expected file)
// Paths are relative to SRCDIR (images hold the source file's name), the
// corpus at SRCDIR/../shared/corpus.  With LDC_UPDATE=1 in the environment
// it rewrites the expected file, to be reviewed as a diff.
#include <dirent.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "driver/driver.h"
#include "driver/targets.h"

using namespace ldc;

namespace {

std::vector<std::string> files_in(const std::string& dir, const std::vector<std::string>& endings) {
  std::vector<std::string> out;
  if (DIR* h = opendir(dir.c_str())) {
    while (dirent* e = readdir(h)) {
      std::string n = e->d_name;
      for (const std::string& end : endings)
        if (n.size() > end.size() && n.compare(n.size() - end.size(), end.size(), end) == 0) out.push_back(dir + "/" + n);
    }
    closedir(h);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string line_for(const std::string& file, const std::string& target, int level, const Image& im) {
  std::vector<uint8_t> b = write_image(im);
  char buf[64];
  std::snprintf(buf, sizeof buf, " -O%d %-6s %08x %7zu", level, target.c_str(), crc32(b), b.size());
  return file + buf + "\n";
}

std::string hashes() {
  std::vector<std::string> files = files_in("examples", {".ld", ".sfc", ".il"});
  for (const char* d : {"../shared/corpus/ldmicro", "../shared/corpus/plcopen"})
    for (const std::string& f : files_in(d, {".ld", ".xml"})) files.push_back(f);
  std::string out;
  for (const std::string& f : files) {
    Compiled c;
    try {
      c = compile_source(f);
    } catch (const std::exception&) {
      out += f + " refused\n";
      continue;
    }
    for (int level = 0; level <= 2; level++)
      for (const Target& t : targets()) {
        Image im = target_image(t, c.il, f, level);
        std::string why = find_image_kind(uint8_t(t.image_kind))->check(im.code, im.entry, im.layout, nullptr);
        out += why.empty() ? line_for(f, std::string(t.name), level, im)
                           : f + " -O" + std::to_string(level) + " " + std::string(t.name) + " refused by the code check: " + why + "\n";
      }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: image_hashes SRCDIR   (LDC_UPDATE=1 rewrites the expected file)\n");
    return 2;
  }
  if (chdir(argv[1]) != 0) {
    std::fprintf(stderr, "image_hashes: cannot enter %s\n", argv[1]);
    return 2;
  }
  const std::string expected_file = "tests/golden/image_hashes.txt";
  std::string got = hashes();
  if (const char* u = std::getenv("LDC_UPDATE"); u && std::string(u) == "1") {
    write_file_atomic(expected_file, got);
    return 0;
  }
  std::string want;
  try {
    want = read_file(expected_file);
  } catch (const std::exception&) {
  }
  if (got == want) {
    std::printf("%zu images as recorded\n", size_t(std::count(got.begin(), got.end(), '\n')));
    return 0;
  }
  std::fprintf(stderr, "images differ from %s (rerun with LDC_UPDATE=1 and review the diff):\n", expected_file.c_str());
  size_t a = 0, b = 0;
  while (a < got.size() || b < want.size()) {
    std::string g = a < got.size() ? got.substr(a, got.find('\n', a) - a) : "";
    std::string w = b < want.size() ? want.substr(b, want.find('\n', b) - b) : "";
    if (g != w) std::fprintf(stderr, "  want %s\n  got  %s\n", w.c_str(), g.c_str());
    a = a < got.size() ? got.find('\n', a) + 1 : a;
    b = b < want.size() ? want.find('\n', b) + 1 : b;
  }
  return 1;
}
