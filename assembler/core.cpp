// The target-independent core: label tables, blockwise layout, relaxation
// and fixup resolution. Knows nothing about any instruction set.
#include "assembler/assembler.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <unordered_map>

namespace ldc::as {

std::string listing_field(const char* fmt, uint32_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// The name table: chunks of strings that never move, so views into them
// (and ids read without the lock) stay valid while others intern.  `chunks`
// is reserved once and never reallocates; untouched, the reservation costs
// address space, not memory.
namespace {
constexpr uint32_t kChunkBits = 10, kChunkSize = 1u << kChunkBits, kMaxChunks = 1u << 16;  // 2^26 names
struct NameTable {
  std::mutex lock;
  std::unordered_map<std::string_view, uint32_t> ids;
  std::vector<std::unique_ptr<std::string[]>> chunks;
  uint32_t next = 1;  // 0: the empty name
  NameTable() { chunks.reserve(kMaxChunks); }
};
NameTable& names() {
  static NameTable* t = new NameTable;  // never destroyed: names outlive static destructors
  return *t;
}
}  // namespace

uint32_t Name::intern(std::string_view text) {
  NameTable& t = names();
  std::lock_guard<std::mutex> g(t.lock);
  auto it = t.ids.find(text);
  if (it != t.ids.end()) return it->second;
  uint32_t id = t.next;
  if ((id >> kChunkBits) >= kMaxChunks) throw AsmError("too many distinct label names");
  if ((id >> kChunkBits) >= t.chunks.size()) t.chunks.push_back(std::make_unique<std::string[]>(kChunkSize));
  std::string& slot = t.chunks[id >> kChunkBits][id & (kChunkSize - 1)];
  slot = text;
  t.ids.emplace(std::string_view(slot), id);
  t.next++;
  return id;
}

std::string_view Name::view() const {
  if (id_ == 0) return {};
  return names().chunks[id_ >> kChunkBits][id_ & (kChunkSize - 1)];
}

const std::string& Note::str() const {
  static const std::string empty;
  return p_ ? *p_ : empty;
}

AsmError::AsmError(Error e) : std::runtime_error(e.message), error_(std::move(e)) {}

void Encoding::too_long() { throw AsmError("instruction longer than 16 bytes"); }

void Encoding::too_many_fixups() { throw AsmError("too many fixups in one instruction"); }

bool fixup_value(const FixupKind& k, int64_t target, int64_t addend,
                int64_t inst_start, int64_t inst_size, int64_t& value) {
  int64_t v = target + addend;
  if (k.pc_relative) {
    int64_t pc = (k.pc_base == PcBase::InstructionEnd ? inst_start + inst_size : inst_start) +
                 int64_t(k.pc_bias) * k.scale;
    v -= pc;
  }
  if (k.scale > 1) {
    if (v % k.scale != 0) return false;
    v /= k.scale;
  }
  value = v;
  return true;
}

bool fixup_fits(const FixupKind& k, int64_t value) {
  if (k.bit_width >= 64) return true;
  if (k.is_signed) {
    int64_t lim = int64_t(1) << (k.bit_width - 1);
    return value >= -lim && value < lim;
  }
  return value >= 0 && uint64_t(value) < (uint64_t(1) << k.bit_width);
}

void apply_fixup(const FixupKind& k, std::span<uint8_t> code, size_t offset, int64_t value) {
  uint64_t c = 0;
  for (unsigned i = 0; i < k.container_bytes; ++i) c |= uint64_t(code[offset + i]) << (8 * i);
  uint64_t mask = k.bit_width >= 64 ? ~uint64_t(0) : (uint64_t(1) << k.bit_width) - 1;
  c &= ~(mask << k.bit_shift);
  c |= (uint64_t(value) & mask) << k.bit_shift;
  for (unsigned i = 0; i < k.container_bytes; ++i) code[offset + i] = uint8_t(c >> (8 * i));
}

namespace detail {
namespace core_impl {

enum class RefType : uint8_t { Dead, Local, Global, Absolute };

struct Ref {
  RefType type = RefType::Dead;
  uint32_t index = 0;  // local slot or global index
};

struct InstState {
  uint32_t block = 0, item = 0;
  Encoding enc;
  bool long_form = false;
  bool bad = false;  // failed to encode
  bool has_local = false;
  uint32_t offset = 0;  // unit-relative
  std::array<Ref, 2> refs{};
};

struct LocalKey {
  uint32_t block;
  std::string_view name;
  bool operator==(const LocalKey&) const = default;
};
struct LocalKeyHash {
  size_t operator()(const LocalKey& k) const {
    return std::hash<std::string_view>()(k.name) * 31 + k.block;
  }
};

struct Pending {
  uint32_t inst_start, inst_size, field_offset;
  uint16_t kind;
  Ref ref;
  int64_t addend;
  uint32_t block;
  std::string_view label;
};

class Core {
 public:
  // The declared global names must outlive the core (the table keeps views).
  Core(const TargetInfo& t, std::span<const std::string> globals, Mode mode) : t_(t), mode_(mode) {
    r_.global_addresses.assign(globals.size(), -1);
    globalDefBlock_.assign(globals.size(), -1);
    globalNames_ = globals;
    for (uint32_t i = 0; i < globals.size(); ++i) {
      if (!globals_.emplace(std::string_view(globals[i]), i).second)
        error(-1, "duplicate global label '" + globals[i] + "'");
    }
  }

  // The whole program at once (assemble()).
  Result run(const ProgramView& p) {
    p_ = &p;
    size_t nb = p.num_blocks();
    lines_.reserve(nb);
    for (size_t b = 0; b < nb; ++b) lines_.push_back(p.source_line(b));
    r_.block_offsets.assign(nb, 0);
    r_.items.resize(nb);
    for (size_t b = 0; b < nb; ++b) r_.items[b].resize(p.num_items(b));
    for (uint32_t b = 0; b < nb; ++b) {
      gather_kinds(b, b + 1);
      define_globals(b);
    }
    note_peak();
    if (mode_ == Mode::Blockwise) {
      for (uint32_t b = 0; b < nb; ++b) {
        gather_kinds(b, b + 1);
        assemble_unit(b, b + 1);
      }
    } else {
      gather_kinds(0, uint32_t(nb));
      assemble_unit(0, uint32_t(nb));
    }
    return finish();
  }

  // One block more (Assembler::add): `p` answers for block `b` only, which is
  // the next one; its items are not looked at again after this call.
  // With keep_items false the block's item layout replaces the last block's
  // (last_items) instead of joining Result::items.
  void block(const ProgramView& p, uint32_t b, bool keep_items) {
    p_ = &p;
    lines_.push_back(p.source_line(b));
    r_.block_offsets.push_back(0);
    keep_items_ = keep_items;
    if (keep_items) r_.items.emplace_back(p.num_items(b));
    else last_.assign(p.num_items(b), ItemLayout{});
    gather_kinds(b, b + 1);
    define_globals(b);
    assemble_unit(b, b + 1);
    p_ = nullptr;
  }

  std::span<const ItemLayout> last_items() const { 
    if (!keep_items_) return last_;
    return r_.items.empty() ? std::span<const ItemLayout>() : std::span<const ItemLayout>(r_.items.back());
  }
  uint32_t code_size() const { return uint32_t(r_.code.size()); }

  Result finish() {
    resolve_pending();
    return std::move(r_);
  }

 private:
  void error(int block, std::string msg) {
    int line = block >= 0 ? lines_[size_t(block)] : 0;
    r_.errors.push_back(Error{block, line, std::move(msg)});
  }

  void note_peak() {
    size_t n = globals_.size() + locals_.size();
    if (n > r_.stats.peak_label_entries) r_.stats.peak_label_entries = n;
  }

  // The kinds of the items of blocks [first, last), read once from the view
  // (a virtual call a block): every pass over a unit looks at each item's.
  void gather_kinds(uint32_t first, uint32_t last) {
    kinds_first_ = first;
    kinds_.clear();
    kinds_at_.clear();
    for (uint32_t b = first; b < last; ++b) {
      kinds_at_.push_back(uint32_t(kinds_.size()));
      p_->append_kinds(b, kinds_);
    }
    kinds_at_.push_back(uint32_t(kinds_.size()));
  }
  // The kinds of block b's items (one a item), of the blocks gathered last.
  std::span<const ItemKind> kinds_of(uint32_t b) const {
    const uint32_t at = kinds_at_[b - kinds_first_];
    return {kinds_.data() + at, kinds_at_[b - kinds_first_ + 1] - at};
  }

  // Pass 1: each global label definition of block b must be declared and
  // defined once.
  // Does block b (of those gathered last) define a label?  Most blocks define
  // none: one memchr, not a look at each item.
  bool has_labels(uint32_t b) const {
    static_assert(sizeof(ItemKind) == 1);
    const std::span<const ItemKind> kinds = kinds_of(b);
    return !kinds.empty() && std::memchr(kinds.data(), int(ItemKind::Label), kinds.size());
  }

  void define_globals(uint32_t b) {
    if (!has_labels(b)) return;
    const std::span<const ItemKind> kinds = kinds_of(b);
    for (size_t i = 0; i < kinds.size(); ++i) {
      if (kinds[i] != ItemKind::Label || !p_->is_global(b, i)) continue;
      std::string_view name = p_->label(b, i);
      auto it = globals_.find(name);
      if (it == globals_.end()) {
        error(int(b), "global label '" + std::string(name) + "' is not declared");
      } else if (globalDefBlock_[it->second] >= 0) {
        error(int(b), "duplicate global label '" + std::string(name) + "'");
      } else {
        globalDefBlock_[it->second] = int(b);
      }
    }
  }

  void encode_state(InstState& s) {
    ++r_.stats.encode_calls;
    s.enc.size = 0, s.enc.num_fixups = 0;  // empty: what lies past the counts is never read
    try {
      p_->encode(s.block, s.item, s.long_form, s.enc);
      if (s.enc.num_fixups) check_fixups(s.enc);
    } catch (const AsmError& e) {
      failed(s, e);
    }
  }
  void check_fixups(const Encoding& enc) const {
    for (unsigned f = 0; f < enc.num_fixups; ++f) {
      const Fixup& fx = enc.fixups[f];
      if (fx.kind >= t_.fixup_kinds.size() || fx.offset + t_.fixup_kinds[fx.kind].container_bytes > enc.size)
        throw AsmError("encoder produced an invalid fixup");
    }
  }
  // An encoding that failed (apart from encode_state, every instruction's path:
  // building this message there made it save six registers a call).
  void failed(InstState& s, const AsmError& e) {
    if (!s.bad) error(int(s.block), "item " + std::to_string(s.item) + ": " + e.what());
    s.bad = true;
    s.enc = Encoding{};
  }

  Ref resolve(uint32_t block, std::string_view name, bool report) {
    if (name.empty()) return {RefType::Absolute, 0};
    auto l = locals_.find(LocalKey{block, name});
    if (l != locals_.end()) return {RefType::Local, l->second};
    auto g = globals_.find(name);
    if (g != globals_.end()) return {RefType::Global, g->second};
    if (report) error(int(block), "undefined label '" + std::string(name) + "'");
    return {RefType::Dead, 0};
  }

  void resolve_refs(InstState& s, bool report = false) {
    s.has_local = false;
    for (unsigned f = 0; f < s.enc.num_fixups; ++f) {
      s.refs[f] = resolve(s.block, s.enc.fixups[f].label, report);
      if (s.refs[f].type == RefType::Local) s.has_local = true;
    }
  }

  // Lays out and relaxes blocks [first, last) as one unit, then emits it.
  void assemble_unit(uint32_t first, uint32_t last) {
    ++r_.stats.units;
    locals_.clear();
    localAddr_.clear();
    // Local label table.
    for (uint32_t b = first; b < last; ++b) {
      if (!has_labels(b)) continue;
      const std::span<const ItemKind> kinds = kinds_of(b);
      for (size_t i = 0; i < kinds.size(); ++i) {
        if (kinds[i] != ItemKind::Label || p_->is_global(b, i)) continue;
        std::string_view name = p_->label(b, i);
        if (globals_.count(name)) {
          error(int(b), "local label '" + std::string(name) + "' clashes with a global label");
          continue;
        }
        if (!locals_.emplace(LocalKey{b, name}, uint32_t(localAddr_.size())).second) {
          error(int(b), "duplicate label '" + std::string(name) + "'");
          continue;
        }
        localAddr_.push_back(0);
      }
    }
    note_peak();

    // First encoding: short forms, long ones for non-local targets.  The states
    // are kept from unit to unit and reset field by field: a new one is zeroed
    // whole (128 bytes), which cost more than the rest of its setting up.
    size_t count = 0;
    bool any_local = false;
    for (uint32_t b = first; b < last; ++b) {
      const std::span<const ItemKind> kinds = kinds_of(b);
      for (uint32_t i = 0; i < uint32_t(kinds.size()); ++i) {
        if (kinds[i] != ItemKind::Instruction) continue;
        if (count == insts_.size()) insts_.emplace_back();
        InstState& s = insts_[count++];
        s.block = b;
        s.item = i;
        s.long_form = s.bad = false;  // the rest is set by encode_state, resolve_refs and layout
        encode_state(s);
        resolve_refs(s, true);
        bool far = false;
        for (unsigned f = 0; f < s.enc.num_fixups; ++f)
          far |= s.refs[f].type == RefType::Global || s.refs[f].type == RefType::Absolute;
        if (far && !s.bad) {
          s.long_form = true;
          encode_state(s);
          resolve_refs(s);
        }
        any_local |= s.has_local;
      }
    }

    const std::span<InstState> insts(insts_.data(), count);
    std::vector<uint32_t>& block_start = block_start_;
    block_start.assign(last - first, 0);
    if (any_local) {
      relax(first, last, insts, block_start);
    } else {  // nothing can grow: one pass, for the blocks' starts only
      ++r_.stats.relax_passes;
      block_starts(first, last, insts, block_start);
    }
    emit(first, last, insts, block_start);
  }

  // Relaxation: grow the forms that do not reach, until nothing changes.
  void relax(uint32_t first, uint32_t last, std::span<InstState> insts, std::vector<uint32_t>& block_start) {
    for (;;) {
      ++r_.stats.relax_passes;
      layout(first, last, insts, block_start);
      bool changed = false;
      for (auto& s : insts) {
        if (!s.has_local || s.long_form || s.bad) continue;
        for (unsigned f = 0; f < s.enc.num_fixups; ++f) {
          if (s.refs[f].type != RefType::Local) continue;
          const Fixup& fx = s.enc.fixups[f];
          const FixupKind& k = t_.fixup_kinds[fx.kind];
          if (k.relax_to < 0) continue;
          int64_t v;
          bool ok = fixup_value(k, localAddr_[s.refs[f].index], fx.addend, s.offset,
                               s.enc.size, v);
          if (!ok || !fixup_fits(k, v)) {
            s.long_form = true;
            encode_state(s);
            resolve_refs(s);
            changed = true;
            break;
          }
        }
      }
      if (!changed) break;
    }
  }

  // Where each block of a unit starts: its instructions (insts, in order) end there.
  static void block_starts(uint32_t first, uint32_t last, std::span<const InstState> insts,
                           std::vector<uint32_t>& block_start) {
    uint32_t cur = 0;
    size_t n = 0;
    for (uint32_t b = first; b < last; ++b) {
      block_start[b - first] = cur;
      for (; n < insts.size() && insts[n].block == b; ++n) cur += insts[n].enc.size;
    }
  }

  void layout(uint32_t first, uint32_t last, std::span<InstState> insts,
              std::vector<uint32_t>& block_start) {
    uint32_t cur = 0;
    size_t n = 0;
    for (uint32_t b = first; b < last; ++b) {
      block_start[b - first] = cur;
      const std::span<const ItemKind> kinds = kinds_of(b);
      for (size_t i = 0; i < kinds.size(); ++i) {
        switch (kinds[i]) {
          case ItemKind::Label:
            if (!p_->is_global(b, i)) {
              auto it = locals_.find(LocalKey{b, p_->label(b, i)});
              if (it != locals_.end()) localAddr_[it->second] = cur;
            }
            break;
          case ItemKind::Instruction:
            insts[n].offset = cur;
            cur += insts[n].enc.size;
            ++n;
            break;
          case ItemKind::Comment:
            break;
        }
      }
    }
  }

  void emit(uint32_t first, uint32_t last, std::span<InstState> insts,
            const std::vector<uint32_t>& block_start) {
    const uint32_t base = uint32_t(r_.code.size());
    size_t unit_bytes = 0;
    for (const InstState& s : insts) unit_bytes += s.enc.size;
    r_.code.resize(base + unit_bytes);  // the unit's bytes copied in place below
    // (read once: each byte copied might alias the vector's own fields)
    uint8_t* const code = r_.code.data();
    const size_t code_size = r_.code.size();
    size_t n = 0;
    for (uint32_t b = first; b < last; ++b) {
      r_.block_offsets[b] = base + block_start[b - first];
      uint32_t cur = r_.block_offsets[b];
      const std::span<const ItemKind> kinds = kinds_of(b);
      ItemLayout* const lays = keep_items_ ? r_.items[b].data() : last_.data();
      for (size_t i = 0; i < kinds.size(); ++i) {
        ItemLayout& lay = lays[i];
        lay.offset = cur;
        const ItemKind k = kinds[i];
        if (k == ItemKind::Label && p_->is_global(b, i)) {
          auto g = globals_.find(p_->label(b, i));
          if (g != globals_.end() && globalDefBlock_[g->second] == int(b))
            r_.global_addresses[g->second] = cur;
        }
        if (k != ItemKind::Instruction) continue;
        InstState& s = insts[n++];
        lay.size = s.enc.size;
        lay.long_form = s.long_form;
        // all 16 bytes where they fit (a fixed-size copy, no call); the bytes past
        // the size are the next instruction's, copied over them after
        if (code_size - cur >= s.enc.bytes.size()) std::memcpy(code + cur, s.enc.bytes.data(), s.enc.bytes.size());
        else std::copy_n(s.enc.bytes.begin(), s.enc.size, code + cur);
        for (unsigned f = 0; f < s.enc.num_fixups; ++f) {
          const Fixup& fx = s.enc.fixups[f];
          // a pending fixup outlives the block: name its label from the global table
          std::string_view label =
              s.refs[f].type == RefType::Global ? std::string_view(globalNames_[s.refs[f].index]) : fx.label;
          Pending pd{cur, s.enc.size, cur + fx.offset, fx.kind, s.refs[f], fx.addend, b, label};
          if (s.refs[f].type == RefType::Local) {
            const FixupKind& k = t_.fixup_kinds[fx.kind];
            patch(pd, base + localAddr_[s.refs[f].index]);
            if (!k.pc_relative) r_.relocations.push_back({pd.field_offset, pd.kind});
          } else if (s.refs[f].type != RefType::Dead) {
            pending_.push_back(pd);
          }
        }
        cur += s.enc.size;
      }
    }
  }

  void patch(const Pending& pd, int64_t target) {
    const FixupKind& k = t_.fixup_kinds[pd.kind];
    int64_t v;
    auto what = [&] {  // only for an error: most patches succeed
      return pd.label.empty() ? "address " + std::to_string(pd.addend) : "label '" + std::string(pd.label) + "'";
    };
    if (!fixup_value(k, target, pd.addend, pd.inst_start, pd.inst_size, v)) {
      error(int(pd.block), what() + " is not aligned for fixup " + std::string(k.name));
      return;
    }
    if (!fixup_fits(k, v)) {
      error(int(pd.block), what() + " out of range for fixup " + std::string(k.name));
      return;
    }
    apply_fixup(k, r_.code, pd.field_offset, v);
  }

  // After all blocks are laid out: references to globals and addresses.
  void resolve_pending() {
    for (const Pending& pd : pending_) {
      ++r_.stats.global_fixups;
      int64_t target = 0;
      if (pd.ref.type == RefType::Global) {
        target = r_.global_addresses[pd.ref.index];
        if (target < 0) {
          error(int(pd.block), "undefined label '" + std::string(pd.label) + "'");
          continue;
        }
      }
      patch(pd, target);
      if (!t_.fixup_kinds[pd.kind].pc_relative) r_.relocations.push_back({pd.field_offset, pd.kind});
    }
  }

  const TargetInfo& t_;
  const ProgramView* p_ = nullptr;
  Mode mode_;
  Result r_;
  std::vector<int> lines_;  // each block's source line, for errors
  std::span<const std::string> globalNames_;
  std::unordered_map<std::string_view, uint32_t> globals_;
  std::vector<int> globalDefBlock_;
  std::unordered_map<LocalKey, uint32_t, LocalKeyHash> locals_;
  std::vector<int64_t> localAddr_;
  std::vector<Pending> pending_;
  std::vector<InstState> insts_;       // assemble_unit's instructions (the first of them), reused
  std::vector<uint32_t> block_start_;  // assemble_unit's block starts
  std::vector<ItemKind> kinds_;        // gather_kinds: the items' kinds, block after block
  std::vector<uint32_t> kinds_at_;     // where each block starts in kinds_, and the end
  uint32_t kinds_first_ = 0;           // the first block gathered
  bool keep_items_ = true;             // every block's item layout goes into r_.items
  std::vector<ItemLayout> last_;       // else the last block's, alone
};

}  // namespace core_impl
using core_impl::Core;

Result assemble(const TargetInfo& target, const ProgramView& program, Mode mode) {
  auto t0 = std::chrono::steady_clock::now();
  Result r = Core(target, program.globals(), mode).run(program);
  r.stats.elapsed_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::steady_clock::now() - t0)
                          .count();
  return r;
}

// The streaming assembler keeps no clock: read twice a block, it cost more than a
// small block's layout (Stats::elapsed_ns stays 0; its callers time their calls).
struct Stream {
  std::vector<std::string> globals;
  Core core;
  uint32_t blocks = 0;
  Stream(const TargetInfo& t, std::vector<std::string> g)
      : globals(std::move(g)), core(t, globals, Mode::Blockwise) {}
};

void StreamDeleter::operator()(Stream* s) const { delete s; }

std::unique_ptr<Stream, StreamDeleter> stream_begin(const TargetInfo& target, std::vector<std::string> globals) {
  return std::unique_ptr<Stream, StreamDeleter>(new Stream(target, std::move(globals)));
}

void stream_block(Stream& s, const ProgramView& block, bool keep_items) { s.core.block(block, s.blocks++, keep_items); }

std::span<const ItemLayout> stream_last_items(const Stream& s) { return s.core.last_items(); }
uint32_t stream_code_size(const Stream& s) { return s.core.code_size(); }

Result stream_finish(Stream& s) { return s.core.finish(); }

}  // namespace detail
}  // namespace ldc::as
