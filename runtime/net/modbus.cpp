// runtime/net/modbus.cpp -- the Modbus TCP protocol (runtime/net/modbus.h): framing,
// the eight function codes, the address map, exception replies.  A pure
// function of the request bytes and a read-only view of the memory.
#include "runtime/net/modbus.h"

#include <cctype>
#include <cstring>
#include <stdexcept>

#include "ir/typed.h"
#include "runtime/runtime.h"

namespace ldc::modbus {

namespace {

uint16_t be16(const uint8_t* p) { return uint16_t(p[0] << 8 | p[1]); }
void put16(std::vector<uint8_t>& v, uint32_t x) {
  v.push_back(uint8_t(x >> 8));
  v.push_back(uint8_t(x));
}

uint32_t word_at(const uint8_t* mem, const Layout& l, Area a, uint32_t i) {
  uint32_t w;
  std::memcpy(&w, mem + l.addr(a, i), 4);
  return w;
}

// A request being answered: the header to echo, the PDU, the reply.
struct Req {
  const uint8_t* mbap;  // transaction (2), protocol (2), length (2), unit (1)
  const uint8_t* pdu;
  size_t n;             // PDU bytes
  const View& v;
  const uint8_t* task;  // the unit's task memory
  Outcome out;
};

// The named point at coil or register `a` (task 0's units only), or null.
const NamedPoint* named_at(const Req& r, bool coil, uint32_t a) {
  if (!r.v.named || r.out.task != 0) return nullptr;
  for (const NamedPoint& p : *r.v.named)
    if (p.coil == coil && a >= p.address && a < p.address + (coil ? 1 : registers_of(p.ty))) return &p;
  return nullptr;
}
bool coil_ok(const Req& r, uint32_t a) { return a < kCoilEnd || named_at(r, true, a); }
bool holding_ok(const Req& r, uint32_t a) { return a < kHoldEnd || named_at(r, false, a); }
bool all_ok(const Req& r, bool coil, uint32_t start, uint32_t count) {
  for (uint32_t i = 0; i < count; i++)
    if (!(coil ? coil_ok(r, start + i) : holding_ok(r, start + i))) return false;
  return true;
}

// A named value's register k (0 = the most significant 16 bits).
uint16_t named_register(const Req& r, const NamedPoint& p, uint32_t k) {
  const Layout& l = *r.v.layout;
  uint32_t n = registers_of(p.ty);
  uint64_t v = word_at(r.task, l, p.area, p.index);
  if (ty_info(p.ty).cells == 2) v |= uint64_t(word_at(r.task, l, p.area, p.index + 1)) << 32;
  return uint16_t(v >> (16 * (n - 1 - k)));
}

// Register k of a named value written: a 16-bit type takes the register
// wrapped to its width (sign-extended for the signed ones), as its cell
// holds it; a 32-bit one the half of its cell, a 64-bit one the half of the
// cell holding those bits.
Write named_write(const NamedPoint& p, uint32_t k, uint16_t value) {
  uint32_t n = registers_of(p.ty);
  if (n == 1) {
    uint64_t x = typed::is_signed(p.ty) ? uint64_t(int64_t(int16_t(value))) : uint64_t(value);
    return {p.area, p.index, uint32_t(typed::norm(p.ty, x)), 0xFFFFFFFFu};
  }
  uint32_t from_low = n - 1 - k;  // registers below this one
  uint32_t cell = p.index + from_low / 2;
  if (from_low % 2) return {p.area, cell, uint32_t(value) << 16, 0xFFFF0000u};
  return {p.area, cell, value, 0x0000FFFFu};
}

// The reply frame for PDU bytes `pdu`.
void reply(Req& r, const std::vector<uint8_t>& pdu) {
  auto& o = r.out.reply;
  o.assign(r.mbap, r.mbap + 4);
  put16(o, uint32_t(pdu.size() + 1));
  o.push_back(r.mbap[6]);
  o.insert(o.end(), pdu.begin(), pdu.end());
  r.out.kind = Outcome::Reply;
}

void exception(Req& r, uint8_t code) {
  r.out.writes.clear();
  reply(r, {uint8_t(r.pdu[0] | 0x80), code});
}

// ---- bits

uint8_t coil_at(const Req& r, uint32_t a) {
  const Layout& l = *r.v.layout;
  if (a >= kCoilEnd) {
    const NamedPoint* p = named_at(r, true, a);
    return r.task[l.addr(p->area, p->index)];  // its M bit (task 0's snapshot holds M too)
  }
  if (a < kCoilM) return r.v.global[l.addr(Area::Y, a - kCoilY)];
  if (a < kCoilK) return r.v.global[l.addr(Area::M, a - kCoilM)];
  return r.v.global[l.addr(Area::K, a - kCoilK)];
}

Write coil_write(const Req& r, uint32_t a, bool on) {
  if (a >= kCoilEnd) {
    const NamedPoint* p = named_at(r, true, a);
    return {p->area, p->index, on, 1};
  }
  if (a < kCoilM) return {Area::Y, a - kCoilY, on, 1};
  if (a < kCoilK) return {Area::M, a - kCoilM, on, 1};
  return {Area::K, a - kCoilK, on, 1};
}

// Discrete input `a`: X, then the done bits of the unit's task's timers and counters.
uint8_t discrete_at(const Req& r, uint32_t a) {
  const Layout& l = *r.v.layout;
  if (a < kDiscreteT) return r.v.global[l.addr(Area::X, a - kDiscreteX)];
  if (a < kDiscreteC) return r.task[l.addr(Area::TQ, a - kDiscreteT)];
  return r.task[l.addr(Area::CQ, a - kDiscreteC)];
}

// FC 1 and 2: quantity 1..2000, packed LSB first.
void read_bits(Req& r) {
  if (r.n != 5) return exception(r, kIllegalDataValue);
  uint32_t start = be16(r.pdu + 1), count = be16(r.pdu + 3);
  bool coils = r.pdu[0] == kReadCoils;
  if (count < 1 || count > 2000) return exception(r, kIllegalDataValue);
  if (coils ? !all_ok(r, true, start, count) : start + count > kDiscreteEnd) return exception(r, kIllegalDataAddress);
  std::vector<uint8_t> p{r.pdu[0], uint8_t((count + 7) / 8)};
  p.resize(2 + (count + 7) / 8);
  for (uint32_t i = 0; i < count; i++) {
    uint8_t b = coils ? coil_at(r, start + i) : discrete_at(r, start + i);
    if (b) p[2 + i / 8] |= uint8_t(1u << (i % 8));
  }
  reply(r, p);
}

// FC 5: 0xFF00 on, 0x0000 off.
void write_coil(Req& r) {
  if (r.n != 5) return exception(r, kIllegalDataValue);
  uint32_t a = be16(r.pdu + 1), value = be16(r.pdu + 3);
  if (value != 0xFF00 && value != 0) return exception(r, kIllegalDataValue);
  if (!coil_ok(r, a)) return exception(r, kIllegalDataAddress);
  r.out.writes.push_back(coil_write(r, a, value != 0));
  reply(r, std::vector<uint8_t>(r.pdu, r.pdu + 5));
}

// FC 15: quantity 1..1968, byte count = ceil(quantity / 8).
void write_coils(Req& r) {
  if (r.n < 6) return exception(r, kIllegalDataValue);
  uint32_t start = be16(r.pdu + 1), count = be16(r.pdu + 3), bytes = r.pdu[5];
  if (count < 1 || count > 1968 || bytes != (count + 7) / 8 || r.n != 6 + bytes) return exception(r, kIllegalDataValue);
  if (!all_ok(r, true, start, count)) return exception(r, kIllegalDataAddress);
  for (uint32_t i = 0; i < count; i++) r.out.writes.push_back(coil_write(r, start + i, (r.pdu[6 + i / 8] >> (i % 8)) & 1));
  reply(r, std::vector<uint8_t>(r.pdu, r.pdu + 5));
}

// ---- registers

// Holding register `a`: WY's low half; D and F high half at even addresses.
uint16_t holding_at(const Req& r, uint32_t a) {
  const Layout& l = *r.v.layout;
  if (a >= kHoldEnd) {
    const NamedPoint* p = named_at(r, false, a);
    return named_register(r, *p, a - p->address);
  }
  if (a < kHoldD) return uint16_t(word_at(r.v.global, l, Area::WY, a - kHoldWY));
  Area area = a < kHoldF ? Area::D : Area::F;
  uint32_t k = a - (a < kHoldF ? kHoldD : kHoldF);
  uint32_t w = word_at(r.task, l, area, k / 2);
  return uint16_t(k % 2 ? w : w >> 16);
}

// A register written: WY sign-extended; a half of D or F.
Write holding_write(const Req& r, uint32_t a, uint16_t value) {
  if (a >= kHoldEnd) {
    const NamedPoint* p = named_at(r, false, a);
    return named_write(*p, a - p->address, value);
  }
  if (a < kHoldD) return {Area::WY, a - kHoldWY, uint32_t(int32_t(int16_t(value))), 0xFFFFFFFFu};
  Area area = a < kHoldF ? Area::D : Area::F;
  uint32_t k = a - (a < kHoldF ? kHoldD : kHoldF);
  if (k % 2) return {area, k / 2, value, 0x0000FFFFu};
  return {area, k / 2, uint32_t(value) << 16, 0xFFFF0000u};
}

// Input register `a`: WX's low half; a timer's elapsed ms or a counter's
// value, the high half at even addresses (as D).
uint16_t input_at(const Req& r, uint32_t a) {
  const Layout& l = *r.v.layout;
  if (a < kInputT) return uint16_t(word_at(r.v.global, l, Area::WX, a - kInputWX));
  Area area = a < kInputC ? Area::TW : Area::CW;
  uint32_t k = a - (a < kInputC ? kInputT : kInputC);
  uint32_t w = word_at(r.task, l, area, k / 2);
  return uint16_t(k % 2 ? w : w >> 16);
}

// FC 3 and 4: quantity 1..125.
void read_registers(Req& r) {
  if (r.n != 5) return exception(r, kIllegalDataValue);
  uint32_t start = be16(r.pdu + 1), count = be16(r.pdu + 3);
  bool holding = r.pdu[0] == kReadHoldingRegisters;
  if (count < 1 || count > 125) return exception(r, kIllegalDataValue);
  if (holding ? !all_ok(r, false, start, count) : start + count > kInputEnd) return exception(r, kIllegalDataAddress);
  std::vector<uint8_t> p{r.pdu[0], uint8_t(2 * count)};
  for (uint32_t i = 0; i < count; i++)
    put16(p, holding ? holding_at(r, start + i) : input_at(r, start + i));
  reply(r, p);
}

// FC 6.
void write_register(Req& r) {
  if (r.n != 5) return exception(r, kIllegalDataValue);
  uint32_t a = be16(r.pdu + 1);
  if (!holding_ok(r, a)) return exception(r, kIllegalDataAddress);
  r.out.writes.push_back(holding_write(r, a, be16(r.pdu + 3)));
  reply(r, std::vector<uint8_t>(r.pdu, r.pdu + 5));
}

// FC 16: quantity 1..123, byte count = 2 x quantity.
void write_registers(Req& r) {
  if (r.n < 6) return exception(r, kIllegalDataValue);
  uint32_t start = be16(r.pdu + 1), count = be16(r.pdu + 3), bytes = r.pdu[5];
  if (count < 1 || count > 123 || bytes != 2 * count || r.n != 6 + bytes) return exception(r, kIllegalDataValue);
  if (!all_ok(r, false, start, count)) return exception(r, kIllegalDataAddress);
  for (uint32_t i = 0; i < count; i++) r.out.writes.push_back(holding_write(r, start + i, be16(r.pdu + 6 + 2 * i)));
  reply(r, std::vector<uint8_t>(r.pdu, r.pdu + 5));
}

}  // namespace

uint32_t registers_of(Ty t) { return ty_info(t).bits <= 16 ? 1 : ty_info(t).bits <= 32 ? 2 : 4; }

std::vector<NamedPoint> read_map(std::string_view text, const std::string& file, const std::vector<Alias>& aliases) {
  std::vector<NamedPoint> out;
  int line = 0;
  for (size_t pos = 0; pos < text.size();) {
    size_t nl = text.find('\n', pos);
    std::string_view l = text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() : nl + 1;
    line++;
    std::vector<std::pair<std::string, int>> w;  // the words and their columns
    for (size_t i = 0; i < l.size();) {
      if (std::isspace((unsigned char)l[i])) { i++; continue; }
      if (l[i] == '#') break;
      size_t s = i;
      while (i < l.size() && !std::isspace((unsigned char)l[i]) && l[i] != '#') i++;
      w.emplace_back(std::string(l.substr(s, i - s)), int(s) + 1);
    }
    auto fail = [&](int col, const std::string& m) {
      throw std::runtime_error(file + ":" + std::to_string(line) + ":" + std::to_string(col) + ": error: " + m);
    };
    if (w.empty()) continue;
    if (w.size() != 3 || (w[1].first != "coil" && w[1].first != "holding"))
      fail(w[0].second, "expected NAME coil|holding ADDRESS");
    NamedPoint p;
    p.name = w[0].first;
    p.coil = w[1].first == "coil";
    Probe pr;
    try {
      pr = resolve_probe(p.name, aliases);
    } catch (std::exception& e) { fail(w[0].second, e.what()); }
    if (pr.area != Area::M && pr.area != Area::D && pr.area != Area::F)
      fail(w[0].second, "'" + p.name + "' is located (" + std::string(area_name(pr.area)) + std::to_string(pr.index) +
                            "): it is already at that device's address in the map");
    p.area = pr.area, p.index = pr.index;
    p.ty = pr.ty != Ty::None ? pr.ty : pr.area == Area::M ? Ty::BOOL : pr.area == Area::F ? Ty::REAL : Ty::DINT;
    if (p.coil != (p.ty == Ty::BOOL)) fail(w[1].second, p.coil ? "a coil is a BOOL; '" + p.name + "' is a " + ty_info(p.ty).name
                                                               : "'" + p.name + "' is a BOOL: map it to a coil");
    if (p.ty == Ty::STRING) fail(w[0].second, "a STRING has no Modbus form");
    const std::string& as = w[2].first;
    if (as.empty() || as.size() > 5 || as.find_first_not_of("0123456789") != std::string::npos) fail(w[2].second, "bad address '" + as + "'");
    p.address = uint32_t(std::stoul(as));
    uint32_t lo = p.coil ? kCoilEnd : kHoldEnd, n = p.coil ? 1 : registers_of(p.ty);
    if (p.address < lo || p.address + n > 65536)
      fail(w[2].second, std::string(p.coil ? "coils" : "holding registers") + " of named variables are " + std::to_string(lo) +
                            "..65535 (below is the device map); '" + p.name + "' takes " + std::to_string(n));
    for (const NamedPoint& q : out)
      if (q.coil == p.coil && p.address < q.address + (q.coil ? 1 : registers_of(q.ty)) && q.address < p.address + n)
        fail(w[2].second, "'" + p.name + "' overlaps '" + q.name + "'");
    out.push_back(std::move(p));
  }
  return out;
}

Outcome serve(std::span<const uint8_t> buf, const View& v) {
  Outcome none;
  if (buf.size() < kMbapSize) return none;
  const uint8_t* h = buf.data();
  uint32_t length = be16(h + 4);
  if (be16(h + 2) != 0 || length < 2 || length > kMaxPdu + 1) {
    none.kind = Outcome::Close;
    none.consumed = buf.size();
    none.error = be16(h + 2) != 0 ? "protocol identifier " + std::to_string(be16(h + 2)) + ", not 0 (Modbus)"
                                  : "length field " + std::to_string(length) + " outside 2..254";
    return none;
  }
  if (buf.size() < 6 + length) return none;
  Req r{h, h + kMbapSize, length - 1, v, nullptr, {}};
  r.out.consumed = 6 + length;
  uint8_t unit = h[6];
  size_t task = unit == 0 || unit == 255 ? 0 : size_t(unit) - 1;
  if (task >= v.tasks.size()) {
    exception(r, kGatewayTargetFailed);
    return std::move(r.out);
  }
  r.out.task = task;
  r.task = v.tasks[task];
  switch (r.pdu[0]) {
    case kReadCoils:
    case kReadDiscreteInputs: read_bits(r); break;
    case kReadHoldingRegisters:
    case kReadInputRegisters: read_registers(r); break;
    case kWriteSingleCoil: write_coil(r); break;
    case kWriteSingleRegister: write_register(r); break;
    case kWriteMultipleCoils: write_coils(r); break;
    case kWriteMultipleRegisters: write_registers(r); break;
    default: exception(r, kIllegalFunction);
  }
  return std::move(r.out);
}

}  // namespace ldc::modbus
