// driver/x86_target.h -- the x86-64 target's route for the tests and the
// benchmarks that look inside it (the tools go through driver/targets.h):
// the macro compiler then the blockwise assembler, and the image.
#pragma once

#include <string>

#include "backend-x86/backend_x86.h"
#include "ir/ir.h"
#include "ir/regions.h"
#include "loader/loader.h"
#include "runtime/runtime.h"

namespace ldc {

// Assembly errors become UserError with the rung's source line.  Without notes
// (an image) in Mode::Blockwise the blocks are streamed: each is assembled as
// soon as it is generated and dropped (as::Assembler), so gen.program holds
// only the global names, and neither gen.il_items nor asm_result.items is
// kept (line_offsets is made block by block); with notes (listings,
// --emit=asm) gen holds every block and asm_result every item's layout.
struct NativeBuild {
  X86Code gen;
  as::Result asm_result;
  std::vector<uint32_t> line_offsets;  // each IL instruction's code offset (loader.h, line_offsets)
};
NativeBuild build_x86(const Program& p, const std::string& source_name, as::Mode mode = as::Mode::Blockwise,
                      int opt_level = 0, bool notes = true);

// The change-driven scan's native code (issue 28, docs/change-driven.md):
// each region of `plan` (ir/regions.h) compiled at `opt_level` as a scan
// function of its own (region_program), one right after another.
struct RegionCode {
  std::vector<uint8_t> code;
  std::vector<uint32_t> start, size;
};
RegionCode build_x86_regions(const Program& p, const RegionPlan& plan, int opt_level);
// The same as an image's region table (loader.h RegionTable).
RegionTable x86_region_table(const Program& p, uint32_t max_rungs, int opt_level);
// The change-driven engine of an image with a region table: its regions
// found again from its IL and line map (refused unless they are the
// table's), its region code checked region by region; adaptive with `full`
// (what ldrun's native engine does), walking the regions every scan without.
std::unique_ptr<Engine> make_change_driven_engine(const Image& img, std::unique_ptr<Engine> full);
// The change-driven engine (runtime/change_driven.h) on that code, checked
// region by region (map_checked_regions); adaptive, with the program's full
// scan at the same level, unless `adaptive` is false.
std::unique_ptr<Engine> make_change_driven_native(const Program& p, int opt_level, uint32_t max_rungs = 1, bool adaptive = true);

// The image ldc writes for the x86-64 target: code, binary IL, line map, names.
Image make_x86_image(const Program& p, const NativeBuild& nb);

}  // namespace ldc
