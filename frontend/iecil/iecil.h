// frontend/iecil/iecil.h -- what the two readers of IEC 61131-3 IL share
// (docs/iec-il.md): the lexer, and the typed reader that takes a program
// with typed declarations (typed.cpp).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "ir/ir.h"

namespace ldc::iecil {

struct Tok {
  enum Kind { Word, Punct, Eol, End } kind = End;
  std::string text;
  int line = 0, col = 0;
};
std::string upper(std::string_view s);
// Words (names, numbers, literals, %addresses), punctuation ( ) [ ] : , ;
// := => .., one Eol per line end, and End.  Throws CompileError.
std::vector<Tok> lex(std::string_view s);
// Is `head` (a word up to its '#', e.g. "DT#2024") a date literal's, whose '-'
// and ':' before a digit belong to the word (DATE#2024-01-31, TOD#12:30:00)?
bool date_literal_head(std::string_view head);
// A direct address (%IX0.4, %QW2 ...); without the size letter (%I0.4, %Q0.0,
// %M1.2) a bit, as IEC 61131-3 has it.  nullopt and `why` if it is none.
std::optional<DeviceRef> iec_address(const std::string& text, std::string& why);

// Does the program need the typed reader: a TYPE, FUNCTION_BLOCK or FUNCTION,
// VAR_IN_OUT/VAR_TEMP/VAR_EXTERNAL, a CONSTANT or RETAIN block, or a declared
// type outside the classic subset (docs/iec-il.md, "Two readers")?
bool needs_typed_reader(const std::vector<Tok>& t);
// The typed reader: the program through the typed program model (ir/model.h)
// to typed IL.  `from_st`: the tokens are Structured Text written as IL
// (frontend/st), whose temporaries __Tn/__Sn take the type of the value
// stored into them.  Throws CompileError.
Program parse_typed_il(const std::vector<Tok>& t, const std::string& filename, bool from_st = false);

}  // namespace ldc::iecil
