// driver/x86_target.cpp -- the x86-64 row of the table of targets
// (targets.h): backend-x86's macro compiler, the assembler's x86-64 target,
// the x86-64 code check and the native engine.
#include "driver/x86_target.h"

#include <cstdio>

#include "driver/targets.h"
#include "runtime/change_driven.h"

namespace ldc {

namespace {

// An image's build: each block assembled as it is made, then dropped, and
// the line map's code offsets taken from its item layout right away.
void stream_x86(const Program& p, int opt_level, NativeBuild& b) {
  b.gen.program.globals = x86_globals(p);
  using Asm = as::Assembler<as::x86::Instruction>;
  Asm a(as::x86::target(), b.gen.program.globals, Asm::Items::LastOnly);
  std::vector<std::vector<uint32_t>> il_items;  // a rung's, cleared once its block is laid out
  size_t il = 0;
  for (const Rung& r : p.rungs) il += r.code.size();
  b.line_offsets.reserve(il);  // an entry an IL instruction: not copied as it grows
  size_t blocks = 0;
  auto sink = [&](as::Block<as::x86::Instruction>& blk) {
    a.add(blk);
    if (!il_items.empty() && X86Code::rung_block(il_items.size() - 1) == blocks) {
      append_line_offsets(b.line_offsets, a.last_items(), a.code_size(), il_items.back());
      il_items.back().clear();  // read: the generator reuses its storage
    }
    blocks++;
  };
  generate_x86_blocks(p, p.layout(), opt_level, false, sink, il_items);
  b.asm_result = a.finish();
}

}  // namespace

NativeBuild build_x86(const Program& p, const std::string& source_name, as::Mode mode, int opt_level, bool notes) {
  NativeBuild b;
  if (mode == as::Mode::Blockwise && !notes) {  // an image
    stream_x86(p, opt_level, b);
    throw_assembly_errors(b.asm_result, source_name);
    return b;
  }
  b.gen = generate_x86(p, p.layout(), opt_level, notes);
  b.asm_result = assemble_or_throw(as::x86::target(), b.gen.program, source_name, mode);
  b.line_offsets = line_offsets(b.asm_result, b.gen.il_items, rung_blocks(b.gen));
  return b;
}

Image make_x86_image(const Program& p, const NativeBuild& nb) {
  return make_image(ImageTarget::X86_64, p, nb.asm_result.code, nb.line_offsets);
}

namespace {

TargetCode generate(const Program& p, const std::string& source_name, int opt_level, bool notes) {
  NativeBuild b = build_x86(p, source_name, as::Mode::Blockwise, opt_level, notes);
  TargetCode c = target_code(std::move(b.gen), std::move(b.asm_result));
  c.line_offsets = std::move(b.line_offsets);
  return c;
}

std::string gnu_as(const Program& p, const std::string& source_name, int opt_level) {
  return "# ldc " + source_name + ": x86-64, GNU as syntax (.intel_syntax noprefix)\n" +
         as::x86::to_gnu_as(generate_x86(p, p.layout(), opt_level).program);
}

std::string listing(const Program& p, const std::string& source_name, int opt_level) {
  NativeBuild nb = build_x86(p, source_name, as::Mode::Blockwise, opt_level);
  return as::x86::listing(nb.gen.program, nb.asm_result);
}

// Branch sites: each conditional or unconditional jump is a place the branch
// predictor may have to remember (docs/x86.md, "Branch sites").
std::string branch_sites(const Image& img, const as::x86::Disassembly& d) {
  size_t jcc = 0, jmp = 0, call = 0;
  for (const auto& di : d.insts) {
    jcc += di.inst.mnemonic == as::x86::Mnemonic::Jcc;
    jmp += di.inst.mnemonic == as::x86::Mnemonic::Jmp;
    call += di.inst.mnemonic == as::x86::Mnemonic::Call;
  }
  return "\n; " + std::to_string(img.code.size()) + " bytes, " + std::to_string(d.insts.size()) + " instructions, " +
         std::to_string(img.lines.size()) + " IL; branch sites: " + std::to_string(jcc) + " jcc, " + std::to_string(jmp) +
         " jmp, " + std::to_string(call) + " call\n";
}

std::string disassemble(const Image& img) {
  std::string out = "Disassembly of section .code:\n\n";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%016x <scan>:\n", img.entry);
  out += buf;
  std::multimap<uint32_t, std::string> notes = line_notes(img, 1);
  as::x86::Disassembly d = as::x86::disassemble(img.code);
  for (const auto& di : d.insts) {
    auto [lo, hi] = notes.equal_range(di.offset);
    for (auto it = lo; it != hi; ++it) out += it->second + "\n";
    std::snprintf(buf, sizeof buf, "%8x:\t", di.offset);
    out += buf;
    std::string bytes;
    for (uint32_t i = 0; i < di.length; i++) {
      std::snprintf(buf, sizeof buf, "%02x ", img.code[di.offset + i]);
      bytes += buf;
    }
    if (bytes.size() < 21) bytes.resize(21, ' ');
    out += bytes + "\t" + as::x86::print(di.inst) + "\n";
  }
  if (d.error) out += "  (cannot decode at offset " + std::to_string(d.error->offset) + ": " + d.error->message + ")\n";
  return out + branch_sites(img, d);
}

const as::TargetInfo& assembler() { return as::x86::target(); }

std::unique_ptr<Engine> native_engine(const Image& img) {
  std::unique_ptr<Engine> full = make_native_engine(map_checked_code(img.code, img.entry, img.layout));
  if (img.regions) return make_change_driven_engine(img, std::move(full));
  return full;
}

const TargetEngine kEngines[] = {{"native", true, native_engine}};

}  // namespace

const Target& x86_64_target() {
  static const Target t{
      .name = "x86-64",
      .title = "x86-64",
      .an_image = "an x86-64 image",
      .image_kind = ImageTarget::X86_64,
      .host = true,
      .assembler = assembler,
      .generate = generate,
      .gnu_as = gnu_as,
      .listing = listing,
      .disassemble = disassemble,
      .engines = kEngines,
  };
  return t;
}

}  // namespace ldc

