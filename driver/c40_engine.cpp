// driver/c40_engine.cpp -- the C40 engines (c40_target.h): the simulated
// board of backend-c40sim/machine running native C40 code or the C40-hosted
// interpreter, behind the runtime's Engine interface.  The driver wires the
// two together, so that runtime/ includes no backend.
#include "backend-c40sim/machine/c40interp.h"
#include "backend-c40sim/machine/c40machine.h"
#include "driver/c40_target.h"

namespace ldc {
namespace {

class C40MachineEngine : public Engine {
 public:
  C40MachineEngine(const Layout& layout, std::span<const uint32_t> code, uint32_t entry, std::span<const uint32_t> il)
      : m_(layout, code, entry, il) {}
  void scan(ImageBytes& mem_bytes) override {
    uint8_t* mem = mem_bytes.data();
    c40gen::ScanCost c = m_.scan(mem);
    last_ = ScanCost{c.cycles, c.instructions, c40gen::kNsPerCycle};
  }
  std::optional<ScanCost> last_cost() const override { return last_; }

 private:
  c40gen::C40Machine m_;
  ScanCost last_{0, 0, c40gen::kNsPerCycle};
};

}  // namespace

std::unique_ptr<Engine> make_c40sim_engine(std::span<const uint8_t> code, uint32_t entry, const Layout& layout) {
  if (code.size() % 4 || entry % 4) throw std::runtime_error("C40 code is not whole 32-bit words");
  std::vector<uint32_t> words = as::c40::words_of(code);
  return std::make_unique<C40MachineEngine>(layout, words, entry / 4, std::span<const uint32_t>{});
}

std::unique_ptr<Engine> make_c40interp_engine(std::span<const uint8_t> il, const Layout& layout) {
  const c40gen::InterpProgram& ip = c40gen::interp_program();
  std::vector<uint32_t> wil = c40gen::word_il(il, layout);
  return std::make_unique<C40MachineEngine>(layout, ip.words, ip.entry, wil);
}

}  // namespace ldc
