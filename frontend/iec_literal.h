// frontend/iec_literal.h -- IEC 61131-3 literals with their types, for the
// front ends that read typed programs (PLCopen XML; docs/plcopen.md).  A
// literal's value is the canonical 64 bits of its type (ir/typed.h): TIME in
// nanoseconds, so T#3.5ms and T#5d14h12m18s3.5ms hold exactly.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "ir/ir.h"

namespace ldc {

struct IecLiteral {
  Ty type = Ty::None;  // the type it is written in; an untyped integer is LINT, an untyped real LREAL
  bool typed = false;  // written with its type (INT#5, T#1s, D#2024-01-01, TRUE)
  uint64_t bits = 0;   // canonical bits of `type`
  bool based = false;  // an integer written in base 2, 8 or 16 (a bit pattern)
  bool is_real() const { return type == Ty::REAL || type == Ty::LREAL; }
  double real() const;        // a REAL/LREAL literal's value (exact)
  int64_t integer() const { return int64_t(bits); }  // an integer, time or date literal's value
};

// TRUE FALSE; integers 42 -7 1_000 16#FF 2#1010_0101 8#17; reals 1.5 -2.0e-3;
// typed TYPE#literal (INT#5, LREAL#1e-9, DWORD#16#FF, BOOL#1); durations
// T#1h2m3.5s TIME#..  LT#.. LTIME#.. (d h m s ms us ns, fractions allowed,
// a leading '-'); dates D#2024-01-31 DATE#..; times of day TOD#12:30:15.5
// TIME_OF_DAY#..; date and time DT#2024-01-31-12:30:15 DATE_AND_TIME#...
// nullopt with `why` empty: not a literal (a name); with `why` set: a malformed
// or out-of-range literal.
std::optional<IecLiteral> parse_iec_literal(std::string_view text, std::string& why);

// The IEC type named `name` (upper or lower case; TIME_OF_DAY is TOD,
// DATE_AND_TIME is DT); Ty::None if it is not an elementary type of types.def.
Ty iec_type_named(std::string_view name);

}  // namespace ldc
