#include "c40_test_util.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace ldc::as::c40::test {

namespace {
std::string trim(const std::string& s) {
  size_t a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  size_t b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}
}  // namespace

std::vector<Row> load_rows(const std::string& path) {
  std::vector<Row> rows;
  std::ifstream in(path);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    Row r;
    r.line = n;
    size_t sp = t.find_first_of(" \t");
    r.hex = t.substr(0, sp);
    std::string rest = sp == std::string::npos ? "" : t.substr(sp);
    size_t semi = rest.find(';');
    r.text = trim(rest.substr(0, semi));
    if (semi != std::string::npos) r.source = trim(rest.substr(semi + 1));
    rows.push_back(r);
  }
  return rows;
}

void rewrite_rows(const std::vector<std::string>& hexes, const std::string& path) {
  std::ifstream in(path);
  std::string line, out;
  size_t k = 0;
  while (std::getline(in, line)) {
    std::string t = trim(line);
    if (!t.empty() && t[0] != '#' && k < hexes.size()) {
      size_t sp = t.find_first_of(" \t");
      line = hexes[k++] + (sp == std::string::npos ? "" : t.substr(sp));
    }
    out += line + "\n";
  }
  std::ofstream(path) << out;
}

std::string hex_word(uint32_t w) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%08x", w);
  return buf;
}

C40Program build_program(std::vector<std::string> globals, const std::vector<BlockText>& blocks) {
  C40Program p;
  p.globals = std::move(globals);
  for (const BlockText& bt : blocks) {
    Block<Instruction> b;
    b.source_line = bt.line;
    std::istringstream ss(bt.text);
    std::string line;
    while (std::getline(ss, line)) {
      std::string t = trim(line);
      if (t.empty()) continue;
      if (t[0] == ';') {
        b.items.push_back(Item<Instruction>::note(trim(t.substr(1))));
        continue;
      }
      if (t.size() > 2 && t.compare(t.size() - 2, 2, "::") == 0) {
        b.items.push_back(Item<Instruction>::label_def(t.substr(0, t.size() - 2), true));
        continue;
      }
      Line l = parse_line(t);
      if (!l.label.empty()) b.items.push_back(Item<Instruction>::label_def(l.label));
      if (l.inst) b.items.push_back(Item<Instruction>::instr(*l.inst, l.comment));
    }
    p.blocks.push_back(std::move(b));
  }
  return p;
}

int run_command(const std::string& cmd, std::string* out) {
  std::string full = cmd + " 2>&1";
  FILE* f = popen(full.c_str(), "r");
  if (!f) return -1;
  std::string s;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  int st = pclose(f);
  if (out) *out = s;
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string temp_dir() {
  char tmpl[] = "/tmp/ldc_c40_XXXXXX";
  char* d = mkdtemp(tmpl);
  return d ? d : "/tmp";
}

std::string tic4x_tool(const std::string& name) {
  std::string dir;
  if (const char* e = std::getenv("LDC_TIC4X_DIR")) dir = e;
  else if (const char* h = std::getenv("HOME")) dir = std::string(h) + "/.cache/ldc-tic4x";
  else dir = "/tmp/.cache/ldc-tic4x";
  std::string path = dir + "/bin/tic4x-" + name;
  if (access(path.c_str(), X_OK) != 0) {
    ADD_FAILURE() << "the tic4x GNU " << name << " is missing (" << path
                  << "). Build it with tests/assembler/build_tic4x_tools.sh, which needs Debian's "
                     "binutils-source package (apt-get install -y binutils-source); ctest runs "
                     "it as the c40_tools fixture.";
    return "";
  }
  return path;
}

}  // namespace ldc::as::c40::test
