// ldc assembler: a target-independent, blockwise two-pass assembler core.
//
// A program is a list of blocks (one per ladder rung). Each block holds
// label definitions and target instructions. The core lays the blocks out,
// relaxes short/long branch forms, resolves fixups and reports structured
// errors. A target plugs in through one `Target<Inst>` struct: its name, a
// table of fixup kinds and an encode hook. See docs/assembler.md.
//
// The x86-64 target (instruction model, encoder, parser, printer and
// disassembler) is declared in assembler/x86.h, included at the end.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace ldc::as {

// ---------------------------------------------------------------- errors

// A structured error. block is -1 for errors not tied to one block
// (e.g. a duplicate global declaration); line is the block's source line.
struct Error {
  int block = -1;
  int line = 0;
  std::string message;
};

// Thrown by the parser and the encoders; the core catches it and turns it
// into an Error carrying the block index and source line.
class AsmError : public std::runtime_error {
 public:
  explicit AsmError(Error e);
  explicit AsmError(std::string message) : AsmError(Error{-1, 0, std::move(message)}) {}
  const Error& error() const { return error_; }

 private:
  Error error_;
};

// ------------------------------------------------------------------ names

// An interned label name: a 4-byte id, equal ids for equal text.  The text
// lives in a process-wide table (never freed, safe to intern from several
// threads), so a Name is trivially copied and its view() stays valid for
// the life of the process.  Id 0 is the empty name.
class Name {
 public:
  Name() = default;
  Name(std::string_view text) : id_(text.empty() ? 0 : intern(text)) {}  // NOLINT: implicit on purpose
  Name(const std::string& text) : Name(std::string_view(text)) {}        // NOLINT
  Name(const char* text) : Name(std::string_view(text)) {}               // NOLINT
  std::string_view view() const;
  std::string str() const { return std::string(view()); }
  operator std::string_view() const { return view(); }  // NOLINT
  bool empty() const { return id_ == 0; }
  uint32_t id() const { return id_; }
  friend bool operator==(Name, Name) = default;

 private:
  static uint32_t intern(std::string_view text);
  uint32_t id_ = 0;
};

inline std::string operator+(std::string a, Name b) { return a.append(b.view()); }
inline std::string operator+(Name a, std::string_view b) { return a.str().append(b); }

// An optional comment: one pointer, no allocation when empty.
class Note {
 public:
  Note() = default;
  Note(std::string text)  // NOLINT: implicit on purpose
      : p_(text.empty() ? nullptr : std::make_unique<std::string>(std::move(text))) {}
  Note(const char* text) : Note(std::string(text)) {}  // NOLINT
  Note(const Note& o) : p_(o.p_ ? std::make_unique<std::string>(*o.p_) : nullptr) {}
  Note(Note&&) noexcept = default;
  Note& operator=(const Note& o) { return *this = Note(o); }
  Note& operator=(Note&&) noexcept = default;
  bool empty() const { return !p_; }
  const std::string& str() const;
  operator const std::string&() const { return str(); }  // NOLINT
  friend bool operator==(const Note& a, const Note& b) { return a.str() == b.str(); }

 private:
  std::unique_ptr<std::string> p_;
};

// ----------------------------------------------------------- fixup kinds

// Where a pc-relative field measures from.
enum class PcBase : uint8_t { InstructionStart, InstructionEnd };

// One kind of field an encoder may leave for the core to fill in.
// The field lives in a little-endian container of `container_bytes` bytes at
// the fixup's offset; it is `bit_width` bits wide starting at bit `bit_shift`.
// value = (target + addend - pc) / scale        if pc_relative
//       = (target + addend) / scale             otherwise
// where pc = (start or end of the instruction) + pc_bias * scale.
// Addresses are byte offsets from the start of the code.
struct FixupKind {
  std::string_view name;
  uint8_t container_bytes;  // 1, 2, 4 or 8
  uint8_t bit_shift;
  uint8_t bit_width;
  bool pc_relative;
  bool is_signed;
  PcBase pc_base;
  int32_t pc_bias;    // in units of `scale` bytes
  uint8_t scale;     // bytes per unit of the field (x86: 1, C40: 4)
  int16_t relax_to;   // index of the longer kind to grow to, -1 if none
};

// A field to fill: `label` empty means an absolute code address `addend`.
struct Fixup {
  uint32_t offset = 0;  // of the container, from the instruction start
  uint16_t kind = 0;
  std::string_view label;  // points into the instruction being encoded
  int64_t addend = 0;
};

// What an encode hook produces for one instruction.
struct Encoding {
  std::array<uint8_t, 16> bytes{};
  uint8_t size = 0;
  std::array<Fixup, 2> fixups{};
  uint8_t num_fixups = 0;

