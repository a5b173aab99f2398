// frontend/st/st.h -- IEC 61131-3 Structured Text (docs/st.md): the lexer and
// the translation of ST bodies into the typed IEC IL reader's tokens.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "frontend/iecil/iecil.h"

namespace ldc::st {

// Names, numbers, literals and %addresses as Words (a.b.c one Word, as the IL
// lexer has them); operators and punctuation as Punct.  No Eol tokens: ST is
// free-form.  Comments (* *) (nested), // and pragmas {...} are skipped.
// Ends with End.  Throws CompileError.
std::vector<iecil::Tok> lex(std::string_view s);

// The whole file: declarations passed on, every POU body's statements written
// as IEC IL instructions located at their ST source, read by the typed IL
// reader.  Throws CompileError.
std::vector<iecil::Tok> to_il_tokens(const std::vector<iecil::Tok>& st);

}  // namespace ldc::st
