// runtime/native.cpp -- running native scan code: the code is mapped writable,
// copied, checked where it lies (the loader's x86-64 code check), then made
// read+execute (never writable and executable at once).
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <functional>
#include <stdexcept>

#include "ir/mathfn.h"
#include "loader/loader.h"
#include "runtime/runtime.h"

namespace ldc {
namespace {

constexpr size_t kHuge = size_t(2) << 20;

// Read+write memory for n bytes of code: code of 256 KiB and more on 2 MiB-
// aligned memory with MADV_HUGEPAGE (one iTLB entry where the kernel grants
// it; docs/runtime.md), the rest on ordinary pages.  `mapped` gets its size.
void* map_code(size_t n, size_t& mapped) {
  size_t page = size_t(sysconf(_SC_PAGESIZE));
  mapped = (n + page - 1) / page * page;
  if (n >= kHuge / 8) {
    size_t huge = (n + kHuge - 1) / kHuge * kHuge;
    void* q = mmap(nullptr, huge + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (q != MAP_FAILED) {
      uintptr_t a = (reinterpret_cast<uintptr_t>(q) + kHuge - 1) & ~(kHuge - 1);
      size_t before = a - reinterpret_cast<uintptr_t>(q), after = kHuge - before;
      if (before) munmap(q, before);
      if (after) munmap(reinterpret_cast<void*>(a + huge), after);
      madvise(reinterpret_cast<void*>(a), huge, MADV_HUGEPAGE);
      mapped = huge;
      return reinterpret_cast<void*>(a);
    }
  }
  void* p = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::runtime_error(std::string("cannot map code: ") + std::strerror(errno));
  return p;
}

}  // namespace

namespace {

// A writable copy of `code` in a fresh mapping, made read+execute once
// `check` (on the copy: the bytes that will run) says "".
struct Mapped {
  void* base;
  size_t mapped;
};
Mapped map_and_check(std::span<const uint8_t> code, const std::function<std::string(std::span<const uint8_t>)>& check);

}  // namespace

CheckedCode map_checked_code(std::span<const uint8_t> code, uint32_t entry, const Layout& layout) {
  if (code.empty() || entry >= code.size()) throw std::runtime_error("native code: empty, or entry outside the code");
  Mapped m = map_and_check(code, [&](std::span<const uint8_t> copy) { return check_x86_code(copy, entry, layout); });
  return CheckedCode(m.base, m.mapped, code.size(), entry);
}

CheckedRegions map_checked_regions(std::span<const uint8_t> code, std::span<const uint32_t> start,
                                   std::span<const uint32_t> size, const Layout& layout) {
  if (code.empty() || start.empty() || start.size() != size.size())
    throw std::runtime_error("native code: no regions, or a region without its size");
  auto check = [&](std::span<const uint8_t> copy) -> std::string {
    uint64_t end = 0;
    for (size_t i = 0; i < start.size(); i++) {
      const std::string at = "region " + std::to_string(i) + " ";
      if (start[i] < end) return at + "starts at " + std::to_string(start[i]) + ", inside the region before it";
      if (size[i] == 0 || uint64_t(start[i]) + size[i] > copy.size())
        return at + "[" + std::to_string(start[i]) + ", +" + std::to_string(size[i]) + ") is empty or outside the code (" +
               std::to_string(copy.size()) + " bytes)";
      end = uint64_t(start[i]) + size[i];
      std::string why = check_x86_code(copy.subspan(start[i], size[i]), 0, layout);
      if (!why.empty()) return at + "(its bytes from code offset " + std::to_string(start[i]) + "): " + why;
    }
    return "";
  };
  Mapped m = map_and_check(code, check);
  return CheckedRegions(CheckedCode(m.base, m.mapped, code.size(), start[0]), std::vector<uint32_t>(start.begin(), start.end()));
}

namespace {

Mapped map_and_check(std::span<const uint8_t> code, const std::function<std::string(std::span<const uint8_t>)>& check) {
  size_t mapped = 0;
  void* p = map_code(code.size(), mapped);
  std::memcpy(p, code.data(), code.size());
  // the copy is what will run: check it, not the caller's bytes
  std::string why = check({static_cast<const uint8_t*>(p), code.size()});
  if (!why.empty()) {
    munmap(p, mapped);
    throw std::runtime_error("native code refused: " + why);
  }
  if (mprotect(p, mapped, PROT_READ | PROT_EXEC) != 0) {
    int e = errno;
    munmap(p, mapped);
    throw std::runtime_error(std::string("cannot make code executable: ") + std::strerror(e));
  }
  return {p, mapped};
}

}  // namespace

CheckedCode::CheckedCode(CheckedCode&& o) noexcept : base_(o.base_), mapped_(o.mapped_), size_(o.size_), entry_(o.entry_) {
  o.base_ = nullptr, o.mapped_ = 0;
}
CheckedCode& CheckedCode::operator=(CheckedCode&& o) noexcept {
  if (this != &o) {
    if (base_) munmap(base_, mapped_);
    base_ = o.base_, mapped_ = o.mapped_, size_ = o.size_, entry_ = o.entry_;
    o.base_ = nullptr, o.mapped_ = 0;
  }
  return *this;
}
CheckedCode::~CheckedCode() {
  if (base_) munmap(base_, mapped_);
}

class NativeEngine : public Engine {
 public:
  explicit NativeEngine(CheckedCode code)
      : code_(std::move(code)), fn_(reinterpret_cast<void (*)(uint8_t*)>(static_cast<uint8_t*>(code_.base_) + code_.entry_)) {}
  void scan(ImageBytes& mem) override {
    ScanImageScope strings(mem.data(), mem.size());  // the image its STRING instructions work in (ir/mathfn.h)
    fn_(mem.data());
  }

 private:
  CheckedCode code_;
  void (*fn_)(uint8_t*) = nullptr;
};

std::unique_ptr<Engine> make_native_engine(CheckedCode code) { return std::make_unique<NativeEngine>(std::move(code)); }

// Region i of a change-driven scan: its function in the shared mapping.
class NativeRegionEngine : public Engine {
 public:
  NativeRegionEngine(std::shared_ptr<const CheckedRegions> code, size_t i)
      : code_(std::move(code)),
        fn_(reinterpret_cast<void (*)(uint8_t*)>(static_cast<uint8_t*>(code_->code_.base_) + code_->start_[i])) {}
  void scan(ImageBytes& mem) override {
    ScanImageScope strings(mem.data(), mem.size());
    fn_(mem.data());
  }

 private:
  std::shared_ptr<const CheckedRegions> code_;
  void (*fn_)(uint8_t*) = nullptr;
};

std::vector<std::unique_ptr<Engine>> make_native_region_engines(std::shared_ptr<const CheckedRegions> code) {
  std::vector<std::unique_ptr<Engine>> v;
  for (size_t i = 0; i < code->regions(); i++) v.push_back(std::make_unique<NativeRegionEngine>(code, i));
  return v;
}

}  // namespace ldc
