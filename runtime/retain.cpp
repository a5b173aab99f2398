// runtime/retain.cpp -- the retentive memory file (docs/runtime.md,
// "Retentive memory"): a checksummed snapshot, replaced atomically.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "loader/loader.h"
#include "runtime/plc.h"

namespace ldc::plc {
namespace {

constexpr uint8_t kRetainMagic[8] = {'L', 'D', 'C', 'R', 'E', 'T', 0x00, 0x01};
constexpr uint32_t kRetainVersion = 1;
constexpr uint32_t kRetainHeader = 36;       // magic, version, size, sequence, time, record count
constexpr uint32_t kRetainMaxSize = 64u << 20;

void put32(std::vector<uint8_t>& b, uint32_t v) {
  for (int i = 0; i < 4; i++) b.push_back(uint8_t(v >> (8 * i)));
}
void put64(std::vector<uint8_t>& b, uint64_t v) {
  for (int i = 0; i < 8; i++) b.push_back(uint8_t(v >> (8 * i)));
}
uint32_t get32(std::span<const uint8_t> b, size_t at) {
  return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}
uint64_t get64(std::span<const uint8_t> b, size_t at) { return get32(b, at) | uint64_t(get32(b, at + 4)) << 32; }

}  // namespace

std::vector<uint8_t> encode_retain(const RetainSnapshot& s) {
  std::vector<uint8_t> b(kRetainMagic, kRetainMagic + 8);
  put32(b, kRetainVersion);
  put32(b, 0);  // total size, patched
  put64(b, s.sequence);
  put64(b, s.saved_ns);
  put32(b, uint32_t(s.records.size()));
  for (const RetainRecord& r : s.records) {
    put32(b, uint32_t(r.scope.size()));
    b.insert(b.end(), r.scope.begin(), r.scope.end());
    put32(b, uint32_t(r.area));
    put32(b, r.first);
    put32(b, r.count);
    put32(b, uint32_t(r.bytes.size()));
    b.insert(b.end(), r.bytes.begin(), r.bytes.end());
  }
  uint32_t total = uint32_t(b.size() + 4);
  for (int i = 0; i < 4; i++) b[12 + i] = uint8_t(total >> (8 * i));
  put32(b, crc32(b));
  return b;
}

RetainSnapshot decode_retain(std::span<const uint8_t> b, const std::string& name) {
  auto fail = [&](const std::string& m) { return std::runtime_error(name + ": error: " + m); };
  if (b.size() < kRetainHeader + 4) throw fail("retentive file truncated (" + std::to_string(b.size()) + " bytes)");
  if (std::memcmp(b.data(), kRetainMagic, 8) != 0) throw fail("not an ldc retentive file (bad magic)");
  if (uint32_t v = get32(b, 8); v != kRetainVersion) throw fail("unsupported retentive file version " + std::to_string(v));
  uint32_t total = get32(b, 12);
  if (total != b.size())
    throw fail("retentive file is " + std::to_string(b.size()) + " bytes, its header says " + std::to_string(total) +
               " (torn or truncated)");
  if (total > kRetainMaxSize) throw fail("retentive file too large");
  uint32_t want = get32(b, total - 4), have = crc32(b.subspan(0, total - 4));
  if (want != have) {
    char m[96];
    std::snprintf(m, sizeof m, "retentive file is corrupt: checksum 0x%08x, the contents give 0x%08x", want, have);
    throw fail(m);
  }
  RetainSnapshot s;
  s.sequence = get64(b, 16);
  s.saved_ns = get64(b, 24);
  uint32_t n = get32(b, 32);
  size_t pos = kRetainHeader, end = total - 4;
  auto need = [&](size_t k) {
    if (k > end - pos) throw fail("retentive record " + std::to_string(s.records.size()) + " runs past the end");
  };
  for (uint32_t i = 0; i < n; i++) {
    RetainRecord r;
    need(4);
    uint32_t len = get32(b, pos);
    pos += 4;
    need(len);
    r.scope.assign(reinterpret_cast<const char*>(b.data() + pos), len);
    pos += len;
    need(16);
    uint32_t area = get32(b, pos), first = get32(b, pos + 4), count = get32(b, pos + 8), nbytes = get32(b, pos + 12);
    pos += 16;
    if (area == 0 || area >= uint32_t(kAreaCount)) throw fail("retentive record " + std::to_string(i) + ": bad area");
    Layout L = Layout::standard(0);
    Area a = Area(area);
    if (a == Area::E || count == 0 || uint64_t(first) + count > L.count[area] ||
        uint64_t(count) * L.elem_size(a) != nbytes)
      throw fail("retentive record " + std::to_string(i) + ": bad range " + area_name(a) + "[" + std::to_string(first) +
                 "+" + std::to_string(count) + "]");
    need(nbytes);
    r.area = a, r.first = first, r.count = count;
    r.bytes.assign(b.begin() + pos, b.begin() + pos + nbytes);
    pos += nbytes;
    s.records.push_back(std::move(r));
  }
  if (pos != end) throw fail(std::to_string(end - pos) + " unexpected bytes after the last retentive record");
  return s;
}

std::string write_retain_file(const std::string& path, const RetainSnapshot& s) {
  std::vector<uint8_t> bytes = encode_retain(s);
  std::string tmp = path + ".tmp";
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return "cannot create " + tmp + ": " + std::strerror(errno);
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t w = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      int e = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      return "cannot write " + tmp + ": " + std::strerror(e);
    }
    done += size_t(w);
  }
  if (::fsync(fd) != 0) {
    int e = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    return "cannot fsync " + tmp + ": " + std::strerror(e);
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    int e = errno;
    ::unlink(tmp.c_str());
    return "cannot rename " + tmp + " to " + path + ": " + std::strerror(e);
  }
  // The rename is durable once the directory is on disk.
  size_t slash = path.rfind('/');
  std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0) return "cannot open directory " + dir + ": " + std::strerror(errno);
  int rc = ::fsync(dfd);
  int e = errno;
  ::close(dfd);
  if (rc != 0) return "cannot fsync directory " + dir + ": " + std::strerror(e);
  return "";
}

}  // namespace ldc::plc
