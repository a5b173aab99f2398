// Fuzz the Modbus TCP protocol (runtime/net/modbus.h): the input is the byte
// stream of one connection, served request by request as the server does,
// over a two-task view; every reply must be a well-formed frame answering its
// request, and every write must land inside the memory image (ASan checks).
#include <cstring>
#include <vector>

#include "runtime/net/modbus.h"
#include "tests/fuzz/fuzz_common.h"

using namespace ldc;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Layout layout = Layout::standard(0);
  // Exactly-sized images (no slack past the layout) so a stray access is
  // caught; made once (writes of earlier inputs stay: the checks do not
  // depend on the contents).
  static std::vector<uint8_t> global(layout.size), t0(layout.size), t1(layout.size);
  static bool filled = false;
  if (!filled) {
    for (size_t i = 0; i < layout.size; i++) global[i] = uint8_t(i * 7), t0[i] = uint8_t(i * 13), t1[i] = uint8_t(i * 31);
    filled = true;
  }
  modbus::View view{&layout, global.data(), {t0.data(), t1.data()}};
  std::span<const uint8_t> in(data, size);
  while (true) {
    modbus::Outcome o = modbus::serve(in, view);
    if (o.kind == modbus::Outcome::NeedMore) break;
    if (o.consumed == 0 || o.consumed > in.size()) __builtin_trap();  // no progress, or past the input
    if (o.kind == modbus::Outcome::Close) break;
    const std::vector<uint8_t>& r = o.reply;
    // MBAP: transaction echoed, protocol 0, length = what follows, unit echoed; then the function code.
    if (r.size() < 9 || r.size() > modbus::kMaxAdu) __builtin_trap();
    if (std::memcmp(r.data(), in.data(), 4) != 0 || r[6] != in[6]) __builtin_trap();
    if (size_t(r[4] << 8 | r[5]) != r.size() - 6) __builtin_trap();
    if ((r[7] & 0x7F) != (in[7] & 0x7F)) __builtin_trap();
    bool exception = r[7] & 0x80;
    if (exception && (r.size() != 9 || !o.writes.empty())) __builtin_trap();
    if (o.task >= view.tasks.size()) __builtin_trap();
    for (const modbus::Write& w : o.writes) {
      if (w.index >= layout.count[int(w.area)]) __builtin_trap();
      plc::apply_element(w, w.area == Area::D || w.area == Area::F ? (o.task ? t1.data() : t0.data()) : global.data(), layout);
    }
    in = in.subspan(o.consumed);
  }
  return 0;
}
