// loader/loader.h -- the ldc binary image: what `ldc prog.ld -o prog.bin` writes
// and `ldrun prog.bin` loads, its Intel HEX form, and the checks that make the
// runtime refuse a bad image before anything runs (docs/image-format.md).
#pragma once

#include <cstdint>
#include <cstdio>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "assembler/assembler.h"
#include "ir/ir.h"
#include "loader/config.h"

namespace ldc {

// The kind of machine code an image holds: the header's target byte.
enum class ImageTarget : uint8_t { X86_64 = 1, C40 = 2 };

// A set of offsets into a section, one bit per byte: where the instructions
// of the code (or of the IL) start.  It costs an eighth of the section's size,
// whatever the section holds (a vector of offsets cost four bytes per
// instruction, 4x a section of one-byte instructions; docs/image-format.md,
// "What the loader allocates").
class OffsetBits {
 public:
  OffsetBits() = default;
  explicit OffsetBits(size_t size) : bits_((size + 63) / 64), size_(size) {}
  size_t size() const { return size_; }  // offsets 0 .. size-1
  void add(uint32_t off) {
    if (off < size_) bits_[off / 64] |= uint64_t(1) << (off % 64);
  }
  bool has(uint64_t off) const { return off < size_ && (bits_[off / 64] >> (off % 64) & 1); }
  // The greatest offset in the set below `off`, or -1 if none.
  int64_t before(uint64_t off) const;
  // Is any offset in both sets?
  bool meets(const OffsetBits& o) const;

 private:
  std::vector<uint64_t> bits_;
  size_t size_ = 0;
};

// One row per ImageTarget (loader/image_kinds.cpp): what read_image needs to
// know of a kind of code.  A new target adds its value above and one row.
struct ImageKind {
  ImageTarget id;
  const char* name;  // in messages: "x86-64", "C40"
  uint32_t unit;     // the code is a sequence of `unit`-byte words (1: bytes)
  // "" if the code passes its check, else "at ...: why"; if it passes and
  // `starts` is given, makes it the set of offsets where an instruction starts
  // (line map entries must hit one).
  std::string (*check)(std::span<const uint8_t> code, uint32_t entry, const Layout& layout, OffsetBits* starts);
};
std::span<const ImageKind> image_kinds();
const ImageKind* find_image_kind(uint8_t id);  // nullptr for an unknown byte

// One per IL instruction: where its machine code starts, where it starts in the
// IL section, the source line of its element and the index of its rung.
struct LineEntry {
  uint32_t code_offset;
  uint32_t il_offset;
  int32_t line;
  uint32_t rung;
  bool operator==(const LineEntry&) const = default;
};

// Elements first .. first+count-1 of `area` keep their value across a restart.
struct RetentiveRange {
  Area area;
  uint32_t first, count;
  bool operator==(const RetentiveRange&) const = default;
};

// The change-driven scan's native code (ldc --change-driven, docs/change-driven.md):
// the program cut into regions of up to max_rungs rungs (ir/regions.h,
// plan_regions), region i starting at rung first[i], its scan function the
// bytes [start[i], start[i] + size[i]) of `code`.  x86-64 only.
struct RegionTable {
  uint32_t max_rungs = 1;
  std::vector<uint32_t> first, start, size;
  std::vector<uint8_t> code;
  bool operator==(const RegionTable&) const = default;
};

struct Image {
  ImageTarget target = ImageTarget::X86_64;
  std::string source;                    // source file name
  Layout layout;                         // the memory image layout
  std::vector<uint8_t> code;             // machine code (x86-64 bytes; C40: little-endian 32-bit words)
  uint32_t entry = 0;                    // entry offset of the scan function in code
  std::vector<uint8_t> il;               // binary IL (encode_il), run by --engine=interp
  std::vector<LineEntry> lines;          // rung/line/address map for listings
  std::vector<std::string> rung_titles;  // one per rung ("" if none)
  std::vector<Alias> aliases;            // so traces and --watch can use the program's names
  std::vector<VarPlace> vars;            // variables as wholes, for online change; section written only if any
  std::vector<RetentiveRange> retentive = {{Area::K, 0, 8192}};  // the K area by default
  std::optional<IoConfig> config;        // the configuration table (ldc --project); section written only if set
  std::optional<RegionTable> regions;    // ldc --change-driven; section 'regions' written only if set
  bool operator==(const Image&) const = default;
};

// A refused image or HEX file.  what() names the file and the place:
//   "prog.bin: section 'code' at offset 0x140: at code offset 0x1c: ..."
//   "prog.bin: offset 0x18: bad checksum ..."
//   "prog.hex:3:10: error: bad checksum ..."
struct ImageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The image of a program and its assembled code, for any target: rung r's
// code is block rung_blocks[r] (the backend says which), and il_items[r][i]
// is the item of that block where IL instruction i of rung r starts (the line
// map).  The K area and the IL's .retain words are retentive.
Image make_image(ImageTarget target, const Program& p, const as::Result& code,
                 const std::vector<std::vector<uint32_t>>& il_items, std::span<const uint32_t> rung_blocks);
// The same, taking the code bytes over instead of copying them.
Image make_image(ImageTarget target, const Program& p, as::Result&& code,
                 const std::vector<std::vector<uint32_t>>& il_items, std::span<const uint32_t> rung_blocks);
std::vector<RetentiveRange> retentive_ranges(const Program& p);

// The line map's code column: where each IL instruction's code starts, in
// program order.  Made whole from il_items and rung_blocks as above, or block
// by block while assembling (as::Assembler<...>::Items::LastOnly): for one
// rung's block, `items` its item layout, `block_end` the code offset where it
// ends, starts[i] the item where IL instruction i starts (past the items: the
// block's end).  Both ways give the same offsets.
void append_line_offsets(std::vector<uint32_t>& out, std::span<const as::ItemLayout> items, uint32_t block_end,
                         std::span<const uint32_t> starts);
std::vector<uint32_t> line_offsets(const as::Result& code, const std::vector<std::vector<uint32_t>>& il_items,
                                   std::span<const uint32_t> rung_blocks);
// The image of a program, its code bytes and the line map's code column
// (one offset per IL instruction, line_offsets).
Image make_image(ImageTarget target, const Program& p, std::vector<uint8_t> code, std::span<const uint32_t> offsets);

// Serializes an image.  Writes the fields as they are (read_image does the
// checking); throws ImageError only if the image is too large for the format.
std::vector<uint8_t> write_image(const Image& image);
// The same bytes written to `file` (open for writing and seeking, at its
// start) as they are made, in pieces of 64 KiB, the checksum last: no copy
// of the image is held.  Throws ImageError as write_image does, before
// writing anything.  Returns the bytes written, or 0 if the file cannot seek;
// a failed write is left in the file's error indicator (std::ferror).
size_t write_image_file(const Image& image, std::FILE* file);

// The target byte of an image's header, from the file's first bytes and
// nothing else checked (read_image checks it all); nullopt if `head` does not
// start with "LDCIMG" or is too short to hold the byte.
std::optional<uint8_t> peek_image_target(std::span<const uint8_t> head);

// Parses and checks an image; `name` is the file name used in messages.
// Never reads outside `bytes`; throws ImageError for anything not exactly right.
Image read_image(std::span<const uint8_t> bytes, const std::string& name);

// The x86-64 code check read_image applies: every byte decodes, every memory
// operand is [rbx+disp] inside [0, layout.size), every direct branch lands on an
// instruction boundary inside the code, the entry is an instruction boundary.
// Returns "" if the code passes, else "at code offset 0x..: reason".
std::string check_x86_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout);

// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), as in the image header.
uint32_t crc32(std::span<const uint8_t> bytes, uint32_t crc = 0);

// Intel HEX: 16-byte type-00 data records from address 0, a type-04 record at
// each 64 KiB boundary, a type-01 end record.  Lines end in "\n".
std::string write_intel_hex(std::span<const uint8_t> bytes);
// Reads what write_intel_hex writes (any data record length, CRLF accepted).
// Refuses bad digits, lengths, checksums, record types, gaps or overlaps, a
// missing end record and anything after it: "name:line:col: error: ...".
std::vector<uint8_t> read_intel_hex(std::string_view text, const std::string& name);
// True if the first non-blank character is ':'.
bool looks_like_intel_hex(std::span<const uint8_t> bytes);

// Reads an image file (binary, or Intel HEX by its first character) and checks
// it fully; every ImageError, a file that cannot be read included, reads
// "FILE: error: ..." naming the file and the place.
Image read_image_file(const std::string& path);
// The same, but a file of more than `max_bytes` bytes is refused before it is
// read whole: "FILE: error: the file has N bytes, more than the M MiB <whose>;
// it was not read" (read_image_file(path) passes the format's limit, whose =
// "an image file may have").
Image read_image_file(const std::string& path, uint64_t max_bytes, const std::string& whose);
// True for files ldrun treats as an image: *.bin, *.hex, or the image magic.
bool is_image_file(const std::string& path);

// Limits of format version 1.
constexpr uint32_t kImageMaxSize = 256u << 20;    // whole file, bytes
constexpr uint32_t kImageMaxEdgeSlots = 1u << 20;  // count of the E area
// Counts whose entries cost the loader more than their bytes in the file (a
// string each): with these limits a strings or aliases section, however
// large, costs at most 32 MiB and 2.5 MiB held (docs/image-format.md, "What
// the loader allocates").
constexpr uint32_t kImageMaxRungTitles = 1u << 20;
constexpr uint32_t kImageMaxAliases = 1u << 16;
constexpr uint32_t kImageMaxVars = 1u << 16;        // entries of the `vars` section (two strings each)
constexpr uint32_t kImageVarsVersion = 1;           // the `vars` section's own version

}  // namespace ldc
