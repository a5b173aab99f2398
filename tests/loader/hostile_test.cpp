// Hostile images, built by hand: each is valid in every field (magic, version,
// layout, sections, IL, CRC) except its intent, one per class of escape of the
// threat model (docs/image-format.md, "Threat model").  Each must be refused
// by read_image with a message naming the file, the section, the offset of the
// hostile instruction and the reason.  Positive controls beside them show that
// the same frame with a harmless body is accepted, so no case passes by being
// malformed in some other way.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <regex>
#include <sstream>

#include "assembler/c40.h"
#include "assembler/x86.h"
#include "assembler/x86_forms.h"
#include "ir/mathfn.h"
#include "loader/loader.h"
#include "runtime/fastinterp.h"
#include "runtime/runtime.h"
#include "runtime/sandbox.h"

#include <fcntl.h>
#include <sys/syscall.h>
#include <unistd.h>

using namespace ldc;
namespace x86 = ldc::as::x86;

namespace {

// ------------------------------------------------------------------ x86-64

// The -O2 frame the tests of base registers build: ldc's (rbp the image,
// pointing kImageBias bytes into it), rbp at the image's start (images made
// before the bias), or rbx (images made before bl was a bit-stack slot); the
// loader takes all three.
struct O2Frame {
  x86::RegNum image;
  int32_t bias;
};
constexpr O2Frame kLdcFrame{x86::image_reg(true), x86::kImageBias}, kUnbiasedFrame{x86::image_reg(true), 0},
    kRbxFrame{x86::BX, 0};
O2Frame g_o2 = kLdcFrame;
std::string img_name() { return std::string(x86::reg_name(x86::r64(g_o2.image))); }

// text with every "IMG" made that frame's image register, and the image
// offset after it in an operand ("[IMG+0x80]", "[IMG+rax*1-0x40]") its
// displacement in that frame, printed as the disassembler prints it
std::string with_image(std::string text) {
  static const std::regex operand(R"(\[IMG((?:\+\w+\*\d)?)([+-])(0x[0-9a-f]+|\d+)\])");
  std::string out;
  std::sregex_iterator it(text.begin(), text.end(), operand), end;
  size_t done = 0;
  for (; it != end; ++it) {
    const std::smatch& m = *it;
    int64_t off = std::stoll(m[3].str(), nullptr, 0) * (m[2] == "-" ? -1 : 1), disp = off - g_o2.bias;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s0x%llx", disp < 0 ? "-" : "+", static_cast<unsigned long long>(disp < 0 ? -disp : disp));
    out += text.substr(done, size_t(m.position()) - done) + "[IMG" + m[1].str() + buf + "]";
    done = size_t(m.position() + m.length());
  }
  text = out + text.substr(done);
  for (size_t at; (at = text.find("IMG")) != std::string::npos;) text.replace(at, 3, img_name());
  return text;
}
// the loader's words for a base register set to image offset k
std::string sets(const std::string& reg, int64_t k) {
  return "sets " + reg + " = " + img_name() + "+" + std::to_string(k - g_o2.bias) +
         (g_o2.bias ? " (image offset " + std::to_string(k) + ")" : "");
}

std::span<const x86::Instruction> o2_prologue() {
  if (g_o2.image == x86::BX) return x86::scan_prologue_rbx_slots();
  return g_o2.bias ? x86::scan_prologue(true) : x86::scan_prologue_unbiased();
}

// One instruction of a hostile body: GNU-as-style Intel syntax that our
// assembler encodes (branch targets are offsets from the body's start), or
// "raw: 0f 05" for bytes it would never produce.
std::vector<uint8_t> piece(const std::string& text, size_t at, size_t body) {
  if (text.rfind("raw:", 0) == 0) {
    std::vector<uint8_t> b;
    std::istringstream in(text.substr(4));
    for (std::string h; in >> h;) b.push_back(uint8_t(std::stoul(h, nullptr, 16)));
    return b;
  }
  x86::Instruction in = x86::parse(with_image(text));
  if (in.num_operands && in.ops[0].kind == x86::OperandKind::Address) in.ops[0].imm += int64_t(body);
  return x86::encode_at(in, at);
}

const uint32_t kSize = Layout::standard(0).size;
// The base registers' offsets of the -O2 frames built here, at the ends of
// the range the validator accepts: rdi's window [K0-0x80, K0+0x7f] starts at
// the image's first byte, r15's 8-byte accesses end at its last byte
// (K1 = size - 135), r14's is in the middle.
const int32_t kKMin = 0x80, kKMax = int32_t(kSize) - 135;
const int32_t kK0 = kKMin, kK1 = kKMax, kK2 = 0x1000;

// A branch target "@N" in a body piece: piece N (its offset from the body's
// start, from `at`, the pieces' offsets), so that the target follows the
// sizes the frame's displacements give the pieces before it.
std::string at_piece(std::string text, const std::vector<uint32_t>& at) {
  size_t p = text.find('@');
  if (p == std::string::npos) return text;
  size_t n = std::stoul(text.substr(p + 1));
  char target[16];
  std::snprintf(target, sizeof target, "0x%x", n < at.size() ? at[n] - at[0] : 0u);
  return text.replace(p, std::string::npos, target);
}

// A scan function: the -O0 prologue (the -O2 one with `slots`, followed by
// its base registers' leas, `leas` of them, with K0 and K1), the body, the
// epilogue; `offsets` gets the code offset of every body piece.
std::vector<uint8_t> scan_function(const std::vector<std::string>& body, std::vector<uint32_t>& offsets,
                                   bool slots = false, int leas = x86::kNumBases, int32_t k0 = kK0, int32_t k1 = kK1) {
  if (std::any_of(body.begin(), body.end(), [](const std::string& t) { return t.find('@') != std::string::npos; })) {
    std::vector<std::string> placed;
    for (const std::string& t : body) placed.push_back(at_piece(t, {}));  // "@N" as 0: the pieces' sizes
    scan_function(placed, offsets, slots, leas, k0, k1);
    placed.clear();
    for (const std::string& t : body) placed.push_back(at_piece(t, offsets));
    return scan_function(placed, offsets, slots, leas, k0, k1);
  }
  std::vector<uint8_t> code;
  auto put = [&](const std::vector<uint8_t>& b) { code.insert(code.end(), b.begin(), b.end()); };
  for (const auto& in : slots ? o2_prologue() : x86::scan_prologue(false)) put(x86::encode_at(in, code.size()));
  for (int i = 0; slots && i < leas; i++)
    put(x86::encode_at(x86::base_lea(x86::kBaseRegs[i], (i == 0 ? k0 : i == 1 ? k1 : kK2) - g_o2.bias, g_o2.image), code.size()));
  const size_t base = code.size();
  offsets.clear();
  for (const std::string& t : body) {
    offsets.push_back(uint32_t(code.size()));
    put(piece(t, code.size(), base));
  }
  for (const auto& in : x86::scan_epilogue(slots)) put(x86::encode_at(in, code.size()));
  return code;
}

// An image valid in every field: the IL `LOAD X0 / OUT Y0`, `edges` edge slots.
Image image_around(std::vector<uint8_t> code, uint32_t edges = 0) {
  Program p = parse_il_text(".rung line 1 \"hostile\"\nLOAD X0\nOUT Y0\n.end\n", "hostile.il");
  p.edge_slots = edges;
  Image im;
  im.source = "hostile.ld";
  im.layout = p.layout();
  im.code = std::move(code);
  im.entry = 0;
  im.il = encode_il(p).code;
  return im;
}

std::string refusal(const Image& im) {
  try {
    read_image(write_image(im), "hostile.bin");
  } catch (const ImageError& e) {
    return e.what();
  }
  return "";
}

std::string hex(uint64_t v) {
  char b[24];
  std::snprintf(b, sizeof b, "0x%llx", (unsigned long long)v);
  return b;
}

struct Case {
  const char* klass;
  std::vector<std::string> body;
  size_t hostile;      // index of the piece the validator must name
  const char* reason;  // in the message after the offset
};

const std::string S = hex(kSize);             // one past the image
const std::string S1 = hex(kSize - 1);        // its last byte
const std::string S3 = hex(kSize - 3), S4 = hex(kSize - 4), S7 = hex(kSize - 7), S8 = hex(kSize - 8);

const std::vector<Case>& cases() {
  static const std::vector<Case> c = {
      // writes to control data: the REAL function table, the frame, the code
      {"control data: the table hijack of issue 12",
       {"mov dword ptr [rbx+0x10], 0x41414141", "mov dword ptr [rbx+0x14], 0x0", "call qword ptr [rbx+0x10]"}, 2,
       "indirect call not through the REAL function table"},
      {"control data: overwrite a slot of the read-only table", {"mov dword ptr [rbx-0x40], 0x41414141"}, 0,
       "outside the memory image"},
      {"control data: overwrite the table with a qword", {"mov qword ptr [rbx-0x38], rax"}, 0, "outside the memory image"},
      {"control data: the return address", {"mov qword ptr [rsp+0x18], rax"}, 0, "stack-relative memory operand based on rsp"},
      {"control data: the saved registers through rbp", {"mov dword ptr [rbp+0x8], eax"}, 0, "stack-relative memory operand based on rbp"},
      {"control data: the code itself", {"mov byte ptr [rip+0x0], 0x0"}, 0, "rip-relative memory operand"},
      {"control data: through another base register", {"mov byte ptr [rcx+0x10], al"}, 0, "memory operand based on rcx, not rbx"},
      // indirect branches, every form
      {"indirect branch: jmp reg", {"jmp rax"}, 0, "indirect branch through a register"},
      {"indirect branch: call reg", {"call rax"}, 0, "indirect branch through a register"},
      {"indirect branch: jmp r11", {"raw: 41 ff e3"}, 0, "indirect branch through a register"},
      {"indirect branch: jmp mem", {"jmp qword ptr [rbx-0x40]"}, 0, "indirect branch through memory"},
      {"indirect branch: call through the image", {"call qword ptr [rbx+0x40]"}, 0, "indirect call not through the REAL function table"},
      {"indirect branch: call inside a slot", {"call qword ptr [rbx-0x3c]"}, 0, "indirect call not through the REAL function table"},
      {"indirect branch: call below the tables", {"call qword ptr [rbx-0xa0]"}, 0, "indirect call not through the REAL function table"},
      {"indirect branch: call inside a math slot", {"call qword ptr [rbx-0x8c]"}, 0, "indirect call not through the REAL function table"},
      {"indirect branch: call past the table", {"call qword ptr [rbx-0x18]"}, 0, "indirect call not through the REAL function table"},
      {"indirect branch: indexed call into the table", {"call qword ptr [rbx+rcx*8-0x40]"}, 0, "indirect call not through the REAL function table"},
      {"indirect branch: call through another base", {"call qword ptr [rcx-0x40]"}, 0, "indirect call not through the REAL function table"},
      {"indirect branch: ret in the body", {"ret"}, 0, "the stack is touched only by the prologue and the epilogue"},
      {"indirect branch: far call", {"raw: ff 1b"}, 0, "undecodable bytes ff 1b"},
      {"indirect branch: far jmp", {"raw: ff 2b"}, 0, "undecodable bytes ff 2b"},
      {"indirect branch: iret", {"raw: 48 cf"}, 0, "undecodable bytes 48 cf"},
      {"indirect branch: syscall", {"raw: 0f 05"}, 0, "undecodable bytes 0f 05"},
      {"indirect branch: int 0x80", {"raw: cd 80"}, 0, "undecodable bytes cd 80"},
      // backward branches and loops
      {"loop: jmp to itself", {"raw: eb fe"}, 0, "backward branch"},
      {"loop: jcc back", {"nop", "jne 0x0"}, 1, "backward branch"},
      {"loop: jmp rel32 into the prologue", {"jmp -0x8"}, 0, "backward branch"},
      {"loop: the loop instruction", {"raw: e2 fe"}, 0, "undecodable bytes e2 fe"},
      {"loop: jrcxz", {"raw: e3 00"}, 0, "undecodable bytes e3 00"},
      {"loop: a direct call", {"call 0x5", "nop"}, 0, "a direct call"},
      {"loop: a branch past the epilogue", {"jmp 0x40"}, 0, "outside the scan body"},
      // writes to rbx or rsp, every width, and implicit writes
      {"fixed registers: mov rbx", {"mov rbx, rax"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: mov ebx", {"mov ebx, eax"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: mov bl", {"mov bl, al"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: mov bh (no REX)", {"raw: 88 c7"}, 0, "undecodable bytes 88 c7"},
      {"fixed registers: movzx ebx", {"movzx ebx, al"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: lea rbx", {"lea rbx, [rbx+0x10]"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: setcc bl", {"setne bl"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: cmovcc ebx", {"cmovne ebx, eax"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: xor ebx", {"xor ebx, ebx"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: not ebx", {"not ebx"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: shl ebx", {"shl ebx, 0x1"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: imul ebx", {"imul ebx, eax"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: movd ebx", {"movd ebx, xmm0"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: cvttss2si ebx", {"cvttss2si ebx, xmm0"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: add esp", {"add esp, 0x8"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: mov spl", {"mov spl, al"}, 0, "the image base and the stack pointer are fixed"},
      {"fixed registers: mov rsp", {"mov rsp, rax"}, 0, "the image base and the stack pointer are fixed"},
      {"callee-saved: r12 in the -O0 frame", {"mov r12, rax"}, 0, "which the caller owns: only the -O2 frame saves r12-r15"},
      {"callee-saved: r15b in the -O0 frame", {"setne r15b"}, 0, "which the caller owns"},
      {"callee-saved: r13d in the -O0 frame", {"xor r13d, r13d"}, 0, "which the caller owns"},
      {"fixed registers: pop rbx", {"pop rbx"}, 0, "the stack is touched only by the prologue and the epilogue"},
      {"fixed registers: push", {"push rax"}, 0, "the stack is touched only by the prologue and the epilogue"},
      {"implicit write: xchg rbx, rax", {"raw: 48 93"}, 0, "undecodable bytes 48 93"},
      {"implicit write: cpuid", {"raw: 0f a2"}, 0, "undecodable bytes 0f a2"},
      {"implicit write: div ebx", {"raw: f7 f3"}, 0, "a division not guarded"},
      {"implicit write: leave", {"raw: c9"}, 0, "undecodable bytes c9"},
      {"implicit write: popf", {"raw: 9d"}, 0, "undecodable bytes 9d"},
      {"implicit write: pop rsp", {"raw: 5c"}, 0, "the stack is touched only by the prologue and the epilogue"},
      {"implicit write: bswap ebx", {"raw: 0f cb"}, 0, "undecodable bytes 0f cb"},
      {"implicit write: xadd", {"raw: 48 0f c1 d8"}, 0, "undecodable bytes 48 0f c1 d8"},
      {"string instruction: stosb", {"raw: aa"}, 0, "undecodable bytes aa"},
      {"string instruction: rep movsb", {"raw: f3 a4"}, 0, "undecodable bytes f3 a4"},
      {"string instruction: rep stosq", {"raw: f3 48 ab"}, 0, "undecodable bytes f3 48 ab"},
      // division: #DE (divisor 0, or INT_MIN / -1) would kill the process, so
      // idiv stands only at the end of ldc's guard, and nothing jumps past the guard
      {"division: unguarded idiv", {"mov ecx, 0x0", "cdq", "idiv ecx"}, 2, "a division not guarded against 0 and -1"},
      {"division: -1 not tested", {"test ecx, ecx", "je 0x7", "cdq", "idiv ecx", "nop"}, 3, "a division not guarded"},
      {"division: the guard tests another register", {"test eax, eax", "je 0xc", "cmp ecx, -0x1", "je 0xc", "cdq", "idiv ecx", "nop"},
       5, "a division not guarded"},
      {"division: a memory divisor", {"test ecx, ecx", "je 0xd", "cmp ecx, -0x1", "je 0xd", "cdq", "idiv dword ptr [rbx+0x50]", "nop"},
       5, "a division not guarded"},
      {"division: a branch past the test", {"jmp 0xb", "test ecx, ecx", "je 0xe", "cmp ecx, -0x1", "je 0xe", "cdq", "idiv ecx", "nop"},
       0, "is inside a guarded division"},
      {"division: a branch onto the idiv", {"jmp 0xc", "test ecx, ecx", "je 0xe", "cmp ecx, -0x1", "je 0xe", "cdq", "idiv ecx", "nop"},
       0, "is inside a guarded division"},
      // the -O2 guard: a divisor of 0 or -1 (ecx+1 unsigned <= 1) becomes 1 (as::x86::safe_divisor)
      {"division: safe guard with cmovb (lets -1 through)",
       {"lea edx, [rcx+0x1]", "cmp edx, 0x1", "mov edx, 0x1", "cmovb ecx, edx", "cdq", "idiv ecx"}, 5, "a division not guarded"},
      {"division: safe guard compares 0",
       {"lea edx, [rcx+0x1]", "cmp edx, 0x0", "mov edx, 0x1", "cmovbe ecx, edx", "cdq", "idiv ecx"}, 5, "a division not guarded"},
      {"division: safe guard replaces by 0",
       {"lea edx, [rcx+0x1]", "cmp edx, 0x1", "mov edx, 0x0", "cmovbe ecx, edx", "cdq", "idiv ecx"}, 5, "a division not guarded"},
      {"division: safe guard of another register",
       {"lea edx, [rax+0x1]", "cmp edx, 0x1", "mov edx, 0x1", "cmovbe ecx, edx", "cdq", "idiv ecx"}, 5, "a division not guarded"},
      {"division: safe guard, then ecx written",
       {"lea edx, [rcx+0x1]", "cmp edx, 0x1", "mov edx, 0x1", "cmovbe ecx, edx", "xor ecx, ecx", "cdq", "idiv ecx"}, 6,
       "a division not guarded"},
      {"division: a branch past the safe guard's compare",
       {"jmp 0x8", "lea edx, [rcx+0x1]", "cmp edx, 0x1", "mov edx, 0x1", "cmovbe ecx, edx", "cdq", "idiv ecx", "nop"},
       0, "is inside a guarded division"},
      // the typed instructions' divisions (docs/x86.md, "Typed instructions"): 64-bit and unsigned
      {"division: 64-bit idiv, -1 not tested", {"test rcx, rcx", "je @4", "cqo", "idiv rcx", "nop"}, 3, "a division not guarded"},
      {"division: 64-bit idiv after cdq", {"test rcx, rcx", "je @6", "cmp rcx, -0x1", "je @6", "cdq", "idiv rcx", "nop"}, 5,
       "a division not guarded"},
      {"division: div with edx not cleared", {"test ecx, ecx", "je @3", "div ecx", "nop"}, 2, "a division not guarded"},
      {"division: div of 0 not tested", {"xor edx, edx", "div ecx"}, 1, "a division not guarded"},
      {"division: div rcx, its test of ecx", {"test ecx, ecx", "je @4", "xor edx, edx", "div rcx", "nop"}, 3, "a division not guarded"},
      {"division: a branch onto the div", {"jmp @4", "test ecx, ecx", "je @5", "xor edx, edx", "div ecx", "nop"}, 0,
       "is inside a guarded division"},
      // indexed accesses (the typed LDX / STX): each right after its bounds
      // check `cmp r, n; ja` on its own index register, every byte it may
      // reach inside the image, and no branch past the check
      {"indexed: no bounds check", {"mov eax, dword ptr [rbx+r11*4+0x100]"}, 0, "indexed memory operand without its bounds check"},
      {"indexed: the check of another register", {"cmp r10, 0x3", "ja @3", "mov eax, dword ptr [rbx+r11*4+0x100]", "nop"}, 2,
       "indexed memory operand without its bounds check"},
      {"indexed: the check's 32-bit form", {"cmp r11d, 0x3", "ja @3", "mov eax, dword ptr [rbx+r11*4+0x100]", "nop"}, 2,
       "indexed memory operand without its bounds check"},
      {"indexed: jb for ja", {"cmp r11, 0x3", "jb @3", "mov dword ptr [rbx+r11*4+0x100], eax", "nop"}, 2,
       "indexed memory operand without its bounds check"},
      {"indexed: a signed test", {"cmp r11, 0x3", "jg @3", "mov dword ptr [rbx+r11*4+0x100], eax", "nop"}, 2,
       "indexed memory operand without its bounds check"},
      {"indexed: the index written after its check", {"cmp r11, 0x3", "ja @4", "mov r11, rax", "mov eax, dword ptr [rbx+r11*4+0x100]", "nop"},
       3, "indexed memory operand without its bounds check"},
      {"indexed: a negative bound", {"cmp r11, -0x1", "ja @3", "mov eax, dword ptr [rbx+r11*4+0x100]", "nop"}, 2,
       "indexed memory operand without its bounds check"},
      {"indexed: the extent leaves the image", {"cmp r11, 0x10000000", "ja @3", "mov qword ptr [rbx+r11*8+0x100], rax", "nop"}, 2,
       "its bounds check lets it reach"},
      {"indexed: the last element one byte past", {"cmp r11, " + hex((kSize - 0x100 - 4) / 4 + 1), "ja @3",
       "mov dword ptr [rbx+r11*4+0x100], eax", "nop"}, 2, "its bounds check lets it reach"},
      {"indexed: the first element below the image", {"cmp r11, 0x3", "ja @3", "mov eax, dword ptr [rbx+r11*4-0x4]", "nop"}, 2,
       "its bounds check lets it reach"},
      {"indexed: based on another register", {"cmp r11, 0x3", "ja @3", "mov eax, dword ptr [rcx+r11*4+0x100]", "nop"}, 2,
       "indexed memory operand based on rcx"},
      {"indexed: a jump onto the access", {"jmp @3", "cmp r11, 0x3", "ja @4", "mov eax, dword ptr [rbx+r11*4+0x100]", "nop"}, 0,
       "or an indexed access's bounds check"},
      {"indexed: a jump onto the ja", {"jmp @2", "cmp r11, 0x3", "ja @4", "mov eax, dword ptr [rbx+r11*4+0x100]", "nop"}, 0,
       "or an indexed access's bounds check"},
      // branches into the middle of an instruction
      {"mid-instruction: jmp", {"jmp 0x4", "mov eax, 0xc3c3c3c3"}, 0, "is inside an instruction, not on an instruction boundary"},
      {"mid-instruction: jcc rel32", {"raw: 0f 85 01 00 00 00", "mov eax, 0x90909090"}, 0,
       "is inside an instruction, not on an instruction boundary"},
      // prefixes
      {"prefix: fs segment", {"raw: 64 8b 43 50"}, 0, "undecodable bytes 64 8b 43 50"},
      {"prefix: gs segment", {"raw: 65 8b 43 50"}, 0, "undecodable bytes 65 8b 43 50"},
      {"prefix: cs branch hint", {"raw: 2e 74 00"}, 0, "undecodable bytes 2e 74 00"},
      {"prefix: lock", {"raw: f0 01 43 50"}, 0, "undecodable bytes f0 01 43 50"},
      {"prefix: rep on a mov", {"raw: f3 89 43 50"}, 0, "undecodable bytes f3 89 43 50"},
      {"prefix: repne", {"raw: f2 89 43 50"}, 0, "undecodable bytes f2 89 43 50"},
      {"prefix: address size ([ebx])", {"raw: 67 8b 43 50"}, 0, "undecodable bytes 67 8b 43 50"},
      {"prefix: operand size (a word store)", {"raw: 66 89 43 50"}, 0, "undecodable bytes 66 89 43 50"},
      {"prefix: two REX", {"raw: 40 48 89 c0"}, 0, "undecodable bytes 40 48 89 c0"},
      // rip-relative and absolute operands
      {"addressing: rip-relative read", {"mov eax, dword ptr [rip+0x10]"}, 0, "rip-relative memory operand"},
      {"addressing: absolute (SIB, no base)", {"raw: 8b 04 25 00 10 00 00"}, 0, "absolute memory operand"},
      {"addressing: moffs", {"raw: a1 00 10 00 00 00 00 00 00"}, 0, "undecodable bytes a1"},
      {"addressing: indexed", {"movzx eax, byte ptr [rbx+rcx*1]"}, 0, "indexed memory operand"},
      // displacements one byte outside the layout
      {"displacement: a byte one past the image", {"movzx eax, byte ptr [rbx+" + S + "]"}, 0, "outside the memory image"},
      {"displacement: a dword one byte past", {"mov dword ptr [rbx+" + S3 + "], eax"}, 0, "outside the memory image"},
      {"displacement: a REAL one byte past", {"movss dword ptr [rbx+" + S3 + "], xmm0"}, 0, "outside the memory image"},
      {"displacement: a qword one byte past", {"mov qword ptr [rbx+" + S7 + "], rax"}, 0, "outside the memory image"},
      {"displacement: one byte below", {"mov byte ptr [rbx-0x1], al"}, 0, "outside the memory image"},
      {"displacement: a huge disp32", {"mov byte ptr [rbx+0x7fffffff], al"}, 0, "outside the memory image"},
  };
  return c;
}

TEST(Hostile, EveryClassOfEscapeIsRefusedAtItsOffset) {
  int n = 0;
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.klass);
    std::vector<uint32_t> at;
    std::string why = refusal(image_around(scan_function(c.body, at)));
    std::string where = "hostile.bin: section 'code' at offset ";
    ASSERT_EQ(why.rfind(where, 0), 0u) << why;
    std::string off = ": at code offset " + hex(at[c.hostile]) + ": ";
    EXPECT_NE(why.find(off), std::string::npos) << why << "\n(want the offset " << hex(at[c.hostile]) << ")";
    EXPECT_NE(why.find(c.reason), std::string::npos) << why;
    if (getenv("LDC_HOSTILE_VERBOSE")) std::printf("%-48s %s\n", c.klass, why.c_str());
    n++;
  }
  EXPECT_GE(n, 80);
}

// Hand-made IL for the IL-section attacks below: a device operand, an integer
// constant, a typed instruction, and the rung heads TRUE, LOAD X0, JMP l.
Operand il_dev(Area a, uint32_t i) {
  Operand o;
  o.area = a, o.index = i, o.kind = area_is_bit(a) ? OpdKind::Bit : OpdKind::Int;
  return o;
}
Operand il_int(int32_t v) {
  Operand o;
  o.kind = OpdKind::ConstInt, o.ival = v;
  return o;
}
Instr il_typed(Op op, Ty t, Ty u, Operand a, Operand b, Operand c = {}) {
  Instr in;
  in.op = op, in.ty = t, in.src = u, in.a[0] = a, in.a[1] = b, in.a[2] = c;
  return in;
}
Instr il_op(Op op, Operand a = {}) {
  Instr in;
  in.op = op, in.a[0] = a;
  return in;
}
Instr il_jmp_l() {
  Instr in;
  in.op = Op::JMP, in.a[0].kind = OpdKind::Label, in.a[0].label = "l";
  return in;
}

struct IlCase {
  const char* what;
  std::vector<std::vector<Instr>> rungs;  // the last rung's first instruction after a label "l" if jumped to
  size_t at;                              // the refused instruction: its index in the program
  const char* reason;
};

// The case's rungs as an image's IL section: refused at the IL offset of its
// instruction `at`, for its reason.
void expect_il_refused(const IlCase& c) {
  SCOPED_TRACE(c.what);
  Program p;
  p.source = "hostile.il";
  for (size_t r = 0; r < c.rungs.size(); r++) {
    Rung rung;
    rung.line = int(r) + 1;
    rung.code = c.rungs[r];
    if (r == 2) rung.labels.push_back("l");
    p.rungs.push_back(rung);
  }
  Image im = image_around({});
  std::vector<uint32_t> at;
  im.code = scan_function({"nop"}, at);
  BinaryIl bin = encode_il(p);
  im.il = bin.code;
  std::string why = refusal(im);
  EXPECT_NE(why.find("hostile.bin: section 'il' at offset "), std::string::npos) << why;
  EXPECT_NE(why.find("offset " + std::to_string(bin.instr_offset[c.at]) + ": "), std::string::npos)
      << why << " (want the IL offset " << bin.instr_offset[c.at] << ")";
  EXPECT_NE(why.find(c.reason), std::string::npos) << why;
}

// The typed IL's arrays (docs/il.md, "Index faults"): the image's IL section
// is refused, naming the section and the instruction's offset, for an LDX not
// right after an IDX, an array whose last element leaves its area, and a
// jump onto an LDX past its IDX.  Programs built directly (the IL text reader
// refuses them before).
TEST(Hostile, TypedArraysInTheIlSection) {
  const Instr truth = il_op(Op::TRUE), load_x0 = il_op(Op::LOAD, il_dev(Area::X, 0)), jmp = il_jmp_l();
  const Instr idx = il_typed(Op::TIDX, Ty::INT, Ty::None, il_dev(Area::D, 9), il_int(1), il_int(10));
  const Instr ldx = il_typed(Op::TLDX, Ty::DINT, Ty::None, il_dev(Area::D, 20), il_int(1), il_dev(Area::D, 16));
  const Instr move = il_typed(Op::TMOVE, Ty::INT, Ty::None, Operand::typed_const(1), il_dev(Area::D, 0));
  // 8185 + 9 + 1 > 8191
  const Instr far_ldx = il_typed(Op::TLDX, Ty::LINT, Ty::None, il_dev(Area::D, 8185), il_int(1), il_dev(Area::D, 16));
  for (const IlCase& c : std::vector<IlCase>{
           {"an LDX not after an IDX", {{truth, move, ldx}}, 2, "LDX not right after an IDX"},
           {"an LDX whose array leaves its area", {{truth, idx, far_ldx}}, 2, "extends past its area"},
           {"a jump onto an LDX", {{load_x0, jmp}, {truth, idx}, {ldx}}, 1, "jump to an LDX / STX past its IDX"},
       })
    expect_il_refused(c);
}

// STRING operands in the IL section (docs/il.md, "Strings"): a string whose 33
// cells leave their area, a STRING constant, a MID not right after its ARGS or
// jumped to, a CONV from STRING to STRING: each refused at its offset.
TEST(Hostile, StringsInTheIlSection) {
  const Instr truth = il_op(Op::TRUE), load_x0 = il_op(Op::LOAD, il_dev(Area::X, 0)), jmp = il_jmp_l();
  const uint32_t d_count = Layout::standard(0).count[int(Area::D)];
  const Instr args = il_typed(Op::TARGS, Ty::DINT, Ty::None, Operand::typed_const(1), Operand::typed_const(2));
  const Instr mid = il_typed(Op::TMID, Ty::STRING, Ty::None, il_dev(Area::D, 0), il_dev(Area::D, 100));
  const Instr past_end = il_typed(Op::TMOVE, Ty::STRING, Ty::None, il_dev(Area::D, 0), il_dev(Area::D, d_count - 32));
  const Instr konst = il_typed(Op::TMOVE, Ty::STRING, Ty::None, Operand::typed_const(3), il_dev(Area::D, 100));
  const Instr twice = il_typed(Op::TCONV, Ty::STRING, Ty::STRING, il_dev(Area::D, 0), il_dev(Area::D, 100));
  for (const IlCase& c : std::vector<IlCase>{
           {"a STRING whose last cell is past D", {{truth, past_end}}, 1, "cannot hold this STRING operand"},
           {"a STRING constant", {{truth, konst}}, 1, "a STRING operand is a device"},
           {"a MID not after an ARGS", {{truth, mid}}, 1, "MID not right after an ARGS"},
           {"a jump onto a MID", {{load_x0, jmp}, {truth, args}, {mid}}, 1, "past its ARGS"},
           {"CONV from STRING to STRING", {{truth, twice}}, 1, "does not take type STRING.STRING"},
       })
    expect_il_refused(c);
}

// What an image's memory holds in a length cell is untrusted: 0x7fffffff,
// -1, 127, lengths and positions of INT64's extremes.  Every string
// instruction on the last string that fits in D, run by both interpreters,
// changes no byte outside its destination's 132 bytes and S0, and reads a
// length of 126 (its watched results are MatIEC's for 126 bytes).
TEST(Hostile, StringLengthCellsAreClamped) {
  const Layout L = Layout::standard(0);
  const uint32_t last = L.count[int(Area::D)] - 33;  // the last STRING that fits in D
  auto d = [](uint32_t i) {
    Operand o;
    o.area = Area::D, o.index = i, o.kind = OpdKind::Int;
    return o;
  };
  auto k = [](int64_t v) { return Operand::typed_const(uint64_t(v)); };
  auto typed = [](Op op, Ty t, Ty u, Operand a, Operand b, Operand c = {}) {
    Instr in;
    in.op = op, in.ty = t, in.src = u, in.a[0] = a, in.a[1] = b, in.a[2] = c;
    return in;
  };
  Instr truth;
  truth.op = Op::TRUE;
  const int64_t big = INT64_MAX, small = INT64_MIN;
  // each rung writes the string at `last` (or a LINT at D0), reading it too
  const std::vector<std::vector<Instr>> rungs = {
      {truth, typed(Op::TLEN, Ty::LINT, Ty::STRING, d(last), d(0))},
      {truth, typed(Op::TCONCAT, Ty::STRING, Ty::None, d(last), d(last), d(last))},
      {truth, typed(Op::TARGS, Ty::LINT, Ty::None, k(big), k(0)), typed(Op::TMID, Ty::STRING, Ty::None, d(last), d(last))},
      {truth, typed(Op::TARGS, Ty::LINT, Ty::None, k(big), k(big)), typed(Op::TINSERT, Ty::STRING, Ty::None, d(last), d(last), d(last))},
      {truth, typed(Op::TARGS, Ty::LINT, Ty::None, k(big), k(big)), typed(Op::TREPLACE, Ty::STRING, Ty::None, d(last), d(last), d(last))},
      {truth, typed(Op::TARGS, Ty::LINT, Ty::None, k(small), k(1)), typed(Op::TDELETE, Ty::STRING, Ty::None, d(last), d(last))},
      {truth, typed(Op::TLEFT, Ty::STRING, Ty::LINT, d(last), k(big), d(last))},
      {truth, typed(Op::TRIGHT, Ty::STRING, Ty::LINT, d(last), k(big), d(last))},
      {truth, typed(Op::TFIND, Ty::LINT, Ty::STRING, d(last), d(last), d(2))},
      {truth, typed(Op::TCONV, Ty::LREAL, Ty::STRING, d(last), d(4))},
      {truth, typed(Op::TCONV, Ty::STRING, Ty::LREAL, d(4), d(last))},
  };
  for (int32_t length : {INT32_MAX, -1, 127, INT32_MIN}) {
    for (size_t r = 0; r < rungs.size(); r++)
      for (int engine = 0; engine < 2; engine++) {
        SCOPED_TRACE("length cell " + std::to_string(length) + ", rung " + std::to_string(r) + (engine ? ", fast" : ", interp"));
        Program p;
        p.source = "hostile.il";
        Rung rung;
        rung.line = 1;
        rung.code = rungs[r];
        p.rungs.push_back(rung);
        BinaryIl bin = encode_il(p);
        ASSERT_EQ(validate_il(bin.code, L), "");
        ImageBytes mem(L.size);
        std::memset(mem.data(), 0xA5, L.size);  // '.'-free bytes everywhere, the string's body too
        const uint32_t at = L.addr(Area::D, last);
        std::memcpy(mem.data() + at, &length, 4);
        std::vector<uint8_t> before(mem.data(), mem.data() + L.size);
        if (engine == 0) Interpreter(bin.code, L).scan(mem.data());
        else FastInterpreter(bin.code, L).scan(mem);
        const uint32_t s0 = L.addr(Area::S, kBitError), d0 = L.addr(Area::D, 0);
        for (uint32_t b = 0; b < L.size; b++) {
          const bool dest = (b >= at && b < at + 132) || b == s0 || (b >= d0 && b < d0 + 24);
          if (!dest && mem.data()[b] != before[b]) {
            ADD_FAILURE() << "byte " << b << " outside the destination changed";
            break;
          }
        }
        uint32_t len;
        std::memcpy(&len, mem.data() + at, 4);
        if (r != 0 && r != 8 && r != 9) { EXPECT_LE(len, 126u); }  // a string result (the others only read it)
        if (r == 0) {
          int64_t n;
          std::memcpy(&n, mem.data() + d0, 8);
          EXPECT_EQ(n, 126);  // LEN of any length cell outside 0..126 is 126
        }
      }
  }
}

// The frame and the checks are not refusing everything: the harmless twins of
// the cases above are accepted.
TEST(Hostile, HarmlessTwinsAreAccepted) {
  const std::vector<std::vector<std::string>> ok = {
      {"call qword ptr [rbx-0x40]", "call qword ptr [rbx-0x20]"},           // sinf, logf
      {"mov dword ptr [rbx+0x10], 0x41414141"},                             // Sys+16 is plain reserved memory now
      {"movzx eax, byte ptr [rbx+" + S1 + "]", "mov dword ptr [rbx+" + S4 + "], eax"},
      {"movss dword ptr [rbx+" + S4 + "], xmm0", "mov qword ptr [rbx+" + S8 + "], rax"},
      {"jmp 0x2", "nop", "nop", "jne 0x6"},                                  // forward, to boundaries and to the exit
      {"mov eax, ebx", "lea eax, [rbx+0x10]", "cmp ebx, eax", "test ebx, ebx"},  // rbx read, not written
      {"jmp 0x2", "test ecx, ecx", "je 0xe", "cmp ecx, -0x1", "je 0xe", "cdq", "idiv ecx", "nop"},  // into the guard's test
      {"lea edx, [rcx+0x1]", "cmp edx, 0x1", "mov edx, 0x1", "cmovbe ecx, edx", "cdq", "idiv ecx"},  // the -O2 guard
      // the typed instructions': the math table's first and last slots, the
      // 64-bit and unsigned divisions, indexed accesses after their checks
      // (the last byte of the image reachable, a jump onto the check itself)
      {"call qword ptr [rbx-0x90]", "call qword ptr [rbx-0x48]"},  // log, pow
      {"test rcx, rcx", "je @6", "cmp rcx, -0x1", "je @6", "cqo", "idiv rcx", "nop"},
      {"test ecx, ecx", "je @4", "xor edx, edx", "div ecx", "test rcx, rcx", "je @8", "xor edx, edx", "div rcx", "nop"},
      {"jmp @1", "cmp r11, 0x3", "ja @4", "mov eax, dword ptr [rbx+r11*4+0x100]", "nop"},
      {"cmp r10, " + hex(kSize - 0x10 - 8), "ja @3", "mov qword ptr [rbx+r10*1+0x10], rax", "imul r10, r11, 0xc",
       "cmp r10, 0x24", "ja @7", "movsx eax, word ptr [rbx+r10*1+0x100]", "nop"},
  };
  for (const auto& body : ok) {
    std::vector<uint32_t> at;
    EXPECT_EQ(refusal(image_around(scan_function(body, at))), "") << body[0];
  }
  std::vector<uint32_t> at;  // the -O2 frame saves r12-r15, so its body may use them
  EXPECT_EQ(refusal(image_around(scan_function({"mov r12, rax", "setne r13b", "xor r13d, r13d"}, at, true))), "");
}

// Loops (docs/image-format.md, "Loops"): the one backward branch is a loop's
// counted back edge, `add dword [rbx+0x18], 1; cmp dword [rbx+0x18], B; jae
// <forward>; jmp <back>` with B <= the budget (100,000 = 0x186a0), and nothing
// but such adds writes the counter inside the loop.  Each attack is the
// accepted loop with one thing changed; the validator names the piece.
TEST(Hostile, LoopsTakeOnlyCountedBackEdges) {
  const std::string reset = "mov dword ptr [rbx+0x18], 0x0", add = "add dword ptr [rbx+0x18], 0x1",
                    cmp = "cmp dword ptr [rbx+0x18], 0x186a0";
  std::vector<uint32_t> at;
  EXPECT_EQ(refusal(image_around(scan_function({reset, "nop", add, cmp, "jae @6", "jmp @1", "nop"}, at))), "");
  EXPECT_EQ(refusal(image_around(scan_function({reset, "nop", add, "cmp dword ptr [rbx+0x18], 0x3", "jae @6", "jmp @1", "nop"}, at))), "")
      << "a smaller budget";
  const std::vector<Case> attacks = {
      {"no add before the compare", {reset, "nop", cmp, "jae @5", "jmp @1", "nop"}, 4, "backward branch"},
      {"the add of 2 bytes further", {reset, "nop", "add dword ptr [rbx+0x1a], 0x1", cmp, "jae @6", "jmp @1", "nop"}, 5, "backward branch"},
      {"a budget above 100,000", {reset, "nop", add, "cmp dword ptr [rbx+0x18], 0x186a1", "jae @6", "jmp @1", "nop"}, 5, "backward branch"},
      {"jb instead of jae", {reset, "nop", add, cmp, "jb @6", "jmp @1", "nop"}, 5, "backward branch"},
      {"a conditional back edge", {reset, "nop", add, cmp, "jae @6", "jne @1", "nop"}, 5, "backward branch"},
      {"the reset inside the loop", {"nop", reset, add, cmp, "jae @6", "jmp @0", "nop"}, 5, "a write of the loop counter"},
      {"a sub inside the loop", {reset, "nop", "sub dword ptr [rbx+0x18], 0x5", add, cmp, "jae @7", "jmp @1", "nop"}, 6,
       "a write of the loop counter"},
      {"a byte of the counter cleared", {reset, "nop", "mov byte ptr [rbx+0x1b], 0x0", add, cmp, "jae @7", "jmp @1", "nop"}, 6,
       "a write of the loop counter"},
      {"an indexed write that reaches the counter",
       {reset, "nop", "cmp r11, 0x10", "ja @9", "mov dword ptr [rbx+r11*4+0x0], eax", add, cmp, "jae @9", "jmp @1", "nop"}, 8,
       "a write of the loop counter"},
  };
  for (const Case& c : attacks) {
    SCOPED_TRACE(c.klass);
    std::string why = refusal(image_around(scan_function(c.body, at)));
    EXPECT_NE(why.find(": at code offset " + hex(at[c.hostile]) + ": "), std::string::npos) << why;
    EXPECT_NE(why.find(c.reason), std::string::npos) << why;
  }
  // a branch onto the compare skips the add: refused as a landing inside the guard
  std::string why = refusal(image_around(scan_function({reset, "jmp @3", add, cmp, "jae @6", "jmp @2", "nop"}, at)));
  EXPECT_NE(why.find("guard"), std::string::npos) << why;
  // The -O2 frame takes a loop where it sets no base register (ldc's -O2 code
  // of a program with loops: docs/x86.md, "Loops"): the counter at IMG's
  // Sys+24; with the base registers set, the same loop is refused (their
  // plans carry each register forward only)
  const std::string add2 = "add dword ptr [IMG+0x18], 0x1", cmp2 = "cmp dword ptr [IMG+0x18], 0x186a0",
                    reset2 = "mov dword ptr [IMG+0x18], 0x0";
  EXPECT_EQ(refusal(image_around(scan_function({reset2, "nop", add2, cmp2, "jae @6", "jmp @1", "nop"}, at, true, 0))), "");
  why = refusal(image_around(scan_function({reset2, "nop", add2, cmp2, "jae @6", "jmp @1", "nop"}, at, true)));
  EXPECT_NE(why.find("backward branch"), std::string::npos) << why;
  EXPECT_NE(why.find(": at code offset " + hex(at[5]) + ": "), std::string::npos) << why;
  // and its counter's rules hold there as in the -O0 frame
  why = refusal(image_around(scan_function({"nop", reset2, add2, cmp2, "jae @6", "jmp @0", "nop"}, at, true, 0)));
  EXPECT_NE(why.find("a write of the loop counter"), std::string::npos) << why;
  why = refusal(image_around(scan_function({reset2, "nop", "add dword ptr [IMG+0x1a], 0x1", cmp2, "jae @6", "jmp @1", "nop"}, at, true, 0)));
  EXPECT_NE(why.find("backward branch"), std::string::npos) << why;
}

// The -O2 frame's base registers (docs/x86.md, "Compact addressing"): the
// prologue sets rdi, r15 and r14 to rbx+K, and so may `lea reg, [rbx+K]`
// anywhere in the body, any K in [128, size-135]; the body addresses
// [rdi+d] / [r15+d] / [r14+d] with d in [-0x80, 0x7f] only, never writes them
// otherwise, and resets rdi right after each call through the REAL function
// table.  No K is tracked: whatever path a branch takes, every access stays
// inside the image.
void base_registers() {
  const std::string lo = "[rdi-0x80]", hi = "[r15+0x7f]";  // image byte 0; bytes kSize-8.. of r15
  const std::string kmin = hex(kKMin), kmax = hex(uint32_t(kKMax));
  std::vector<uint32_t> at;
  // harmless twins: the edges of the image, lea arithmetic, leas anywhere, the reload
  const std::vector<std::vector<std::string>> ok = {
      {"movzx eax, byte ptr " + lo, "mov byte ptr " + hi + ", al", "mov dword ptr [r15+0x7f], eax",
       "mov qword ptr [r15+0x7f], rax"},
      {"call qword ptr [IMG-0x40]", "lea rdi, [IMG+" + kmin + "]", "mov eax, dword ptr [rdi+0x10]"},
      {"lea rax, [rdi+0x7f]", "lea eax, [r15-0x80]", "cmp rdi, rax", "test r15, r15", "mov rax, rdi"},
      {"mov eax, dword ptr [r14-0x80]", "add dword ptr [r14+0x7c], eax", "cmp r14d, 0x1"},
      // a reload to another K, a branch over it
      {"lea rdi, [IMG+" + kmin + "]", "je @4", "call qword ptr [IMG-0x20]", "lea rdi, [IMG+" + kmax + "]", "nop"},
      // the body points every register again, at both ends of the range, and a branch skips one lea
      {"lea r15, [IMG+" + kmin + "]", "lea r14, [IMG+" + kmax + "]", "jne @4", "lea rdi, [IMG+0x5000]",
       "mov byte ptr [r15-0x80], al", "mov qword ptr [r14+0x7f], rax", "mov byte ptr [rdi+0x7f], al"},
  };
  for (const auto& body : ok) EXPECT_EQ(refusal(image_around(scan_function(body, at, true))), "") << body[0];
  // the prologue at both ends of the range
  EXPECT_EQ(refusal(image_around(scan_function({"mov byte ptr [rdi-0x80], al"}, at, true, x86::kNumBases, kKMax, kKMin))), "");

  auto refused = [&](const std::vector<std::string>& body, size_t hostile, const std::string& reason, bool slots = true,
                     int leas = x86::kNumBases, int32_t k0 = kK0, int32_t k1 = kK1) {
    std::string why = refusal(image_around(scan_function(body, at, slots, leas, k0, k1)));
    EXPECT_NE(why.find("at code offset " + hex(at[hostile]) + ": "), std::string::npos) << body[hostile] << ": " << why;
    EXPECT_NE(why.find(with_image(reason)), std::string::npos) << body[hostile] << ": " << why;
  };
  const std::string base = "a base register of the -O2 frame (only 'lea ";
  // writing a base register, every width and form but the lea
  refused({"nop", "mov edi, eax"}, 1, base);
  refused({"mov rdi, IMG"}, 0, base);  // even to the image base
  refused({"setne dil"}, 0, base);
  refused({"add r15, 0x10"}, 0, base);
  refused({"xor r15d, r15d"}, 0, base);
  refused({"mov r15b, 0x1"}, 0, base);
  refused({"imul edi, eax, 0x3"}, 0, base);
  refused({"setne r14b"}, 0, base);  // r14 was a bit-stack slot before compact addressing
  refused({"mov r14, rdi"}, 0, base);
  refused({"movzx r14d, al"}, 0, base);
  // near misses of the lea: another base, an index, 32 bits
  refused({"lea rdi, [rdi+0x0]"}, 0, base);
  refused({"lea r15, [r14+0x100]"}, 0, base);
  refused({"lea rdi, [IMG+rax*1+0x100]"}, 0, base);
  refused({"lea edi, [IMG+0x100]"}, 0, base);
  refused({"lea r14d, [IMG+0x100]"}, 0, base);
  refused({"pop rdi"}, 0, "the stack is touched only by the prologue and the epilogue");
  refused({"raw: 48 87 f8"}, 0, "undecodable bytes");  // xchg rax, rdi: outside the subset
  // a K one byte outside the range, in the body and in the prologue
  const std::string range = "outside [128, " + std::to_string(kKMax) + "]";
  refused({"lea rdi, [IMG+0x7f]"}, 0, sets("rdi", 127) + ", " + range);
  refused({"nop", "lea r15, [IMG+" + hex(uint32_t(kKMax) + 1) + "]"}, 1, sets("r15", kKMax + 1));
  refused({"lea r14, [IMG-0x40]"}, 0, sets("r14", -64) + ", " + range);
  for (int32_t k : {kKMin - 1, kKMax + 1}) {
    for (int i : {0, 1}) {
      std::string why = refusal(image_around(scan_function({"nop"}, at, true, x86::kNumBases, i ? kK0 : k, i ? k : kK1)));
      std::string reg = i ? "r15" : "rdi";
      EXPECT_NE(why.find(with_image("'lea " + reg + ", [IMG+" + hex(uint32_t(k)) + "]': " + sets(reg, k) + ", " + range)),
                std::string::npos)
          << why;
    }
  }
  // the REAL call without its reload (or with a bad one, or at the end)
  refused({"call qword ptr [IMG-0x40]", "nop"}, 0, "not followed at once by 'lea rdi, [IMG+K]'");
  refused({"call qword ptr [IMG-0x40]", "lea r15, [IMG+0x100]"}, 0, "not followed at once by 'lea rdi, [IMG+K]'");
  refused({"call qword ptr [IMG-0x40]", "lea rdi, [IMG+rax*1+0x100]"}, 0, "not followed at once");
  refused({"call qword ptr [IMG-0x40]", "lea rdi, [IMG+0x7f]"}, 1, sets("rdi", 127) + ", " + range);
  refused({"nop", "call qword ptr [IMG-0x38]"}, 1, "not followed at once");
  // displacements one past the disp8 reach, on every register, whatever K
  const std::string reach = "a base register of the -O2 frame takes a displacement in [-0x80, 0x7f] only";
  refused({"mov byte ptr [rdi-0x81], al"}, 0, reach);
  refused({"mov byte ptr [r15+0x80], al"}, 0, reach);
  refused({"mov dword ptr [r14+0x1000], eax"}, 0, reach);
  refused({"lea rdi, [IMG+0x5000]", "movzx eax, byte ptr [rdi+0x80]"}, 1, reach);  // even where K+d is inside
  // indexed through a base register
  refused({"mov al, byte ptr [rdi+rax*1]"}, 0, "indexed memory operand");
  // the wrong frame: the -O0 frame sets no base register
  refused({"mov byte ptr [rdi+0x10], al"}, 0, "memory operand based on rdi, not rbx", false);
  refused({"movzx eax, byte ptr [r15+0x10]"}, 0, "memory operand based on r15, not rbx", false);
  refused({"mov byte ptr [r14+0x10], al"}, 0, "memory operand based on r14, not rbx", false);
  // a -O2 prologue without all leas, or with them swapped, is the frame
  // before compact addressing: it sets no base register, and a lea in its body
  // does not make one (a branch could pass it by)
  for (int leas = 0; leas < x86::kNumBases; leas++) {
    refused({"mov byte ptr [rdi+0x10], al"}, 0, "memory operand based on rdi, not IMG", true, leas);
    refused({"mov byte ptr [r15+0x10], al"}, 0, "memory operand based on r15, not IMG", true, leas);
    refused({"nop", "lea r14, [IMG+0x100]", "mov byte ptr [r14+0x10], al"}, 2, "memory operand based on r14, not IMG", true, leas);
  }
  EXPECT_EQ(refusal(image_around(scan_function({"setne r15b"}, at, true, 0))), "");  // that frame's slot
  std::vector<uint8_t> swapped;
  auto put = [&](const x86::Instruction& in) {
    auto b = x86::encode_at(in, swapped.size());
    swapped.insert(swapped.end(), b.begin(), b.end());
  };
  for (const auto& in : o2_prologue()) put(in);
  for (int i : {1, 0}) put(x86::base_lea(x86::kBaseRegs[i], (i ? kK1 : kK0) - g_o2.bias, g_o2.image));
  size_t hostile_at = swapped.size();
  put(x86::parse("mov byte ptr [r15+0x10], al"));
  for (const auto& in : x86::scan_epilogue(true)) put(in);
  std::string why = refusal(image_around(swapped));
  EXPECT_NE(why.find(with_image("at code offset " + hex(hostile_at) + ": 'mov byte ptr [r15+0x10], al': memory operand based on r15, not IMG")),
            std::string::npos)
      << why;
  // the shared routines, which run between base-register accesses without a
  // reload, write no base register (the loader matches them whole)
  x86::RoutineAreas areas;
  for (int r = 0; r < int(x86::Routine::Count); r++)
    for (const x86::Instruction& in : x86::scan_routine(x86::Routine(r), areas))
      for (x86::RegNum b : x86::kBaseRegs)
        EXPECT_FALSE(in.num_operands && in.ops[0].kind == x86::OperandKind::Reg && in.ops[0].reg.cls != x86::RegClass::Xmm &&
                     in.ops[0].reg.num == b && in.mnemonic != x86::Mnemonic::Cmp && in.mnemonic != x86::Mnemonic::Test)
            << x86::print(in);
}

TEST(Hostile, BaseRegisters) { base_registers(); }

// The same attacks on the -O2 frame of images made before bl became a
// bit-stack slot (rbx the image), which the loader still accepts.
TEST(Hostile, BaseRegistersOfTheOlderO2Frame) {
  g_o2 = kRbxFrame;
  base_registers();
  g_o2 = kLdcFrame;
}

// And on the -O2 frame of images made before rbp pointed into the image.
TEST(Hostile, BaseRegistersOfTheUnbiasedO2Frame) {
  g_o2 = kUnbiasedFrame;
  base_registers();
  g_o2 = kLdcFrame;
}

// The -O2 frame's image register is rbp and its first bit-stack slot bl: the
// body may write rbx at every width but never rbp, addresses memory through
// rbp (or a base register) only, and calls the REAL functions through
// [rbp+slot]; the older -O2 frame the other way round.
TEST(Hostile, TheO2FrameSwapsRbxAndRbp) {
  std::vector<uint32_t> at;
  const std::string k = hex(kKMin);
  for (const std::vector<std::string>& ok : std::vector<std::vector<std::string>>{
           {"movzx ebx, byte ptr [rbp+0x50]", "and bl, byte ptr [rbp+0x51]", "mov byte ptr [rbp+0x60], bl"},
           {"setne bl", "xor ebx, ebx", "lea ebx, [rax+rbx*2]", "mov rbx, rax", "test bl, bl"},
           {"call qword ptr [IMG-0x40]", "lea rdi, [rbp+" + k + "]", "mov eax, dword ptr [IMG+0x0]"}})
    EXPECT_EQ(refusal(image_around(scan_function(ok, at, true))), "") << ok[0];
  auto refused = [&](const std::vector<std::string>& body, size_t hostile, const std::string& reason) {
    std::string why = refusal(image_around(scan_function(body, at, true)));
    EXPECT_NE(why.find("at code offset " + hex(at[hostile]) + ": "), std::string::npos) << body[hostile] << ": " << why;
    EXPECT_NE(why.find(reason), std::string::npos) << body[hostile] << ": " << why;
  };
  const std::string fixed = "(the image base and the stack pointer are fixed in the scan body)";
  for (const char* w : {"mov ebp, eax", "setne bpl", "xor ebp, ebp", "lea rbp, [rbp+0x10]", "add rbp, 0x8", "movzx ebp, al"})
    refused({"nop", w}, 1, fixed);
  refused({"mov byte ptr [rbx+0x10], al"}, 0, "memory operand based on rbx, not rbp");
  refused({"movzx eax, byte ptr [IMG+" + S + "]"}, 0,
          with_image("memory operand [IMG+" + S + "] (1 bytes, image offset " + std::to_string(kSize) + ") outside the memory image"));
  refused({"call qword ptr [rbx-0x40]", "lea rdi, [rbp+" + k + "]"}, 0, "indirect call not through the REAL function table");
  // rbp points kImageBias bytes into the image: a displacement counts from there
  refused({"movzx eax, byte ptr [IMG-0x1]"}, 0, "memory operand [rbp-0x41] (1 bytes, image offset -1) outside the memory image");
  refused({"mov qword ptr [IMG+" + hex(kSize - 7) + "], rax"}, 0, "(8 bytes, image offset " + std::to_string(kSize - 7) + ")");
  refused({"call qword ptr [rbp-0x40]", "lea rdi, [rbp+" + k + "]"}, 0, "indirect call not through the REAL function table");
  refused({"lea rdi, [rbx+" + k + "]"}, 0, "a base register of the -O2 frame (only 'lea rdi, [rbp+K]' may set one)");
  // the older frame: rbp is a slot there, rbx the image
  g_o2 = kRbxFrame;
  EXPECT_EQ(refusal(image_around(scan_function({"setne bpl", "mov byte ptr [rbx+0x60], bpl"}, at, true))), "");
  refused({"nop", "setne bl"}, 1, fixed);
  refused({"mov byte ptr [rbp+0x10], al"}, 0, "stack-relative memory operand based on rbp (only [rbx+disp] may address memory)");
  g_o2 = kLdcFrame;
}

// The shared timer/counter routines after the epilogue (docs/x86.md, "Shared
// routines"): a call may go only to the entry of a routine that is exactly one
// of the bodies as::x86::scan_routine makes for the image's layout.
x86::RoutineAreas layout_areas(uint32_t edges) {
  Layout l = Layout::standard(edges);
  x86::RoutineAreas a;
  a.tw = int32_t(l.addr(Area::TW, 0));
  a.tq = int32_t(l.addr(Area::TQ, 0));
  a.ti = int32_t(l.addr(Area::TI, 0));
  a.cw = int32_t(l.addr(Area::CW, 0));
  a.cq = int32_t(l.addr(Area::CQ, 0));
  a.dt = int32_t(kSysDt);
  a.e = int32_t(l.addr(Area::E, 0));
  a.e_count = int32_t(l.count[int(Area::E)]);
  return a;
}

// A scan function in the -O2 frame (the routines' own) whose body is `setup`,
// then a call to `call_to` (an offset from the first routine's entry), then a
// nop, followed by the routines; `call_at` gets the call's offset.
std::vector<uint8_t> with_routines(const std::vector<std::vector<x86::Instruction>>& routines, int64_t call_to,
                                   uint32_t& call_at,
                                   std::vector<std::string> setup = {"mov esi, 0x1", "mov edx, 0x3", "mov ecx, 0x64"}) {
  std::vector<uint32_t> at;
  std::vector<std::string> body = std::move(setup);
  const size_t call = body.size();
  body.insert(body.end(), {"call 0x0", "nop"});
  std::vector<uint8_t> code = scan_function(body, at, true);  // the call is rel32: its size does not change
  const int64_t base = at[0], entry = int64_t(code.size());
  body[call] = "call " + std::to_string(entry + call_to - base);
  code = scan_function(body, at, true);
  call_at = at[call];
  for (const auto& r : routines)
    for (const auto& in : r) {
      std::vector<uint8_t> b = x86::encode_at(in, code.size());
      code.insert(code.end(), b.begin(), b.end());
    }
  return code;
}

TEST(Hostile, CallsOnlyToTheSharedRoutines) {
  constexpr uint32_t kEdges = 4;  // the counters' edge slots: the image's
  const x86::RoutineAreas areas = layout_areas(kEdges);
  const auto ton = x86::scan_routine(x86::Routine::Ton, areas), ctu = x86::scan_routine(x86::Routine::Ctu, areas);
  uint32_t call_at = 0;
  // the harmless twin: a call to the entry of a canonical routine, with another after it
  EXPECT_EQ(refusal(image_around(with_routines({ton, ctu}, 0, call_at), kEdges)), "");
  int64_t ton_size = 0;
  for (const auto& in : ton) ton_size += int64_t(x86::encode_at(in, 0).size());
  EXPECT_EQ(refusal(image_around(with_routines({ton, ctu}, ton_size, call_at), kEdges)), "");  // rt_ctu's entry
  auto refused = [&](const Image& im, const std::string& reason, bool at_call) {
    std::string why = refusal(im);
    EXPECT_NE(why.find(reason), std::string::npos) << why;
    if (at_call) {
      EXPECT_NE(why.find("at code offset " + hex(call_at) + ": "), std::string::npos) << why;
    }
  };
  // a call into the middle of a routine (past its mask, on an instruction boundary)
  int64_t mask = int64_t(x86::encode_at(ton[0], 0).size());
  refused(image_around(with_routines({ton}, mask, call_at), kEdges), "a direct call not to the entry of one of the code's routines", true);
  // a call to code that is no routine: the epilogue, and the body itself
  int64_t epilogue = 0;
  for (const auto& in : x86::scan_epilogue(true)) epilogue += int64_t(x86::encode_at(in, 0).size());
  refused(image_around(with_routines({ton}, -epilogue, call_at), kEdges), "a direct call not to the entry", true);
  refused(image_around(with_routines({}, -epilogue - 1, call_at), kEdges), "a direct call not to the entry", true);
  // an unmasked operand: the routine without its `movzx edx, dl`
  std::vector<x86::Instruction> unmasked(ton.begin() + 1, ton.end());
  refused(image_around(with_routines({unmasked}, 0, call_at), kEdges), "does not end with the scan function's epilogue", false);
  // a routine that loops: a jump back to its entry before the ret
  std::vector<x86::Instruction> loops = ctu;
  loops.insert(loops.end() - 1, x86::parse("jmp -0x40"));
  refused(image_around(with_routines({loops}, 0, call_at), kEdges), "does not end with the scan function's epilogue", false);
  // a routine built for rbp at the image's start (the unbiased frame's)
  refused(image_around(with_routines({x86::scan_routine(x86::Routine::Ton, areas, x86::image_reg(true), 0)}, 0, call_at), kEdges),
          "does not end with the scan function's epilogue", false);
  // a routine built for the older -O2 frame's image register (rbx)
  refused(image_around(with_routines({x86::scan_routine(x86::Routine::Ton, areas, x86::BX)}, 0, call_at), kEdges),
          "does not end with the scan function's epilogue", false);
  // a routine built for other areas: its accesses are not the layout's timers
  x86::RoutineAreas off = areas;
  off.tw = int32_t(kSize) - 4;
  refused(image_around(with_routines({x86::scan_routine(x86::Routine::Ton, off)}, 0, call_at), kEdges),
          "does not end with the scan function's epilogue", false);
  // a counter routine that keeps its edge slot number below another count
  // than the image's edge slots, or in an image without edge slots
  x86::RoutineAreas more = areas;
  more.e_count = int32_t(kEdges) + 1;
  refused(image_around(with_routines({x86::scan_routine(x86::Routine::Ctu, more)}, 0, call_at), kEdges),
          "does not end with the scan function's epilogue", false);
  refused(image_around(with_routines({x86::scan_routine(x86::Routine::Ctd, layout_areas(0))}, 0, call_at), 0),
          "does not end with the scan function's epilogue", false);
}

// Every -O2 frame runs: a body in ldc's frame (rbp the image, kImageBias
// bytes into it, bl a slot), the same with rbp at the image's start, and in
// the oldest (rbx the image, bpl a slot), each calling its frame's counter
// routine, is accepted by the loader and counts the rising edges of X0 into
// C0, its bit-stack slot copied to Y0.
TEST(Hostile, EveryO2FrameRunsItsCounterRoutine) {
  constexpr uint32_t kEdges = 1;
  const Layout L = Layout::standard(kEdges);
  const x86::RoutineAreas areas = layout_areas(kEdges);
  const std::string x0 = hex(L.addr(Area::X, 0)), y0 = hex(L.addr(Area::Y, 0)), e0 = hex(L.addr(Area::E, 0));
  for (O2Frame frame : {kLdcFrame, kUnbiasedFrame, kRbxFrame}) {
    g_o2 = frame;
    const x86::RegNum image = frame.image;
    const bool ldc_frame = image == x86::image_reg(true);
    const std::string slot = ldc_frame ? "bl" : "bpl", slot32 = ldc_frame ? "ebx" : "ebp";
    // the older frame's call site computes the edge itself and passes it in esi
    std::vector<std::string> body = {"movzx " + slot32 + ", byte ptr [IMG+" + x0 + "]",
                                     "mov byte ptr [IMG+" + y0 + "], " + slot};
    if (ldc_frame) {
      body.insert(body.end(), {"mov esi, " + slot32, "mov r8d, 0x0"});
    } else {
      body.insert(body.end(), {"movzx eax, " + slot, "movzx esi, byte ptr [IMG+" + e0 + "]", "mov byte ptr [IMG+" + e0 + "], al",
                               "not esi", "and esi, eax"});
    }
    body.insert(body.end(), {"mov dl, 0x0", "mov ecx, 0x64"});
    uint32_t call_at = 0;
    Image im = image_around(with_routines({x86::scan_routine(x86::Routine::Ctu, areas, image, frame.bias)}, 0, call_at, body),
                            kEdges);
    ASSERT_EQ(refusal(im), "") << x86::reg_name(x86::r64(image));
    Memory m(L);
    auto eng = make_native_engine(map_checked_code(im.code, im.entry, im.layout));
    int rising = 0, before = 0;
    for (int x : {1, 0, 1, 1, 0, 1}) {
      m.bytes[L.addr(Area::X, 0)] = uint8_t(x);
      eng->scan(m.bytes);
      rising += x && !before;
      before = x;
      EXPECT_EQ(m.bytes[L.addr(Area::Y, 0)], x);
      int32_t cv;
      std::memcpy(&cv, m.data() + L.addr(Area::CW, 0), 4);
      EXPECT_EQ(cv, rising) << x86::reg_name(x86::r64(image)) << " bias " << frame.bias;
    }
  }
  g_o2 = kLdcFrame;
}

// The write rule follows the form table (assembler/x86.h, Effects): every
// form whose row writes a register operand is refused with the image
// register, rsp, r12 (in the -O0 frame) or a base register (in the -O2
// frame) there, and a form whose row only reads the operand is never refused
// for writing it.  So a form added to the assembler is covered by its row,
// with no list of mnemonics here or in the loader.
TEST(Hostile, TheWriteRuleFollowsTheFormTable) {
  namespace D = x86::detail;
  using D::OT;
  std::vector<uint32_t> at;
  int refused = 0, read_only = 0;
  for (const D::Form& f : D::forms()) {
    for (unsigned k = 0; k < D::num_ops(f); k++) {
      x86::RegClass cls = f.ops[k] == OT::R8 || f.ops[k] == OT::RM8     ? x86::RegClass::Gp8
                          : f.ops[k] == OT::R32 || f.ops[k] == OT::RM32 ? x86::RegClass::Gp32
                          : f.ops[k] == OT::R64 || f.ops[k] == OT::RM64 ? x86::RegClass::Gp64
                                                                        : x86::RegClass::None;
      if (cls == x86::RegClass::None) continue;  // a fixed register, memory, xmm, an immediate or a target
      // the other operands: eax, xmm1, [rbx+0x50] (X0), 1
      x86::Instruction in;
      in.mnemonic = f.mn;
      in.cond = x86::Cond::NE;
      in.num_operands = uint8_t(D::num_ops(f));
      for (unsigned j = 0; j < in.num_operands; j++) {
        using O = x86::Operand;
        OT t = f.ops[j];
        if (t == OT::R8 || t == OT::RM8 || t == OT::Al) in.ops[j] = O::r(x86::r8(x86::AX));
        else if (t == OT::R32 || t == OT::RM32 || t == OT::Eax) in.ops[j] = O::r(x86::r32(x86::AX));
        else if (t == OT::R64 || t == OT::RM64 || t == OT::Rax) in.ops[j] = O::r(x86::r64(x86::AX));
        else if (t == OT::Cl) in.ops[j] = O::r(x86::r8(x86::CX));
        else if (t == OT::X || t == OT::XM32 || t == OT::XM64) in.ops[j] = O::r(x86::xmm(1));
        else if (t == OT::M8 || t == OT::M16 || t == OT::M32 || t == OT::M64 || t == OT::MA) {
          x86::Mem m;
          m.base = x86::r64(x86::BX);
          m.disp = 0x1000;
          m.size = t == OT::M8 ? x86::Size::Byte : t == OT::M16 ? x86::Size::Word : t == OT::M32 ? x86::Size::Dword
                 : t == OT::M64 ? x86::Size::Qword : x86::Size::None;
          in.ops[j] = O::m(m);
        } else in.ops[j] = O::i(1);
      }
      const bool writes = x86::writes_operand(f.effects.ops[k]);
      struct Target {
        uint8_t reg;
        bool slots;
        const char* reason;
      };
      for (const Target& t : {Target{x86::BX, false, "the image base and the stack pointer are fixed"},
                              Target{x86::SP, false, "the image base and the stack pointer are fixed"},
                              Target{x86::R12, false, "which the caller owns"},
                              Target{x86::R15, true, "a base register of the -O2 frame"}}) {
        x86::Instruction v = in;
        v.ops[k].reg = x86::Reg{cls, t.reg};
        std::string text;
        try {
          x86::encode(v);
          text = x86::print(v);
          if (t.slots) text = std::regex_replace(text, std::regex(R"(\[rbx)"), "[IMG");
        } catch (const std::exception&) {
          continue;  // not a form this operand can take (a fixed register elsewhere)
        }
        if (x86::effects(v) != f.effects) continue;  // the encoder picks another form for it
        std::string why = refusal(image_around(scan_function({text}, at, t.slots)));
        bool for_writing = why.find(t.reason) != std::string::npos;
        if (f.effects.stack == x86::StackUse::Push || f.effects.stack == x86::StackUse::Pop) {
          EXPECT_NE(why.find("the stack is touched only by the prologue and the epilogue"), std::string::npos) << why;
        } else if (t.slots && f.mn == x86::Mnemonic::Lea && cls == x86::RegClass::Gp64) {
          EXPECT_EQ(why, "") << text << ": the one write of a base register, K in range";  // lea r15, [rbp+K]
        } else if (writes) {
          EXPECT_TRUE(for_writing) << text << " (its row writes operand " << k + 1 << "): " << why;
          refused++;
        } else {
          EXPECT_FALSE(for_writing) << text << " (its row only reads operand " << k + 1 << "): " << why;
          read_only++;
        }
      }
    }
  }
  EXPECT_GT(refused, 200);
  EXPECT_GT(read_only, 50);
}

TEST(Hostile, EntryPointsMustBeTheFrame) {
  std::vector<uint32_t> at;
  Image im = image_around(scan_function({"nop"}, at));
  im.entry = 1;  // inside push rbp? no: after push rbx, a boundary, but not the prologue
  EXPECT_NE(refusal(im).find("the entry is not the scan function's prologue"), std::string::npos) << refusal(im);
  im = image_around(scan_function({"mov eax, 0x12345678"}, at));
  im.entry = at[0] + 1;
  EXPECT_NE(refusal(im).find("entry point " + hex(at[0] + 1) + " is inside an instruction"), std::string::npos) << refusal(im);
}

TEST(Hostile, HugeEdgeCounts) {
  std::vector<uint32_t> at;
  Layout big = Layout::standard(kImageMaxEdgeSlots);
  uint32_t last_edge = big.addr(Area::E, kImageMaxEdgeSlots - 1);
  // the largest edge memory is allowed, and its last byte is addressable ...
  Image im = image_around(scan_function({"mov byte ptr [rbx+" + hex(last_edge) + "], al"}, at), kImageMaxEdgeSlots);
  EXPECT_EQ(refusal(im), "");
  // ... one byte past its image is not
  im = image_around(scan_function({"mov byte ptr [rbx+" + hex(big.size) + "], al"}, at), kImageMaxEdgeSlots);
  EXPECT_NE(refusal(im).find("outside the memory image"), std::string::npos);
  // a larger count is refused before the code is looked at, naming the field
  std::vector<uint8_t> b = write_image(image_around(scan_function({"nop"}, at), kImageMaxEdgeSlots + 1));
  std::string why;
  try {
    read_image(b, "hostile.bin");
  } catch (const ImageError& e) {
    why = e.what();
  }
  EXPECT_NE(why.find("hostile.bin: offset 0x60: layout: 1048577 edge slots exceed the limit 1048576"), std::string::npos) << why;
  b = write_image(image_around(scan_function({"nop"}, at), 0xffffffffu / 2));
  try {
    read_image(b, "hostile.bin");
    why = "";
  } catch (const ImageError& e) {
    why = e.what();
  }
  EXPECT_NE(why.find("offset 0x60"), std::string::npos) << why;
}

// ------------------------------------------------------------------ the guard pages
// Every memory image (ImageBytes, ir/ir.h) sits on its own pages: a PROT_NONE
// page, the read-only page whose last 40 bytes are the REAL function table,
// the image with a canary to the end of its last page, another PROT_NONE page.

uint8_t touch(volatile uint8_t* p, bool write) {
  if (write) *p = 1;
  return *p;
}

TEST(Guard, TheTableSitsReadOnlyRightBelowTheImage) {
  ImageBytes b(Layout::standard(0).size);
  for (int f = 0; f < kCallSlots; f++) {
    uint64_t slot;
    std::memcpy(&slot, b.data() + kCallTableDisp + 8 * f, 8);
    EXPECT_EQ(slot, uint64_t(reinterpret_cast<uintptr_t>(real_fn(RealFn(f))))) << f;
  }
  for (int f = 0; f < kMathSlots; f++) {  // the typed instructions' double functions, right below (ir/mathfn.h)
    uint64_t slot;
    std::memcpy(&slot, b.data() + kMathTableDisp + 8 * f, 8);
    EXPECT_EQ(slot, uint64_t(reinterpret_cast<uintptr_t>(math_fn_address(MathFn(f))))) << f;
  }
  uint64_t str;  // the STRING routine's, right below
  std::memcpy(&str, b.data() + kStrSlotDisp, 8);
  EXPECT_EQ(str, uint64_t(reinterpret_cast<uintptr_t>(&native_string)));
  EXPECT_DEATH(touch(b.data() + kMathTableDisp, true), "");
  EXPECT_DEATH(touch(b.data() + kStrSlotDisp, true), "");
  EXPECT_TRUE(b.slack_intact());
  EXPECT_DEATH(touch(b.data() + kCallTableDisp, true), "");  // the table is not writable
  EXPECT_DEATH(touch(b.data() - 1, true), "");
}

TEST(Guard, NothingAroundTheImageIsMapped) {
  const size_t page = size_t(sysconf(_SC_PAGESIZE));
  for (size_t size : {size_t(Layout::standard(0).size), page, size_t(1)}) {
    ImageBytes b(size);
    ImageBytes copy = b;  // copies keep their own guards
    for (ImageBytes* x : {&b, &copy}) {
      size_t end = (size + page - 1) / page * page;
      EXPECT_DEATH(touch(x->data() + end, false), "") << size;             // the guard page after
      EXPECT_DEATH(touch(x->data() - page - 1, false), "") << size;        // the guard page before the table
      EXPECT_EQ(touch(x->data() + end - 1, false), size == end ? 0 : ImageBytes::kSlackByte) << size;
    }
  }
}

// ------------------------------------------------------------------ the sandbox
// Engines that do what hostile code would do, were it to escape the validator:
// the sandboxed child must stop each one, name what it did, and leave the
// caller's image and process as they were.

struct Copy : Engine {
  Layout L = Layout::standard(0);
  void scan(ImageBytes& m) override { m[L.addr(Area::Y, 0)] = m[L.addr(Area::X, 0)]; }
};
struct Syscall : Engine {
  void scan(ImageBytes&) override { syscall(SYS_getppid); }
};
struct OpenFile : Engine {
  void scan(ImageBytes&) override { open("/tmp/ldc_sandbox_escape", O_CREAT | O_WRONLY, 0600); }
};
struct Fault : Engine {
  volatile uintptr_t where = 0x10;
  void scan(ImageBytes&) override { *reinterpret_cast<volatile int*>(where) = 1; }
};
struct WritePast : Engine {  // into the canary after the image, inside its last page
  void scan(ImageBytes& m) override { m.data()[Layout::standard(0).size + 5] = 1; }
};
struct Spin : Engine {
  volatile int sink = 0;
  void scan(ImageBytes&) override {
    for (;;) sink = 1;
  }
};

std::string sandboxed_failure(std::unique_ptr<Engine> e, int timeout_ms = 2000) {
  Layout L = Layout::standard(0);
  Memory m(L);
  auto s = make_sandboxed_engine(std::move(e), L, timeout_ms);
  std::string why;
  try {
    s->scan(m.bytes);
  } catch (const SandboxError& x) {
    why = x.what();
  }
  try {  // a dead sandbox stays dead
    s->scan(m.bytes);
    return "the second scan after a failure ran";
  } catch (const SandboxError& x) {
    if (why != x.what()) return "the second scan failed differently: " + std::string(x.what());
  }
  return why;
}

TEST(Sandbox, ScansRunInTheChildAndTheImageComesBack) {
  Layout L = Layout::standard(0);
  Memory m(L);
  auto s = make_sandboxed_engine(std::make_unique<Copy>(), L);
  for (int k = 0; k < 50; k++) {
    m.set_bit(Area::X, 0, k % 3 == 0);
    s->scan(m.bytes);
    ASSERT_EQ(m.get_bit(Area::Y, 0), k % 3 == 0) << k;
  }
}

TEST(Sandbox, NativeCodeWithItsCallTableRunsAsInProcess) {
  Layout L = Layout::standard(0);
  std::string f0 = hex(L.addr(Area::F, 0)), f1 = hex(L.addr(Area::F, 1));
  std::vector<uint32_t> at;
  std::vector<uint8_t> code = scan_function(
      {"movss xmm0, dword ptr [rbx+" + f0 + "]", "call qword ptr [rbx-0x40]", "movss dword ptr [rbx+" + f1 + "], xmm0"}, at);
  ASSERT_EQ(refusal(image_around(code)), "");
  Memory a(L), b(L);
  auto plain = make_native_engine(map_checked_code(code, 0, L));
  auto boxed = make_sandboxed_engine(make_native_engine(map_checked_code(code, 0, L)), L);
  for (float x : {0.5f, 1.0f, -2.25f}) {
    a.set_real(0, x), b.set_real(0, x);
    plain->scan(a.bytes);
    boxed->scan(b.bytes);
    EXPECT_EQ(a.get_real(1), ::sinf(x));
    EXPECT_TRUE(a.bytes == b.bytes);
  }
}

// The STRING routine (ir/mathfn.h, native_string) is reached through the
// math table's Str slot with its arguments in registers, which crafted code
// sets as it likes: whatever they say, it works only inside the image being
// scanned.  Each scan below is crafted code the loader accepts (a call through
// the table is all it needs); the expected effects are the routine's rules.
TEST(Hostile, TheStringRoutineStaysInTheImage) {
  Layout L = Layout::standard(0);
  const uint32_t d0 = L.addr(Area::D, 0), d40 = L.addr(Area::D, 40), size = L.size;
  const std::string str_slot = "call qword ptr [rbx-" + hex(uint32_t(-kStrSlotDisp)) + "]";
  auto run = [&](uint32_t desc, uint64_t a0, uint64_t a1, Memory& m) {
    std::vector<uint32_t> at;
    std::vector<uint8_t> code = scan_function({"mov esi, " + hex(desc), "mov rdx, " + hex(a0), "mov rcx, " + hex(a1),
                                               "xor r8d, r8d", str_slot, "mov dword ptr [rbx+" + hex(L.addr(Area::D, 100)) + "], eax"},
                                              at);
    ASSERT_EQ(refusal(image_around(code)), "");
    make_native_engine(map_checked_code(code, 0, L))->scan(m.bytes);
  };
  const uint32_t move = native_string_desc(Op::TMOVE, Ty::STRING, Ty::None, 0);
  Memory m(L);
  m.set_int(Area::D, 0, 3), m.set_int(Area::D, 1, 0x636261);  // 'abc' in D0..D32
  run(move, d0, d40, m);                       // a real MOVE.STRING D0 D40: it runs
  EXPECT_EQ(m.get_int(Area::D, 40), 3);
  EXPECT_EQ(m.get_int(Area::D, 41), 0x636261);
  // then every argument hostile: nothing changes but the result cell (0)
  struct Case {
    const char* what;
    uint32_t desc;
    uint64_t a0, a1;
  } cases[] = {
      {"a destination past the image", move, d0, size - 4},
      {"a destination whose 33 cells end past the image", move, d0, size - 131},
      {"a destination at 2^32 - 1", move, d0, 0xffffffffu},
      {"a 64-bit destination", move, d0, 0x100000000ull + d40},
      {"a source past the image", move, size, d40},
      {"a constant STRING source", native_string_desc(Op::TMOVE, Ty::STRING, Ty::None, 1), 0x4141, d40},
      {"an op that is no string instruction", native_string_desc(Op::TADD, Ty::DINT, Ty::None, 0), d0, d40},
      {"a type the op does not take", native_string_desc(Op::TMOVE, Ty::None, Ty::None, 0) | 0x70u << 8, d0, d40},
      {"an op past the table", 0xff | 0xc00u << 8, d0, d40},
      {"bits above the constant mask", move | 1u << 27, d0, d40},
  };
  for (const Case& c : cases) {
    m.set_int(Area::D, 100, 77);
    Memory before = m;
    run(c.desc, c.a0, c.a1, m);
    EXPECT_EQ(m.get_int(Area::D, 100), 0) << c.what;
    m.set_int(Area::D, 100, 77);
    EXPECT_TRUE(m.bytes == before.bytes) << c.what;
    EXPECT_TRUE(m.bytes.slack_intact()) << c.what;
  }
  // outside a native scan (no ScanImageScope) the routine has no image: it does nothing
  EXPECT_EQ(native_string(0, move, d0, d40, 0), 0u);
}

TEST(Sandbox, ASystemCallIsStoppedAndNamed) {
  EXPECT_EQ(sandboxed_failure(std::make_unique<Syscall>()),
            "the sandboxed scan made system call " + std::to_string(SYS_getppid) + ", which the sandbox refuses");
  unlink("/tmp/ldc_sandbox_escape");
  EXPECT_NE(sandboxed_failure(std::make_unique<OpenFile>()).find("made system call"), std::string::npos);
  EXPECT_NE(access("/tmp/ldc_sandbox_escape", F_OK), 0) << "the child created a file";
}

TEST(Sandbox, AFaultIsStoppedAndNamed) {
  std::string why = sandboxed_failure(std::make_unique<Fault>());
  EXPECT_NE(why.find("the sandboxed scan was stopped by Segmentation fault at address 0x10 (instruction at 0x"), std::string::npos) << why;
}

TEST(Sandbox, AWritePastTheImageIsCaught) {
  EXPECT_EQ(sandboxed_failure(std::make_unique<WritePast>()), "the sandboxed scan wrote past the end of the memory image");
}

TEST(Sandbox, AScanThatNeverEndsIsStopped) {
  EXPECT_EQ(sandboxed_failure(std::make_unique<Spin>(), 300), "the sandboxed scan did not end within 300 ms");
}

}  // namespace
