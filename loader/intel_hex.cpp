// loader/intel_hex.cpp -- the image as Intel HEX (the paper's loader output):
// type-00 data records of 16 bytes from address 0, a type-04 extended linear
// address record at every 64 KiB boundary, and the type-01 end record.
#include <cctype>
#include <cstdio>

#include "loader/loader.h"

namespace ldc {

namespace {

const char kDigits[] = "0123456789ABCDEF";

void put_byte(std::string& s, uint8_t b, uint8_t& sum) {
  s += kDigits[b >> 4];
  s += kDigits[b & 15];
  sum = uint8_t(sum + b);
}

void record(std::string& s, uint8_t type, uint16_t addr, std::span<const uint8_t> data) {
  uint8_t sum = 0;
  s += ':';
  put_byte(s, uint8_t(data.size()), sum);
  put_byte(s, uint8_t(addr >> 8), sum);
  put_byte(s, uint8_t(addr), sum);
  put_byte(s, type, sum);
  for (uint8_t b : data) put_byte(s, b, sum);
  uint8_t ignored = 0;
  put_byte(s, uint8_t(-sum), ignored);
  s += '\n';
}

int digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

}  // namespace

std::string write_intel_hex(std::span<const uint8_t> bytes) {
  std::string s;
  s.reserve(bytes.size() / 16 * 44 + 64);
  uint32_t upper = 0;
  for (size_t pos = 0; pos < bytes.size(); pos += 16) {
    uint32_t hi = uint32_t(pos >> 16);
    if (hi != upper) {
      const uint8_t ela[2] = {uint8_t(hi >> 8), uint8_t(hi)};
      record(s, 0x04, 0, ela);
      upper = hi;
    }
    size_t n = bytes.size() - pos < 16 ? bytes.size() - pos : 16;
    record(s, 0x00, uint16_t(pos & 0xFFFF), bytes.subspan(pos, n));
  }
  record(s, 0x01, 0, {});
  return s;
}

bool looks_like_intel_hex(std::span<const uint8_t> bytes) {
  for (uint8_t b : bytes) {
    if (b == ' ' || b == '\t' || b == '\r' || b == '\n') continue;
    return b == ':';
  }
  return false;
}

std::vector<uint8_t> read_intel_hex(std::string_view text, const std::string& name) {
  std::vector<uint8_t> out;
  uint64_t upper = 0;  // from the last type-04 record, already shifted left by 16
  bool ended = false;
  int line_no = 0;
  size_t pos = 0;
  int last_line = 1;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    std::string_view line = text.substr(pos, eol == std::string_view::npos ? std::string_view::npos : eol - pos);
    pos = eol == std::string_view::npos ? text.size() : eol + 1;
    line_no++;
    last_line = line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    auto err = [&](size_t col, const std::string& msg) {
      return ImageError(name + ":" + std::to_string(line_no) + ":" + std::to_string(col + 1) + ": error: " + msg);
    };
    // Blank lines (spaces, tabs) are allowed anywhere; anything else after the end record is not.
    size_t first = 0;
    while (first < line.size() && (line[first] == ' ' || line[first] == '\t')) first++;
    if (first == line.size()) continue;
    if (ended) throw err(first, "text after the end-of-file record");
    if (line[first] != ':') throw err(first, "expected ':' to start a record");
    // The record's bytes: pairs of hex digits up to the end of the line (trailing blanks allowed).
    size_t last = line.size();
    while (last > first && (line[last - 1] == ' ' || line[last - 1] == '\t')) last--;
    std::vector<uint8_t> rec;
    size_t p = first + 1;
    for (; p < last; p += 2) {
      int h = digit(line[p]);
      if (h < 0) throw err(p, std::string("bad hex digit '") + (std::isprint((unsigned char)line[p]) ? std::string(1, line[p]) : "?") + "'");
      if (p + 1 >= last) throw err(p + 1, "odd number of hex digits");
      int l = digit(line[p + 1]);
      if (l < 0) throw err(p + 1, std::string("bad hex digit '") + (std::isprint((unsigned char)line[p + 1]) ? std::string(1, line[p + 1]) : "?") + "'");
      rec.push_back(uint8_t(h << 4 | l));
      if (rec.size() > 255 + 5) throw err(first, "record too long (more than 255 data bytes)");
    }
    if (rec.size() < 5) throw err(first, "record too short (" + std::to_string(rec.size()) + " bytes; at least 5)");
    size_t n = rec[0];
    if (rec.size() != n + 5)
      throw err(first + 1, "record length field says " + std::to_string(n) + " data bytes, the record has " +
                               std::to_string(rec.size() - 5));
    uint8_t sum = 0;
    for (uint8_t b : rec) sum = uint8_t(sum + b);
    if (sum != 0) {
      uint8_t want = uint8_t(rec.back() - sum);
      char buf[64];
      std::snprintf(buf, sizeof buf, "bad checksum %02X (expected %02X)", rec.back(), want);
      throw err(first + 1 + 2 * (rec.size() - 1), buf);
    }
    uint16_t addr = uint16_t(rec[1] << 8 | rec[2]);
    uint8_t type = rec[3];
    switch (type) {
      case 0x00: {
        uint64_t at = upper + addr;
        if (at != out.size()) {
          char buf[128];
          std::snprintf(buf, sizeof buf, "data at address 0x%llX, expected 0x%llX (%s; images are contiguous)",
                        (unsigned long long)at, (unsigned long long)out.size(),
                        at > out.size() ? "a gap" : "an overlap");
          throw err(first + 3, buf);
        }
        if (uint32_t(addr) + n > 0x10000) throw err(first + 3, "data record crosses a 64 KiB boundary");
        if (out.size() + n > kImageMaxSize) throw err(first, "more data than an image may hold");
        out.insert(out.end(), rec.begin() + 4, rec.end() - 1);
        break;
      }
      case 0x01:
        if (n != 0) throw err(first + 1, "end-of-file record with data");
        if (addr != 0) throw err(first + 3, "end-of-file record with a nonzero address");
        ended = true;
        break;
      case 0x04:
        if (n != 2) throw err(first + 1, "extended linear address record must have 2 data bytes");
        if (addr != 0) throw err(first + 3, "extended linear address record with a nonzero address field");
        upper = uint64_t(rec[4] << 8 | rec[5]) << 16;
        break;
      default: {
        char buf[96];
        std::snprintf(buf, sizeof buf, "unsupported record type %02X (only 00, 01 and 04)", type);
        throw err(first + 7, buf);
      }
    }
  }
  if (!ended)
    throw ImageError(name + ":" + std::to_string(last_line) + ":1: error: missing end-of-file record (:00000001FF)");
  return out;
}

}  // namespace ldc
