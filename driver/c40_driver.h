// driver/c40_driver.h -- the TMS320C40 route of ldc, ldrun and ldobjdump
// (docs/c40.md): the C40 macro compiler and the blockwise assembler, the
// ImageTarget::C40 image, its listing, and running it on the simulator.
#pragma once

#include <string>

#include "backend-c40sim/gen/c40gen.h"
#include "driver/driver.h"
#include "runtime/runtime.h"

namespace ldc {

// Engines on the cycle-counting C40 simulator (backend-c40sim, docs/c40.md):
// the C40 native code of an image (ImageTarget::C40), or the C40-hosted
// interpreter (backend-c40sim/machine/interp.c40s) running the image's IL in its word
// form.  Both keep the cost of the last scan (50 ns per cycle).
struct C40ScanCost {
  uint64_t cycles = 0;
  uint64_t instructions = 0;
  double us() const { return double(cycles) * 0.05; }
};
class C40Engine : public Engine {
 public:
  virtual C40ScanCost last_scan() const = 0;
};
std::unique_ptr<C40Engine> make_c40sim_engine(std::span<const uint8_t> code, uint32_t entry, const Layout& layout);
std::unique_ptr<C40Engine> make_c40interp_engine(std::span<const uint8_t> il, const Layout& layout);

struct C40Build {
  c40gen::C40Code gen;
  as::Result asm_result;
};
// Assembly errors become UserError with the rung's source line.  opt_level
// 0, 1, 2: the code generator's level (c40gen.h, docs/c40.md).
C40Build build_c40(const Program& p, const std::string& source_name, int opt_level = 0);

// The image ldc writes for --target=c40: code words, binary IL, line map, names.
Image make_c40_image(const Program& p, const C40Build& b);

// ldc --target=c40: --emit=asm (GNU as tic4x source), --emit=listing,
// --emit=hex, or (emit empty) the image bytes, which need -o.
std::string c40_output(const Program& p, const std::string& input, const std::string& emit, bool to_file,
                       int opt_level = 0);

// ldobjdump of a C40 image: word address, word and instruction, with the
// rungs and IL interleaved.
std::string c40_objdump(const Image& img, const std::string& path);

// ldrun --engine=c40sim|c40interp (and --engine=native on a C40 image, which
// is refused with a hint): loads or compiles the program, runs the trace and
// prints the watched devices, with --cycles two more columns: the scan's
// cycles and microseconds on a 40 MHz TMS320C40 (50 ns per cycle).
int run_c40(const std::string& input, const std::string& engine, const std::string& trace_file,
            const std::string& watch, RunOptions opt, bool cycles);

// True if the program is a C40 image (read cheaply: only its header).
bool is_c40_image(const std::string& path);

}  // namespace ldc
