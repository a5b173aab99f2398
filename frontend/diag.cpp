// frontend/diag.cpp -- the diagnostics engine (docs/diagnostics.md).
#include "frontend/diag.h"

#include <algorithm>
#include <cstdlib>

namespace ldc {

const std::vector<WarningInfo>& warning_table() {
  static const std::vector<WarningInfo> table = {
      {"double-coil", true, "one bit driven by the coils of two rungs (or twice in one rung): the last one wins"},
      {"shared-timer", true, "one timer driven by two timer elements, or one counter by two of the same direction"},
      {"undriven", true, "a timer's or counter's done bit read, but no timer or counter element drives it"},
      {"unreachable", true, "rungs that an unconditional (JMP) or (END) always skips"},
      {"shared-output", true, "an output or relay written by two programs of a project that run on one processor"},
      {"trace-output", true, "ldrun: a trace column that writes an output (Y, WY), which the program's coils write too"},
      {"period", true, "ldrun: a period of 0 in trace mode: dt is 0 in every scan, so no timer advances"},
      {"unused", false, "an alias that no rung, declaration or label uses"},
      {"unused-label", false, "a label that no (JMP) targets"},
  };
  return table;
}

static const WarningInfo* find_warning(std::string_view name) {
  for (const WarningInfo& w : warning_table())
    if (name == w.name) return &w;
  return nullptr;
}

bool DiagOptions::enabled(std::string_view name) const {
  if (silent) return false;
  if (auto it = chosen.find(std::string(name)); it != chosen.end()) return it->second;
  const WarningInfo* w = find_warning(name);
  return w && (w->by_default || all);
}

bool DiagOptions::is_error(std::string_view name) const {
  if (auto it = chosen_error.find(std::string(name)); it != chosen_error.end()) return it->second;
  return werror;
}

std::optional<std::string> DiagOptions::parse(std::string_view a) {
  auto known = [&](std::string_view name, std::string_view spelled) -> std::string {
    if (find_warning(name)) return "";
    std::vector<std::string> names;
    for (const WarningInfo& w : warning_table()) names.push_back(w.name);
    std::string near = closest_name(name, names);
    return "unknown warning option '" + std::string(spelled) + "'" +
           (near.empty() ? " (ldc --help lists them)"
                         : "; did you mean '" + std::string(spelled.substr(0, spelled.size() - name.size())) + near + "'?");  // -Wno-NAME: -Wno-
  };
  if (a == "-Wall") return all = true, "";
  if (a == "-Werror") return werror = true, "";
  if (a == "-w") return silent = true, "";
  if (a.starts_with("-fmax-errors=")) {
    std::string_view n = a.substr(13);
    if (n.empty() || n.size() > 6 || n.find_first_not_of("0123456789") != std::string_view::npos)
      return "bad -fmax-errors value '" + std::string(n) + "' (a count; 0 for no limit)";
    max_errors = std::atoi(std::string(n).c_str());
    return "";
  }
  if (a.starts_with("-Werror=") || a.starts_with("-Wno-error=")) {
    bool on = a[2] == 'e';
    std::string_view name = a.substr(on ? 8 : 11);
    std::string why = known(name, a);
    if (why.empty()) chosen_error[std::string(name)] = on;
    return why;
  }
  if (a.starts_with("-Wno-")) {
    std::string why = known(a.substr(5), a);
    if (why.empty()) chosen[std::string(a.substr(5))] = false;
    return why;
  }
  if (a.starts_with("-W") && a.size() > 2) {
    std::string why = known(a.substr(2), a);
    if (why.empty()) chosen[std::string(a.substr(2))] = true;
    return why;
  }
  return std::nullopt;
}

// ------------------------------------------------------------------ reporting

static const char* kind_name(Severity s) {
  return s == Severity::Error ? "error" : s == Severity::Warning ? "warning" : "note";
}

std::string format_diagnostic(const std::string& file, std::string_view text, int line, int col, Severity s,
                              const std::string& msg) {
  std::string out = file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": " + kind_name(s) + ": " + msg + "\n";
  size_t pos = 0;
  for (int l = 1; l < line && pos != std::string_view::npos; l++) {
    pos = text.find('\n', pos);
    if (pos != std::string_view::npos) pos++;
  }
  if (pos == std::string_view::npos || pos > text.size()) return out;
  size_t end = text.find('\n', pos);
  std::string src(text.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos));
  if (!src.empty() && src.back() == '\r') src.pop_back();
  out += src + "\n";
  std::string caret;
  for (int i = 0; i + 1 < col && i < int(src.size()); i++) caret += src[i] == '\t' ? '\t' : ' ';
  out += caret + "^\n";
  return out;
}

