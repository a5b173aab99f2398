// loader/image.cpp -- writing and reading the ldc binary image (docs/image-format.md).
//
// The reader trusts nothing: every length is checked against what is left
// before it is used, in 64-bit arithmetic, and every refusal names the file,
// the section and the offset.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>

#include "loader/checks.h"
#include "loader/loader.h"
#include "loader/c40_check.h"

namespace ldc {

namespace {

// ---------------------------------------------------------------- the format

constexpr uint8_t kMagic[8] = {'L', 'D', 'C', 'I', 'M', 'G', 0x00, 0x01};
constexpr uint16_t kVersion = 2;

// Fixed header.
constexpr uint32_t kOffMagic = 0, kOffVersion = 8, kOffTarget = 10, kOffFlags = 11, kOffHeaderSize = 12,
                   kOffTotalSize = 16, kOffSectionCount = 20, kOffChecksum = 24, kOffReserved = 28;
constexpr uint32_t kFixedHeaderSize = 32;
// Layout block: area count, count[], offset[], size.
constexpr uint32_t kOffLayout = kFixedHeaderSize;
constexpr uint32_t kLayoutSize = 4 + 4 * kAreaCount + 4 * kAreaCount + 4;
// Section table: {id, offset, size} entries of three u32.
constexpr uint32_t kOffSections = kOffLayout + kLayoutSize;
constexpr uint32_t kSectionEntrySize = 12;
constexpr uint32_t kMaxSections = 64;

enum SectionId : uint32_t { kCode = 1, kIl, kLines, kStrings, kAliases, kRetentive, kEntry, kConfig, kSectionIdEnd };
constexpr const char* kSectionNames[] = {"?", "code", "il", "lines", "strings", "aliases", "retentive", "entry", "config"};

constexpr uint32_t kLineEntrySize = 16;
constexpr uint32_t kRetentiveEntrySize = 12;
constexpr uint32_t kConfigRowSize = 16;

std::string hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

// ---------------------------------------------------------------- writing

struct Writer {
  std::vector<uint8_t> out;
  void u8(uint8_t v) { out.push_back(v); }
  void u16(uint16_t v) { u8(uint8_t(v)); u8(uint8_t(v >> 8)); }
  void u32(uint32_t v) { for (int i = 0; i < 4; i++) u8(uint8_t(v >> (8 * i))); }
  void bytes(std::span<const uint8_t> b) { out.insert(out.end(), b.begin(), b.end()); }
  void str(const std::string& s) {
    if (s.size() > kImageMaxSize) throw ImageError("image: string too long for the image format");
    u32(uint32_t(s.size()));
    out.insert(out.end(), s.begin(), s.end());
  }
  void align4() { while (out.size() % 4) u8(0); }
  void put32_at(size_t at, uint32_t v) { for (int i = 0; i < 4; i++) out[at + i] = uint8_t(v >> (8 * i)); }
};

uint32_t count32(size_t n, const char* what) {
  if (n > kImageMaxSize) throw ImageError(std::string("image: too many ") + what + " for the image format");
  return uint32_t(n);
}

// ---------------------------------------------------------------- reading

uint32_t get32(std::span<const uint8_t> b, size_t at) {
  return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}
uint16_t get16(std::span<const uint8_t> b, size_t at) { return uint16_t(b[at] | b[at + 1] << 8); }

// Reads the fields of one section; every read is bounds-checked and a short
// read reports the file offset it needed.
struct SectionReader {
  std::span<const uint8_t> data;  // the section's bytes
  uint32_t file_offset;           // where they start in the file
  size_t pos = 0;
  std::string error;              // first problem, "" if none

