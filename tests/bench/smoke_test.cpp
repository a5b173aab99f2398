// tests/bench/smoke_test.cpp -- ldbench --smoke writes every CSV and SVG, and
// they parse: CSV rows as wide as their header, numbers where numbers belong,
// SVG documents with balanced tags.  Also the plot helpers' ticks and labels.
// No timing is asserted.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "bench/svgplot.h"

extern "C" char** environ;

namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// RFC 4180: fields separated by ',', quoted with '"' ("" inside quotes).
// Returns false on a malformed line.
bool parse_csv(const std::string& text, std::vector<std::vector<std::string>>& rows) {
  std::vector<std::string> row;
  std::string cell;
  bool quoted = false, was_quoted = false;
  for (size_t i = 0; i < text.size(); i++) {
    char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') { cell += '"'; i++; }
      else if (c == '"') quoted = false;
      else cell += c;
      continue;
    }
    if (c == '"') {
      if (!cell.empty() || was_quoted) return false;
      quoted = was_quoted = true;
    } else if (c == ',') {
      row.push_back(cell); cell.clear(); was_quoted = false;
    } else if (c == '\n') {
      row.push_back(cell); cell.clear(); was_quoted = false;
      rows.push_back(row); row.clear();
    } else {
      if (was_quoted) return false;
      cell += c;
    }
  }
  return !quoted && cell.empty() && row.empty();
}

bool is_number(const std::string& s) {
  if (s.empty()) return false;
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(s.c_str(), &end);
  return *end == 0 && errno == 0 && std::isfinite(v);
}

// A small XML check: every tag closes in order, attributes are quoted, the root is <svg>.
std::string check_svg(const std::string& s) {
  if (s.rfind("<svg ", 0) != 0) return "does not start with <svg";
  std::vector<std::string> stack;
  size_t i = 0;
  int elements = 0;
  while ((i = s.find('<', i)) != std::string::npos) {
    size_t j = s.find('>', i);
    if (j == std::string::npos) return "unclosed tag";
    std::string tag = s.substr(i + 1, j - i - 1);
    size_t quotes = 0;
    for (char c : tag) quotes += c == '"';
    if (quotes % 2) return "odd quotes in <" + tag + ">";
    if (tag.empty()) return "empty tag";
    if (tag[0] == '/') {
      if (stack.empty() || stack.back() != tag.substr(1)) return "unbalanced </" + tag.substr(1) + ">";
      stack.pop_back();
    } else if (tag.back() != '/') {
      stack.push_back(tag.substr(0, tag.find(' ')));
      elements++;
    } else {
      elements++;
    }
    i = j + 1;
  }
  if (!stack.empty()) return "unclosed <" + stack.back() + ">";
  if (s.find("&") != std::string::npos && s.find("&amp;") == std::string::npos && s.find("&lt;") == std::string::npos &&
      s.find("&gt;") == std::string::npos && s.find("&quot;") == std::string::npos)
    return "a raw &";
  return elements > 5 ? "" : "almost empty";
}