void Diagnostics::emit(Severity s, const std::string& file, int line, int col, const std::string& msg) {
  auto it = texts_.find(file);
  if (it == texts_.end())  // a file whose text is not known: the first line only
    out_ += file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": " + kind_name(s) + ": " + msg + "\n";
  else
    out_ += format_diagnostic(file, it->second, line, col, s, msg);
}

// Before an error is reported: one past the limit stops the run (so the
// notes of the last error allowed are printed with it).
void Diagnostics::count_error() {
  if (opt_.max_errors > 0 && errors_ >= opt_.max_errors) {
    out_ += "fatal error: too many errors emitted, stopping now [-fmax-errors=" + std::to_string(opt_.max_errors) + "]\n";
    throw ErrorsReported();
  }
  errors_++;
}

void Diagnostics::error(const std::string& file, int line, int col, const std::string& msg) {
  dropping_ = false;
  count_error();
  emit(Severity::Error, file, line, col, msg);
}

void Diagnostics::error(const std::string& file, const CompileError& e) {
  dropping_ = false;
  count_error();
  emit(Severity::Error, file, e.line, e.col, e.what());
  if (auto* n = dynamic_cast<const NotedError*>(&e))
    for (const DiagNote& d : n->notes) emit(Severity::Note, file, d.line, d.col, d.message);
}

bool Diagnostics::warning(const char* name, const std::string& file, int line, int col, const std::string& msg) {
  dropping_ = !opt_.enabled(name);
  if (dropping_) return false;
  bool as_error = opt_.is_error(name);
  if (as_error) count_error();
  else warnings_++;
  emit(as_error ? Severity::Error : Severity::Warning, file, line, col,
       msg + " [-W" + (as_error ? "error=" : "") + name + "]");
  return true;
}

void Diagnostics::note(const std::string& file, int line, int col, const std::string& msg) {
  if (dropping_) return;
  emit(Severity::Note, file, line, col, msg);
}

// ------------------------------------------------------------------ names

size_t edit_distance(std::string_view a, std::string_view b) {
  auto up = [](char c) { return c >= 'a' && c <= 'z' ? char(c - 'a' + 'A') : c; };
  size_t n = a.size(), m = b.size();
  // three rows of the optimal-string-alignment table
  std::vector<size_t> prev2(m + 1), prev(m + 1), cur(m + 1);
  for (size_t j = 0; j <= m; j++) prev[j] = j;
  for (size_t i = 1; i <= n; i++) {
    cur[0] = i;
    for (size_t j = 1; j <= m; j++) {
      size_t cost = up(a[i - 1]) == up(b[j - 1]) ? 0 : 1;
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + cost});
      if (i > 1 && j > 1 && up(a[i - 1]) == up(b[j - 2]) && up(a[i - 2]) == up(b[j - 1]))
        cur[j] = std::min(cur[j], prev2[j - 2] + 1);
    }
    std::swap(prev2, prev);
    std::swap(prev, cur);
  }
  return prev[m];
}

bool recover_unit(Diagnostics* diag, const std::string& file, const std::function<void()>& read,
                  const std::function<bool()>& quiet) {
  if (!diag) return read(), true;
  try {
    read();
    return true;
  } catch (const Stop&) {
    throw;
  } catch (const Cascade&) {
    return false;
  } catch (const CompileError& e) {
    if (!quiet || !quiet()) diag->error(file, e);
    return false;
  }
}

std::string closest_name(std::string_view word, const std::vector<std::string>& names) {
  size_t limit = word.size() <= 3 ? 1 : 2;
  size_t best = limit + 1;
  const std::string* pick = nullptr;
  for (const std::string& n : names) {
    // names far longer or shorter cannot be near: skip the table
    if (n.size() > word.size() + limit || word.size() > n.size() + limit) continue;
    size_t d = edit_distance(word, n);
    if (d == 0 || d >= best) continue;
    best = d;
    pick = &n;
  }
  return pick ? *pick : "";
}

std::string did_you_mean(std::string_view word, const std::vector<std::string>& names) {
  std::string n = closest_name(word, names);
  return n.empty() ? "" : "; did you mean '" + n + "'?";
}

}  // namespace ldc
