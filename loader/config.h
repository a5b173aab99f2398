// loader/config.h -- the configuration system of paper 002: which I/O blocks
// every program reads and writes (found in its IL), merged per processor,
// checked across processors, and the system-level table that is stored in
// each task's image (section 'config', docs/image-format.md) and used by the
// runtime to refresh only the blocks a task uses (docs/runtime.md).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc {

// The areas every task of a configuration shares (the global image):
// the I/O image X Y WX WY and the global relays M K.  Every other area (D F
// T C S and the hidden ones) belongs to one program instance.
bool area_is_shared(Area a);
constexpr Area kSharedAreas[] = {Area::X, Area::Y, Area::M, Area::K, Area::WX, Area::WY};

// One access of a program to a shared device, in program order.
struct IoAccess {
  Area area;
  uint32_t index;
  bool write;
  uint32_t il_offset;  // the instruction's offset in the binary IL
  bool operator==(const IoAccess&) const = default;
};
// Every access to a shared area in a binary IL that validate_il accepts:
// operands of signature b v i are reads, w d writes.
std::vector<IoAccess> io_accesses(std::span<const uint8_t> il);

// Block flags of a row of the table.
constexpr uint8_t kBlockRead = 1;     // this program reads a point of the block
constexpr uint8_t kBlockWrite = 2;    // this program writes a point of the block
constexpr uint8_t kBlockWritten = 4;  // some program of the system writes it (see writer)
constexpr uint32_t kNoProcessor = 0xFFFFFFFFu;
constexpr uint32_t kMaxBlockSize = 8192;

// One row of the system-level table: a block some program of the system uses.
struct ConfigRow {
  Area area;
  uint32_t block;               // block number: points block*size .. block*size+size-1
  uint8_t flags;                // kBlock*
  uint32_t writer;              // processor that writes the block, kNoProcessor if none
  uint32_t period_us;           // the shortest period of the tasks that use it (refresh period)
  bool operator==(const ConfigRow&) const = default;
};

// The image section 'config': who this program is in the configuration and
// the system-level table, with this program's own use marked.
struct IoConfig {
  uint32_t block_size = 16;   // points per block, a multiple of 16
  uint32_t processor = 0;     // the processor (resource) the program runs on
  uint32_t period_us = 0;     // its task's period
  uint32_t priority = 0;      // its task's priority (0 highest)
  std::string resource, task, program;
  std::vector<ConfigRow> rows;  // ascending by (area, block), no duplicates
  bool operator==(const IoConfig&) const = default;
};

// Number of blocks of `block_size` points covering a shared area (the last
// one may be partial).
uint32_t block_count(Area a, uint32_t block_size);
// "Y0..Y15", "WX32..WX47" (the last block of an area is cut at its end).
std::string block_name(Area a, uint32_t block, uint32_t block_size);
// "Y3", "WX12": a shared device as the user spells it.
std::string point_name(Area a, uint32_t index);

// This program's own rows (flags kBlockRead/kBlockWrite only), ascending.
std::vector<ConfigRow> own_rows(std::span<const IoAccess> accesses, uint32_t block_size);

// The checks read_image applies to a 'config' section: well-formed (block
// size, areas, order, flags, writer) and its own rows exactly what the IL
// does.  "" if it passes, else the reason.
std::string check_io_config(const IoConfig& c, std::span<const uint8_t> il);

// ---------------------------------------------------------------- the system

// A program bound to a task, as the configuration system sees it.
struct ConfigTask {
  std::string program, task, resource;
  uint32_t processor = 0;
  uint32_t period_us = 0;
  uint32_t priority = 0;
  bool exclusive = false;  // its blocks may not be written by any other task, even on its processor
  std::vector<IoAccess> accesses;
};

// Two tasks that write the same block although they may not: on different
// processors, or one of them declared exclusive.
struct WriteConflict {
  Area area;
  uint32_t block;
  size_t first, second;                    // task indices, first < second
  std::vector<IoAccess> first_writes, second_writes;  // their writes inside the block
};

struct SystemConfig {
  uint32_t block_size = 16;
  std::vector<ConfigRow> system;        // every used block; flags only kBlockWritten
  std::vector<WriteConflict> conflicts; // empty if the configuration is accepted
  std::vector<IoConfig> per_task;       // the 'config' section of every task
};

// Paper 002: per task, the blocks it reads and writes; merged per processor;
// every block written by one processor only (and by one task only when a
// task is exclusive); then the system-level table.  block_size must be a
// multiple of 16 in 16..8192.
SystemConfig configure(const std::vector<ConfigTask>& tasks, uint32_t block_size);

}  // namespace ldc
