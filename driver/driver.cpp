// driver/driver.cpp -- shared by the executables.
#include "driver/driver.h"

#include <dirent.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <fcntl.h>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "backend-c/backend_c.h"
#include "frontend/frontend.h"

namespace ldc {

std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw UserError(path + ": error: cannot open: " + std::strerror(errno));
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) throw UserError(path + ": error: cannot read");
  return ss.str();
}

void write_file_atomic(const std::string& path, const std::string& data) {
  std::string tmp = path + ".tmp." + std::to_string(getpid());
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw UserError(path + ": error: cannot create: " + std::strerror(errno));
  bool ok = std::fwrite(data.data(), 1, data.size(), f) == data.size();
  ok &= std::fflush(f) == 0;
  ok &= std::fclose(f) == 0;
  if (!ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
    int e = errno;
    std::remove(tmp.c_str());
    throw UserError(path + ": error: cannot write: " + std::strerror(e));
  }
}

static bool ends_with(const std::string& s, const std::string& suf) {
  return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

Compiled compile_source(const std::string& path) {
  std::string text = read_file(path);
  Compiled c;
  try {
    if (ends_with(path, ".il")) {
      c.il = parse_il_text(text, path);
    } else if (text.compare(text.compare(0, 3, "\xEF\xBB\xBF") ? 0 : 3, 7, "LDmicro") == 0) {
      c.from_ld = true;
      c.tree = parse_ldmicro(text, path);
      c.il = lower_to_il(c.tree);
    } else if (ends_with(path, ".xml")) {
      c.from_ld = true;
      c.tree = parse_plcopen(text, path);
      c.il = lower_to_il(c.tree);
    } else {
      c.from_ld = true;
      c.tree = parse_ld(text, path);
      c.il = lower_to_il(c.tree);
    }
  } catch (CompileError& e) {
    std::string msg = format_error(path, text, e.line, e.col, e.what());
    if (!msg.empty() && msg.back() == '\n') msg.pop_back();
    throw UserError(msg);
  }
  return c;
}

NativeBuild build_x86(const Program& p, const std::string& source_name, as::Mode mode, int opt_level, bool notes) {
  NativeBuild b;
  b.gen = generate_x86(p, p.layout(), opt_level, notes);
  b.asm_result = as::assemble(as::x86::target(), b.gen.program, mode);
  if (!b.asm_result.ok()) {
    std::string msg;
    for (const auto& e : b.asm_result.errors)
      msg += (msg.empty() ? "" : "\n") + source_name + ":" + std::to_string(e.line) + ":1: error: " + e.message;
    throw UserError(msg);
  }
  return b;
}

Image make_x86_image(const Program& p, const NativeBuild& nb) {
  Image img;
  img.target = ImageTarget::X86_64;
  img.source = p.source;
  img.layout = p.layout();
  img.code = nb.asm_result.code;
  img.entry = 0;
  BinaryIl bin = encode_il(p);
  img.il = bin.code;
  img.aliases = p.aliases;
  size_t k = 0;
  for (size_t r = 0; r < p.rungs.size(); r++) {
    img.rung_titles.push_back(p.rungs[r].title);
    const auto& items = nb.asm_result.items[r + 1];  // block 0 is the prologue
    uint32_t block_end = nb.asm_result.blockOffsets[r + 2];
    for (size_t i = 0; i < p.rungs[r].code.size(); i++, k++) {
      const Instr& in = p.rungs[r].code[i];
      uint32_t at = nb.gen.il_items[r][i];
      img.lines.push_back({at < items.size() ? items[at].offset : block_end, bin.instr_offset[k],
                           in.loc.line ? in.loc.line : p.rungs[r].line, uint32_t(r)});
    }
  }
  return img;
}

bool is_image_file(const std::string& path) {
  if (ends_with(path, ".bin") || ends_with(path, ".hex")) return true;
  std::ifstream f(path, std::ios::binary);
  char magic[6] = {};
  f.read(magic, 6);
  return f.gcount() == 6 && std::string(magic, 6) == "LDCIMG";
}

Image load_image_file(const std::string& path) {
  std::string data = read_file(path);
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
    throw UserError(m);
  }
}

std::string make_temp_dir() {
  const char* t = std::getenv("TMPDIR");
  std::string tmpl = std::string(t && *t ? t : "/tmp") + "/ldc.XXXXXX";
  if (!mkdtemp(tmpl.data())) throw UserError(std::string("error: cannot create a temporary directory: ") + std::strerror(errno));
  return tmpl;
}

void remove_tree(const std::string& dir) {
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      std::string n = e->d_name;
      if (n != "." && n != "..") std::remove((dir + "/" + n).c_str());
    }
    closedir(d);
  }
  rmdir(dir.c_str());
}

extern "C" char** environ;

std::string build_c_shared_object(const Program& p, const std::string& dir) {
  std::string c = dir + "/prog.c", so = dir + "/prog.so", log = dir + "/cc.log";
  write_file_atomic(c, generate_c(p, p.layout()));
  const char* cc_env = std::getenv("CC");
  std::string cc = cc_env && *cc_env ? cc_env : "cc";
  std::vector<std::string> args = {cc, "-O2", "-shared", "-fPIC", "-ffp-contract=off", "-o", so, c, "-lm"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid;
  int rc = posix_spawnp(&pid, cc.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw UserError("error: cannot run the C compiler '" + cc + "': " + std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string out;
    try { out = read_file(log); } catch (...) {}
    throw UserError("error: the C compiler failed on the generated C (" + c + "):\n" + out);
  }
  return so;
}

std::optional<int32_t> parse_period(const std::string& s) {
  char* end = nullptr;
  errno = 0;
  long long v = std::strtoll(s.c_str(), &end, 10);
  if (end == s.c_str() || errno || v < 0) return std::nullopt;
  std::string unit = end;
  long long ms = unit.empty() || unit == "ms" ? v : unit == "s" ? v * 1000 : -1;
  if (ms < 0 || ms > INT32_MAX) return std::nullopt;
  return int32_t(ms);
}

}  // namespace ldc
