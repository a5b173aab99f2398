#include "test_util.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

namespace ldc::as::test {

std::vector<Row> load_rows(const std::string& path) {
  std::ifstream in(path);
  std::vector<Row> rows;
  if (!in) return rows;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    size_t b = line.find_first_not_of(" \t");
    if (b == std::string::npos || line[b] == '#') continue;
    size_t e = line.find_first_of(" \t", b);
    Row r;
    r.line = n;
    r.hex = line.substr(b, e == std::string::npos ? std::string::npos : e - b);
    size_t t = e == std::string::npos ? std::string::npos : line.find_first_not_of(" \t", e);
    r.text = t == std::string::npos ? "" : line.substr(t);
    while (!r.text.empty() && (r.text.back() == ' ' || r.text.back() == '\t')) r.text.pop_back();
    rows.push_back(r);
  }
  return rows;
}

void rewrite_rows(const std::vector<std::string>& hexes, const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  in.close();
  size_t width = 0;
  for (const auto& h : hexes) width = std::max(width, h.size());
  size_t k = 0;
  std::ostringstream out;
  for (const auto& l : lines) {
    size_t b = l.find_first_not_of(" \t");
    if (b == std::string::npos || l[b] == '#' || k >= hexes.size()) {
      out << l << "\n";
      continue;
    }
    size_t e = l.find_first_of(" \t", b);
    size_t t = e == std::string::npos ? std::string::npos : l.find_first_not_of(" \t", e);
    std::string text = t == std::string::npos ? "" : l.substr(t);
    std::string h = hexes[k++];
    h.resize(width, ' ');
    out << h << "  " << text << "\n";
  }
  std::ofstream(path) << out.str();
}

std::string to_hex(const std::vector<uint8_t>& bytes) {
  std::string s;
  char buf[4];
  for (uint8_t b : bytes) {
    std::snprintf(buf, sizeof buf, "%02x", b);
    s += buf;
  }
  return s;
}

std::vector<uint8_t> from_hex(const std::string& hex) {
  std::vector<uint8_t> v;
  for (size_t i = 0; i + 1 < hex.size(); i += 2)
    v.push_back(uint8_t(std::stoul(hex.substr(i, 2), nullptr, 16)));
  return v;
}

std::vector<x86::Instruction> variants(const x86::Instruction& in) {
  using namespace x86;
  std::vector<Instruction> out;
  std::set<std::string> seen;
  auto add = [&](const Instruction& v) {
    try {
      x86::encode(v);
    } catch (const AsmError&) {
      return;
    }
    if (seen.insert(print(v)).second) out.push_back(v);
  };
  add(in);
  for (unsigned i = 0; i < in.num_operands; ++i) {
    const Operand& o = in.ops[i];
    Instruction v = in;
    Operand& w = v.ops[i];
    switch (o.kind) {
      case OperandKind::Reg:
        for (unsigned n = 0; n < 16; ++n) {
          w.reg.num = uint8_t(n);
          add(v);
        }
        break;
      case OperandKind::Mem: {
        std::vector<Reg> regs = {Reg{}, rip()};
        for (unsigned n = 0; n < 16; ++n) regs.push_back(r64(n));
        for (Reg b : regs) {
          w.mem = o.mem;
          w.mem.base = b;
          add(v);
        }
        for (Reg x : regs) {
          if (x.cls == RegClass::Rip || (x.valid() && x.num == SP)) continue;
          w.mem = o.mem;
          w.mem.index = x;
          w.mem.scale = x.valid() ? o.mem.scale : 1;
          add(v);
          if (x.valid())
            for (uint8_t s : {1, 2, 4, 8}) {
              w.mem.scale = s;
              add(v);
            }
        }
        for (int32_t d : {0, 1, -1, 0x7f, 0x80, -0x80, -0x81, 0x12345678, INT32_MIN}) {
          w.mem = o.mem;
          w.mem.disp = d;
          add(v);
        }
        break;
      }
      case OperandKind::Imm:
        for (int64_t imm : {0ll, 1ll, 2ll, 0x7fll, 0x80ll, 0xffll, 0x100ll, 0x7fffffffll, 0x80000000ll,
                            0xffffff80ll, 0xffffffffll, -1ll, -0x80ll, -0x81ll, -0x80000000ll}) {
          w.imm = imm;
          add(v);
        }
        break;
      default:
        break;
    }
  }
  return out;
}

std::vector<x86::Instruction> all_row_variants() {
  std::vector<x86::Instruction> all;
  std::set<std::string> seen;
  for (const Row& r : load_rows()) {
    x86::Instruction in = x86::parse(r.text);
    if (in.num_operands && in.ops[0].kind == x86::OperandKind::Address) continue;
    for (auto& v : variants(in))
      if (seen.insert(x86::print(v)).second) all.push_back(v);
  }
  return all;
}