  void put(uint8_t b) {  // inline: the encoders call it per byte
    if (size >= bytes.size()) too_long();
    bytes[size++] = b;
  }
  void put32(uint32_t v) {
    for (int i = 0; i < 4; ++i) put(uint8_t(v >> (8 * i)));
  }
  void add_fixup(Fixup f) {
    if (num_fixups >= fixups.size()) too_many_fixups();
    fixups[num_fixups++] = f;
  }
  [[noreturn]] static void too_long();
  [[noreturn]] static void too_many_fixups();
  std::span<const uint8_t> view() const { return {bytes.data(), size}; }
};

// Computes the value to store for a fixup (before range checking).
// Returns false if the distance is not a multiple of the kind's scale.
bool fixup_value(const FixupKind& k, int64_t target, int64_t addend,
                int64_t inst_start, int64_t inst_size, int64_t& value);
// True if value fits the kind's field.
bool fixup_fits(const FixupKind& k, int64_t value);
// Stores value into the field at code[offset]; the caller checked the range.
void apply_fixup(const FixupKind& k, std::span<uint8_t> code, size_t offset,
                int64_t value);

// ----------------------------------------------------------------- target

// The data and hooks that describe a target.
struct TargetInfo {
  std::string_view name;
  std::span<const FixupKind> fixup_kinds;
};

template <class Inst>
struct Target : TargetInfo {
  // Encodes one instruction. long_form asks for the long variant of a
  // relaxable instruction (and is set from the start for references to
  // global labels and absolute addresses). `out` comes empty (size and
  // num_fixups 0; the bytes and fixups past them are stale, never read).
  // Throws AsmError.
  void (*encode)(const Inst& inst, bool long_form, Encoding& out) = nullptr;
};

// ---------------------------------------------------------------- program

enum class ItemKind : uint8_t { Label, Instruction, Comment };

template <class Inst>
struct Item {
  ItemKind kind = ItemKind::Comment;
  bool global = false;  // for Label: defines a declared global label
  Name label;           // for Label
  Inst inst{};          // for Instruction
  Note comment;         // optional, for listings

  static Item label_def(Name name, bool is_global = false) {
    Item it;
    it.kind = ItemKind::Label;
    it.label = name;
    it.global = is_global;
    return it;
  }
  static Item instr(Inst i, Note comment = {}) {
    Item it;
    it.kind = ItemKind::Instruction;
    it.inst = std::move(i);
    it.comment = std::move(comment);
    return it;
  }
  static Item note(Note comment) {
    Item it;
    it.comment = std::move(comment);
    return it;
  }
};

// For peephole passes: is the first item after `i` that is neither a
// comment nor dropped the definition of `label`?
template <class Inst>
bool label_follows(const std::vector<Item<Inst>>& items, size_t i, Name label,
                  const std::vector<char>& drop) {
  for (size_t j = i + 1; j < items.size(); j++) {
    if (items[j].kind == ItemKind::Comment || drop[j]) continue;
    return items[j].kind == ItemKind::Label && items[j].label == label;
  }
  return false;
}

// Removes the items marked in `drop` (one flag per item); `index` holds item
// indices (e.g. where each IL instruction's code starts) and is moved along.
// In place: the kept items move down, and the vector keeps its storage for
// the code generator's next block.
template <class Inst>
void remove_items(std::vector<Item<Inst>>& items, const std::vector<char>& drop, std::vector<uint32_t>& index) {
  std::vector<uint32_t> new_index(items.size() + 1);
  size_t kept = 0;
  for (size_t i = 0; i < items.size(); i++) {
    new_index[i] = uint32_t(kept);
    if (drop[i]) continue;
    if (kept != i) items[kept] = std::move(items[i]);
    kept++;
  }
  new_index[items.size()] = uint32_t(kept);
  for (auto& s : index) s = new_index[s];
  items.erase(items.begin() + ptrdiff_t(kept), items.end());
}

template <class Inst>
struct Block {
  int source_line = 0;
  std::vector<Item<Inst>> items;
};

template <class Inst>
struct Program {
  std::vector<std::string> globals;  // declared up front
  std::vector<Block<Inst>> blocks;
};

// ----------------------------------------------------------------- result

enum class Mode : uint8_t {
  Blockwise,     // global table first, then each block with its own table
  WholeProgram,  // one two-pass over everything, one table
};

struct Stats {
  size_t peak_label_entries = 0;  // max entries alive in the label tables
  size_t relax_passes = 0;       // layout passes summed over all units
  size_t units = 0;             // blocks (blockwise) or 1 (whole program)
  size_t encode_calls = 0;
  size_t global_fixups = 0;      // fixups resolved after layout
  int64_t elapsed_ns = 0;        // wall time of assemble(); 0 from the streaming Assembler
};

struct ItemLayout {
  uint32_t offset = 0;  // from the start of the code
  uint32_t size = 0;
  bool long_form = false;
};

