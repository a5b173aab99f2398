// runtime/native.cpp -- running native scan code: the code is mapped writable,
// copied, then made read+execute (never writable and executable at once).
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "runtime/runtime.h"

namespace ldc {
namespace {

constexpr size_t kHuge = size_t(2) << 20;

class NativeEngine : public Engine {
 public:
  NativeEngine(std::span<const uint8_t> code, uint32_t entry) {
    if (code.empty() || entry >= code.size()) throw std::runtime_error("native code: empty, or entry outside the code");
    void* p = map_code(code.size());
    std::memcpy(p, code.data(), code.size());
    if (mprotect(p, size_, PROT_READ | PROT_EXEC) != 0) {
      int e = errno;
      munmap(p, size_);
      throw std::runtime_error(std::string("cannot make code executable: ") + std::strerror(e));
    }
    base_ = p;
    fn_ = reinterpret_cast<void (*)(uint8_t*)>(static_cast<uint8_t*>(p) + entry);
  }
  ~NativeEngine() override { munmap(base_, size_); }
  void scan(uint8_t* mem) override { fn_(mem); }

 private:
  void* map_code(size_t n) {
    size_t page = size_t(sysconf(_SC_PAGESIZE));
    size_ = (n + page - 1) / page * page;
    if (n >= kHuge / 8) {
      size_t huge = (n + kHuge - 1) / kHuge * kHuge;
      void* q = mmap(nullptr, huge + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (q != MAP_FAILED) {
        uintptr_t a = (reinterpret_cast<uintptr_t>(q) + kHuge - 1) & ~(kHuge - 1);
        size_t before = a - reinterpret_cast<uintptr_t>(q), after = kHuge - before;
        if (before) munmap(q, before);
        if (after) munmap(reinterpret_cast<void*>(a + huge), after);
        madvise(reinterpret_cast<void*>(a), huge, MADV_HUGEPAGE);
        size_ = huge;
        return reinterpret_cast<void*>(a);
      }
    }
    void* p = mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::runtime_error(std::string("cannot map code: ") + std::strerror(errno));
    return p;
  }
  void* base_ = nullptr;
  size_t size_ = 0;
  void (*fn_)(uint8_t*) = nullptr;
};

}  // namespace

std::unique_ptr<Engine> make_native_engine(std::span<const uint8_t> code, uint32_t entry) {
  return std::make_unique<NativeEngine>(code, entry);
}

}  // namespace ldc
