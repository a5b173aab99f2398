// ir/time_scale.cpp -- MatIEC's __time_mul / __time_div in typed instructions
// (ir/time_scale.h).
#include "ir/time_scale.h"

#include "ir/typed.h"

namespace ldc {

std::vector<TypedStep> time_scale_steps(bool mul, Operand t, Operand x, Operand d,
                                        const std::function<Operand(const char*, Ty)>& temp) {
  const Ty L = Ty::LINT, R = Ty::LREAL, N = Ty::None;
  const Operand giga = Operand::typed_const(1000000000), giga_r = Operand::typed_const(typed::bits_of(1e9));
  const Operand sec = temp("sec", L), nsec = temp("nsec", L), sf = temp("sf", R), s = temp("s", L), f = temp("f", R),
                g = temp("g", R), rs = temp("rs", L), rn = temp("rn", L), p = temp("p", L);
  const Op scale = mul ? Op::TMUL : Op::TDIV;
  std::vector<TypedStep> k = {
      {Op::TDIV, L, N, t, giga, sec},   {Op::TMOD, L, N, t, giga, nsec},   // the timespec
      {Op::TCONV, R, L, sec, f, {}},    {scale, R, N, f, x, sf},           // s_f
      {Op::TTRUNC, L, R, sf, s, {}},    {Op::TCONV, R, L, s, f, {}},       // s
      {Op::TSUB, R, N, sf, f, f},       {Op::TMUL, R, N, f, giga_r, f},    // (s_f - s) * 10^9
      {Op::TCONV, R, L, nsec, g, {}},   {scale, R, N, g, x, g},            // nsec * x, nsec / x
  };
  if (mul)
    k.insert(k.end(), {{Op::TTRUNC, L, R, g, p, {}},
                       {Op::TDIV, L, N, p, giga, rs},
                       {Op::TADD, L, N, s, rs, rs},
                       {Op::TMOD, L, N, p, giga, p},
                       {Op::TCONV, R, L, p, g, {}}});
  else
    k.push_back({Op::TMOVE, L, N, s, rs, {}});
  k.insert(k.end(), {{Op::TADD, R, N, g, f, g},
                     {Op::TTRUNC, L, R, g, rn, {}},
                     {Op::TMUL, L, N, rs, giga, d},
                     {Op::TADD, L, N, d, rn, d}});
  if (!mul) {  // by 0 (or a NaN): 0.  x / x is 1, or NaN there, which MAX never takes: the factor 1 or 0
    const Operand q = temp("q", R), one = temp("one", L);
    k.insert(k.end(), {{Op::TDIV, R, N, x, x, q},
                       {Op::TMAX, R, N, Operand::typed_const(typed::bits_of(0.0)), q, q},
                       {Op::TTRUNC, L, R, q, one, {}},
                       {Op::TMUL, L, N, d, one, d}});
  }
  return k;
}

}  // namespace ldc
