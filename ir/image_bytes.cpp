// ir/image_bytes.cpp -- the pages a memory image lives on (ImageBytes in ir.h):
// guard, read-only call table, the image, guard.
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <new>

#include "ir/ir.h"
#include "ir/mathfn.h"
#include "ir/typed.h"

namespace ldc {
namespace {

// One function of our own per FN row (the table holds their addresses).
#define FN(name, libm, called, ints) float fn_##name(float x) { return ::libm(x); }
#include "ir/ops.def"

// The typed instructions' double functions (ir.h, MathFn), as ir/typed.h
// calls them: a NaN result by typed::nan_rule (docs/il.md, "NaN results"), so
// native code stores the reference's bits whatever the C library's NaN is.
double m_log(double x) { return typed::nan_rule(std::log(x), x, x); }
double m_log10(double x) { return typed::nan_rule(std::log10(x), x, x); }
double m_exp(double x) { return typed::nan_rule(std::exp(x), x, x); }
double m_sin(double x) { return typed::nan_rule(std::sin(x), x, x); }
double m_cos(double x) { return typed::nan_rule(std::cos(x), x, x); }
double m_tan(double x) { return typed::nan_rule(std::tan(x), x, x); }
double m_asin(double x) { return typed::nan_rule(std::asin(x), x, x); }
double m_acos(double x) { return typed::nan_rule(std::acos(x), x, x); }
double m_atan(double x) { return typed::nan_rule(std::atan(x), x, x); }
double m_pow(double x, double y) { return typed::nan_rule(std::pow(x, y), x, y); }

size_t page_size() {
  static const size_t page = size_t(sysconf(_SC_PAGESIZE));
  return page;
}

}  // namespace

RealFnPtr real_fn(RealFn f) {
  static const RealFnPtr table[] = {
#define FN(name, libm, called, ints) fn_##name,
#include "ir/ops.def"
  };
  static_assert(sizeof table / sizeof table[0] == size_t(RealFn::None));
  return table[size_t(f)];
}

const void* math_fn_address(MathFn f) {
  static const void* const table[] = {reinterpret_cast<const void*>(m_log),  reinterpret_cast<const void*>(m_log10),
                                      reinterpret_cast<const void*>(m_exp),  reinterpret_cast<const void*>(m_sin),
                                      reinterpret_cast<const void*>(m_cos),  reinterpret_cast<const void*>(m_tan),
                                      reinterpret_cast<const void*>(m_asin), reinterpret_cast<const void*>(m_acos),
                                      reinterpret_cast<const void*>(m_atan), reinterpret_cast<const void*>(m_pow)};
  static_assert(sizeof table / sizeof table[0] == size_t(kMathSlots));
  return table[size_t(f)];
}

static_assert(kCallTableDisp + 8 * kCallSlots <= 0, "the call table lies below the image");
static_assert(kMathTableDisp + 8 * kMathSlots == kCallTableDisp, "the typed math table lies right below the REAL one");
static_assert(kStrSlotDisp + 8 == kMathTableDisp, "the STRING routine's slot lies right below the math table");

void ImageBytes::map(size_t size, Sharing sharing) {
  const size_t page = page_size();
  size_t pages = (size + page - 1) / page;
  mapped_ = (pages + 3) * page;  // guard, table, image, guard
  void* p = mmap(nullptr, mapped_, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  base_ = static_cast<uint8_t*>(p);
  uint8_t* table = base_ + page;
  image_ = table + page;
  size_ = size;
  bool image_ok = pages == 0 ||
                  (sharing == Sharing::Shared
                       ? mmap(image_, pages * page, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS | MAP_FIXED, -1, 0) == image_
                       : mprotect(image_, pages * page, PROT_READ | PROT_WRITE) == 0);
  if (mprotect(table, page, PROT_READ | PROT_WRITE) != 0 || !image_ok) {
    unmap();
    throw std::bad_alloc();
  }
  for (int k = 0; k < kCallSlots; k++) {
    RealFnPtr f = real_fn(RealFn(k));
    std::memcpy(image_ + kCallTableDisp + 8 * k, &f, sizeof f);
  }
  for (int k = 0; k < kMathSlots; k++) {
    const void* f = math_fn_address(MathFn(k));
    std::memcpy(image_ + kMathTableDisp + 8 * k, &f, sizeof f);
  }
  const void* str = reinterpret_cast<const void*>(native_string);
  std::memcpy(image_ + kStrSlotDisp, &str, sizeof str);
  std::memset(image_ + size, kSlackByte, pages * page - size);
  if (mprotect(table, page, PROT_READ) != 0) {
    unmap();
    throw std::bad_alloc();
  }
}

void ImageBytes::unmap() {
  if (base_) munmap(base_, mapped_);
  base_ = image_ = nullptr;
  mapped_ = size_ = 0;
}

ImageBytes::ImageBytes(size_t size, Sharing sharing) { map(size, sharing); }
ImageBytes::ImageBytes(const ImageBytes& o) {
  map(o.size_, Sharing::Private);
  std::memcpy(image_, o.image_, size_);
}
ImageBytes::ImageBytes(ImageBytes&& o) noexcept
    : base_(o.base_), mapped_(o.mapped_), image_(o.image_), size_(o.size_) {
  o.base_ = o.image_ = nullptr;
  o.mapped_ = o.size_ = 0;
}
ImageBytes& ImageBytes::operator=(const ImageBytes& o) {
  if (this != &o) {
    ImageBytes copy(o);
    *this = std::move(copy);
  }
  return *this;
}
ImageBytes& ImageBytes::operator=(ImageBytes&& o) noexcept {
  if (this != &o) {
    unmap();
    base_ = o.base_, mapped_ = o.mapped_, image_ = o.image_, size_ = o.size_;
    o.base_ = o.image_ = nullptr;
    o.mapped_ = o.size_ = 0;
  }
  return *this;
}
ImageBytes::~ImageBytes() { unmap(); }

bool ImageBytes::operator==(const ImageBytes& o) const {
  return size_ == o.size_ && (size_ == 0 || std::memcmp(image_, o.image_, size_) == 0);
}

bool ImageBytes::slack_intact() const {
  const size_t page = page_size();
  size_t end = (size_ + page - 1) / page * page;
  for (size_t i = size_; i < end; i++)
    if (image_[i] != kSlackByte) return false;
  return true;
}

}  // namespace ldc