x86::X86Program build_program(std::vector<std::string> globals, const std::vector<BlockText>& blocks) {
  x86::X86Program p;
  p.globals = std::move(globals);
  for (const BlockText& bt : blocks) {
    Block<x86::Instruction> b;
    b.source_line = bt.line;
    std::istringstream in(bt.text);
    std::string l;
    while (std::getline(in, l)) {
      size_t s = l.find_first_not_of(" \t");
      if (s == std::string::npos) continue;
      l = l.substr(s);
      while (!l.empty() && (l.back() == ' ' || l.back() == '\t')) l.pop_back();
      if (l[0] == '#') {
        size_t t = l.find_first_not_of(" \t", 1);
        b.items.push_back(Item<x86::Instruction>::note(t == std::string::npos ? "" : l.substr(t)));
      } else if (l.size() > 2 && l.substr(l.size() - 2) == "::") {
        b.items.push_back(Item<x86::Instruction>::label_def(l.substr(0, l.size() - 2), true));
      } else if (l.back() == ':') {
        b.items.push_back(Item<x86::Instruction>::label_def(l.substr(0, l.size() - 1)));
      } else {
        b.items.push_back(Item<x86::Instruction>::instr(x86::parse(l)));
      }
    }
    p.blocks.push_back(std::move(b));
  }
  return p;
}

namespace {

// Runs argv, capturing stdout+stderr. Returns the exit status (-1 if it
// could not run).
int run(const std::vector<std::string>& argv, std::string& output) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  close(fds[1]);
  char buf[4096];
  ssize_t n;
  output.clear();
  while ((n = read(fds[0], buf, sizeof buf)) > 0) output.append(buf, size_t(n));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct TempDir {
  std::string path;
  TempDir() {
    const char* t = std::getenv("TMPDIR");
    std::string tmpl = std::string(t && *t ? t : "/tmp") + "/ldc-asm-XXXXXX";
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    if (mkdtemp(buf.data())) path = buf.data();
  }
  ~TempDir() {
    if (path.empty()) return;
    std::string out;
    run({"rm", "-rf", path}, out);
  }
};

std::vector<uint8_t> read_file(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

bool binutils_available(std::string* why) {
  for (const char* tool : {"as", "objcopy", "objdump"}) {
    std::string out;
    if (run({tool, "--version"}, out) != 0 || out.find("GNU") == std::string::npos) {
      *why = std::string("GNU ") + tool +
             " not found or not working: binutils is a required test dependency "
             "(apt-get install binutils)";
      return false;
    }
  }
  return true;
}

std::vector<uint8_t> gnu_assemble(const std::string& source, std::string* error) {
  TempDir dir;
  if (dir.path.empty()) return *error = "cannot create a temporary directory", std::vector<uint8_t>{};
  std::string s = dir.path + "/x.s", o = dir.path + "/x.o", bin = dir.path + "/x.bin", out;
  std::ofstream(s) << source;
  if (run({"as", "--64", "-o", o, s}, out) != 0) return *error = "as failed:\n" + out, std::vector<uint8_t>{};
  if (run({"objcopy", "-O", "binary", "-j", ".text", o, bin}, out) != 0)
    return *error = "objcopy failed:\n" + out, std::vector<uint8_t>{};
  return read_file(bin);
}

std::vector<ObjdumpInsn> objdump_intel(const std::vector<uint8_t>& code, std::string* error) {
  TempDir dir;
  std::vector<ObjdumpInsn> r;
  if (dir.path.empty()) return *error = "cannot create a temporary directory", r;
  std::string bin = dir.path + "/x.bin", out;
  std::ofstream(bin, std::ios::binary).write(reinterpret_cast<const char*>(code.data()),
                                              std::streamsize(code.size()));
  if (run({"objdump", "-D", "-b", "binary", "-m", "i386:x86-64", "-M", "intel", "-w", bin}, out) != 0)
    return *error = "objdump failed:\n" + out, r;
  // "   1a:\tf7 c3 10 00 00 00 \ttest   ebx,0x10"
  static const std::regex line(R"(^\s*([0-9a-f]+):\t[0-9a-f ]+\t(.*)$)");
  std::istringstream in(out);
  std::string l;
  std::smatch m;
  while (std::getline(in, l))
    if (std::regex_match(l, m, line)) r.push_back({std::stoull(m[1], nullptr, 16), m[2]});
  return r;
}

std::string normalize_objdump(const std::string& text) {
  std::string t = std::regex_replace(text, std::regex(R"(\s*<[^>]*>)"), "");
  t = std::regex_replace(t, std::regex(R"(\s*#.*$)"), "");
  // objdump prints negative rip displacements as 64-bit unsigned numbers.
  static const std::regex wide(R"(\+0x([0-9a-f]{16})\])");
  std::smatch w;
  if (std::regex_search(t, w, wide)) {
    uint64_t v = std::stoull(w[1], nullptr, 16);
    char buf[32];
    std::snprintf(buf, sizeof buf, "-0x%llx]", static_cast<unsigned long long>(0 - v));
    t = w.prefix().str() + buf + w.suffix().str();
  }
  // Branch targets are printed as bare hex: "jmp    14" in some versions.
  static const std::regex branch(R"(^((?:j[a-z]+|call)\s+)([0-9a-f]+)$)");
  std::smatch m;
  if (std::regex_match(t, m, branch)) t = m[1].str() + "0x" + m[2].str();
  return t;
}

}  // namespace ldc::as::test