// Runs ldbench with `args`; its exit status.  With `log`, its stderr (the
// progress lines) goes to that file.
int run_ldbench(std::vector<std::string> args, const std::string& log = "") {
  args.insert(args.begin(), LDC_LDBENCH_PATH);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  if (!log.empty()) posix_spawn_file_actions_addopen(&fa, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  int spawned = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (spawned != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(Ldbench, SmokeRunWritesCsvAndSvgThatParse) {
  fs::path dir = fs::temp_directory_path() / ("ldbench_smoke_" + std::to_string(getpid()));
  fs::remove_all(dir);
  ASSERT_EQ(run_ldbench({"--smoke", "--out", dir.string()}), 0) << "ldbench --smoke failed";

  // Every file ldbench promises, with the columns the docs read.
  const std::map<std::string, std::vector<std::string>> csvs = {
      {"timings.csv", {"experiment", "program", "n_exe", "engine", "median_ns", "p99_ns", "status"}},
      {"classes.csv", {"class", "powered", "classic_ns_per_instr", "native_ns_per_instr", "c40_cycles_per_instr"}},
      {"fig10.csv", {"n_exe", "p_basic", "classic_ns", "native_ns", "native_eq2_ns", "native_code_bytes"}},
      {"scaling.csv", {"n_exe", "classic_ns", "fast_ns", "native_ns", "c_ns", "c40_cycles"}},
      {"codesize.csv", {"program", "n_exe", "native_code_bytes", "image_bytes"}},
      {"codesize_fits.csv", {"quantity", "slope_bytes_per_il", "intercept_bytes", "r2"}},
      {"examples.csv", {"example", "n_exe", "native_ns"}},
      {"compile.csv", {"source", "il", "parse_s", "generate_s", "assemble_s", "total_s", "il_per_s"}},
      {"memory.csv", {"rungs", "il", "rss_before_kb", "hwm_after_image_kb"}},
      {"machine.csv", {"key", "value"}},
      {"levels.csv", {"program", "n_exe", "o0_ns", "o1_ns", "o2_ns", "c_ns", "o0_bytes", "o2_bytes", "o2_build_s", "c40_o2_cycles"}},
  };
  for (const auto& [name, cols] : csvs) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(fs::exists(dir / name));
    std::vector<std::vector<std::string>> rows;
    ASSERT_TRUE(parse_csv(read(dir / name), rows));
    ASSERT_GE(rows.size(), 2u) << "no data rows";
    for (size_t r = 1; r < rows.size(); r++) EXPECT_EQ(rows[r].size(), rows[0].size()) << "row " << r;
    for (const std::string& c : cols) EXPECT_NE(std::find(rows[0].begin(), rows[0].end(), c), rows[0].end()) << c;
  }
  // Numbers where numbers belong: every timed row of timings.csv.
  std::vector<std::vector<std::string>> t;
  ASSERT_TRUE(parse_csv(read(dir / "timings.csv"), t));
  auto col = [&](const std::string& c) { return size_t(std::find(t[0].begin(), t[0].end(), c) - t[0].begin()); };
  int timed = 0;
  for (size_t r = 1; r < t.size(); r++) {
    EXPECT_TRUE(is_number(t[r][col("n_exe")])) << r;
    if (t[r][col("status")] != "ok") continue;
    timed++;
    EXPECT_TRUE(is_number(t[r][col("median_ns")])) << r;
    EXPECT_TRUE(is_number(t[r][col("p99_ns")])) << r;
  }
  EXPECT_GT(timed, 20);
  std::set<std::string> engines;
  for (size_t r = 1; r < t.size(); r++)
    if (t[r][col("status")] == "ok") engines.insert(t[r][col("engine")]);
  for (const char* e : {"classic", "fast", "native", "native-O1", "native-O2"}) EXPECT_TRUE(engines.count(e)) << e << " never timed";
  // the simulated C40: cycles for both its engines on every program
  int c40 = 0;
  for (size_t r = 1; r < t.size(); r++)
    if (t[r][col("engine")].rfind("c40", 0) == 0) {
      if (t[r][col("status")].rfind("refused: ", 0) == 0) continue;  // the typed program's LREAL: refused by name
      c40++;
      EXPECT_TRUE(is_number(t[r][col("median_ns")])) << "row " << r << ": " << t[r][col("status")];
    }
  EXPECT_GT(c40, 20);

  for (const char* name : {"scaling.svg", "ns_per_il.svg", "speedup.svg", "classes.svg", "fig10_classic.svg",
                           "fig10_fast.svg", "fig10_native.svg", "fig10_c40.svg", "classes_c40.svg", "pbasic.svg", "codesize.svg",
                           "compile.svg"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(fs::exists(dir / name));
    EXPECT_EQ(check_svg(read(dir / name)), "");
  }
  std::string md = read(dir / "tables.md");
  EXPECT_NE(md.find("## Headline"), std::string::npos);
  EXPECT_NE(md.find("C40 interp/native"), std::string::npos);
  fs::remove_all(dir);
}

// `ldbench FILE...` on Structured Text (docs/BENCHMARKS.md, issue 26): every
// engine times the sort; native code refuses the STRING parse by name, at every
// level, and the other engines still time it; both have their rows of code
// sizes per level.
TEST(Ldbench, StFilesTimedAndStringRefusedOnNative) {
  fs::path dir = fs::temp_directory_path() / ("ldbench_st_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string st = LDC_BENCH_ST_DIR;
  fs::create_directories(dir);
  const std::string log = (dir / "progress.txt").string();
  ASSERT_EQ(run_ldbench({"--smoke", "--no-c", "--no-c40", "--out", dir.string(), st + "/sort.st", st + "/parse_string.st"}, log), 0);
  // The progress lines (issue 27): an engine not run is "-", never "nan", and no
  // time is printed as "0 ns" (a scan under the loop overhead is said to be).
  std::string progress = read(log);
  EXPECT_NE(progress.find(", C -; C40 - / - cycles"), std::string::npos) << progress;
  EXPECT_EQ(progress.find("nan"), std::string::npos) << progress;
  EXPECT_EQ(progress.find(" 0 ns"), std::string::npos) << progress;
  std::vector<std::vector<std::string>> t;
  ASSERT_TRUE(parse_csv(read(dir / "timings.csv"), t));
  auto col = [&](const std::string& c) { return size_t(std::find(t[0].begin(), t[0].end(), c) - t[0].begin()); };
  std::map<std::string, std::string> status;  // "sort.st native-O2" -> its status
  for (size_t r = 1; r < t.size(); r++)
    status[fs::path(t[r][col("program")]).filename().string() + " " + t[r][col("engine")]] = t[r][col("status")];
  for (const char* e : {"classic", "fast", "native", "native-O1", "native-O2"}) {
    EXPECT_EQ(status[std::string("sort.st ") + e], "ok") << e;
    EXPECT_EQ(status[std::string("parse_string.st ") + e].rfind("ok", 0), 0u) << e;  // STRING in native code too
  }
  std::string levels = read(dir / "levels.csv");
  EXPECT_NE(levels.find("sort.st"), std::string::npos);
  EXPECT_NE(levels.find("parse_string.st"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Plot, TicksAndLabels) {
  using ldc::plot::tick_label;
  using ldc::plot::ticks;
  EXPECT_EQ(ticks(100, 100000, true), (std::vector<double>{100, 1000, 10000, 100000}));
  EXPECT_EQ(ticks(10, 1000, true), (std::vector<double>{10, 20, 50, 100, 200, 500, 1000}));
  EXPECT_EQ(ticks(0, 3000, false), (std::vector<double>{0, 500, 1000, 1500, 2000, 2500, 3000}));
  EXPECT_EQ(tick_label(3000), "3000");
  EXPECT_EQ(tick_label(30000), "30k");
  EXPECT_EQ(tick_label(1.5e6), "1.5M");
  EXPECT_EQ(tick_label(0.25), "0.25");
}

TEST(Plot, RendersEscapedWellFormedSvg) {
  ldc::plot::LinePlot p;
  p.title = "a < b & c";
  p.logx = p.logy = true;
  p.series.push_back({"s1", {1, 10, 100}, {5, 50, 0}});  // 0 is skipped on a log axis
  p.series.push_back({"s2 \"q\"", {1, 100}, {NAN, 7}});
  std::string svg = ldc::plot::render(p);
  EXPECT_EQ(check_svg(svg), "");
  EXPECT_NE(svg.find("a &lt; b &amp; c"), std::string::npos);
  ldc::plot::BarPlot b;
  b.categories = {"x", "y"};
  b.series.push_back({"one", {}, {1, 2}});
  EXPECT_EQ(check_svg(ldc::plot::render(b)), "");
}

}  // namespace
