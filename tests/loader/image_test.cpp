// Tests of the binary image: round trips, and one refusal per class of bad input.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include "test_image.h"

namespace ldc::test {
namespace {

// Runs read_image and returns its message ("" if it accepted the image).
std::string refusal(const std::vector<uint8_t>& b, const std::string& name = "t.bin") {
  try {
    read_image(b, name);
  } catch (const ImageError& e) {
    return e.what();
  }
  return "";
}
std::string refusal(const Image& im) { return refusal(write_image(im)); }

#define EXPECT_REFUSED(expr, ...)                                                     \
  do {                                                                                \
    std::string msg_ = (expr);                                                        \
    EXPECT_FALSE(msg_.empty()) << "accepted";                                         \
    for (const std::string& part_ : std::initializer_list<std::string>{__VA_ARGS__}) EXPECT_NE(msg_.find(part_), std::string::npos) << msg_; \
  } while (0)

// ------------------------------------------------------------------ the checksum

// The CRC-32 check value, and the sixteen-bytes-a-step loop and the folds of
// carry-less multiplication against the plain bitwise definition at every
// length and split point near their steps.
TEST(Image, Crc32MatchesTheBitwiseDefinition) {
  const std::string check = "123456789";
  EXPECT_EQ(crc32({reinterpret_cast<const uint8_t*>(check.data()), check.size()}), 0xCBF43926u);
  auto bitwise = [](std::span<const uint8_t> b, uint32_t c) {
    c = ~c;
    for (uint8_t x : b) {
      c ^= x;
      for (int k = 0; k < 8; k++) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
  };
  std::mt19937 rng(7);
  std::vector<uint8_t> b(70);
  for (auto& x : b) x = uint8_t(rng());
  for (size_t n = 0; n <= b.size(); n++) {
    std::span<const uint8_t> s(b.data(), n);
    EXPECT_EQ(crc32(s), bitwise(s, 0)) << n;
    for (size_t cut = 0; cut <= n; cut += 3) EXPECT_EQ(crc32(s.subspan(cut), crc32(s.subspan(0, cut))), bitwise(s, 0)) << n << " " << cut;
  }
  // the carry-less multiplication's folds (64 bytes and more, where the
  // machine has it): every length to 300 from unaligned starts, and long runs
  b.resize(5000);
  for (auto& x : b) x = uint8_t(rng());
  for (size_t from = 0; from < 3; from++)
    for (size_t n = 0; n <= 300; n++) {
      std::span<const uint8_t> s(b.data() + from, n);
      EXPECT_EQ(crc32(s), bitwise(s, 0)) << from << " " << n;
    }
  for (size_t cut : {0, 1, 64, 1000, 2047, 4999}) {
    std::span<const uint8_t> s(b);
    EXPECT_EQ(crc32(s.subspan(cut), crc32(s.subspan(0, cut))), bitwise(s, 0)) << cut;
  }
}

// ------------------------------------------------------------------ round trips

TEST(Image, RoundTripKeepsEveryField) {
  Image im = tiny_image();
  im.entry = 0;
  std::vector<uint8_t> b = write_image(im);
  EXPECT_EQ(b.size() % 4, 0u);
  EXPECT_EQ(std::string(b.begin(), b.begin() + 6), "LDCIMG");
  Image back = read_image(b, "t.bin");
  EXPECT_EQ(back.target, im.target);
  EXPECT_EQ(back.source, im.source);
  EXPECT_EQ(back.layout, im.layout);
  EXPECT_EQ(back.code, im.code);
  EXPECT_EQ(back.entry, im.entry);
  EXPECT_EQ(back.il, im.il);
  EXPECT_EQ(back.lines, im.lines);
  EXPECT_EQ(back.rung_titles, im.rung_titles);
  EXPECT_EQ(back.aliases, im.aliases);
  EXPECT_EQ(back.retentive, im.retentive);
  EXPECT_TRUE(back == im);
  EXPECT_EQ(write_image(back), b);  // the writer is deterministic
}

// write_image_file writes write_image's bytes, a piece at a time: a tiny
// image, one with a configuration table, and one of many 64 KiB pieces
// (code, line map and titles each larger than a piece).
std::vector<uint8_t> written_to_file(const Image& im) {
  std::FILE* f = std::tmpfile();
  EXPECT_NE(f, nullptr);
  size_t n = write_image_file(im, f);
  EXPECT_FALSE(std::ferror(f));
  std::vector<uint8_t> b(n);
  std::rewind(f);
  EXPECT_EQ(std::fread(b.data(), 1, n, f), n);
  EXPECT_EQ(std::fgetc(f), EOF);
  std::fclose(f);
  return b;
}

TEST(Image, WrittenToAFileAsWriteImageWritesIt) {
  Image tiny = tiny_image();
  Image configured = tiny_image();
  configured.config = IoConfig{32, 1, 10000, 2, "cpu", "fast", "prog", {{Area::X, 0, kBlockRead, kNoProcessor, 10000}}};
  Image big = tiny_image();
  std::mt19937 rng(11);
  big.code.resize(300001);
  for (auto& x : big.code) x = uint8_t(rng());
  for (uint32_t i = 0; i < 20000; i++) big.lines.push_back({uint32_t(rng() % 300001), 0, int32_t(i), i});
  for (int i = 0; i < 9000; i++) big.rung_titles.push_back(std::string(rng() % 20, char('a' + i % 26)));
  for (const Image* im : {&tiny, &configured, &big}) EXPECT_EQ(written_to_file(*im), write_image(*im));
}

TEST(Image, RoundTripEmptyOptionalFields) {
  Image im = tiny_image();
  im.source.clear();
  im.lines.clear();
  im.rung_titles.clear();
  im.aliases.clear();
  im.retentive.clear();
  EXPECT_TRUE(read_image(write_image(im), "t.bin") == im);
}

TEST(Image, RoundTripThroughIntelHex) {
  Image im = tiny_image();
  std::vector<uint8_t> b = write_image(im);
  std::string hex = write_intel_hex(b);
  EXPECT_TRUE(looks_like_intel_hex(std::span(reinterpret_cast<const uint8_t*>(hex.data()), hex.size())));
  EXPECT_FALSE(looks_like_intel_hex(b));
  std::vector<uint8_t> back = read_intel_hex(hex, "t.hex");
  EXPECT_EQ(back, b);
  EXPECT_TRUE(read_image(back, "t.hex") == im);
}

TEST(Image, RoundTripEdgeSlots) {
  Program p = parse_il_text(".edges 2\n.rung line 1\nLOADP X0 E0\nLOADF X1 E1\nORBLK\nOUT Y0\n.end\n", "t.il");
  ASSERT_EQ(p.edge_slots, 2u);
  Image im = tiny_image();
  im.layout = p.layout();
  im.il = encode_il(p).code;
  im.lines.clear();
  uint32_t e1 = im.layout.addr(Area::E, 1);
  im.code = framed({"mov byte ptr [rbx+" + disp(e1) + "], 1"});  // a non-zero entry: RoundTripC40
  Image back = read_image(write_image(im), "t.bin");
  EXPECT_TRUE(back == im);
  EXPECT_EQ(back.layout.count[int(Area::E)], 2u);
}

TEST(Image, RoundTripC40) {
  Image im = tiny_image();
  im.target = ImageTarget::C40;
  // NOP, NOP, RETSU: the loader decodes C40 code (c40_check.h)
  im.code = {0x00, 0x00, 0x80, 0x0c, 0x00, 0x00, 0x80, 0x0c, 0x00, 0x00, 0x80, 0x78};
  im.entry = 4;
  im.lines = {{4, im.lines[0].il_offset, 2, 0}, {12, im.lines[1].il_offset, 2, 0}};
  EXPECT_TRUE(read_image(write_image(im), "t.bin") == im);
}

TEST(Image, C40CodeMustBeWords) {
  Image im = tiny_image();
  im.target = ImageTarget::C40;
  im.code = {1, 2, 3, 4, 5, 6};
  im.lines.clear();
  EXPECT_REFUSED(refusal(im), "section 'code'", "32-bit words");
  im.code = {1, 2, 3, 4, 5, 6, 7, 8};
  im.entry = 2;
  EXPECT_REFUSED(refusal(im), "section 'entry'", "not word-aligned");
}

// ------------------------------------------------------------------ file structure

TEST(Image, TruncatedAtEveryLengthIsRefused) {
  std::vector<uint8_t> b = write_image(tiny_image());
  for (size_t n = 0; n < b.size(); n++) {
    std::vector<uint8_t> cut(b.begin(), b.begin() + long(n));
    std::string msg = refusal(cut);
    ASSERT_FALSE(msg.empty()) << "accepted at length " << n;
    EXPECT_NE(msg.find("truncated"), std::string::npos) << n << ": " << msg;
    EXPECT_EQ(msg.rfind("t.bin: ", 0), 0u) << msg;
  }
}

TEST(Image, TrailingBytesAreRefused) {
  std::vector<uint8_t> b = write_image(tiny_image());
  b.push_back(0);
  EXPECT_REFUSED(refusal(b), "trailing bytes");
}

TEST(Image, WrongMagic) {
  std::vector<uint8_t> b = write_image(tiny_image());
  b[0] = 'X';
  EXPECT_REFUSED(refusal(b), "t.bin: offset 0x0: ", "bad magic");
  std::vector<uint8_t> text(b.size(), ' ');
  EXPECT_REFUSED(refusal(text), "bad magic");
}

TEST(Image, UnsupportedVersion) {
  std::vector<uint8_t> b = write_image(tiny_image());
  b[8] = 3;
  reseal(b);
  EXPECT_REFUSED(refusal(b), "offset 0x8: ", "unsupported format version 3");
  b[8] = 1;  // version 1 kept the REAL function table inside the memory image
  reseal(b);
  EXPECT_REFUSED(refusal(b), "offset 0x8: ", "unsupported format version 1 (this loader reads version 2)");
}

TEST(Image, UnknownTarget) {
  std::vector<uint8_t> b = write_image(tiny_image());
  b[10] = 7;
  reseal(b);
  EXPECT_REFUSED(refusal(b), "offset 0xa: ", "unknown target 7");
}

TEST(Image, UnknownFlags) {
  std::vector<uint8_t> b = write_image(tiny_image());
  b[11] = 1;
  reseal(b);
  EXPECT_REFUSED(refusal(b), "offset 0xb: ", "unknown flags");
}

TEST(Image, FlippedByteAnywhereIsRefused) {
  std::vector<uint8_t> b = write_image(tiny_image());
  for (size_t i = 0; i < b.size(); i++) {
    for (uint8_t mask : {0x01, 0x80}) {
      std::vector<uint8_t> c = b;
      c[i] ^= mask;
      std::string msg = refusal(c);
      ASSERT_FALSE(msg.empty()) << "accepted with byte " << i << " flipped";
      // Past the fields checked before the checksum, only the checksum can tell.
      if (i >= 24) {
        EXPECT_NE(msg.find("bad checksum"), std::string::npos) << i << ": " << msg;
      }
    }
  }
}

TEST(Image, BadChecksumNamesTheField) {
  std::vector<uint8_t> b = write_image(tiny_image());
  b[b.size() - 1] ^= 0xFF;
  EXPECT_REFUSED(refusal(b), "t.bin: offset 0x18: bad checksum");
}

TEST(Image, SectionPastTheEnd) {
  std::vector<uint8_t> b = write_image(tiny_image());
  int il = find_section(b, 2);
  put32(b, entry_at(il) + 8, uint32_t(b.size()));
  reseal(b);
  EXPECT_REFUSED(refusal(b), "section table entry 1 ('il')", "runs past the end of the file");
  // An offset near 2^32 must not wrap around.
  b = write_image(tiny_image());
  put32(b, entry_at(il) + 4, 0xFFFFFFFC);
  put32(b, entry_at(il) + 8, 8);
  reseal(b);
  EXPECT_REFUSED(refusal(b), "runs past the end of the file");
}

TEST(Image, OverlappingSections) {
  std::vector<uint8_t> b = write_image(tiny_image());
  int code = find_section(b, 1), il = find_section(b, 2);
  put32(b, entry_at(il) + 4, get32(b, entry_at(code) + 4) + 4);  // the IL starts inside the code
  reseal(b);
  EXPECT_REFUSED(refusal(b), "section 'il'", "overlaps section 'code'");
}

TEST(Image, SectionInsideTheHeader) {
  std::vector<uint8_t> b = write_image(tiny_image());
  put32(b, entry_at(0) + 4, 32);
  reseal(b);
  EXPECT_REFUSED(refusal(b), "lies inside the header");
}

TEST(Image, MisalignedSection) {
  std::vector<uint8_t> b = write_image(tiny_image());
  put32(b, entry_at(1) + 4, get32(b, entry_at(1) + 4) + 1);
  reseal(b);
  EXPECT_REFUSED(refusal(b), "not 4-byte aligned");
}

TEST(Image, DuplicateSection) {
  std::vector<uint8_t> b = write_image(tiny_image());
  put32(b, entry_at(find_section(b, 3)), 2);  // the line map claims to be a second IL
  reseal(b);
  EXPECT_REFUSED(refusal(b), "second 'il' section");
}

TEST(Image, UnknownSectionId) {
  std::vector<uint8_t> b = write_image(tiny_image());
  put32(b, entry_at(2), 99);
  reseal(b);
  EXPECT_REFUSED(refusal(b), "unknown section id 99");
}

TEST(Image, MissingRequiredSections) {
  for (uint32_t id : {1u, 2u}) {
    std::vector<uint8_t> b = write_image(tiny_image());
    // Swap the entry to the end of the table and drop it from the count.
    int i = find_section(b, id), last = int(get32(b, 20)) - 1;
    for (int k = 0; k < 12; k++) std::swap(b[entry_at(i) + k], b[entry_at(last) + k]);
    put32(b, 20, uint32_t(last));
    put32(b, 12, get32(b, 12) - 12);
    reseal(b);
    EXPECT_REFUSED(refusal(b), id == 1 ? "no 'code' section" : "no 'il' section");
  }
}

TEST(Image, HeaderSizeMustMatchTheTable) {
  std::vector<uint8_t> b = write_image(tiny_image());
  put32(b, 12, get32(b, 12) + 4);
  EXPECT_REFUSED(refusal(b), "offset 0xc: header size");
  b = write_image(tiny_image());
  put32(b, 20, 1000);
  EXPECT_REFUSED(refusal(b), "section count 1000");
}

TEST(Image, SectionContentsMustFillTheSection) {
  std::vector<uint8_t> b = write_image(tiny_image());
  int s = find_section(b, 7);  // entry: exactly 4 bytes
  put32(b, entry_at(s) + 8, 0);
  reseal(b);
  EXPECT_REFUSED(refusal(b), "section 'entry'", "truncated entry point");
  b = write_image(tiny_image());
  s = find_section(b, 4);  // strings: a title count far beyond the section
  uint32_t off = get32(b, entry_at(s) + 4);
  put32(b, off + 4 + 4, 0x7FFFFFFF);  // after the 4-char source name "t.ld"
  reseal(b);
  EXPECT_REFUSED(refusal(b), "section 'strings'", "does not fit");
  b = write_image(tiny_image());
  s = find_section(b, 3);  // lines: not a whole number of entries
  put32(b, entry_at(s) + 8, get32(b, entry_at(s) + 8) - 4);
  reseal(b);
  EXPECT_REFUSED(refusal(b), "section 'lines'", "not a multiple");
}

// ------------------------------------------------------------------ layout and IL

TEST(Image, LayoutMismatch) {
  Image im = tiny_image();
  im.layout.offset[int(Area::Y)] += 4;
  EXPECT_REFUSED(refusal(im), "layout mismatch: area Y at");
  im = tiny_image();
  im.layout.count[int(Area::D)] = 100;
  EXPECT_REFUSED(refusal(im), "layout mismatch: area D has 100 elements");
  im = tiny_image();
  im.layout.size += 16;
  EXPECT_REFUSED(refusal(im), "layout mismatch: memory image size");
  im = tiny_image();
  im.layout = Layout::standard(3);  // consistent, but the IL and code were built for 0 edge slots: still valid
  EXPECT_EQ(refusal(im), "");
  im.layout.count[int(Area::E)] = 0xFFFFFFFF;  // would overflow the layout arithmetic
  EXPECT_REFUSED(refusal(im), "edge slots exceed the limit");
}

TEST(Image, InvalidIl) {
  Image im = tiny_image();
  im.il.push_back(0xFF);
  EXPECT_REFUSED(refusal(im), "section 'il' at offset 0x", "invalid IL: offset 8: unknown opcode 255");
  im = tiny_image();
  im.il.pop_back();  // truncated operand
  EXPECT_REFUSED(refusal(im), "section 'il'", "invalid IL");
  // An edge slot beyond the layout's E area.
  Program p = parse_il_text(".edges 1\n.rung line 1\nLOADP X0 E0\nOUT Y0\n.end\n", "t.il");
  im = tiny_image();
  im.il = encode_il(p).code;
  im.lines.clear();
  EXPECT_REFUSED(refusal(im), "invalid IL", "edge slot 0 outside the edge area");
}

// ------------------------------------------------------------------ the x86 code check

TEST(Image, CodeMemoryOperandOutsideTheImage) {
  Image im = tiny_image();
  uint32_t size = im.layout.size;
  im.code = framed({"movzx eax, byte ptr [rbx+" + disp(size) + "]"});
  im.lines.clear();
  EXPECT_REFUSED(refusal(im), "section 'code'", "at code offset 0x8", "outside the memory image");
  im.code = framed({"nop", "mov dword ptr [rbx+" + disp(size - 2) + "], eax"});  // straddles the end
  EXPECT_REFUSED(refusal(im), "at code offset 0x9", "(4 bytes) outside the memory image");
  im.code = framed({"mov eax, dword ptr [rbx-0x4]"});
  EXPECT_REFUSED(refusal(im), "[rbx-0x4]", "outside the memory image");
  im.code = framed({"mov dword ptr [rbx+" + disp(size - 4) + "], eax"});  // the last word is fine
  EXPECT_EQ(refusal(im), "");
}

TEST(Image, CodeWrongBaseRegister) {
  Image im = tiny_image();
  im.lines.clear();
  im.code = framed({"movzx eax, byte ptr [rcx+0x10]"});
  EXPECT_REFUSED(refusal(im), "based on rcx, not rbx");
  im.code = framed({"mov eax, dword ptr [r11+0x10]"});
  EXPECT_REFUSED(refusal(im), "based on r11, not rbx");
  im.code = framed({"mov dword ptr [rsp+0x8], eax"});
  EXPECT_REFUSED(refusal(im), "stack-relative");
  im.code = framed({"mov eax, dword ptr [rbp-0x8]"});
  EXPECT_REFUSED(refusal(im), "stack-relative");
  im.code = framed({"mov eax, dword ptr [rip+0x10]"});
  EXPECT_REFUSED(refusal(im), "rip-relative");
  im.code = framed({"mov eax, dword ptr [rbx+rcx*4+0x10]"});
  EXPECT_REFUSED(refusal(im), "indexed memory operand");
}

TEST(Image, CodeUndecodableBytes) {
  Image im = tiny_image();
  im.lines.clear();
  im.code = assemble({"xor eax, eax"});
  size_t bad = im.code.size();
  im.code.push_back(0x0F);
  im.code.push_back(0x0B);  // ud2: not in the subset
  im.code.push_back(0xC3);
  EXPECT_REFUSED(refusal(im), "at code offset " + disp(uint32_t(bad)) + ": undecodable bytes 0f 0b c3");
  im.code = assemble({"mov eax, dword ptr [rbx+0x40]"});
  im.code.pop_back();  // cut inside the displacement
  EXPECT_REFUSED(refusal(im), "at code offset 0x0: undecodable bytes");
}

TEST(Image, CodeJumpIntoTheMiddleOfAnInstruction) {
  Image im = tiny_image();
  im.lines.clear();
  // 0: test al, al (2)  2: je 7 (2)  4: mov eax, 0x1 (5)  9: ret -- 7 is inside the mov.
  // body offsets: test al, al 0; je 2; mov eax, 0x1 4..8; the epilogue at 9
  im.code = framed({"test al, al", "je 0x7", "mov eax, 0x1"});
  EXPECT_REFUSED(refusal(im), "at code offset 0xa", "branch target 0xf is inside an instruction");
  im.code = framed({"test al, al", "je 0x9", "mov eax, 0x1"});  // to the epilogue: scan_exit
  EXPECT_EQ(refusal(im), "");
  im.code = framed({"jmp 0x40"});
  EXPECT_REFUSED(refusal(im), "branch target 0x48 outside the scan body");
  im.code = framed({"nop", "jmp 0x0"});  // backward: a loop
  EXPECT_REFUSED(refusal(im), "backward branch");
  im.code = framed({"jmp 0x5", "nop"});  // onto itself or behind: still backward/not forward
  EXPECT_NE(refusal(im), "");
  im.code = framed({"call 0x5", "nop", "nop", "nop", "nop", "nop"});  // a direct call: never emitted
  EXPECT_REFUSED(refusal(im), "direct call");
  im.code = framed({"jmp rax"});
  EXPECT_REFUSED(refusal(im), "indirect branch through a register");
  im.code = framed({"call rax"});
  EXPECT_REFUSED(refusal(im), "indirect branch through a register");
  im.code = framed({"call qword ptr [rbx-0x18]"});  // past the call table
  EXPECT_REFUSED(refusal(im), "indirect call not through the REAL function table");
  im.code = framed({"call qword ptr [rbx-0x3c]"});  // inside a slot
  EXPECT_REFUSED(refusal(im), "indirect call not through the REAL function table");
  im.code = framed({"call qword ptr [rbx+0x10]"});  // where the table was before format version 2
  EXPECT_REFUSED(refusal(im), "indirect call not through the REAL function table");
  im.code = framed({"jmp qword ptr [rbx-0x40]"});
  EXPECT_REFUSED(refusal(im), "indirect branch through memory");
  im.code = framed({"call qword ptr [rbx-0x40]", "call qword ptr [rbx-0x20]"});  // sinf, logf
  EXPECT_EQ(refusal(im), "");
}

TEST(Image, TheScanBodyKeepsTheFrame) {
  Image im = tiny_image();
  im.lines.clear();
  im.code = framed({"push rax"});
  EXPECT_REFUSED(refusal(im), "the stack is touched only by the prologue and the epilogue");
  im.code = framed({"pop rax"});
  EXPECT_REFUSED(refusal(im), "the stack is touched only");
  im.code = framed({"ret"});
  EXPECT_REFUSED(refusal(im), "the stack is touched only");
  for (const char* w : {"mov rbx, rax", "xor ebx, ebx", "lea rbx, [rbx+0x10]", "add rsp, 0x8", "mov bl, al", "setne bl"}) {
    im.code = framed({w});
    SCOPED_TRACE(w);
    EXPECT_REFUSED(refusal(im), "the image base and the stack pointer are fixed");
  }
  im.code = framed({"mov r12b, byte ptr [rbx+0x50]"});  // an -O2 slot needs the -O2 frame, which saves r12-r15
  EXPECT_REFUSED(refusal(im), "writes r12b, which the caller owns: only the -O2 frame saves r12-r15");
  std::vector<uint8_t> no_epilogue = framed({"nop"});
  no_epilogue.pop_back();  // drop the ret
  im.code = no_epilogue;
  EXPECT_REFUSED(refusal(im), "does not end with the scan function's epilogue");
}

TEST(Image, LeaIsArithmeticNotAMemoryAccess) {
  Image im = tiny_image();
  im.lines.clear();
  im.code = framed({"lea ebp, [rax+rbp*2]", "lea ebp, [rbp+rbp*1+0x1]"});
  EXPECT_EQ(refusal(im), "");
  im.code = framed({"movzx eax, byte ptr [rax+rbp*2]"});
  EXPECT_REFUSED(refusal(im), "not rbx");
}

TEST(Image, EntryPoint) {
  Image im = tiny_image();
  im.entry = uint32_t(im.code.size());
  EXPECT_REFUSED(refusal(im), "section 'entry'", "entry point", "outside the code");
  im.entry = 4;  // inside `mov rbx, rdi`
  EXPECT_REFUSED(refusal(im), "section 'code'", "entry point 0x4 is inside an instruction");
  im.entry = 8;  // a boundary, but not the prologue
  EXPECT_REFUSED(refusal(im), "section 'code'", "not the scan function's prologue");
  im = tiny_image();
  im.code.clear();
  im.lines.clear();
  EXPECT_REFUSED(refusal(im), "outside the code (0 bytes)");
}

TEST(Image, CheckX86CodeAcceptsTheTinyProgram) {
  Image im = tiny_image();
  EXPECT_EQ(check_x86_code(im.code, 0, im.layout), "");
  EXPECT_NE(check_x86_code(im.code, 2, im.layout), "");
}

// ------------------------------------------------------------------ line map, aliases, retentive ranges

TEST(Image, LineMapOutsideCodeOrIl) {
  Image im = tiny_image();
  im.lines[1].code_offset = uint32_t(im.code.size()) + 1;
  EXPECT_REFUSED(refusal(im), "section 'lines'", "entry 1", "outside the code");
  im = tiny_image();
  im.lines[1].code_offset = 9;  // inside the movzx
  EXPECT_REFUSED(refusal(im), "code offset 0x9 is not an instruction boundary");
  im = tiny_image();
  im.lines[0].code_offset = uint32_t(im.code.size());  // an instruction with no code, at the end: fine
  EXPECT_EQ(refusal(im), "");
  im = tiny_image();
  im.lines[0].il_offset = uint32_t(im.il.size());
  EXPECT_REFUSED(refusal(im), "IL offset", "outside the IL");
  im = tiny_image();
  im.lines[0].il_offset = 1;
  EXPECT_REFUSED(refusal(im), "IL offset 1 is not an IL instruction boundary");
  im = tiny_image();
  im.lines[0].rung = 1;
  EXPECT_REFUSED(refusal(im), "rung 1 but the image has 1 rungs");
  im = tiny_image();
  im.lines[0].line = -3;
  EXPECT_REFUSED(refusal(im), "negative source line");
}

TEST(Image, AliasOutOfRange) {
  Image im = tiny_image();
  im.aliases.push_back({"big", {Dev::T, 256}});
  EXPECT_REFUSED(refusal(im), "section 'aliases'", "alias 3", "'big' names T256, outside T0..T255");
  im = tiny_image();
  im.aliases.push_back({"odd", {Dev(42), 0}});
  EXPECT_REFUSED(refusal(im), "unknown device kind 42");
  im = tiny_image();
  im.aliases.push_back({"", {Dev::X, 1}});
  EXPECT_REFUSED(refusal(im), "empty alias name");
}

// Typed aliases (docs/image-format.md): bit 7 of the kind and a type byte
// after the name; they round-trip, and the reader holds them to the rules the
// IL text's reader holds them to, whatever the file says.
TEST(Image, TypedAliases) {
  Image im = tiny_image();
  im.aliases.push_back({"big", {Dev::D, 10}, Ty::LINT});
  im.aliases.push_back({"on", {Dev::T, 3}, Ty::BOOL});
  std::vector<uint8_t> file = write_image(im);
  EXPECT_EQ(read_image(file, "t.bin").aliases, im.aliases);
  im = tiny_image();
  im.aliases.push_back({"b", {Dev::D, 0}, Ty::BOOL});
  EXPECT_REFUSED(refusal(im), "section 'aliases'", "alias 3", "a BOOL names a bit device");
  im = tiny_image();
  im.aliases.push_back({"n", {Dev::D, 8191}, Ty::LREAL});
  EXPECT_REFUSED(refusal(im), "alias 3", "its 2 cells run past D8191");
  im = tiny_image();
  im.aliases.push_back({"n", {Dev::Y, 0}, Ty::DINT});
  EXPECT_REFUSED(refusal(im), "a DINT names a word device");
  im = tiny_image();
  im.aliases.push_back({"n", {Dev::D, 0}, Ty(200)});
  EXPECT_REFUSED(refusal(im), "alias 3", "'n': unknown type 200");
  im = tiny_image();
  im.aliases.push_back({"n", {Dev::D, 0}, Ty::None});
  EXPECT_EQ(refusal(im), "");
}

TEST(Image, RetentiveRangeOutsideItsArea) {
  Image im = tiny_image();
  im.retentive = {{Area::D, 8000, 193}};
  EXPECT_REFUSED(refusal(im), "section 'retentive'", "range 0", "D[8000..8192] outside the area (8192 elements)");
  im.retentive = {{Area::D, 0xFFFFFFFF, 2}};  // must not wrap
  EXPECT_REFUSED(refusal(im), "outside the area");
  im.retentive = {{Area::E, 0, 1}};  // no edge slots in this program
  EXPECT_REFUSED(refusal(im), "outside the area (0 elements)");
  im.retentive = {{Area::Sys, 0, 4}};
  EXPECT_REFUSED(refusal(im), "Sys area cannot be retentive");
  im.retentive = {{Area::Count, 0, 4}};
  EXPECT_REFUSED(refusal(im), "unknown area 16");
  im.retentive = {{Area::K, 0, 0}};
  EXPECT_REFUSED(refusal(im), "empty range");
}

// ------------------------------------------------------------------ robustness

TEST(Image, RandomCodeNeverCrashes) {
  Layout layout = Layout::standard(0);
  std::mt19937 rng(5);
  std::vector<uint8_t> good = tiny_image().code;
  for (int iter = 0; iter < 20000; iter++) {
    std::vector<uint8_t> code = good;
    if (iter % 2) {
      code.resize(rng() % 24);
      for (auto& x : code) x = uint8_t(rng());
    } else {
      code[rng() % code.size()] = uint8_t(rng());
    }
    std::string why = check_x86_code(code, 0, layout);
    if (!why.empty()) {
      EXPECT_TRUE(why.rfind("at code offset", 0) == 0 || why.rfind("entry point", 0) == 0) << why;
    }
  }
}

// docs/image-format.md shows the bytes of an example image; they must be what
// the writer produces.
TEST(Image, DocExampleMatchesWriter) {
  std::ifstream f(LDC_IMAGE_DOC);
  ASSERT_TRUE(f) << LDC_IMAGE_DOC;
  std::stringstream ss;
  ss << f.rdbuf();
  std::string doc = ss.str();
  size_t begin = doc.find("<!-- image-dump-begin -->"), end = doc.find("<!-- image-dump-end -->");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  std::vector<uint8_t> dumped;
  std::istringstream lines(doc.substr(begin, end - begin));
  for (std::string line; std::getline(lines, line);) {
    if (line.size() < 5 || line[4] != ':') continue;
    std::istringstream in(line.substr(5));
    for (std::string byte; in >> byte;) dumped.push_back(uint8_t(std::stoul(byte, nullptr, 16)));
  }
  Image im = tiny_image();
  im.aliases = {{"start", {Dev::X, 0}}};
  im.retentive = {{Area::K, 0, 8192}};
  std::vector<uint8_t> b = write_image(im);
  std::string want;  // the dump as the doc spells it, to paste there when the format changes
  for (size_t i = 0; i < b.size(); i++) {
    char buf[24];
    if (i % 16 == 0) std::snprintf(buf, sizeof buf, "%s%04zx:", i ? "\n" : "", i), want += buf;
    std::snprintf(buf, sizeof buf, " %02x", b[i]), want += buf;
  }
  EXPECT_EQ(dumped, b) << "the writer's bytes:\n" << want;
  std::string hex = write_intel_hex(b);
  EXPECT_NE(doc.find("\n" + hex.substr(0, hex.find('\n') + 1)), std::string::npos) << "first HEX record not in the doc";
}

// Random edits with the checksum fixed up reach the structural and semantic
// checks; every outcome must be an accepted image or an ImageError.
TEST(Image, RandomEditsNeverCrash) {
  std::vector<uint8_t> good = write_image(tiny_image());
  std::mt19937 rng(12345);
  int accepted = 0;
  for (int iter = 0; iter < 20000; iter++) {
    std::vector<uint8_t> b = good;
    int edits = 1 + int(rng() % 4);
    for (int k = 0; k < edits; k++) {
      size_t at = 32 + rng() % (b.size() - 32);
      switch (rng() % 3) {
        case 0: b[at] = uint8_t(rng()); break;
        case 1: b[at] ^= uint8_t(1u << (rng() % 8)); break;
        default: if (at + 4 <= b.size()) put32(b, at, (rng() % 2) ? uint32_t(rng()) : 0xFFFFFFFFu - rng() % 16); break;
      }
    }
    reseal(b);
    try {
      read_image(b, "r.bin");
      accepted++;
    } catch (const ImageError&) {
    }
  }
  SUCCEED() << accepted << " edited images accepted";
}

TEST(Image, RandomBytesNeverCrash) {
  std::mt19937 rng(99);
  for (int iter = 0; iter < 2000; iter++) {
    std::vector<uint8_t> b(rng() % 400);
    for (auto& x : b) x = uint8_t(rng());
    if (b.size() >= 8 && rng() % 2) std::copy_n("LDCIMG\0\1", 8, b.begin());
    EXPECT_THROW(read_image(b, "r.bin"), ImageError);
  }
}

}  // namespace
}  // namespace ldc::test
