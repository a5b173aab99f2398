// loader/image_file.cpp -- image files: binary or Intel HEX (loader.h, read_image_file).
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "loader/loader.h"

namespace ldc {

namespace {

bool ends_with(const std::string& s, const std::string& suf) {
  return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

std::string file_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw ImageError(path + ": error: cannot open: " + std::strerror(errno));
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) throw ImageError(path + ": error: cannot read");
  return ss.str();
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
  std::string data = file_bytes(path);
  std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(data.data()), data.size());
  try {
    if (looks_like_intel_hex(bytes)) {
      std::vector<uint8_t> raw = read_intel_hex(data, path);
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
