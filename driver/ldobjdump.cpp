// ldobjdump -- an objdump-style listing of an ldc image: address, bytes and
// instruction, with each rung's source line and IL interleaved.
#include <cstdio>
#include <string>

#include "driver/driver.h"
#include "driver/targets.h"
#include "driver/version.h"

using namespace ldc;

static const char kUsage[] = "usage: ldobjdump IMAGE.bin|IMAGE.hex\n";

namespace {

int ldobjdump_main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "--version") return print_version("ldobjdump");
  if (argc != 2 || argv[1][0] == '-') {
    std::fputs(kUsage, argc == 2 && std::string(argv[1]) == "--help" ? stdout : stderr);
    return argc == 2 && std::string(argv[1]) == "--help" ? 0 : 1;
  }
  Image img = load_image_file(argv[1]);
  const Target& t = target_of(img.target);
  std::string out = "\n" + std::string(argv[1]) + ":     file format ldc-" + std::string(t.assembler().name) +
                    " (image of " + img.source + ")\n\n" + t.disassemble(img);
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("ldobjdump", [&] { return ldobjdump_main(argc, argv); });
}
