// loader/image.cpp -- writing and reading the ldc binary image (docs/image-format.md).
//
// The reader trusts nothing: every length is checked against what is left
// before it is used, in 64-bit arithmetic, and every refusal names the file,
// the section and the offset.
#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <set>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

#include "loader/loader.h"

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

enum SectionId : uint32_t { kCode = 1, kIl, kLines, kStrings, kAliases, kRetentive, kEntry, kConfig, kRegions, kVars, kSectionIdEnd };
constexpr const char* kSectionNames[] = {"?", "code", "il", "lines", "strings", "aliases", "retentive", "entry", "config", "regions", "vars"};

constexpr uint32_t kLineEntrySize = 16;
constexpr uint8_t kAliasTyped = 0x80;  // in an alias's device kind: a type byte follows its name
constexpr uint32_t kRetentiveEntrySize = 12;
constexpr uint32_t kConfigRowSize = 16;

std::string hex(uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

// ---------------------------------------------------------------- writing

// v little-endian at p: one store on a little-endian machine
static uint8_t* put_le32(uint8_t* p, uint32_t v) {
  if constexpr (std::endian::native == std::endian::little) std::memcpy(p, &v, 4);
  else
    for (int i = 0; i < 4; i++) p[i] = uint8_t(v >> (8 * i));
  return p + 4;
}

// The bytes of an image in file order: kept whole (write_image), only
// counted (the layout pass of write_image_file), or handed to a file in
// pieces with their CRC-32 summed on the way (write_image_file).
struct Writer {
  enum class Mode : uint8_t { Keep, Count, Stream };
  static constexpr size_t kChunk = 64 << 10;
  Mode mode = Mode::Keep;
  std::vector<uint8_t> out;    // Keep: every byte; Stream: those not yet written
  size_t done = 0;             // Count, Stream: the bytes before `out`
  uint32_t crc = 0;            // Stream: the CRC-32 of those
  std::FILE* file = nullptr;   // Stream

  size_t size() const { return done + out.size(); }
  void u8(uint8_t v) {
    if (mode == Mode::Count) done++;
    else out.push_back(v);
  }
  void u16(uint16_t v) { u8(uint8_t(v)); u8(uint8_t(v >> 8)); }
  void u32(uint32_t v) {  // little-endian, appended at once
    if (mode == Mode::Count) {
      done += 4;
      return;
    }
    uint8_t b[4];
    put_le32(b, v);
    out.insert(out.end(), b, b + 4);
    if (mode == Mode::Stream && out.size() >= kChunk) flush();
  }
  void bytes(std::span<const uint8_t> b) {
    if (mode == Mode::Count) {
      done += b.size();
    } else if (mode == Mode::Stream && b.size() >= kChunk) {  // large: written from where it is, not copied
      flush();
      put(b);
    } else {
      out.insert(out.end(), b.begin(), b.end());
      if (mode == Mode::Stream && out.size() >= kChunk) flush();
    }
  }
  void str(const std::string& s) {
    if (s.size() > kImageMaxSize) throw ImageError("image: string too long for the image format");
    u32(uint32_t(s.size()));
    bytes({reinterpret_cast<const uint8_t*>(s.data()), s.size()});
  }
  void align4() { while (size() % 4) u8(0); }
  void put32_at(size_t at, uint32_t v) { for (int i = 0; i < 4; i++) out[at + i] = uint8_t(v >> (8 * i)); }
  void flush() {
    put(out);
    out.clear();
  }
  void put(std::span<const uint8_t> b) {  // a failed write: the file's error indicator (ferror)
    crc = crc32(b, crc);
    if (!b.empty()) std::fwrite(b.data(), 1, b.size(), file);
    done += b.size();
  }
};

uint32_t count32(size_t n, const char* what, size_t limit = kImageMaxSize) {
  if (n > limit)
    throw ImageError(std::string("image: too many ") + what + " for the image format (" + std::to_string(n) + ", at most " +
                     std::to_string(limit) + ")");
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

#if defined(__x86_64__) && defined(__GNUC__)
#define LDC_CRC32_CLMUL 1
// The CRC register (not inverted) after whole 16-byte blocks, n >= 64 and a
// multiple of 16, by carry-less multiplication: the blocks are folded into
// four 128-bit lanes, the lanes into one, and its 128 bits reduced to 32
// (Gopal, Ozturk et al., "Fast CRC Computation for Generic Polynomials Using
// PCLMULQDQ Instruction", Intel 2009, with its constants for 0xEDB88320,
// bit-reflected: k1 k2 fold 512 bits, k3 k4 128, k5 64, and the polynomial
// and its Barrett constant).  An eighth of the table loop's time (0.27 ->
// 0.033 ms a MiB on an Intel Xeon).
#define LDC_CLMUL __attribute__((target("pclmul,sse4.1")))
LDC_CLMUL static __m128i block16(const uint8_t* q) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(q)); }
// x's halves times k's, plus the next block
LDC_CLMUL static __m128i fold16(__m128i x, __m128i k, __m128i next) {
  return _mm_xor_si128(_mm_xor_si128(_mm_clmulepi64_si128(x, k, 0x00), _mm_clmulepi64_si128(x, k, 0x11)), next);
}
LDC_CLMUL static uint32_t crc32_folded(const uint8_t* p, size_t n, uint32_t crc) {
  const __m128i k1k2 = _mm_set_epi64x(0x01c6e41596, 0x0154442bd4);
  const __m128i k3k4 = _mm_set_epi64x(0x00ccaa009e, 0x01751997d0);
  const __m128i k5 = _mm_set_epi64x(0, 0x0163cd6124);
  const __m128i poly = _mm_set_epi64x(0x01f7011641, 0x01db710641);
  const __m128i low32 = _mm_setr_epi32(~0, 0, ~0, 0);
  __m128i lane[4] = {_mm_xor_si128(block16(p), _mm_cvtsi32_si128(int(crc))), block16(p + 16), block16(p + 32),
                     block16(p + 48)};
  for (p += 64, n -= 64; n >= 64; p += 64, n -= 64)
    for (int i = 0; i < 4; i++) lane[i] = fold16(lane[i], k1k2, block16(p + 16 * i));
  __m128i r = fold16(fold16(fold16(lane[0], k3k4, lane[1]), k3k4, lane[2]), k3k4, lane[3]);
  for (; n >= 16; p += 16, n -= 16) r = fold16(r, k3k4, block16(p));
  r = _mm_xor_si128(_mm_srli_si128(r, 8), _mm_clmulepi64_si128(r, k3k4, 0x10));                 // 128 -> 96 bits
  r = _mm_xor_si128(_mm_clmulepi64_si128(_mm_and_si128(r, low32), k5, 0x00), _mm_srli_si128(r, 4));  // -> 64
  __m128i q = _mm_clmulepi64_si128(_mm_and_si128(r, low32), poly, 0x10);                         // Barrett: -> 32
  q = _mm_clmulepi64_si128(_mm_and_si128(q, low32), poly, 0x00);
  return uint32_t(_mm_extract_epi32(_mm_xor_si128(r, q), 1));
}

