// loader/image_file.cpp -- image files: binary or Intel HEX (loader.h, read_image_file).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>

#include "loader/loader.h"

namespace ldc {

namespace {

bool ends_with(const std::string& s, const std::string& suf) {
  return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

std::string size_text(uint64_t n) {
  return n % (1u << 20) == 0 ? std::to_string(n >> 20) + " MiB" : std::to_string(n) + " bytes";
}

// The file's bytes, refused before they are read whole if there are more than
// `max_bytes` (the size the file says it has, or, for a pipe or a file that
// grows, the bytes read so far): no file makes this hold more than max_bytes.
std::string file_bytes(const std::string& path, uint64_t max_bytes, const std::string& whose) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw ImageError(path + ": error: cannot open: " + std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  auto too_large = [&](uint64_t n, bool at_least) {
    return ImageError(path + ": error: the file has " + (at_least ? "more than " : "") + std::to_string(n) + " bytes, more than the " +
                      size_text(max_bytes) + " " + whose + "; it was not read");
  };
  struct stat st;
  if (::fstat(fd, &st) != 0) throw ImageError(path + ": error: cannot read: " + std::strerror(errno));
  if (S_ISREG(st.st_mode) && uint64_t(st.st_size) > max_bytes) throw too_large(uint64_t(st.st_size), false);
  std::string data;
  if (S_ISREG(st.st_mode)) data.reserve(size_t(st.st_size));
  char buf[1 << 16];
  for (;;) {
    ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw ImageError(path + ": error: cannot read: " + std::strerror(errno));
    if (n == 0) break;
    if (data.size() + size_t(n) > max_bytes) throw too_large(max_bytes, true);
    data.append(buf, size_t(n));
  }
  return data;
}

// The largest file read_image_file(path) reads: an image at the format's limit,
// or its Intel HEX text (44 characters, CRLF 45, per 16 bytes, and a type-04
// record per 64 KiB), told apart by the file's first bytes.
uint64_t format_file_limit(const std::string& path) {
  char head[64] = {};
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  ssize_t n = fd < 0 ? 0 : ::read(fd, head, sizeof head);
  if (fd >= 0) ::close(fd);
  bool hex = n > 0 && looks_like_intel_hex({reinterpret_cast<const uint8_t*>(head), size_t(n)});
  return hex ? uint64_t(kImageMaxSize) / 16 * 46 + (uint64_t(kImageMaxSize) >> 16) * 18 + 64 : kImageMaxSize;
}

}  // namespace

bool is_image_file(const std::string& path) {
  if (ends_with(path, ".bin") || ends_with(path, ".hex")) return true;
  std::ifstream f(path, std::ios::binary);
  char magic[6] = {};
  f.read(magic, 6);
  return f.gcount() == 6 && std::string(magic, 6) == "LDCIMG";
}

Image read_image_file(const std::string& path) {
  return read_image_file(path, format_file_limit(path), "an image file may have");
}

Image read_image_file(const std::string& path, uint64_t max_bytes, const std::string& whose) {
  std::string data = file_bytes(path, max_bytes, whose);
  std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(data.data()), data.size());
  try {
    if (looks_like_intel_hex(bytes)) {
      std::vector<uint8_t> raw = read_intel_hex(data, path);
      data = std::string();  // the text is not needed past here
      return read_image(raw, path);
    }
    return read_image(bytes, path);
  } catch (ImageError& e) {
    std::string m = e.what();  // "prog.bin: section ...": make it "prog.bin: error: section ..."
    if (m.find(" error: ") == std::string::npos && m.rfind(path + ": ", 0) == 0)
      m = path + ": error: " + m.substr(path.size() + 2);
    throw ImageError(m);
  }
}

}  // namespace ldc
