// ir/time_scale.h -- a TIME times or divided by a number as MatIEC computes
// it, in typed instructions, for every front end that reads MULTIME/DIVTIME
// (docs/stdlib.md, "Time and date arithmetic").
#pragma once

#include <functional>
#include <vector>

#include "ir/ir.h"

namespace ldc {

struct TypedStep {
  Op op;
  Ty t, u;
  Operand a, b, c;
};

// d := t * x (mul) or t / x: MatIEC's __time_mul / __time_div (lib/C/
// iec_std_lib.h) on the timespec {sec, nsec} of t's nanoseconds (C's / and %),
// x an LREAL operand (IN2 converted by the caller):
//   mul: s_f = sec * x, s = (LINT) s_f, p = (LINT)(nsec * x),
//        {s + p / 10^9, (LINT)(p % 10^9 + (s_f - s) * 10^9)}
//   div: s_f = sec / x, s = (LINT) s_f, {s, (LINT)(nsec / x + (s_f - s) * 10^9)}
// then sec * 10^9 + nsec (__normalize_timespec moves whole seconds between
// the two and so changes nothing of that sum).  MatIEC holds p in a C `int`,
// which overflows (undefined in C) once nsec * x passes 2^31; here it is 64-bit.
// A divisor of 0 (or NaN) gives 0, where MatIEC converts an infinity or a NaN
// to an integer (undefined in C); so does an infinite one, as in MatIEC.
// `temp(name, type)` gives a scratch operand; t, x and d may not be one.
std::vector<TypedStep> time_scale_steps(bool mul, Operand t, Operand x, Operand d,
                                        const std::function<Operand(const char*, Ty)>& temp);

}  // namespace ldc
