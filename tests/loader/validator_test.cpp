#include <gtest/gtest.h>

#include <sys/mman.h>
#include <sys/wait.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstring>
#include <random>

#include "runtime/runtime.h"
#include "tests/loader/programs.h"

using namespace ldc;
namespace x86 = ldc::as::x86;

namespace {

std::vector<Program> programs() { return test::examples_and_random_programs(30, 30); }

std::vector<uint8_t> image_bytes(const Program& p, int level) {
  return write_image(make_x86_image(p, build_x86(p, p.source, as::Mode::Blockwise, level, false)));
}

TEST(Validator, AcceptsEveryImageLdcMakes) {
  int n = 0;
  for (const Program& p : programs())
    for (int level : {0, 1, 2}) {
      std::vector<uint8_t> b = image_bytes(p, level);
      EXPECT_NO_THROW(read_image(b, p.source)) << p.source << " -O" << level;
      n++;
    }
  EXPECT_GE(n, 100);
}

// Runs an accepted image for a few scans in a child process, with the memory
// image between PROT_NONE guard pages (ImageBytes); the bytes after the image
// in its last page must be untouched.  Returns "" if the child ran and exited normally.
std::string run_guarded(const Image& img, uint64_t seed) {
  pid_t pid = fork();
  if (pid < 0) return "fork failed";
  if (pid == 0) {
    // An accepted image always ends its scan; a hang is a failure.  Bounded in
    // CPU time (SIGXCPU), which a loaded machine does not use up as it does the
    // wall clock; the alarm is only a backstop for a child that waits.
    struct rlimit cpu {10, 11};
    setrlimit(RLIMIT_CPU, &cpu);
    alarm(300);
    Memory m(img.layout);  // between guard pages, the call table below it
    uint8_t* mem = m.data();
    auto eng = make_native_engine(map_checked_code(img.code, img.entry, img.layout));
    std::mt19937_64 rng(seed);
    for (int scan = 0; scan < 8; scan++) {
      for (uint32_t i = 0; i < 16; i++) mem[img.layout.addr(Area::X, i)] = rng() & 1;
      int32_t dt = int32_t(rng() % 50);
      std::memcpy(mem + kSysDt, &dt, 4);
      eng->scan(m.bytes);
    }
    if (!m.bytes.slack_intact()) _exit(4);
    _exit(0);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  return "exit status " + std::to_string(WEXITSTATUS(status));
}

TEST(Validator, AcceptedImagesRunInsideTheirGuardPages) {
  std::vector<Program> ps = programs();
  for (size_t i = 0; i < ps.size(); i += 7) {
    Image img = read_image(image_bytes(ps[i], int(i % 3)), ps[i].source);
    EXPECT_EQ(run_guarded(img, i), "") << ps[i].source;
  }
}

// Mutations of the code section: each image is refused, or accepted and then
// harmless.
TEST(Validator, MutatedImagesAreRefusedOrHarmless) {
  std::vector<Program> ps = programs();
  std::mt19937_64 rng(20261122);
  const std::vector<std::string> hostile = {
      "ret", "push rax", "pop rbx", "mov rbx, rax", "add rsp, 0x8", "lea rbx, [rbx+0x10]",
      "jmp rax", "call rax", "call qword ptr [rbx+0x40]", "mov eax, dword ptr [rsp+0x8]",
      "mov byte ptr [rbx+0x7fffff00], al", "mov dword ptr [rbx-0x8], eax", "mov eax, dword ptr [rip+0x10]",
      "movzx eax, byte ptr [rax+rbx*1]", "mov byte ptr [rcx+0x10], al"};
  int tried = 0, refused = 0, accepted = 0;
  for (int round = 0; round < 2500; round++) {
    const Program& p = ps[rng() % ps.size()];
    int level = int(rng() % 3);
    Image img = read_image(image_bytes(p, level), p.source);
    img.lines.clear();  // so that only the code check can refuse the mutant
    x86::Disassembly d = x86::disassemble(img.code);
    ASSERT_FALSE(d.error);
    std::vector<uint8_t>& code = img.code;
    const x86::Decoded& victim = d.insts[rng() % d.insts.size()];
    switch (round % 5) {
      case 0: {  // flip a bit anywhere in the code
        size_t at = rng() % code.size();
        code[at] ^= uint8_t(1u << (rng() % 8));
        break;
      }
      case 1: {  // overwrite an instruction with something ldc never emits (syscall, int3, ...)
        size_t pick = rng() % (hostile.size() + 2);
        std::vector<uint8_t> b = pick == hostile.size()     ? std::vector<uint8_t>{0x0f, 0x05}  // syscall
                                 : pick == hostile.size() + 1 ? std::vector<uint8_t>{0xcc}      // int3
                                 : x86::encode_at(x86::parse(hostile[pick]), victim.offset);
        for (size_t k = 0; k < b.size() && victim.offset + k < code.size(); k++) code[victim.offset + k] = b[k];
        break;
      }
      case 2: {  // a jump into the middle of an instruction, forward or backward
        uint32_t target = uint32_t(rng() % code.size());
        std::vector<uint8_t> b = x86::encode_at(x86::make(x86::Mnemonic::Jmp, {x86::Operand::a(target)}), victim.offset);
        for (size_t k = 0; k < b.size() && victim.offset + k < code.size(); k++) code[victim.offset + k] = b[k];
        break;
      }
      case 3: {  // a displacement outside the image: rewrite a disp32 field
        size_t at = victim.offset + (victim.length >= 4 ? victim.length - 4 : 0);
        uint32_t v = uint32_t(rng());
        for (int k = 0; k < 4 && at + k < code.size(); k++) code[at + k] = uint8_t(v >> (8 * k));
        break;
      }
      default: {  // a random byte string over an instruction
        for (uint32_t k = 0; k < victim.length; k++) code[victim.offset + k] = uint8_t(rng());
        break;
      }
    }
    tried++;
    std::vector<uint8_t> bytes = write_image(img);  // a well-formed file around the mutated code
    Image back;
    try {
      back = read_image(bytes, "mutant.bin");
    } catch (const ImageError& e) {
      refused++;
      EXPECT_NE(std::string(e.what()).find("mutant.bin: section 'code'"), std::string::npos) << e.what();
      continue;
    }
    accepted++;
    std::string why = run_guarded(back, uint64_t(round));
    EXPECT_EQ(why, "") << "an accepted mutant of " << p.source << " -O" << level << " misbehaved (round " << round << ")";
  }
  std::printf("%d mutants: %d refused, %d accepted and ran inside their guard pages\n", tried, refused, accepted);
  EXPECT_GT(refused, tried / 2);
}

}  // namespace
