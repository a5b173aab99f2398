// runtime/c_engine.cpp -- the C route's scan function, from a shared object
// built by the system C compiler from `ldc --emit=c` (POSIX dlopen).
#include <dlfcn.h>

#include <stdexcept>

#include "runtime/runtime.h"

namespace ldc {
namespace {

class SharedObjectEngine : public Engine {
 public:
  SharedObjectEngine(const std::string& path, const std::string& symbol) {
    handle_ = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle_) throw std::runtime_error(std::string("cannot load ") + path + ": " + dlerror());
    void* f = dlsym(handle_, symbol.c_str());
    if (!f) {
      std::string e = dlerror();
      dlclose(handle_);
      throw std::runtime_error(path + ": no symbol " + symbol + ": " + e);
    }
    fn_ = reinterpret_cast<void (*)(uint8_t*)>(f);
  }
  ~SharedObjectEngine() override { dlclose(handle_); }
  void scan(ImageBytes& mem) override { fn_(mem.data()); }

 private:
  void* handle_ = nullptr;
  void (*fn_)(uint8_t*) = nullptr;
};

}  // namespace

std::unique_ptr<Engine> make_shared_object_engine(const std::string& path, const std::string& symbol) {
  return std::make_unique<SharedObjectEngine>(path, symbol);
}

}  // namespace ldc
