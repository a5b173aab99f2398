// The native engine runs only code the loader's check passed, by type
// (runtime.h, CheckedCode): make_native_engine takes a CheckedCode, which
// nothing but map_checked_code makes, and map_checked_code checks the bytes
// in the mapping they will run from.  The static_asserts are the test: a path
// that hands native code a plain vector or span, or hands any engine a
// memory image outside ImageBytes, stops the build here.
#include <gtest/gtest.h>

#include <span>
#include <type_traits>
#include <vector>

#include "runtime/runtime.h"

namespace ldc {
namespace {

using Bytes = std::vector<uint8_t>;
static_assert(!std::is_constructible_v<CheckedCode, Bytes>, "a vector of bytes is not checked code");
static_assert(!std::is_constructible_v<CheckedCode, std::span<const uint8_t>>, "nor a span");
static_assert(!std::is_constructible_v<CheckedCode, std::span<const uint8_t>, uint32_t>, "nor bytes and an entry");
static_assert(!std::is_default_constructible_v<CheckedCode>, "no empty checked code");
static_assert(!std::is_copy_constructible_v<CheckedCode>, "one mapping, one owner");
static_assert(!std::is_invocable_v<decltype(&make_native_engine), Bytes>, "the native engine takes no plain bytes");
static_assert(!std::is_invocable_v<decltype(&make_native_engine), std::span<const uint8_t>>, "nor a span");
static_assert(std::is_invocable_v<decltype(&make_native_engine), CheckedCode>, "it takes checked code");

// The memory image a scan runs over: only the guarded storage of ir.h
// (ImageBytes: guard pages on both sides, the REAL call table below it), never
// a vector's or any other pointer, for every engine (issue #24).
static_assert(!std::is_invocable_v<decltype(&Engine::scan), Engine&, uint8_t*>, "a scan takes no raw pointer");
static_assert(!std::is_invocable_v<decltype(&Engine::scan), Engine&, Bytes&>, "nor a vector");
static_assert(!std::is_invocable_v<decltype(&Engine::scan), Engine&, std::span<uint8_t>>, "nor a span");
static_assert(!std::is_invocable_v<decltype(&Engine::scan), Engine&, ImageBytes&&>, "nor a temporary");
static_assert(std::is_invocable_v<decltype(&Engine::scan), Engine&, ImageBytes&>, "it takes the guarded image");

// What map_checked_code refuses never maps: the loader's message comes back.
TEST(NativeType, UncheckedBytesAreRefusedWithTheChecksMessage) {
  const Layout L = Layout::standard(0);
  const Bytes ret_only = {0xc3};  // `ret`: not the scan function's frame
  try {
    (void)map_checked_code(ret_only, 0, L);
    FAIL() << "a bare ret was mapped";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "native code refused: at code offset 0x0: the entry is not the scan function's prologue (push rbx; push rbp; "
              "...; mov rbx, rdi, or lea rbp, [rdi+0x40] at -O2)");
  }
}

}  // namespace
}  // namespace ldc