// An absolute fixup; the loader adds the load address.
struct Relocation {
  uint32_t offset = 0;
  uint16_t kind = 0;
};

struct Result {
  std::vector<uint8_t> code;
  std::vector<uint32_t> block_offsets;
  std::vector<std::vector<ItemLayout>> items;  // [block][item]
  std::vector<int64_t> global_addresses;  // per declared global, -1 if undefined
  std::vector<Relocation> relocations;
  std::vector<Error> errors;
  Stats stats;
  bool ok() const { return errors.empty(); }
};

namespace detail {
// The program as the target-independent core sees it.
class ProgramView {
 public:
  virtual ~ProgramView() = default;
  virtual std::span<const std::string> globals() const = 0;
  virtual size_t num_blocks() const = 0;
  virtual int source_line(size_t block) const = 0;
  virtual size_t num_items(size_t block) const = 0;
  // The kinds of the block's items, appended to `out` (one call a block, not an item).
  virtual void append_kinds(size_t block, std::vector<ItemKind>& out) const = 0;
  virtual std::string_view label(size_t block, size_t item) const = 0;
  virtual bool is_global(size_t block, size_t item) const = 0;
  virtual void encode(size_t block, size_t item, bool long_form,
                      Encoding& out) const = 0;
};
Result assemble(const TargetInfo& target, const ProgramView& program, Mode mode);

// The streaming assembler (Assembler<Inst>): the core between blocks.
struct Stream;
struct StreamDeleter {
  void operator()(Stream* s) const;
};
std::unique_ptr<Stream, StreamDeleter> stream_begin(const TargetInfo& target, std::vector<std::string> globals);
// `block` answers for one block only, numbered by how many came before it;
// without keep_items its item layout is kept only until the next block.
void stream_block(Stream& s, const ProgramView& block, bool keep_items);
std::span<const ItemLayout> stream_last_items(const Stream& s);  // the last block's item layout
uint32_t stream_code_size(const Stream& s);                       // the bytes emitted so far
Result stream_finish(Stream& s);
}  // namespace detail

// Assembles a program. Never throws for errors in the input: they are
// returned in Result::errors.
template <class Inst>
Result assemble(const Target<Inst>& target, const Program<Inst>& program,
                Mode mode = Mode::Blockwise) {
  class View final : public detail::ProgramView {
   public:
    View(const Target<Inst>& t, const Program<Inst>& p) : t_(t), p_(p) {}
    std::span<const std::string> globals() const override { return p_.globals; }
    size_t num_blocks() const override { return p_.blocks.size(); }
    int source_line(size_t b) const override { return p_.blocks[b].source_line; }
    size_t num_items(size_t b) const override { return p_.blocks[b].items.size(); }
    void append_kinds(size_t b, std::vector<ItemKind>& out) const override {
      for (const auto& it : p_.blocks[b].items) out.push_back(it.kind);
    }
    std::string_view label(size_t b, size_t i) const override {
      return p_.blocks[b].items[i].label;
    }
    bool is_global(size_t b, size_t i) const override {
      return p_.blocks[b].items[i].global;
    }
    void encode(size_t b, size_t i, bool long_form, Encoding& out) const override {
      t_.encode(p_.blocks[b].items[i].inst, long_form, out);
    }

   private:
    const Target<Inst>& t_;
    const Program<Inst>& p_;
  };
  View view(target, program);
  return detail::assemble(target, view, mode);
}

// ------------------------------------------------------------------ text
// The two text forms every target prints the same way; `mark` starts a
// comment in the target's syntax ("#", ";").

// v in a printf format of one unsigned number ("%08x"), for listing columns.
std::string listing_field(const char* fmt, uint32_t v);

// The GNU-as source of a program: `head`, then per block a comment line
// (`<mark> block B, line L`) and its items, one a line: a label (a block's
// local labels renamed .L<B>_name: blocks may reuse names), an instruction
// after a tab as print(inst, outside) prints it, its label operands renamed
// (outside: one of them is not a local label of its block), and an item's
// comment after a tab and `<mark> `.  A comment item without text is no line.
template <class Inst, class Print>
std::string gnu_as_text(const Program<Inst>& p, std::string head, std::string_view mark, Print print) {
  std::string out = std::move(head);
  for (size_t b = 0; b < p.blocks.size(); ++b) {
    const auto& blk = p.blocks[b];
    std::set<std::string_view> locals;
    for (const auto& it : blk.items)
      if (it.kind == ItemKind::Label && !it.global) locals.insert(it.label);
    auto mangle = [&](std::string_view n) {
      return locals.count(n) ? ".L" + std::to_string(b) + "_" + std::string(n) : std::string(n);
    };
    out += std::string(mark) + " block " + std::to_string(b) + ", line " + std::to_string(blk.source_line) + "\n";
    for (const auto& it : blk.items) {
      if (it.kind == ItemKind::Label) {
        out += mangle(it.label) + ":";
      } else if (it.kind == ItemKind::Instruction) {
        Inst in = it.inst;
        bool outside = false;
        for (unsigned i = 0; i < unsigned(in.num_operands) && i < 3; ++i) {
          auto& o = in.ops[i];
          if (o.kind != decltype(o.kind)::Label) continue;
          outside = outside || !locals.count(o.label);
          o.label = mangle(o.label);
        }
        out += "\t" + print(in, outside);
      }
      if (!it.comment.empty()) out += "\t" + std::string(mark) + " " + it.comment.str();
      if (it.kind != ItemKind::Comment || !it.comment.empty()) out += "\n";
    }
  }
  return out;
}

