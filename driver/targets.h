// driver/targets.h -- the one table of targets (as QBE's `struct Target`):
// each target is one value of data and hooks, and ldc, ldrun, ldobjdump and
// ldbench look targets up here by name or by image kind instead of naming
// them (docs/architecture.md, "Adding a target").
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "assembler/assembler.h"
#include "ir/ir.h"
#include "loader/loader.h"
#include "runtime/runtime.h"

namespace ldc {

// The code a target made of a program, as the driver and the loader see it:
// the assembled bytes, and where each rung's and each IL instruction's code is.
// An image's build (no notes) may keep only line_offsets: il_items,
// rung_blocks and assembled.items are then empty (x86-64: made block by block).
struct TargetCode {
  as::Result assembled;
  std::vector<std::vector<uint32_t>> il_items;  // [rung][IL instruction]: its first item in the rung's block
  std::vector<uint32_t> rung_blocks;            // [rung]: the block holding the rung's code
  std::vector<uint32_t> line_offsets;           // [IL instruction]: its code offset (loader.h, line_offsets)
};

// How ldrun and ldbench run a target's programs: on the image's code (an
// image of this target), or on the image's IL (any image, any source).
struct TargetEngine {
  std::string_view name;  // ldrun --engine=NAME
  bool runs_code;
  std::unique_ptr<Engine> (*make)(const Image& image);
};

struct Target {
  std::string_view name;     // ldc --target=NAME, the column of tests/golden/image_hashes.txt
  std::string_view title;    // in messages: "x86-64", "C40"
  std::string_view an_image; // in messages: "an x86-64 image", "a C40 image"
  ImageTarget image_kind;    // the image header's target byte
  bool host;                 // the code runs on this machine: projects, the soft PLC, --sandbox
  // The assembler's target (its name and fixup kinds; the encoder is typed
  // and used by `generate`).
  const as::TargetInfo& (*assembler)();
  // IL -> the backend's instructions at -O opt_level -> the assembler.
  // notes: comment items for listings (an image does not need them).
  // Assembly errors are UserError "SOURCE:LINE:1: error: ...".
  TargetCode (*generate)(const Program& p, const std::string& source_name, int opt_level, bool notes);
  // ldc --emit=asm: GNU as source with a first comment line naming the input.
  std::string (*gnu_as)(const Program& p, const std::string& source_name, int opt_level);
  // ldc --emit=listing: address, encoding, text and comment of every item.
  std::string (*listing)(const Program& p, const std::string& source_name, int opt_level);
  // ldobjdump: the code of an image of this kind, with the line map's rungs
  // and IL interleaved (line_notes), after the line naming the file.
  std::string (*disassemble)(const Image& image);
  // ldrun --engine=NAME for each of these.
  std::span<const TargetEngine> engines;
};

// Every target, the default (x86-64) first.
std::span<const Target> targets();
// nullptr if there is none of that name.
const Target* find_target(std::string_view name);
// The target of an image (read_image accepts only the kinds of this table).
const Target& target_of(ImageTarget kind);
// The target whose code runs on this machine (the first with `host`): the
// images of projects and of the soft PLC.
const Target& host_target();
// The target of the image in the file at `path`, read cheaply (the header
// only); nullptr if it is not an image or of no target of the table.
const Target* image_file_target(const std::string& path);
// "x86-64 or c40", for messages.
std::string target_names();
// The names of the engines of the targets that run on this machine (host)
// or of the others, in table order.
std::vector<std::string> engine_names(bool host);
// Names for a message: "a", "a or b", "a, b or c".
std::string or_list(const std::vector<std::string>& names);

// The engine named `name` of any target, with its target; nullptr if none.
struct FoundEngine {
  const Target* target;
  const TargetEngine* engine;
};
FoundEngine find_engine(std::string_view name);

// generate without notes, then the image: code, binary IL, line map, names.
Image target_image(const Target& t, const Program& p, const std::string& source_name, int opt_level);

// For the targets' hooks: a backend's result (X86Code, C40Code) and its
// assembled code as TargetCode; the backend says which block is each rung's.
template <class Code>
std::vector<uint32_t> rung_blocks(const Code& gen) {
  std::vector<uint32_t> b;
  for (size_t r = 0; r < gen.il_items.size(); r++) b.push_back(gen.rung_block(r));
  return b;
}
template <class Code>
TargetCode target_code(Code gen, as::Result assembled) {
  std::vector<uint32_t> blocks = rung_blocks(gen);
  std::vector<uint32_t> offsets = line_offsets(assembled, gen.il_items, blocks);
  return {std::move(assembled), std::move(gen.il_items), std::move(blocks), std::move(offsets)};
}
// What a disassembly prints before the instruction at each code address
// (the offset in the code divided by `unit`, the bytes of an address):
// "; rung N, line L \"title\"" where a rung starts, then ";   IL text".
std::multimap<uint32_t, std::string> line_notes(const Image& image, uint32_t unit);

// For the targets' hooks: assembles a backend's program; assembly errors
// become UserError with the rung's source line.
void throw_assembly_errors(const as::Result& r, const std::string& source_name);
template <class Inst>
as::Result assemble_or_throw(const as::Target<Inst>& t, const as::Program<Inst>& prog, const std::string& source_name,
                             as::Mode mode = as::Mode::Blockwise) {
  as::Result r = as::assemble(t, prog, mode);
  throw_assembly_errors(r, source_name);
  return r;
}

}  // namespace ldc
