// The one-line parser and the printer.
#include <gtest/gtest.h>

#include "test_util.h"

using namespace ldc::as;
using namespace ldc::as::x86;

namespace {

TEST(X86Text, ParsesOperandKinds) {
  Instruction in = parse("  MOV EAX, DWORD PTR [RBX+RCX*4-0x10]   # comment");
  EXPECT_EQ(in.mnemonic, Mnemonic::Mov);
  ASSERT_EQ(in.num_operands, 2);
  EXPECT_EQ(in.ops[0].reg, r32(AX));
  const Mem& m = in.ops[1].mem;
  EXPECT_EQ(m.size, Size::Dword);
  EXPECT_EQ(m.base, r64(BX));
  EXPECT_EQ(m.index, r64(CX));
  EXPECT_EQ(m.scale, 4);
  EXPECT_EQ(m.disp, -16);

  in = parse("jne .Lskip");
  EXPECT_EQ(in.mnemonic, Mnemonic::Jcc);
  EXPECT_EQ(in.cond, Cond::NE);
  EXPECT_EQ(in.ops[0].kind, OperandKind::Label);
  EXPECT_EQ(in.ops[0].label, ".Lskip");

  in = parse("jz 0x40");
  EXPECT_EQ(in.cond, Cond::E);
  EXPECT_EQ(in.ops[0].kind, OperandKind::Address);
  EXPECT_EQ(in.ops[0].imm, 0x40);

  in = parse("{disp32} jmp rung_7");
  EXPECT_TRUE(in.long_branch);
  EXPECT_EQ(print(in), "{disp32} jmp rung_7");

  in = parse("add eax, -1");
  EXPECT_EQ(in.ops[1].imm, -1);
  in = parse("setnae r9b");
  EXPECT_EQ(in.cond, Cond::B);
  EXPECT_EQ(print(in), "setb r9b");
}

TEST(X86Text, ReadsObjdumpSpelling) {
  EXPECT_EQ(print(parse("mov    eax,DWORD PTR ds:0x1234")), "mov eax, dword ptr [0x1234]");
  EXPECT_EQ(print(parse("mov    eax,DWORD PTR [rbp+0x0]")), "mov eax, dword ptr [rbp]");
  EXPECT_EQ(print(parse("lea    eax,[rbx*1+0x0]")), "lea eax, [rbx*1]");
  EXPECT_EQ(print(parse("mov    eax,DWORD PTR [rbx+rbp*1]")), "mov eax, dword ptr [rbx+rbp]");
  EXPECT_EQ(print(parse("mov    eax,DWORD PTR [rip+0x10]        # 0x16")),
            "mov eax, dword ptr [rip+0x10]");
  EXPECT_EQ(parse("add    rsp,0xffffffffffffff80").ops[1].imm, -128);
}

TEST(X86Text, PrintsAddressesRelativeToABase) {
  EXPECT_EQ(print(parse("jmp 0x12"), false, ".Lrow"), "jmp .Lrow+0x12");
  EXPECT_EQ(print(parse("jmp -0x12"), true, ".Lrow"), "{disp32} jmp .Lrow-0x12");
  EXPECT_EQ(print(parse("call 0x12"), true), "call 0x12");
}

TEST(X86Text, ErrorsNameTheProblem) {
  struct Case {
    const char* text;
    const char* message;
  } cases[] = {
      {"", "expected a mnemonic"},
      {"frobnicate eax", "unknown mnemonic 'frobnicate'"},
      {"mov eax, ah", "register 'ah' is not supported"},
      {"mov eax, dword ptr [rbx+rsp*2]", "rsp cannot be an index"},
      {"mov eax, dword ptr [rbx+rcx*3]", "scale must be 1, 2, 4 or 8"},
      {"mov eax, dword ptr [ebx]", "address registers must be 64-bit"},
      {"mov eax, dword ptr [rbx+rcx+rdx]", "too many registers"},
      {"mov eax, dword ptr [rbx-rcx]", "cannot subtract a register"},
      {"mov eax, dword ptr [rbx+0x100000000]", "displacement out of range"},
      {"movaps xmm0, xmmword ptr [rbx]", "unknown mnemonic"},
      {"mov eax, xmmword ptr [rbx]", "operand size 'xmmword' is not supported"},
      {"mov eax, dword [rbx]", "expected 'ptr'"},
      {"mov eax, foo", "unexpected 'foo'"},
      {"jmp eax,", "expected an operand"},
      {"jmp byte", "expected 'ptr'"},
      {"mov eax, 0x1 0x2", "unexpected"},
      {"mov eax, 99999999999999999999", "number too large"},
      {"mov eax, 12ab", "malformed number"},
      {"{disp32} mov eax, ebx", "{disp32} is only supported on jmp and jcc"},
      {"{foo} jmp x", "only the {disp32} pseudo-prefix"},
      {"add eax, ebx, ecx, edx", "too many operands"},
      {"mov eax, dword ptr [rbx", "expected"},
      {"push rip", "rip is only allowed as a memory base"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      parse(c.text);
      ADD_FAILURE() << "no error";
    } catch (const AsmError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
      EXPECT_EQ(e.error().block, -1);
    }
  }
}

TEST(X86Text, EveryRegisterNameRoundTrips) {
  for (unsigned n = 0; n < 16; ++n) {
    for (Reg r : {r8(n), r32(n), r64(n), xmm(n)}) {
      std::string name(reg_name(r));
      Instruction in = r.cls == RegClass::Xmm   ? parse("movd " + name + ", eax")
                       : r.cls == RegClass::Gp8 ? parse("sete " + name)
                       : r.cls == RegClass::Gp32 ? parse("not " + name)
                                                 : parse("push " + name);
      EXPECT_EQ(in.ops[0].reg, r) << name;
    }
  }
}

}  // namespace
