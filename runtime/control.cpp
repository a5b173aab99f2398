// runtime/control.cpp -- the stdin/stdout line protocol of ldrun
// (docs/runtime.md, "The line protocol"): one command per line, one reply line.
#include <cctype>
#include <stdexcept>

#include "runtime/plc.h"

namespace ldc::plc {
namespace {

std::vector<std::string> words(const std::string& line) {
  std::vector<std::string> w;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) i++;
    if (i >= line.size() || line[i] == '#') break;
    size_t s = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) i++;
    w.push_back(line.substr(s, i - s));
  }
  return w;
}

// The line from its n-th word (0-based) on, trailing blanks dropped.
std::string rest_of_line(const std::string& line, size_t n) {
  size_t i = 0;
  for (size_t k = 0;; k++) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) i++;
    if (k == n) break;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) i++;
  }
  size_t e = line.find_last_not_of(" \t\r");
  return e == std::string::npos || e < i ? std::string() : line.substr(i, e + 1 - i);
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

constexpr const char* kHelp =
    "commands: set [TASK.]NAME VALUE | get [TASK.]NAME | run | stop | status | stats | load [--strict] [TASK] FILE | restart [TASK] | wait N | save | quit";

}  // namespace

std::string Control::execute(const std::string& line, bool& quit) {
  std::vector<std::string> w = words(line);
  if (w.empty()) return "";
  std::string cmd = lower(w[0]);
  auto args = [&](size_t lo, size_t hi, const char* form) {
    if (w.size() - 1 < lo || w.size() - 1 > hi) throw std::runtime_error(std::string("usage: ") + form);
  };
  try {
    if (cmd == "set") {  // the value is the rest of the line: a STRING 'a b' may hold blanks
      if (w.size() < 3) throw std::runtime_error("usage: set NAME VALUE");
      rt.set(w[1], rest_of_line(line, 2));
      return "ok";
    }
    if (cmd == "get") {
      args(1, 1, "get [TASK.]NAME");
      return w[1] + " = " + rt.get(w[1]);
    }
    if (cmd == "run") {
      args(0, 0, "run");
      rt.run();
      return "ok RUN";
    }
    if (cmd == "stop") {
      args(0, 0, "stop");
      rt.stop();
      return "ok STOP";
    }
    if (cmd == "status") {
      args(0, 0, "status");
      return rt.status();
    }
    if (cmd == "stats") {
      args(0, 0, "stats");
      std::string s;
      for (const TaskStats& t : rt.stats()) {
        if (!s.empty()) s += "; ";
        s += "task " + t.task + ": " + std::to_string(t.scans) + " scans, " + std::to_string(t.overruns) +
             " overruns, scan us min/median/p99/max " + format_us(t.scan_us.min) + "/" + format_us(t.scan_us.median) +
             "/" + format_us(t.scan_us.p99) + "/" + format_us(t.scan_us.max) + ", jitter " + format_us(t.jitter_us.min) +
             "/" + format_us(t.jitter_us.median) + "/" + format_us(t.jitter_us.p99) + "/" + format_us(t.jitter_us.max);
      }
      return s;
    }
    if (cmd == "load") {
      bool strict_here = w.size() > 1 && w[1] == "--strict";
      if (strict_here) w.erase(w.begin() + 1);
      args(1, 2, "load [--strict] [TASK] FILE");
      std::string task = w.size() == 3 ? w[1] : "", file = w.back();
      if (task.empty()) {
        if (rt.task_count() != 1) throw std::runtime_error("the project has several tasks: load TASK FILE");
        task = rt.task_name(0);
      }
      if (rt.find_task(task) == SIZE_MAX) throw std::runtime_error("no task named '" + task + "'");
      Image img = loader(file);  // read and checked in full before anything changes
      return "ok " + rt.replace(task, std::move(img), file, 5000, strict || strict_here).text();
    }
    if (cmd == "restart") {
      args(0, 1, "restart [TASK]");
      std::string task = w.size() == 2 ? w[1] : "";
      if (task.empty()) {
        if (rt.task_count() != 1) throw std::runtime_error("the project has several tasks: restart TASK");
        task = rt.task_name(0);
      }
      size_t i = rt.find_task(task);
      if (i == SIZE_MAX) throw std::runtime_error("no task named '" + task + "'");
      rt.restart_task(i);
      return "ok task " + task + " restarted";
    }
    if (cmd == "wait") {
      args(1, 1, "wait N");
      const std::string& n = w[1];
      if (n.empty() || n.size() > 9 || n.find_first_not_of("0123456789") != std::string::npos)
        throw std::runtime_error("bad scan count '" + n + "'");
      if (!rt.wait_scans(std::stoull(n), 30000)) throw std::runtime_error("timeout waiting for " + n + " scans");
      return "ok";
    }
    if (cmd == "save") {
      args(0, 0, "save");
      std::string e = rt.save_retentive();
      if (!e.empty()) throw std::runtime_error(e);
      return "ok saved";
    }
    if (cmd == "quit" || cmd == "exit") {
      quit = true;
      return "ok bye";
    }
    if (cmd == "help") return kHelp;
    return "error: unknown command '" + w[0] + "' (" + kHelp + ")";
  } catch (std::exception& e) {
    std::string m = e.what();
    for (char& c : m)
      if (c == '\n') c = ' ';
    return "error: " + m;
  }
}

}  // namespace ldc::plc