namespace ldc {

RegionCode build_x86_regions(const Program& p, const RegionPlan& plan, int opt_level) {
  RegionCode rc;
  for (const Region& r : plan.regions) {
    NativeBuild nb = build_x86(region_program(p, r), p.source, as::Mode::Blockwise, opt_level, /*notes=*/false);
    rc.start.push_back(uint32_t(rc.code.size()));
    rc.size.push_back(uint32_t(nb.asm_result.code.size()));
    rc.code.insert(rc.code.end(), nb.asm_result.code.begin(), nb.asm_result.code.end());
  }
  return rc;
}

RegionTable x86_region_table(const Program& p, uint32_t max_rungs, int opt_level) {
  RegionPlan plan = plan_regions(p, p.layout(), max_rungs);
  RegionCode rc = build_x86_regions(p, plan, opt_level);
  RegionTable t;
  t.max_rungs = max_rungs;
  for (const Region& r : plan.regions) t.first.push_back(r.first);
  t.start = std::move(rc.start), t.size = std::move(rc.size), t.code = std::move(rc.code);
  return t;
}

std::unique_ptr<Engine> make_change_driven_native(const Program& p, int opt_level, uint32_t max_rungs, bool adaptive) {
  const Layout L = p.layout();
  RegionPlan plan = plan_regions(p, L, max_rungs);
  RegionCode rc = build_x86_regions(p, plan, opt_level);
  auto code = std::make_shared<const CheckedRegions>(map_checked_regions(rc.code, rc.start, rc.size, L));
  std::unique_ptr<Engine> full;
  if (adaptive) full = make_native_engine(map_checked_code(build_x86(p, p.source, as::Mode::Blockwise, opt_level, false).asm_result.code, 0, L));
  return std::make_unique<ChangeDrivenEngine>(plan, L, make_native_region_engines(code), std::move(full));
}

// An image with a region table (ldc --change-driven): the regions are found
// again from its IL (plan_regions of the program the IL and the line map
// make) and must be the table's, so what each region reads and writes is
// this runtime's finding, not the image's word; the full scan is its code.
std::unique_ptr<Engine> make_change_driven_engine(const Image& img, std::unique_ptr<Engine> full) {
  const RegionTable& t = *img.regions;
  std::vector<uint32_t> rung_of;
  for (const LineEntry& l : img.lines) rung_of.push_back(l.rung);
  const Program p = program_of_il(img.il, rung_of, img.layout.count[int(Area::E)]);
  RegionPlan plan = plan_regions(p, img.layout, t.max_rungs);
  std::vector<uint32_t> first;
  for (const Region& r : plan.regions) first.push_back(r.first);
  if (first != t.first)
    throw std::runtime_error("the image's region table (" + std::to_string(t.first.size()) +
                             " regions) is not the program's (" + std::to_string(first.size()) + " regions of up to " +
                             std::to_string(t.max_rungs) + " rungs)");
  auto code = std::make_shared<const CheckedRegions>(map_checked_regions(t.code, t.start, t.size, img.layout));
  return std::make_unique<ChangeDrivenEngine>(plan, img.layout, make_native_region_engines(code), std::move(full));
}

}  // namespace ldc