// The listing of an assembled program: per block a line
// `block_head(offset) <mark> block B, line L`, then per item
// `item_head(layout)` followed by its label, or a tab and print(inst, layout),
// and its comment after a tab and `<mark> `.
template <class Inst, class BlockHead, class ItemHead, class Print>
std::string listing_text(const Program<Inst>& p, const Result& r, std::string_view mark, BlockHead block_head,
                        ItemHead item_head, Print print) {
  std::string out;
  for (size_t b = 0; b < p.blocks.size(); ++b) {
    const auto& blk = p.blocks[b];
    out += block_head(b < r.block_offsets.size() ? r.block_offsets[b] : 0u) + std::string(mark) + " block " +
           std::to_string(b) + ", line " + std::to_string(blk.source_line) + "\n";
    for (size_t i = 0; i < blk.items.size(); ++i) {
      const auto& it = blk.items[i];
      ItemLayout lay;
      if (b < r.items.size() && i < r.items[b].size()) lay = r.items[b][i];
      std::string line = item_head(lay);
      if (it.kind == ItemKind::Label) line += it.label + ":";
      else if (it.kind == ItemKind::Instruction) line += "\t" + print(it.inst, lay);
      if (!it.comment.empty()) line += "\t" + std::string(mark) + " " + it.comment.str();
      out += line + "\n";
    }
  }
  return out;
}

// The blockwise assembler fed one block at a time (paper 003, Fig. 7): each
// block is laid out, relaxed and emitted when it is added, and may be freed
// right after; only the global table, the code and the fixups to global labels
// stay until finish().  The bytes are those of assemble(target, program) on the
// same blocks (Mode::Blockwise); the errors are the same, though a block's
// global-definition errors come with that block, not before every other one.
// With Items::LastOnly, Result::items stays empty: a caller that needs the
// item layout (a line map) reads each block's from last_items() after add(),
// so that the layout of every item never lives at once.
template <class Inst>
class Assembler {
 public:
  enum class Items : uint8_t { All, LastOnly };
  Assembler(const Target<Inst>& target, std::vector<std::string> globals, Items items = Items::All)
      : t_(target), s_(detail::stream_begin(target, std::move(globals))), keep_(items == Items::All) {}
  void add(const Block<Inst>& b) {
    View v(t_, b, n_++);
    detail::stream_block(*s_, v, keep_);
  }
  size_t blocks() const { return n_; }
  // The layout of the items of the block added last (valid until the next add)
  // and the code bytes emitted so far: the block ends there.
  std::span<const ItemLayout> last_items() const { return detail::stream_last_items(*s_); }
  uint32_t code_size() const { return detail::stream_code_size(*s_); }
  // The result, as assemble() gives it; the assembler is spent afterwards.
  Result finish() { return detail::stream_finish(*s_); }

 private:
  class View final : public detail::ProgramView {
   public:
    View(const Target<Inst>& t, const Block<Inst>& b, size_t index) : t_(t), b_(b), index_(index) {}
    std::span<const std::string> globals() const override { return {}; }
    size_t num_blocks() const override { return index_ + 1; }
    int source_line(size_t) const override { return b_.source_line; }
    size_t num_items(size_t) const override { return b_.items.size(); }
    void append_kinds(size_t, std::vector<ItemKind>& out) const override {
      for (const auto& it : b_.items) out.push_back(it.kind);
    }
    std::string_view label(size_t, size_t i) const override { return b_.items[i].label; }
    bool is_global(size_t, size_t i) const override { return b_.items[i].global; }
    void encode(size_t, size_t i, bool long_form, Encoding& out) const override {
      t_.encode(b_.items[i].inst, long_form, out);
    }

   private:
    const Target<Inst>& t_;
    const Block<Inst>& b_;
    size_t index_;
  };
  const Target<Inst>& t_;
  std::unique_ptr<detail::Stream, detail::StreamDeleter> s_;
  bool keep_;
  size_t n_ = 0;
};

}  // namespace ldc::as