  bool need(uint64_t n, const char* what) {
    if (!error.empty()) return false;
    if (n > data.size() - pos) {
      error = "truncated " + std::string(what) + " at file offset " + hex(uint64_t(file_offset) + pos) + " (needs " +
              std::to_string(n) + " bytes, " + std::to_string(data.size() - pos) + " left in the section)";
      return false;
    }
    return true;
  }
  uint8_t u8(const char* what) {
    if (!need(1, what)) return 0;
    return data[pos++];
  }
  uint32_t u32(const char* what) {
    if (!need(4, what)) return 0;
    uint32_t v = get32(data, pos);
    pos += 4;
    return v;
  }
  std::string str(const char* what) {
    uint32_t n = u32(what);
    if (!need(n, what)) return {};
    std::string s(reinterpret_cast<const char*>(data.data() + pos), n);
    pos += n;
    return s;
  }
  void finish() {
    if (error.empty() && pos != data.size())
      error = std::to_string(data.size() - pos) + " unexpected bytes at file offset " + hex(uint64_t(file_offset) + pos) +
              " after the last field";
  }
};

struct SectionEntry {
  uint32_t id, offset, size, table_index;
};

}  // namespace

// ---------------------------------------------------------------- CRC-32

uint32_t crc32(std::span<const uint8_t> bytes, uint32_t crc) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; i++) {
      uint32_t c = i;
      for (int k = 0; k < 8; k++) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (uint8_t b : bytes) crc = table[(crc ^ b) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

// The checksum of a whole file, its checksum field taken as zero.
static uint32_t image_checksum(std::span<const uint8_t> file) {
  static const uint8_t zero[4] = {};
  uint32_t c = crc32(file.subspan(0, kOffChecksum));
  c = crc32(zero, c);
  return crc32(file.subspan(kOffChecksum + 4), c);
}

// ---------------------------------------------------------------- write_image

std::vector<uint8_t> write_image(const Image& im) {
  Writer w;
  w.bytes(kMagic);
  w.u16(kVersion);
  w.u8(uint8_t(im.target));
  w.u8(0);  // flags
  // Sections 1..7 always; 'config' only when the image has a configuration
  // table, so images without one are byte for byte what they always were.
  const uint32_t nsections = im.config ? kConfig : kConfig - 1;
  w.u32(kOffSections + nsections * kSectionEntrySize);
  w.u32(0);  // total size, patched below
  w.u32(nsections);
  w.u32(0);  // checksum, patched below
  w.u32(0);  // reserved
  w.u32(kAreaCount);
  for (uint32_t c : im.layout.count) w.u32(c);
  for (uint32_t o : im.layout.offset) w.u32(o);
  w.u32(im.layout.size);
  size_t table = w.out.size();
  for (uint32_t i = 1; i <= nsections; i++) w.u32(i), w.u32(0), w.u32(0);

  for (uint32_t id = 1; id <= nsections; id++) {
    w.align4();
    size_t start = w.out.size();
    switch (SectionId(id)) {
      case kCode: w.bytes(im.code); break;
      case kIl: w.bytes(im.il); break;
      case kLines:
        count32(im.lines.size(), "line map entries");
        for (const LineEntry& e : im.lines) w.u32(e.code_offset), w.u32(e.il_offset), w.u32(uint32_t(e.line)), w.u32(e.rung);
        break;
      case kStrings:
        w.str(im.source);
        w.u32(count32(im.rung_titles.size(), "rung titles"));
        for (const std::string& t : im.rung_titles) w.str(t);
        break;
      case kAliases:
        w.u32(count32(im.aliases.size(), "aliases"));
        for (const Alias& a : im.aliases) w.u8(uint8_t(a.dev.dev)), w.u32(a.dev.index), w.str(a.name);
        break;
      case kRetentive:
        count32(im.retentive.size(), "retentive ranges");
        for (const RetentiveRange& r : im.retentive) w.u32(uint32_t(r.area)), w.u32(r.first), w.u32(r.count);
        break;
      case kEntry: w.u32(im.entry); break;
      case kConfig: {
        const IoConfig& c = *im.config;
        w.u32(c.block_size), w.u32(c.processor), w.u32(c.period_us), w.u32(c.priority);
        w.str(c.resource), w.str(c.task), w.str(c.program);
        w.u32(count32(c.rows.size(), "configuration rows"));
        for (const ConfigRow& r : c.rows) {
          w.u8(uint8_t(r.area)), w.u8(r.flags), w.u16(0);
          w.u32(r.block), w.u32(r.writer), w.u32(r.period_us);
        }
        break;
      }
      case kSectionIdEnd: break;
    }
    if (w.out.size() > kImageMaxSize) throw ImageError("image: larger than the format allows (" + hex(kImageMaxSize) + " bytes)");
    size_t at = table + (id - 1) * kSectionEntrySize;
    w.put32_at(at + 4, uint32_t(start));
    w.put32_at(at + 8, uint32_t(w.out.size() - start));
  }
  w.align4();
  if (w.out.size() > kImageMaxSize) throw ImageError("image: larger than the format allows (" + hex(kImageMaxSize) + " bytes)");
  w.put32_at(kOffTotalSize, uint32_t(w.out.size()));
  w.put32_at(kOffChecksum, image_checksum(w.out));
  return std::move(w.out);
}

// ---------------------------------------------------------------- read_image

std::optional<uint8_t> peek_image_target(std::span<const uint8_t> head) {
  if (head.size() <= kOffTarget || !std::equal(kMagic, kMagic + 6, head.begin())) return std::nullopt;
  return head[kOffTarget];
}

Image read_image(std::span<const uint8_t> b, const std::string& name) {
  auto fail = [&](uint64_t off, const std::string& msg) -> ImageError {
    return ImageError(name + ": offset " + hex(off) + ": " + msg);
  };

  // ---- fixed header
  if (b.size() < kFixedHeaderSize)
    throw ImageError(name + ": truncated header: " + std::to_string(b.size()) + " bytes, an image header has " +
                     std::to_string(kFixedHeaderSize));
  if (!std::equal(std::begin(kMagic), std::end(kMagic), b.begin()))
    throw fail(kOffMagic, "not an ldc image (bad magic; expected \"LDCIMG\\0\\1\")");
  if (uint16_t v = get16(b, kOffVersion); v != kVersion)
    throw fail(kOffVersion, "unsupported format version " + std::to_string(v) + " (this loader reads version " +
                                std::to_string(kVersion) + ")");
  uint8_t target = b[kOffTarget];
  if (target != uint8_t(ImageTarget::X86_64) && target != uint8_t(ImageTarget::C40))
    throw fail(kOffTarget, "unknown target " + std::to_string(target) + " (1 = x86-64, 2 = C40)");
  if (b[kOffFlags] != 0) throw fail(kOffFlags, "unknown flags " + hex(b[kOffFlags]) + " (version " + std::to_string(kVersion) + " defines none)");
  uint32_t total = get32(b, kOffTotalSize);
  if (total > kImageMaxSize) throw fail(kOffTotalSize, "total size " + hex(total) + " exceeds the limit " + hex(kImageMaxSize));
  if (b.size() < total)
    throw ImageError(name + ": truncated file: the header says " + std::to_string(total) + " bytes, the file has " +
                     std::to_string(b.size()));
  if (b.size() > total)
    throw fail(total, std::to_string(b.size() - total) + " trailing bytes after the image (header says " +
                          std::to_string(total) + " bytes)");
  uint32_t nsec = get32(b, kOffSectionCount);
  if (nsec > kMaxSections) throw fail(kOffSectionCount, "section count " + std::to_string(nsec) + " exceeds the limit " + std::to_string(kMaxSections));
  uint32_t header_size = get32(b, kOffHeaderSize);
  uint32_t want_header = kOffSections + nsec * kSectionEntrySize;
  if (header_size != want_header)
    throw fail(kOffHeaderSize, "header size " + hex(header_size) + " does not match " + std::to_string(nsec) +
                                   " sections (expected " + hex(want_header) + ")");
  if (header_size > total)
    throw ImageError(name + ": truncated file: the header and section table need " + std::to_string(header_size) +
                     " bytes, the image has " + std::to_string(total));
  if (uint32_t sum = get32(b, kOffChecksum), want = image_checksum(b); sum != want)
    throw fail(kOffChecksum, "bad checksum " + hex(sum) + " (the file's CRC-32 is " + hex(want) + ")");
  if (uint32_t r = get32(b, kOffReserved); r != 0) throw fail(kOffReserved, "reserved field is " + hex(r) + ", not 0");

  Image im;
  im.target = ImageTarget(target);
  im.retentive.clear();

  // ---- layout
  if (uint32_t n = get32(b, kOffLayout); n != uint32_t(kAreaCount))
    throw fail(kOffLayout, "layout has " + std::to_string(n) + " areas, version " + std::to_string(kVersion) + " has " + std::to_string(kAreaCount));
  const uint32_t off_count = kOffLayout + 4, off_offset = off_count + 4 * kAreaCount, off_size = off_offset + 4 * kAreaCount;
  for (int i = 0; i < kAreaCount; i++) im.layout.count[i] = get32(b, off_count + 4 * i);
  for (int i = 0; i < kAreaCount; i++) im.layout.offset[i] = get32(b, off_offset + 4 * i);
  im.layout.size = get32(b, off_size);
  const int e = int(Area::E);
  if (im.layout.count[e] > kImageMaxEdgeSlots)
    throw fail(off_count + 4 * e, "layout: " + std::to_string(im.layout.count[e]) + " edge slots exceed the limit " +
                                      std::to_string(kImageMaxEdgeSlots));
  Layout want = Layout::standard(im.layout.count[e]);
  for (int i = 0; i < kAreaCount; i++)
    if (im.layout.count[i] != want.count[i])
      throw fail(off_count + 4 * i, std::string("layout mismatch: area ") + area_name(Area(i)) + " has " +
                                        std::to_string(im.layout.count[i]) + " elements, the standard layout has " +
                                        std::to_string(want.count[i]));
  for (int i = 0; i < kAreaCount; i++)
    if (im.layout.offset[i] != want.offset[i])
      throw fail(off_offset + 4 * i, std::string("layout mismatch: area ") + area_name(Area(i)) + " at " +
                                         hex(im.layout.offset[i]) + ", the standard layout puts it at " + hex(want.offset[i]));
  if (im.layout.size != want.size)
    throw fail(off_size, "layout mismatch: memory image size " + hex(im.layout.size) + ", the standard layout has " +
                             hex(want.size));

  // ---- section table
  const SectionEntry* by_id[kSectionIdEnd] = {};
  std::vector<SectionEntry> table(nsec);
  for (uint32_t i = 0; i < nsec; i++) {
    uint32_t at = kOffSections + i * kSectionEntrySize;
    SectionEntry s{get32(b, at), get32(b, at + 4), get32(b, at + 8), i};
    std::string where = "section table entry " + std::to_string(i);
    if (s.id == 0 || s.id >= kSectionIdEnd)
      throw fail(at, where + ": unknown section id " + std::to_string(s.id) + " (version " + std::to_string(kVersion) + " has ids 1.." +
                         std::to_string(kSectionIdEnd - 1) + ")");
    where += " ('" + std::string(kSectionNames[s.id]) + "')";
    if (s.offset % 4) throw fail(at + 4, where + ": section offset " + hex(s.offset) + " is not 4-byte aligned");
    if (s.offset < header_size)
      throw fail(at + 4, where + ": section offset " + hex(s.offset) + " lies inside the header (which ends at " +
                             hex(header_size) + ")");
    if (uint64_t(s.offset) + s.size > total)
      throw fail(at + 8, where + ": section [" + hex(s.offset) + ", " + hex(uint64_t(s.offset) + s.size) +
                             ") runs past the end of the file (" + hex(total) + ")");
    table[i] = s;
  }
  for (const SectionEntry& s : table) {
    if (by_id[s.id])
      throw fail(kOffSections + s.table_index * kSectionEntrySize,
                 "section table entry " + std::to_string(s.table_index) + ": second '" + kSectionNames[s.id] +
                     "' section (the first is entry " + std::to_string(by_id[s.id]->table_index) + ")");
    by_id[s.id] = &s;
  }
  // Overlap: sort by offset and compare each non-empty section with the
  // furthest-reaching one before it (empty sections overlap nothing).
  std::vector<const SectionEntry*> sorted;
  for (const SectionEntry& s : table) sorted.push_back(&s);
  std::stable_sort(sorted.begin(), sorted.end(), [](auto* x, auto* y) { return x->offset < y->offset; });
  const SectionEntry* reach = nullptr;
  for (const SectionEntry* s : sorted) {
    if (s->size == 0) continue;
    auto end = [](const SectionEntry& x) { return uint64_t(x.offset) + x.size; };
    if (reach && s->offset < end(*reach))
      throw fail(s->offset, std::string("section '") + kSectionNames[s->id] + "' [" + hex(s->offset) + ", " + hex(end(*s)) +
                                ") overlaps section '" + kSectionNames[reach->id] + "' [" + hex(reach->offset) + ", " +
                                hex(end(*reach)) + ")");
    if (!reach || end(*s) > end(*reach)) reach = s;
  }
  for (uint32_t id : {uint32_t(kCode), uint32_t(kIl)})
    if (!by_id[id])
      throw fail(kOffSections, std::string("the section table has no '") + kSectionNames[id] + "' section (required)");

  auto bytes_of = [&](const SectionEntry& s) { return b.subspan(s.offset, s.size); };
  auto sfail = [&](const SectionEntry& s, const std::string& msg) -> ImageError {
    return ImageError(name + ": section '" + kSectionNames[s.id] + "' at offset " + hex(s.offset) + ": " + msg);
  };
  auto finish = [&](SectionReader& r, const SectionEntry& s) {
    r.finish();
    if (!r.error.empty()) throw sfail(s, r.error);
  };

  // ---- contents
  const SectionEntry& code_sec = *by_id[kCode];
  const SectionEntry& il_sec = *by_id[kIl];
  {
    auto c = bytes_of(code_sec);
    im.code.assign(c.begin(), c.end());
    auto i = bytes_of(il_sec);
    im.il.assign(i.begin(), i.end());
  }
  if (const SectionEntry* s = by_id[kEntry]) {
    SectionReader r{bytes_of(*s), s->offset};
    im.entry = r.u32("entry point");
    finish(r, *s);
  }
  if (const SectionEntry* s = by_id[kConfig]) {
    SectionReader r{bytes_of(*s), s->offset};
    IoConfig c;
    c.block_size = r.u32("block size");
    c.processor = r.u32("processor");
    c.period_us = r.u32("period");
    c.priority = r.u32("priority");
    c.resource = r.str("resource name");
    c.task = r.str("task name");
    c.program = r.str("program name");
    uint32_t n = r.u32("row count");
    if (r.error.empty() && n > (r.data.size() - r.pos) / kConfigRowSize)
      r.error = "row count " + std::to_string(n) + " does not fit in the section";
    for (uint32_t i = 0; i < n && r.error.empty(); i++) {
      ConfigRow row;
      row.area = Area(r.u8("row"));
      row.flags = r.u8("row");
      uint32_t reserved = uint32_t(r.u8("row")) | uint32_t(r.u8("row")) << 8;
      row.block = r.u32("row");
      row.writer = r.u32("row");
      row.period_us = r.u32("row");
      if (r.error.empty() && reserved != 0)
        r.error = "row " + std::to_string(i) + " at file offset " + hex(uint64_t(s->offset) + r.pos - kConfigRowSize) +
                  ": reserved field is " + hex(reserved) + ", not 0";
      c.rows.push_back(row);
    }
    finish(r, *s);
    im.config = std::move(c);
  }
  if (const SectionEntry* s = by_id[kLines]) {
    if (s->size % kLineEntrySize)
      throw sfail(*s, "size " + std::to_string(s->size) + " is not a multiple of the " + std::to_string(kLineEntrySize) +
                          "-byte line map entry");
    SectionReader r{bytes_of(*s), s->offset};
    im.lines.resize(s->size / kLineEntrySize);
    for (LineEntry& l : im.lines) {
      l.code_offset = r.u32("line entry");
      l.il_offset = r.u32("line entry");
      l.line = int32_t(r.u32("line entry"));
      l.rung = r.u32("line entry");
    }
    finish(r, *s);
  }
  if (const SectionEntry* s = by_id[kStrings]) {
    SectionReader r{bytes_of(*s), s->offset};
    im.source = r.str("source name");
    uint32_t n = r.u32("rung title count");
    // Each title takes at least its 4-byte length: n can never exceed what is left.
    if (r.error.empty() && n > (r.data.size() - r.pos) / 4)
      r.error = "rung title count " + std::to_string(n) + " does not fit in the section";
    for (uint32_t i = 0; i < n && r.error.empty(); i++) im.rung_titles.push_back(r.str("rung title"));
    finish(r, *s);
  }
  if (const SectionEntry* s = by_id[kAliases]) {
    SectionReader r{bytes_of(*s), s->offset};
    uint32_t n = r.u32("alias count");
    if (r.error.empty() && n > (r.data.size() - r.pos) / 9)
      r.error = "alias count " + std::to_string(n) + " does not fit in the section";
    for (uint32_t i = 0; i < n && r.error.empty(); i++) {
      size_t at = r.pos;
      uint8_t dev = r.u8("alias");
      uint32_t index = r.u32("alias");
      std::string nm = r.str("alias name");
      if (!r.error.empty()) break;
      std::string where = "alias " + std::to_string(i) + " at file offset " + hex(uint64_t(s->offset) + at) + ": ";
      if (dev > uint8_t(Dev::F)) throw sfail(*s, where + "unknown device kind " + std::to_string(dev));
      if (index >= device_count(Dev(dev)))
        throw sfail(*s, where + "'" + nm + "' names " + dev_name(Dev(dev)) + std::to_string(index) + ", outside " +
                            dev_name(Dev(dev)) + "0.." + dev_name(Dev(dev)) + std::to_string(device_count(Dev(dev)) - 1));
      if (nm.empty()) throw sfail(*s, where + "empty alias name");
      im.aliases.push_back(Alias{nm, DeviceRef{Dev(dev), index}});
    }
    finish(r, *s);
  }
  if (const SectionEntry* s = by_id[kRetentive]) {
    if (s->size % kRetentiveEntrySize)
      throw sfail(*s, "size " + std::to_string(s->size) + " is not a multiple of the " +
                          std::to_string(kRetentiveEntrySize) + "-byte range entry");
    SectionReader r{bytes_of(*s), s->offset};
    for (uint32_t i = 0; i < s->size / kRetentiveEntrySize; i++) {
      uint32_t area = r.u32("range"), first = r.u32("range"), count = r.u32("range");
      std::string where = "range " + std::to_string(i) + " at file offset " + hex(uint64_t(s->offset) + i * kRetentiveEntrySize) + ": ";
      if (area == 0 || area >= uint32_t(kAreaCount))
        throw sfail(*s, where + (area == 0 ? std::string("the Sys area cannot be retentive") : "unknown area " + std::to_string(area)));
      if (count == 0) throw sfail(*s, where + "empty range");
      uint32_t n = im.layout.count[area];
      if (uint64_t(first) + count > n)
        throw sfail(*s, where + area_name(Area(area)) + "[" + std::to_string(first) + ".." + std::to_string(uint64_t(first) + count - 1) +
                            "] outside the area (" + std::to_string(n) + " elements)");
      im.retentive.push_back(RetentiveRange{Area(area), first, count});
    }
    finish(r, *s);
  }

  // ---- meaning
  if (std::string why = validate_il(im.il, im.layout); !why.empty()) throw sfail(il_sec, "invalid IL: " + why);
  if (im.config)
    if (std::string why = check_io_config(*im.config, im.il); !why.empty()) throw sfail(*by_id[kConfig], why);
  std::vector<uint32_t> il_starts;
  for (uint32_t off = 0; off < im.il.size();) {
    il_starts.push_back(off);
    Instr in;
    off = decode_instr(im.il, off, in);
  }

  if (im.entry >= im.code.size()) {
    std::string msg = "entry point " + hex(im.entry) + " is outside the code (" + std::to_string(im.code.size()) + " bytes)";
    if (const SectionEntry* s = by_id[kEntry]) throw sfail(*s, msg);
    throw sfail(code_sec, msg + "; the image has no 'entry' section, so the entry is 0");
  }
  std::vector<uint32_t> code_starts;
  if (im.target == ImageTarget::X86_64) {
    if (std::string why = detail::check_x86(im.code, im.entry, im.layout, &code_starts); !why.empty())
      throw sfail(code_sec, why);
  } else {
    if (im.code.size() % 4)
      throw sfail(code_sec, "C40 code is 32-bit words, but the section has " + std::to_string(im.code.size()) + " bytes");
    if (im.entry % 4) throw sfail(by_id[kEntry] ? *by_id[kEntry] : code_sec, "C40 entry point " + hex(im.entry) + " is not word-aligned");
    if (std::string why = check_c40_code(im.code, im.entry, im.layout); !why.empty()) throw sfail(code_sec, why);
  }

  if (const SectionEntry* s = by_id[kLines]) {
    for (size_t i = 0; i < im.lines.size(); i++) {
      const LineEntry& l = im.lines[i];
      std::string where = "entry " + std::to_string(i) + " at file offset " + hex(uint64_t(s->offset) + i * kLineEntrySize) + ": ";
      if (l.code_offset > im.code.size())
        throw sfail(*s, where + "code offset " + hex(l.code_offset) + " outside the code (" + std::to_string(im.code.size()) + " bytes)");
      if (l.code_offset < im.code.size()) {
        bool boundary = im.target == ImageTarget::X86_64
                            ? std::binary_search(code_starts.begin(), code_starts.end(), l.code_offset)
                            : l.code_offset % 4 == 0;
        if (!boundary) throw sfail(*s, where + "code offset " + hex(l.code_offset) + " is not an instruction boundary");
      }
      if (!std::binary_search(il_starts.begin(), il_starts.end(), l.il_offset))
        throw sfail(*s, where + "IL offset " + std::to_string(l.il_offset) +
                            (l.il_offset >= im.il.size() ? " outside the IL (" + std::to_string(im.il.size()) + " bytes)"
                                                         : " is not an IL instruction boundary"));
      if (l.line < 0) throw sfail(*s, where + "negative source line " + std::to_string(l.line));
      if (l.rung >= im.rung_titles.size())
        throw sfail(*s, where + "rung " + std::to_string(l.rung) + " but the image has " +
                            std::to_string(im.rung_titles.size()) + " rungs (titles)");
    }
  }
  return im;
}

}  // namespace ldc
