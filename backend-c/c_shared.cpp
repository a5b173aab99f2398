// backend-c/c_shared.cpp -- compiling the C route's C into a shared object (c_shared.h).
#include "backend-c/c_shared.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "backend-c/backend_c.h"

extern "C" char** environ;

namespace ldc {

namespace {

// DIR/prog.c: a fresh file in the caller's private directory.
void write_c_file(const std::string& path, const std::string& text) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw CBuildError(path + ": error: cannot create: " + std::strerror(errno));
  bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  ok &= std::fflush(f) == 0;
  ok &= std::fclose(f) == 0;
  if (!ok) throw CBuildError(path + ": error: cannot write: " + std::strerror(errno));
}

std::string compiler_output(const std::string& log) {
  std::ifstream f(log, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Runs argv with its stdout and stderr in `log`; returns the wait status.
int run_logged(const std::vector<std::string>& args, const std::string& log) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid;
  int rc = posix_spawnp(&pid, args[0].c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw CBuildError("error: cannot run the C compiler '" + args[0] + "': " + std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
  return status;
}

}  // namespace

std::string build_c_text(const std::string& text, const std::string& dir, const std::vector<std::string>& extra_flags) {
  std::string c = dir + "/prog.c", so = dir + "/prog.so", log = dir + "/cc.log";
  write_c_file(c, text);
  const char* cc_env = std::getenv("CC");
  std::string cc = cc_env && *cc_env ? cc_env : "cc";
  std::vector<std::string> args = {cc, "-O2", "-shared", "-fPIC", "-ffp-contract=off"};
  args.insert(args.end(), extra_flags.begin(), extra_flags.end());
  for (const char* a : {"-o", so.c_str(), c.c_str(), "-lm"}) args.push_back(a);
  int status = run_logged(args, log);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw CBuildError("error: the C compiler failed on the generated C (" + c + "):\n" + compiler_output(log));
  return so;
}

std::string build_c_shared_object(const Program& p, const std::string& dir) {
  return build_c_text(generate_c(p, p.layout()), dir);
}

}  // namespace ldc
