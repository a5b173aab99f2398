// ir/ladder.h -- any program as the ladder grid of docs/format.md (`ldc --emit=ld`)
// and the grid's geometry for the monitor (`ldrun --monitor`, docs/runtime.md).
//
// A rung's IL is raised back to its series/parallel tree (the inverse of
// lower_to_il: conditions by symbolic evaluation of the bit stack, actions by
// the MPS/MRD/MPP structure), then laid out as rows of characters.  IL whose
// stack use is not a tree (an OR into the power flow after an output, a rung
// reading what an earlier rung left on the stack, ...) has no grid and is
// refused by name.
#pragma once

#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc {

// Raises every rung of `p` to its tree.  Throws CompileError at the offending
// instruction's source line (the rung's if it has none) naming the rung and
// the instruction when a rung has no ladder form.
TreeProgram raise_to_tree(const Program& p);

// The geometry of one drawn rung, in character cells (row 0 is the first row;
// column 0 is the left rail).  Nets are the electrical nodes: net 0 is the
// left rail; an input element conducts from in_net to out_net; an output hangs
// on in_net.  The nets and elements form a DAG from the rail to the outputs.
struct LadderElem {
  int row = 0, col = 0, width = 0;  // the cells of "[...]" or "(...)"
  bool output = false;
  Instr elem;                       // LOAD/LOADN/LOADP/LOADF/LDxx for inputs; the output instruction
  std::string text;                 // the element as drawn, brackets included
  int in_net = 0, out_net = -1;     // out_net: -1 for outputs
};
struct LadderWire {                 // horizontal run of '-' and '+' cells
  int row = 0, col0 = 0, col1 = 0;  // inclusive
  int net = 0;
};
struct LadderLink {                 // vertical run of '|' and '+' cells
  int col = 0, row0 = 0, row1 = 0;  // inclusive
  int net = 0;
};
struct LadderRung {
  std::vector<std::string> labels;
  std::string title;
  int line = 0;                     // the rung's source line
  std::vector<std::string> rows;    // the grid text, rail included
  std::vector<LadderElem> elems;
  std::vector<LadderWire> wires;
  std::vector<LadderLink> links;
  int nets = 1;
};
struct Ladder {
  std::vector<Alias> aliases;
  std::vector<DeviceRef> retain;
  std::vector<LadderRung> rungs;
  std::vector<std::string> end_labels;
};

// Lays out every rung.  Operands are spelled with the program's first alias
// of a device when it has one.  Throws CompileError if something has no
// spelling in the grid (a REAL constant that is infinite or NaN, a title with
// a line break, an alias name the grid cannot read).
Ladder draw_ladder(const TreeProgram& p);

// The grid source text (`ldc --emit=ld`): parse_ld of it lowers to the IL of
// `lower_to_il(p)`, line numbers aside.
std::string print_ladder(const Ladder& l, const std::string& source_name);

}  // namespace ldc