static bool have_clmul() {
  static const bool yes = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("pclmul") && __builtin_cpu_supports("sse4.1");
  }();
  return yes;
}
#endif

// CRC-32 (IEEE 802.3, reflected 0xEDB88320): where the machine has carry-less
// multiplication, whole 16-byte blocks by crc32_folded; else (and for the
// last bytes) sixteen bytes per step with sixteen tables (slicing-by-16):
// table k maps a byte to its CRC shifted through k more zero bytes.  Images
// of several MiB are summed on every write and read.
uint32_t crc32(std::span<const uint8_t> bytes, uint32_t crc) {
  static const auto tables = [] {
    std::array<std::array<uint32_t, 256>, 16> t{};
    for (uint32_t i = 0; i < 256; i++) {
      uint32_t c = i;
      for (int k = 0; k < 8; k++) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; i++)
      for (size_t k = 1; k < t.size(); k++) t[k][i] = t[0][t[k - 1][i] & 0xFF] ^ (t[k - 1][i] >> 8);
    return t;
  }();
  auto le32 = [](const uint8_t* q) {
    return uint32_t(q[0]) | uint32_t(q[1]) << 8 | uint32_t(q[2]) << 16 | uint32_t(q[3]) << 24;
  };
  // byte j of 16 goes through table 15 - j: the CRC's four bytes are xored into the first four
  auto word = [&](uint32_t w, size_t k) {
    return tables[k][w & 0xFF] ^ tables[k - 1][(w >> 8) & 0xFF] ^ tables[k - 2][(w >> 16) & 0xFF] ^
           tables[k - 3][w >> 24];
  };
  crc = ~crc;
  const uint8_t* p = bytes.data();
  size_t n = bytes.size();
#ifdef LDC_CRC32_CLMUL
  if (n >= 64 && have_clmul()) {
    const size_t whole = n & ~size_t(15);
    crc = crc32_folded(p, whole, crc);
    p += whole, n -= whole;
  }
#endif
  for (; n >= 16; p += 16, n -= 16)
    crc = word(crc ^ le32(p), 15) ^ word(le32(p + 4), 11) ^ word(le32(p + 8), 7) ^ word(le32(p + 12), 3);
  for (; n; p++, n--) crc = tables[0][(crc ^ *p) & 0xFF] ^ (crc >> 8);
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

// What write_image will write, give or take the alignment padding: reserved
// at once, so that a large image is not copied while it grows.
static size_t image_size_hint(const Image& im) {
  size_t n = kOffSections + 8 * kSectionEntrySize + 8 * 3 + im.code.size() + im.il.size() + 16 * im.lines.size() +
             4 + im.source.size() + 4 + 12 * im.retentive.size() + 4 + 4 + 64;
  for (const std::string& t : im.rung_titles) n += 4 + t.size();
  for (const Alias& a : im.aliases) n += 10 + a.name.size();
  for (const VarPlace& v : im.vars) n += 8 + 18 + v.name.size() + v.type.size();
  if (im.config) n += 64 + 3 * 256 + 16 * im.config->rows.size();
  if (im.regions) n += 16 + 12 * im.regions->first.size() + im.regions->code.size();
  return n;
}

// Sections 1..7 always; 'config' only when the image has a configuration
// table, 'regions' only when it has a region table and 'vars' only when it
// lists variables, so images without them are byte for byte what they
// always were.
static std::vector<uint32_t> section_ids(const Image& im) {
  std::vector<uint32_t> ids;
  for (uint32_t id = 1; id < kConfig; id++) ids.push_back(id);
  if (im.config) ids.push_back(kConfig);
  if (im.regions) ids.push_back(kRegions);
  if (!im.vars.empty()) ids.push_back(kVars);
  return ids;
}
static uint32_t section_count(const Image& im) { return uint32_t(section_ids(im).size()); }

// The header and the section table: each section's offset and size from
// `table` (two per section), or 0 to be patched (write_image); the checksum 0.
static void put_header(Writer& w, const Image& im, std::span<const uint32_t> table, uint32_t total) {
  const uint32_t nsections = section_count(im);
  w.bytes(kMagic);
  w.u16(kVersion);
  w.u8(uint8_t(im.target));
  w.u8(0);  // flags
  w.u32(kOffSections + nsections * kSectionEntrySize);
  w.u32(total);
  w.u32(nsections);
  w.u32(0);  // checksum
  w.u32(0);  // reserved
  w.u32(kAreaCount);
  for (uint32_t c : im.layout.count) w.u32(c);
  for (uint32_t o : im.layout.offset) w.u32(o);
  w.u32(im.layout.size);
  const std::vector<uint32_t> ids = section_ids(im);
  for (uint32_t i = 1; i <= nsections; i++)
    w.u32(ids[i - 1]), w.u32(table.empty() ? 0 : table[2 * (i - 1)]), w.u32(table.empty() ? 0 : table[2 * i - 1]);
}

// The line map, packed a batch of entries at a time: one entry per IL
// instruction, four u32 each, is the most fields of any section.  The
// layout pass (Mode::Count) needs its size only.
static void put_lines(Writer& w, std::span<const LineEntry> lines) {
  count32(lines.size(), "line map entries");
  if (w.mode == Writer::Mode::Count) {
    w.done += lines.size() * kLineEntrySize;
    return;
  }
  constexpr size_t kBatch = 256;
  uint8_t buf[kBatch * kLineEntrySize];
  for (size_t at = 0; at < lines.size(); at += kBatch) {
    const size_t n = std::min(kBatch, lines.size() - at);
    uint8_t* p = buf;
    for (const LineEntry& e : lines.subspan(at, n)) {
      p = put_le32(p, e.code_offset), p = put_le32(p, e.il_offset);
      p = put_le32(p, uint32_t(e.line)), p = put_le32(p, e.rung);
    }
    w.bytes({buf, n * kLineEntrySize});
  }
}

static void put_section(Writer& w, const Image& im, uint32_t id) {
  switch (SectionId(id)) {
    case kCode: w.bytes(im.code); break;
    case kIl: w.bytes(im.il); break;
    case kLines: put_lines(w, im.lines); break;
    case kStrings:
      w.str(im.source);
      w.u32(count32(im.rung_titles.size(), "rung titles", kImageMaxRungTitles));
      for (const std::string& t : im.rung_titles) w.str(t);
      break;
    case kAliases:
      w.u32(count32(im.aliases.size(), "aliases", kImageMaxAliases));
      for (const Alias& a : im.aliases) {  // a typed alias: bit 7 of the kind, and its type after the name
        w.u8(uint8_t(a.dev.dev) | (a.ty == Ty::None ? 0 : kAliasTyped)), w.u32(a.dev.index), w.str(a.name);
        if (a.ty != Ty::None) w.u8(uint8_t(a.ty));
      }
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
    case kRegions: {
      const RegionTable& t = *im.regions;
      w.u32(t.max_rungs);
      w.u32(count32(t.first.size(), "regions"));
      for (size_t i = 0; i < t.first.size(); i++) w.u32(t.first[i]), w.u32(t.start[i]), w.u32(t.size[i]);
      w.u32(count32(t.code.size(), "region code bytes"));
      w.bytes(t.code);
      break;
    }
    case kVars:
      w.u32(kImageVarsVersion);
      w.u32(count32(im.vars.size(), "variables", kImageMaxVars));
      for (const VarPlace& v : im.vars) {
        w.str(v.name), w.str(v.type);
        w.u8(uint8_t(v.bits)), w.u32(v.bit_first), w.u32(v.bit_count);
        w.u8(uint8_t(v.cells)), w.u32(v.cell_first), w.u32(v.cell_count);
      }
      break;
    case kSectionIdEnd: break;
  }
}

static void check_size(const Writer& w) {
  if (w.size() > kImageMaxSize) throw ImageError("image: larger than the format allows (" + hex(kImageMaxSize) + " bytes)");
}

// The sections after the header, each aligned to 4 bytes, and the padding
// after the last; returns each section's offset and size (two per section).
static std::vector<uint32_t> put_sections(Writer& w, const Image& im) {
  std::vector<uint32_t> table;
  for (uint32_t id : section_ids(im)) {
    w.align4();
    size_t start = w.size();
    put_section(w, im, id);
    check_size(w);
    table.push_back(uint32_t(start));
    table.push_back(uint32_t(w.size() - start));
  }
  w.align4();
  check_size(w);
  return table;
}

std::vector<uint8_t> write_image(const Image& im) {
  Writer w;
  w.out.reserve(image_size_hint(im));
  put_header(w, im, {}, 0);
  std::vector<uint32_t> table = put_sections(w, im);
  for (uint32_t i = 0; i < section_count(im); i++) {
    size_t at = kOffSections + i * kSectionEntrySize;
    w.put32_at(at + 4, table[2 * i]);
    w.put32_at(at + 8, table[2 * i + 1]);
  }
  w.put32_at(kOffTotalSize, uint32_t(w.out.size()));
  w.put32_at(kOffChecksum, image_checksum(w.out));
  return std::move(w.out);
}

size_t write_image_file(const Image& im, std::FILE* file) {
  Writer count{Writer::Mode::Count};  // first the layout: the header names every section's place
  put_header(count, im, {}, 0);
  std::vector<uint32_t> table = put_sections(count, im);
  Writer w{Writer::Mode::Stream};
  w.file = file;
  w.out.reserve(Writer::kChunk + 64);
  put_header(w, im, table, uint32_t(count.size()));
  put_sections(w, im);
  w.flush();
  uint8_t sum[4];
  for (int i = 0; i < 4; i++) sum[i] = uint8_t(w.crc >> (8 * i));  // the checksum field was written as 0
  if (std::fseek(file, kOffChecksum, SEEK_SET) != 0 || std::fwrite(sum, 1, 4, file) != 4 || std::fseek(file, 0, SEEK_END) != 0)
    return 0;
  return w.done;
}

// "1 = x86-64, 2 = C40": the known target bytes, for the header's message.
static std::string known_kinds() {
  std::string s;
  for (const ImageKind& k : image_kinds()) s += (s.empty() ? "" : ", ") + std::to_string(int(k.id)) + " = " + k.name;
  return s;
}

// ---------------------------------------------------------------- read_image

std::optional<uint8_t> peek_image_target(std::span<const uint8_t> head) {
  if (head.size() <= kOffTarget || !std::equal(kMagic, kMagic + 6, head.begin())) return std::nullopt;
  return head[kOffTarget];
}

namespace {

// read_image in named steps: the fixed header, the layout, the section table,
// each section's contents, and last their meaning (IL, code, line map).
class ImageReader {
 public:
  ImageReader(std::span<const uint8_t> b, const std::string& name) : b_(b), name_(name) {}

  Image read() {
    header();
    layout();
    section_table();
    section_overlaps();
    contents();
    check_il_and_config();
    check_code();
    check_lines();
    return std::move(im_);
  }

 private:
  std::span<const uint8_t> b_;
  const std::string& name_;
  Image im_;
  uint32_t total_ = 0, nsec_ = 0, header_size_ = 0;
  std::vector<SectionEntry> table_;
  const SectionEntry* by_id_[kSectionIdEnd] = {};
  const ImageKind* kind_ = nullptr;
  OffsetBits code_starts_;  // instruction starts, for the line map

  ImageError fail(uint64_t off, const std::string& msg) const {
    return ImageError(name_ + ": offset " + hex(off) + ": " + msg);
  }
  ImageError sfail(const SectionEntry& s, const std::string& msg) const {
    return ImageError(name_ + ": section '" + kSectionNames[s.id] + "' at offset " + hex(s.offset) + ": " + msg);
  }
  std::span<const uint8_t> bytes_of(const SectionEntry& s) const { return b_.subspan(s.offset, s.size); }
  SectionReader reader(const SectionEntry& s) const { return SectionReader{bytes_of(s), s.offset}; }
  void finish(SectionReader& r, const SectionEntry& s) const {
    r.finish();
    if (!r.error.empty()) throw sfail(s, r.error);
  }

  void header() {
    if (b_.size() < kFixedHeaderSize)
      throw ImageError(name_ + ": truncated header: " + std::to_string(b_.size()) + " bytes, an image header has " +
                       std::to_string(kFixedHeaderSize));
    if (!std::equal(std::begin(kMagic), std::end(kMagic), b_.begin()))
      throw fail(kOffMagic, "not an ldc image (bad magic; expected \"LDCIMG\\0\\1\")");
    if (uint16_t v = get16(b_, kOffVersion); v != kVersion)
      throw fail(kOffVersion, "unsupported format version " + std::to_string(v) + " (this loader reads version " +
                                  std::to_string(kVersion) + ")");
    uint8_t target = b_[kOffTarget];
    kind_ = find_image_kind(target);
    if (!kind_) throw fail(kOffTarget, "unknown target " + std::to_string(target) + " (" + known_kinds() + ")");
    if (b_[kOffFlags] != 0)
      throw fail(kOffFlags, "unknown flags " + hex(b_[kOffFlags]) + " (version " + std::to_string(kVersion) + " defines none)");
    sizes();
    if (uint32_t sum = get32(b_, kOffChecksum), want = image_checksum(b_); sum != want)
      throw fail(kOffChecksum, "bad checksum " + hex(sum) + " (the file's CRC-32 is " + hex(want) + ")");
    if (uint32_t r = get32(b_, kOffReserved); r != 0) throw fail(kOffReserved, "reserved field is " + hex(r) + ", not 0");
    im_.target = ImageTarget(target);
    im_.retentive.clear();
  }

  // The total size, the section count and the header size, each against the file.
  void sizes() {
    total_ = get32(b_, kOffTotalSize);
    if (total_ > kImageMaxSize) throw fail(kOffTotalSize, "total size " + hex(total_) + " exceeds the limit " + hex(kImageMaxSize));
    if (b_.size() < total_)
      throw ImageError(name_ + ": truncated file: the header says " + std::to_string(total_) + " bytes, the file has " +
                       std::to_string(b_.size()));
    if (b_.size() > total_)
      throw fail(total_, std::to_string(b_.size() - total_) + " trailing bytes after the image (header says " +
                             std::to_string(total_) + " bytes)");
    nsec_ = get32(b_, kOffSectionCount);
    if (nsec_ > kMaxSections)
      throw fail(kOffSectionCount, "section count " + std::to_string(nsec_) + " exceeds the limit " + std::to_string(kMaxSections));
    header_size_ = get32(b_, kOffHeaderSize);
    uint32_t want_header = kOffSections + nsec_ * kSectionEntrySize;
    if (header_size_ != want_header)
      throw fail(kOffHeaderSize, "header size " + hex(header_size_) + " does not match " + std::to_string(nsec_) +
                                     " sections (expected " + hex(want_header) + ")");
    if (header_size_ > total_)
      throw ImageError(name_ + ": truncated file: the header and section table need " + std::to_string(header_size_) +
                       " bytes, the image has " + std::to_string(total_));
  }

  void layout() {
    Layout& l = im_.layout;
    if (uint32_t n = get32(b_, kOffLayout); n != uint32_t(kAreaCount))
      throw fail(kOffLayout, "layout has " + std::to_string(n) + " areas, version " + std::to_string(kVersion) + " has " +
                                 std::to_string(kAreaCount));
    const uint32_t off_count = kOffLayout + 4, off_offset = off_count + 4 * kAreaCount, off_size = off_offset + 4 * kAreaCount;
    for (int i = 0; i < kAreaCount; i++) l.count[i] = get32(b_, off_count + 4 * i);
    for (int i = 0; i < kAreaCount; i++) l.offset[i] = get32(b_, off_offset + 4 * i);
    l.size = get32(b_, off_size);
    const int e = int(Area::E);
    if (l.count[e] > kImageMaxEdgeSlots)
      throw fail(off_count + 4 * e, "layout: " + std::to_string(l.count[e]) + " edge slots exceed the limit " +
                                        std::to_string(kImageMaxEdgeSlots));
    Layout want = Layout::standard(l.count[e]);
    for (int i = 0; i < kAreaCount; i++)
      if (l.count[i] != want.count[i])
        throw fail(off_count + 4 * i, std::string("layout mismatch: area ") + area_name(Area(i)) + " has " +
                                          std::to_string(l.count[i]) + " elements, the standard layout has " +
                                          std::to_string(want.count[i]));
    for (int i = 0; i < kAreaCount; i++)
      if (l.offset[i] != want.offset[i])
        throw fail(off_offset + 4 * i, std::string("layout mismatch: area ") + area_name(Area(i)) + " at " + hex(l.offset[i]) +
                                           ", the standard layout puts it at " + hex(want.offset[i]));
    if (l.size != want.size)
      throw fail(off_size, "layout mismatch: memory image size " + hex(l.size) + ", the standard layout has " + hex(want.size));
  }

  void section_table() {
    table_.resize(nsec_);
    for (uint32_t i = 0; i < nsec_; i++) {
      uint32_t at = kOffSections + i * kSectionEntrySize;
      SectionEntry s{get32(b_, at), get32(b_, at + 4), get32(b_, at + 8), i};
      std::string where = "section table entry " + std::to_string(i);
      if (s.id == 0 || s.id >= kSectionIdEnd)
        throw fail(at, where + ": unknown section id " + std::to_string(s.id) + " (version " + std::to_string(kVersion) +
                           " has ids 1.." + std::to_string(kSectionIdEnd - 1) + ")");
      where += " ('" + std::string(kSectionNames[s.id]) + "')";
      if (s.offset % 4) throw fail(at + 4, where + ": section offset " + hex(s.offset) + " is not 4-byte aligned");
      if (s.offset < header_size_)
        throw fail(at + 4, where + ": section offset " + hex(s.offset) + " lies inside the header (which ends at " +
                               hex(header_size_) + ")");
      if (uint64_t(s.offset) + s.size > total_)
        throw fail(at + 8, where + ": section [" + hex(s.offset) + ", " + hex(uint64_t(s.offset) + s.size) +
                               ") runs past the end of the file (" + hex(total_) + ")");
      table_[i] = s;
    }
    for (const SectionEntry& s : table_) {
      if (by_id_[s.id])
        throw fail(kOffSections + s.table_index * kSectionEntrySize,
                   "section table entry " + std::to_string(s.table_index) + ": second '" + kSectionNames[s.id] +
                       "' section (the first is entry " + std::to_string(by_id_[s.id]->table_index) + ")");
      by_id_[s.id] = &s;
    }
  }

  // Sorts by offset and compares each non-empty section with the
  // furthest-reaching one before it (empty sections overlap nothing).
  void section_overlaps() {
    std::vector<const SectionEntry*> sorted;
    for (const SectionEntry& s : table_) sorted.push_back(&s);
    std::stable_sort(sorted.begin(), sorted.end(), [](auto* x, auto* y) { return x->offset < y->offset; });
    auto end = [](const SectionEntry& x) { return uint64_t(x.offset) + x.size; };
    const SectionEntry* reach = nullptr;
    for (const SectionEntry* s : sorted) {
      if (s->size == 0) continue;
      if (reach && s->offset < end(*reach))
        throw fail(s->offset, std::string("section '") + kSectionNames[s->id] + "' [" + hex(s->offset) + ", " + hex(end(*s)) +
                                  ") overlaps section '" + kSectionNames[reach->id] + "' [" + hex(reach->offset) + ", " +
                                  hex(end(*reach)) + ")");
      if (!reach || end(*s) > end(*reach)) reach = s;
    }
    for (uint32_t id : {uint32_t(kCode), uint32_t(kIl)})
      if (!by_id_[id])
        throw fail(kOffSections, std::string("the section table has no '") + kSectionNames[id] + "' section (required)");
  }

  void contents() {
    auto c = bytes_of(*by_id_[kCode]);
    im_.code.assign(c.begin(), c.end());
    auto i = bytes_of(*by_id_[kIl]);
    im_.il.assign(i.begin(), i.end());
    if (const SectionEntry* s = by_id_[kEntry]) entry(*s);
    if (const SectionEntry* s = by_id_[kConfig]) config(*s);
    if (const SectionEntry* s = by_id_[kRegions]) regions(*s);
    if (const SectionEntry* s = by_id_[kLines]) lines(*s);
    if (const SectionEntry* s = by_id_[kStrings]) strings(*s);
    if (const SectionEntry* s = by_id_[kAliases]) aliases(*s);
    if (const SectionEntry* s = by_id_[kRetentive]) retentive(*s);
    if (const SectionEntry* s = by_id_[kVars]) vars(*s);
  }

  // The variables as wholes (docs/image-format.md, `vars`): its own version
  // first, then the entries; every row inside its area, names unique.
  void vars(const SectionEntry& s) {
    SectionReader r = reader(s);
    uint32_t version = r.u32("version");
    if (r.error.empty() && version != kImageVarsVersion)
      throw sfail(s, "version " + std::to_string(version) + ", this loader reads version " + std::to_string(kImageVarsVersion));
    uint32_t n = r.u32("variable count");
    // Each entry takes at least its 26 fixed bytes: n can never exceed what is left.
    if (r.error.empty() && n > (r.data.size() - r.pos) / 26)
      r.error = "variable count " + std::to_string(n) + " does not fit in the section";
    // An entry held costs two strings (80 bytes with its fields) for its 26 in the file: the limit bounds that.
    if (r.error.empty() && n > kImageMaxVars)
      r.error = "variable count " + std::to_string(n) + " exceeds the limit " + std::to_string(kImageMaxVars);
    std::set<std::string> names;
    for (uint32_t i = 0; i < n && r.error.empty(); i++) {
      size_t at = r.pos;
      VarPlace v;
      v.name = r.str("variable name");
      v.type = r.str("variable type");
      uint8_t bits = r.u8("variable");
      v.bit_first = r.u32("variable"), v.bit_count = r.u32("variable");
      uint8_t cells = r.u8("variable");
      v.cell_first = r.u32("variable"), v.cell_count = r.u32("variable");
      if (!r.error.empty()) break;
      std::string where = "variable " + std::to_string(i) + " at file offset " + hex(uint64_t(s.offset) + at) + ": ";
      if (v.name.empty()) throw sfail(s, where + "empty name");
      if (!names.insert(v.name).second) throw sfail(s, where + "second variable named '" + v.name + "'");
      if (v.type.empty()) throw sfail(s, where + "'" + v.name + "' has an empty type");
      auto row = [&](uint8_t area, uint32_t first, uint32_t count, bool bit, const char* what) {
        if (area == uint8_t(Area::Count)) {
          if (first || count) throw sfail(s, where + "'" + v.name + "': no " + what + " area but a row " + std::to_string(first) + "+" + std::to_string(count));
          return Area::Count;
        }
        bool ok = bit ? area == uint8_t(Area::M) || area == uint8_t(Area::K) : area == uint8_t(Area::D) || area == uint8_t(Area::F);
        if (!ok) throw sfail(s, where + "'" + v.name + "': area " + std::to_string(area) + " cannot hold its " + what + " (" + (bit ? "M or K" : "D or F") + ")");
        if (count == 0 || uint64_t(first) + count > im_.layout.count[area])
          throw sfail(s, where + "'" + v.name + "': " + what + " " + area_name(Area(area)) + std::to_string(first) + "+" +
                             std::to_string(count) + " outside " + area_name(Area(area)) + "0.." + area_name(Area(area)) +
                             std::to_string(im_.layout.count[area] - 1));
        return Area(area);
      };
      v.bits = row(bits, v.bit_first, v.bit_count, true, "bits");
      v.cells = row(cells, v.cell_first, v.cell_count, false, "cells");
      if (v.bits == Area::Count && v.cells == Area::Count) throw sfail(s, where + "'" + v.name + "' has no place");
      im_.vars.push_back(std::move(v));
    }
    finish(r, s);
  }

  void entry(const SectionEntry& s) {
    SectionReader r = reader(s);
    im_.entry = r.u32("entry point");
    finish(r, s);
  }

  void config(const SectionEntry& s) {
    SectionReader r = reader(s);
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
        r.error = "row " + std::to_string(i) + " at file offset " + hex(uint64_t(s.offset) + r.pos - kConfigRowSize) +
                  ": reserved field is " + hex(reserved) + ", not 0";
      c.rows.push_back(row);
    }
    finish(r, s);
    im_.config = std::move(c);
  }

  void regions(const SectionEntry& s) {
    SectionReader r = reader(s);
    RegionTable t;
    t.max_rungs = r.u32("region size");
    const uint32_t n = r.u32("region count");
    if (r.error.empty() && n > (r.data.size() - r.pos) / 12)
      r.error = "region count " + std::to_string(n) + " does not fit in the section";
    for (uint32_t i = 0; i < n && r.error.empty(); i++) {
      t.first.push_back(r.u32("region"));
      t.start.push_back(r.u32("region"));
      t.size.push_back(r.u32("region"));
    }
    const uint32_t bytes = r.u32("region code size");
    if (r.error.empty() && bytes > r.data.size() - r.pos)
      r.error = "region code of " + std::to_string(bytes) + " bytes does not fit in the section";
    if (r.error.empty()) t.code.assign(r.data.begin() + r.pos, r.data.begin() + r.pos + bytes), r.pos += bytes;
    finish(r, s);
    im_.regions = std::move(t);
  }

  void lines(const SectionEntry& s) {
    if (s.size % kLineEntrySize)
      throw sfail(s, "size " + std::to_string(s.size) + " is not a multiple of the " + std::to_string(kLineEntrySize) +
                         "-byte line map entry");
    SectionReader r = reader(s);
    im_.lines.resize(s.size / kLineEntrySize);
    for (LineEntry& l : im_.lines) {
      l.code_offset = r.u32("line entry");
      l.il_offset = r.u32("line entry");
      l.line = int32_t(r.u32("line entry"));
      l.rung = r.u32("line entry");
    }
    finish(r, s);
  }

  void strings(const SectionEntry& s) {
    SectionReader r = reader(s);
    im_.source = r.str("source name");
    uint32_t n = r.u32("rung title count");
    // Each title takes at least its 4-byte length: n can never exceed what is left.
    if (r.error.empty() && n > (r.data.size() - r.pos) / 4)
      r.error = "rung title count " + std::to_string(n) + " does not fit in the section";
    // A title held costs a string (32 bytes) for the 4 of an empty one in the file: the count's limit bounds that.
    if (r.error.empty() && n > kImageMaxRungTitles)
      r.error = "rung title count " + std::to_string(n) + " exceeds the limit " + std::to_string(kImageMaxRungTitles);
    for (uint32_t i = 0; i < n && r.error.empty(); i++) im_.rung_titles.push_back(r.str("rung title"));
    finish(r, s);
  }

  void aliases(const SectionEntry& s) {
    SectionReader r = reader(s);
    uint32_t n = r.u32("alias count");
    if (r.error.empty() && n > (r.data.size() - r.pos) / 9)
      r.error = "alias count " + std::to_string(n) + " does not fit in the section";
    // An alias held costs a string and a device (40 bytes) for its 10 in the file: the count's limit bounds that.
    if (r.error.empty() && n > kImageMaxAliases)
      r.error = "alias count " + std::to_string(n) + " exceeds the limit " + std::to_string(kImageMaxAliases);
    for (uint32_t i = 0; i < n && r.error.empty(); i++) {
      size_t at = r.pos;
      uint8_t kind = r.u8("alias"), dev = kind & uint8_t(~kAliasTyped);
      uint32_t index = r.u32("alias");
      std::string nm = r.str("alias name");
      uint8_t ty = kind & kAliasTyped ? r.u8("alias type") : uint8_t(Ty::None);
      if (!r.error.empty()) break;
      std::string where = "alias " + std::to_string(i) + " at file offset " + hex(uint64_t(s.offset) + at) + ": ";
      if (dev > uint8_t(Dev::F)) throw sfail(s, where + "unknown device kind " + std::to_string(kind));
      if (index >= device_count(Dev(dev)))
        throw sfail(s, where + "'" + nm + "' names " + dev_name(Dev(dev)) + std::to_string(index) + ", outside " +
                           dev_name(Dev(dev)) + "0.." + dev_name(Dev(dev)) + std::to_string(device_count(Dev(dev)) - 1));
      if (nm.empty()) throw sfail(s, where + "empty alias name");
      if (ty >= uint8_t(Ty::None) && (kind & kAliasTyped)) throw sfail(s, where + "'" + nm + "': unknown type " + std::to_string(ty));
      Alias a{nm, DeviceRef{Dev(dev), index}, Ty(ty)};
      if (std::string why = alias_type_problem(a); !why.empty()) throw sfail(s, where + why);
      im_.aliases.push_back(std::move(a));
    }
    finish(r, s);
  }

  void retentive(const SectionEntry& s) {
    if (s.size % kRetentiveEntrySize)
      throw sfail(s, "size " + std::to_string(s.size) + " is not a multiple of the " + std::to_string(kRetentiveEntrySize) +
                         "-byte range entry");
    SectionReader r = reader(s);
    for (uint32_t i = 0; i < s.size / kRetentiveEntrySize; i++) {
      uint32_t area = r.u32("range"), first = r.u32("range"), count = r.u32("range");
      std::string where = "range " + std::to_string(i) + " at file offset " + hex(uint64_t(s.offset) + i * kRetentiveEntrySize) + ": ";
      if (area == 0 || area >= uint32_t(kAreaCount))
        throw sfail(s, where + (area == 0 ? std::string("the Sys area cannot be retentive") : "unknown area " + std::to_string(area)));
      if (count == 0) throw sfail(s, where + "empty range");
      uint32_t n = im_.layout.count[area];
      if (uint64_t(first) + count > n)
        throw sfail(s, where + area_name(Area(area)) + "[" + std::to_string(first) + ".." + std::to_string(uint64_t(first) + count - 1) +
                           "] outside the area (" + std::to_string(n) + " elements)");
      im_.retentive.push_back(RetentiveRange{Area(area), first, count});
    }
    finish(r, s);
  }

  void check_il_and_config() {
    if (std::string why = validate_il(im_.il, im_.layout); !why.empty()) throw sfail(*by_id_[kIl], "invalid IL: " + why);
    if (im_.config)
      if (std::string why = check_io_config(*im_.config, im_.il); !why.empty()) throw sfail(*by_id_[kConfig], why);
  }

  // The entry point, then the target's code check (docs/image-format.md, "Threat model").
  void check_code() {
    const SectionEntry& code = *by_id_[kCode];
    const SectionEntry* entry = by_id_[kEntry];
    if (im_.entry >= im_.code.size()) {
      std::string msg = "entry point " + hex(im_.entry) + " is outside the code (" + std::to_string(im_.code.size()) + " bytes)";
      if (entry) throw sfail(*entry, msg);
      throw sfail(code, msg + "; the image has no 'entry' section, so the entry is 0");
    }
    if (const uint32_t unit = kind_->unit; unit > 1) {
      std::string words = std::string(kind_->name) + " code is " + std::to_string(8 * unit) + "-bit words";
      if (im_.code.size() % unit)
        throw sfail(code, words + ", but the section has " + std::to_string(im_.code.size()) + " bytes");
      if (im_.entry % unit)
        throw sfail(entry ? *entry : code, std::string(kind_->name) + " entry point " + hex(im_.entry) + " is not word-aligned");
    }
    if (std::string why = kind_->check(im_.code, im_.entry, im_.layout, &code_starts_); !why.empty()) throw sfail(code, why);
    if (im_.regions) check_regions(*by_id_[kRegions]);
  }

  // The region table (docs/change-driven.md, docs/image-format.md): x86-64
  // only, with the line map (the rungs), regions starting at rung 0 in
  // ascending rung order, their code in ascending order without overlap,
  // each region's bytes a scan function that passes the code check alone.
  void check_regions(const SectionEntry& s) {
    const RegionTable& t = *im_.regions;
    if (im_.target != ImageTarget::X86_64) throw sfail(s, std::string("a region table on a ") + kind_->name + " image (x86-64 only)");
    size_t instrs = 0;
    for (uint32_t off = 0; off < im_.il.size(); instrs++) {
      Instr in;
      off = decode_instr(im_.il, off, in);
    }
    if (!by_id_[kLines] || im_.lines.size() != instrs)
      throw sfail(s, "a region table needs the 'lines' section with an entry for each of the IL's " + std::to_string(instrs) +
                         " instructions (their rungs); it has " + std::to_string(im_.lines.size()));
    if (t.max_rungs == 0) throw sfail(s, "region size 0");
    if (t.first.empty()) {  // a program of no rungs: no region, no code
      if (instrs || !t.code.empty()) throw sfail(s, "no regions, but the IL has " + std::to_string(instrs) + " instructions");
      return;
    }
    const uint64_t rungs = im_.lines.empty() ? 0 : uint64_t(im_.lines.back().rung) + 1;
    if (t.first.back() >= rungs)
      throw sfail(s, "region " + std::to_string(t.first.size() - 1) + " starts at rung " + std::to_string(t.first.back()) +
                         ", past the program's " + std::to_string(rungs) + " rungs");
    uint64_t code_end = 0;
    for (size_t i = 0; i < t.first.size(); i++) {
      const std::string at = "region " + std::to_string(i) + ": ";
      if (i == 0 ? t.first[0] != 0 : t.first[i] <= t.first[i - 1])
        throw sfail(s, at + "first rung " + std::to_string(t.first[i]) + (i == 0 ? " (the first region starts at rung 0)" : " is not after the region before's"));
      if (t.start[i] < code_end || t.size[i] == 0 || uint64_t(t.start[i]) + t.size[i] > t.code.size())
        throw sfail(s, at + "code [" + std::to_string(t.start[i]) + ", +" + std::to_string(t.size[i]) +
                           ") is empty, overlaps the region before, or lies outside the region code (" + std::to_string(t.code.size()) + " bytes)");
      code_end = uint64_t(t.start[i]) + t.size[i];
      const std::span<const uint8_t> bytes(t.code.data() + t.start[i], t.size[i]);
      if (std::string why = kind_->check(bytes, 0, im_.layout, nullptr); !why.empty())
        throw sfail(s, at + "its code (region code offset " + std::to_string(t.start[i]) + "): " + why);
    }
  }

  bool code_boundary(uint32_t off) const { return code_starts_.has(off); }

  void check_lines() {
    const SectionEntry* s = by_id_[kLines];
    if (!s) return;
    OffsetBits il_starts(im_.il.size());
    for (uint32_t off = 0; off < im_.il.size();) {
      il_starts.add(off);
      Instr in;
      off = decode_instr(im_.il, off, in);
    }
    for (size_t i = 0; i < im_.lines.size(); i++) {
      const LineEntry& l = im_.lines[i];
      std::string where = "entry " + std::to_string(i) + " at file offset " + hex(uint64_t(s->offset) + i * kLineEntrySize) + ": ";
      if (l.code_offset > im_.code.size())
        throw sfail(*s, where + "code offset " + hex(l.code_offset) + " outside the code (" + std::to_string(im_.code.size()) + " bytes)");
      if (l.code_offset < im_.code.size() && !code_boundary(l.code_offset))
        throw sfail(*s, where + "code offset " + hex(l.code_offset) + " is not an instruction boundary");
      if (!il_starts.has(l.il_offset))
        throw sfail(*s, where + "IL offset " + std::to_string(l.il_offset) +
                            (l.il_offset >= im_.il.size() ? " outside the IL (" + std::to_string(im_.il.size()) + " bytes)"
                                                          : " is not an IL instruction boundary"));
      if (l.line < 0) throw sfail(*s, where + "negative source line " + std::to_string(l.line));
      if (l.rung >= im_.rung_titles.size())
        throw sfail(*s, where + "rung " + std::to_string(l.rung) + " but the image has " +
                            std::to_string(im_.rung_titles.size()) + " rungs (titles)");
    }
  }
};

}  // namespace

Image read_image(std::span<const uint8_t> b, const std::string& name) { return ImageReader(b, name).read(); }

}  // namespace ldc
