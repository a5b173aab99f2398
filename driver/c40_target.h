// driver/c40_target.h -- the TMS320C40 target's route for the tests and the
// benchmarks that look inside it (the tools go through driver/targets.h):
// the C40 macro compiler and the blockwise assembler, the ImageTarget::C40
// image, and the engines on the simulated board (docs/c40.md).
#pragma once

#include <memory>
#include <span>
#include <string>

#include "backend-c40sim/gen/c40gen.h"
#include "ir/ir.h"
#include "loader/loader.h"
#include "runtime/runtime.h"

namespace ldc {

// Engines on the cycle-counting C40 simulator (backend-c40sim/machine): the
// C40 native code of an image (ImageTarget::C40), or the C40-hosted
// interpreter (interp.c40s) running the image's IL in its word form.  Both
// report the cost of the last scan (Engine::last_cost, 50 ns per cycle).
std::unique_ptr<Engine> make_c40sim_engine(std::span<const uint8_t> code, uint32_t entry, const Layout& layout);
std::unique_ptr<Engine> make_c40interp_engine(std::span<const uint8_t> il, const Layout& layout);

struct C40Build {
  c40gen::C40Code gen;
  as::Result asm_result;
};
// Assembly errors become UserError with the rung's source line.  opt_level
// 0, 1, 2: the code generator's level (c40gen.h, docs/c40.md).
C40Build build_c40(const Program& p, const std::string& source_name, int opt_level = 0);

// The image ldc writes for --target=c40: code words, binary IL, line map, names.
Image make_c40_image(const Program& p, const C40Build& b);

}  // namespace ldc
