// loader/config.cpp -- the configuration system of paper 002 (loader/config.h).
#include "loader/config.h"

#include <algorithm>
#include <map>
#include <set>

namespace ldc {

bool area_is_shared(Area a) {
  return a == Area::X || a == Area::Y || a == Area::M || a == Area::K || a == Area::WX || a == Area::WY;
}

std::vector<IoAccess> io_accesses(std::span<const uint8_t> il) {
  std::vector<IoAccess> out;
  for (uint32_t off = 0; off < il.size();) {
    Instr in;
    uint32_t next = decode_instr(il, off, in);
    const char* sig = op_info(in.op).operands;
    for (int i = 0; sig[i]; i++) {
      const Operand& o = in.a[i];
      if (o.kind != OpdKind::Bit && o.kind != OpdKind::Int && o.kind != OpdKind::Real) continue;
      if (!area_is_shared(o.area)) continue;
      // a typed destination (r, and STX's array a) is a write too, and a
      // typed value takes all its cells (a LINT in WY: two points)
      bool write = sig[i] == 'w' || sig[i] == 'd' || sig[i] == 'r' || (sig[i] == 'a' && in.op == Op::TSTX);
      Ty t = operand_type(in, i);
      uint32_t cells = t == Ty::None || ty_info(t).cells == 0 ? 1 : ty_info(t).cells;
      uint32_t n = Layout::standard(0).count[int(o.area)];
      for (uint32_t c = 0; c < cells && o.index + c < n; c++) out.push_back(IoAccess{o.area, o.index + c, write, off});
    }
    off = next;
  }
  return out;
}

uint32_t block_count(Area a, uint32_t block_size) {
  uint32_t n = Layout::standard(0).count[int(a)];
  return block_size ? (n + block_size - 1) / block_size : 0;
}

std::string point_name(Area a, uint32_t index) { return std::string(area_name(a)) + std::to_string(index); }

std::string block_name(Area a, uint32_t block, uint32_t block_size) {
  uint32_t n = Layout::standard(0).count[int(a)];
  uint64_t first = uint64_t(block) * block_size, last = std::min<uint64_t>(first + block_size, n) - 1;
  return point_name(a, uint32_t(first)) + ".." + point_name(a, uint32_t(last));
}

std::vector<ConfigRow> own_rows(std::span<const IoAccess> accesses, uint32_t block_size) {
  std::map<std::pair<int, uint32_t>, uint8_t> m;
  for (const IoAccess& a : accesses) m[{int(a.area), a.index / block_size}] |= a.write ? kBlockWrite : kBlockRead;
  std::vector<ConfigRow> rows;
  for (auto& [k, f] : m) rows.push_back(ConfigRow{Area(k.first), k.second, f, kNoProcessor, 0});
  return rows;
}

std::string check_io_config(const IoConfig& c, std::span<const uint8_t> il) {
  if (c.block_size < 16 || c.block_size > kMaxBlockSize || c.block_size % 16)
    return "block size " + std::to_string(c.block_size) + " is not a multiple of 16 in 16.." + std::to_string(kMaxBlockSize);
  if (c.processor == kNoProcessor) return "processor number " + std::to_string(c.processor) + " is reserved";
  for (size_t i = 0; i < c.rows.size(); i++) {
    const ConfigRow& r = c.rows[i];
    std::string where = "row " + std::to_string(i) + ": ";
    if (int(r.area) >= kAreaCount || !area_is_shared(r.area))
      return where + "area " + std::to_string(int(r.area)) + " is not a shared area (X Y M K WX WY)";
    if (r.block >= block_count(r.area, c.block_size))
      return where + "block " + std::to_string(r.block) + " of " + area_name(r.area) + " does not exist (" +
             std::to_string(block_count(r.area, c.block_size)) + " blocks of " + std::to_string(c.block_size) + ")";
    std::string b = "block " + block_name(r.area, r.block, c.block_size);
    if (i > 0) {
      const ConfigRow& p = c.rows[i - 1];
      if (std::pair(int(p.area), p.block) >= std::pair(int(r.area), r.block))
        return where + b + " is out of order or repeated (rows ascend by area, then block)";
    }
    if (r.flags & ~(kBlockRead | kBlockWrite | kBlockWritten)) return where + b + ": unknown flags " + std::to_string(r.flags);
    if ((r.flags & kBlockWritten) != (r.writer != kNoProcessor ? kBlockWritten : 0))
      return where + b + ": the written flag and the writer processor disagree";
    if ((r.area == Area::X || r.area == Area::WX) && (r.flags & (kBlockWrite | kBlockWritten)))
      return where + b + ": an input block cannot be written";
    if ((r.flags & kBlockWrite) && r.writer != c.processor)
      return where + b + ": written by this program on processor " + std::to_string(c.processor) +
             ", but the table names processor " + std::to_string(r.writer);
  }
  // This program's own rows must be exactly what its IL does: the runtime
  // refreshes only these blocks, so a missing one would leave stale inputs.
  std::vector<ConfigRow> own = own_rows(io_accesses(il), c.block_size);
  size_t k = 0;
  for (const ConfigRow& r : c.rows) {
    uint8_t mine = r.flags & (kBlockRead | kBlockWrite);
    if (k < own.size() && std::pair(int(own[k].area), own[k].block) < std::pair(int(r.area), r.block))
      return "block " + block_name(own[k].area, own[k].block, c.block_size) + " is " +
             (own[k].flags & kBlockWrite ? "written" : "read") + " by the IL but missing from the table";
    bool same = k < own.size() && own[k].area == r.area && own[k].block == r.block;
    uint8_t want = same ? own[k].flags : 0;
    if (mine != want) {
      auto text = [](uint8_t f) {
        return f == 0 ? std::string("unused") : f == kBlockRead ? "read" : f == kBlockWrite ? "written" : "read and written";
      };
      return "block " + block_name(r.area, r.block, c.block_size) + " is " + text(want) + " by the IL, the table says " +
             text(mine);
    }
    if (same) k++;
  }
  if (k < own.size())
    return "block " + block_name(own[k].area, own[k].block, c.block_size) + " is " +
           (own[k].flags & kBlockWrite ? "written" : "read") + " by the IL but missing from the table";
  return "";
}

SystemConfig configure(const std::vector<ConfigTask>& tasks, uint32_t block_size) {
  SystemConfig sc;
  sc.block_size = block_size;
  using Key = std::pair<int, uint32_t>;
  // Task-level tables: block -> flags, and the writes inside each block.
  std::vector<std::map<Key, uint8_t>> use(tasks.size());
  std::vector<std::map<Key, std::vector<IoAccess>>> writes(tasks.size());
  for (size_t t = 0; t < tasks.size(); t++)
    for (const IoAccess& a : tasks[t].accesses) {
      Key k{int(a.area), a.index / block_size};
      use[t][k] |= a.write ? kBlockWrite : kBlockRead;
      if (a.write) writes[t][k].push_back(a);
    }
  // Merged per processor, then across processors: every block's writers.
  std::map<Key, std::vector<size_t>> writers;  // task indices, ascending
  std::map<Key, uint32_t> period;              // shortest period of the users
  for (size_t t = 0; t < tasks.size(); t++)
    for (auto& [k, f] : use[t]) {
      if (f & kBlockWrite) writers[k].push_back(t);
      auto [it, fresh] = period.emplace(k, tasks[t].period_us);
      if (!fresh) it->second = std::min(it->second, tasks[t].period_us);
    }
  for (auto& [k, ws] : writers)
    for (size_t i = 0; i < ws.size(); i++)
      for (size_t j = i + 1; j < ws.size(); j++) {
        const ConfigTask &a = tasks[ws[i]], &b = tasks[ws[j]];
        if (a.processor == b.processor && !a.exclusive && !b.exclusive) continue;
        sc.conflicts.push_back(WriteConflict{Area(k.first), k.second, ws[i], ws[j], writes[ws[i]][k], writes[ws[j]][k]});
      }
  for (auto& [k, p] : period) {
    auto w = writers.find(k);
    uint32_t writer = w == writers.end() ? kNoProcessor : tasks[w->second.front()].processor;
    sc.system.push_back(ConfigRow{Area(k.first), k.second, uint8_t(writer == kNoProcessor ? 0 : kBlockWritten), writer, p});
  }
  for (size_t t = 0; t < tasks.size(); t++) {
    IoConfig c;
    c.block_size = block_size;
    c.processor = tasks[t].processor;
    c.period_us = tasks[t].period_us;
    c.priority = tasks[t].priority;
    c.resource = tasks[t].resource;
    c.task = tasks[t].task;
    c.program = tasks[t].program;
    c.rows = sc.system;
    for (ConfigRow& r : c.rows) {
      auto it = use[t].find(Key{int(r.area), r.block});
      if (it != use[t].end()) {
        r.flags |= it->second;
        // A block this task writes names this task's processor (a conflict
        // is refused anyway; this keeps every accepted section consistent).
        if (it->second & kBlockWrite) r.writer = c.processor, r.flags |= kBlockWritten;
      }
    }
    sc.per_task.push_back(std::move(c));
  }
  return sc;
}

}  // namespace ldc
